# scene tests: glTF loading (real shared scenes, malformed and fuzzed files), city, layouts, specs
occ_test(scene_test unit LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/scene_loading_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/scene_gltf_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/scene_generate_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/scene_material_test.cpp)
occ_test(plant_test unit LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/scene_plant_test.cpp)
