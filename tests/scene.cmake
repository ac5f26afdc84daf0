# scene tests: glTF loading (real shared scenes, malformed and fuzzed files), city, layouts, specs
occ_test(scene_test unit LIBS occ_common SOURCES
  scene_loading_test.cpp scene_gltf_test.cpp scene_generate_test.cpp scene_material_test.cpp)
occ_test(plant_test unit LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/scene_plant_test.cpp)
