# Issue 13: exactness of every benchmarked method, per-frame byte attribution, the bench report.
occ_test(exactness_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bench_exactness_test.cpp)
add_dependencies(exactness_test render_client frame_diff)
