# Exactness of every benchmarked method, per-frame byte attribution, the bench report.
occ_test(exactness_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bench_exactness_test.cpp)
add_dependencies(exactness_test render_client frame_diff)
occ_test(frame_bytes_test integration LIBS occ_cluster occ_net Boost::system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bench_frame_bytes_test.cpp)
add_dependencies(frame_bytes_test render_client)
# The bench report's arithmetic (signs, ratios, the three-machine model) on hand-made CSV files.
find_package(Python3 COMPONENTS Interpreter REQUIRED)
add_test(NAME BenchReport.Arithmetic COMMAND ${Python3_EXECUTABLE} -W error ${CMAKE_CURRENT_SOURCE_DIR}/bench_report_test.py)
set_tests_properties(BenchReport.Arithmetic PROPERTIES LABELS unit)
# scripts/limit_table.py (docs/results.md's "cluster / oracle") end to end on one small view.
add_test(NAME LimitTable.OneViewEndToEnd COMMAND ${Python3_EXECUTABLE} -W error ${CMAKE_CURRENT_SOURCE_DIR}/limit_table_test.py
         $<TARGET_FILE_DIR:render_client>)
set_tests_properties(LimitTable.OneViewEndToEnd PROPERTIES LABELS integration)
# The README is a user guide (<= 200 lines, no paths outside the repository, links resolve).
add_test(NAME Docs.ReadmeIsAGuideAndLinksResolve COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/docs_test.py ${PROJECT_SOURCE_DIR})
set_tests_properties(Docs.ReadmeIsAGuideAndLinksResolve PROPERTIES LABELS unit)
# No file names a round of work ("session" followed by a number): facts come with command, date, commit.
add_test(NAME Docs.NoFileNamesASessionNumber COMMAND ${Python3_EXECUTABLE} -W error ${CMAKE_CURRENT_SOURCE_DIR}/docs_test.py ${PROJECT_SOURCE_DIR} --no-session-numbers)
set_tests_properties(Docs.NoFileNamesASessionNumber PROPERTIES LABELS unit)
# README's flag tables agree with the --help of render_client, switch_node and scripts/cluster.sh:
# every flag exists, every value README lists is offered, every default README states is the one printed.
add_test(NAME Docs.ReadmeFlagTablesMatchHelp
         COMMAND ${Python3_EXECUTABLE} -W error ${CMAKE_CURRENT_SOURCE_DIR}/readme_flags_test.py ${PROJECT_SOURCE_DIR}
                 $<TARGET_FILE:render_client> $<TARGET_FILE:switch_node>)
set_tests_properties(Docs.ReadmeFlagTablesMatchHelp PROPERTIES LABELS unit)
# The code's shape: layers include only the layers below, files <= 700 lines, functions <= 120 lines.
add_test(NAME Structure.LayersFileAndFunctionSizes COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/structure_test.py ${PROJECT_SOURCE_DIR})
set_tests_properties(Structure.LayersFileAndFunctionSizes PROPERTIES LABELS unit)
