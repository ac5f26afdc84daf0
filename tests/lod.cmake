# LOD/HLOD, selection, cache and front tracking: no GL (label unit).
occ_test(lod_test unit LIBS occ_cluster SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/lod_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/lod_front_test.cpp)
# stale cache temporaries: real writer processes (lod_cache_writer) killed while they write
add_executable(lod_cache_writer ${CMAKE_CURRENT_SOURCE_DIR}/lod_cache_writer.cpp)
target_link_libraries(lod_cache_writer PRIVATE occ_common)
occ_test(lod_temp_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/lod_temp_test.cpp)
add_dependencies(lod_temp_test lod_cache_writer)
