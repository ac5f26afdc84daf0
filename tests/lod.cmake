# LOD/HLOD, selection, cache and front tracking: no GL (label unit).
occ_test(lod_test unit LIBS occ_cluster SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/lod_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/lod_front_test.cpp)
