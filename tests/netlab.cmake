# scripts/netlab.sh's repeated points: the aggregation (median, min, max, frames) on a hand-made
# runs file, the plots of it, the --repeats check.
find_package(Python3 COMPONENTS Interpreter REQUIRED)
add_test(NAME Netlab.RepeatsAggregate COMMAND ${Python3_EXECUTABLE} -W error ${CMAKE_CURRENT_SOURCE_DIR}/netlab_aggregate_test.py ${PROJECT_SOURCE_DIR})
set_tests_properties(Netlab.RepeatsAggregate PROPERTIES LABELS unit)
