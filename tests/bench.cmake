# Issue 13: exactness of every benchmarked method, per-frame byte attribution, the bench report.
occ_test(exactness_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bench_exactness_test.cpp)
add_dependencies(exactness_test render_client frame_diff)
occ_test(frame_bytes_test integration LIBS occ_cluster occ_net Boost::system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bench_frame_bytes_test.cpp)
add_dependencies(frame_bytes_test render_client)
