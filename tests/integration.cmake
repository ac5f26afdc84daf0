# integration tests: the real binaries over loopback (127.0.0.1, port 0 + port files)
occ_test(cluster_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/integration_cluster_test.cpp)
add_dependencies(cluster_test switch_node render_client frame_diff)
