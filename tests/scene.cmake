# scene tests: glTF loading (real shared scenes, malformed and fuzzed files), city, layouts, specs
occ_test(scene_test unit LIBS occ_common SOURCES
  scene_loading_test.cpp scene_gltf_test.cpp scene_generate_test.cpp scene_material_test.cpp)
occ_test(plant_test unit LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/scene_plant_test.cpp)
# model files other than glTF: PLY (our reader), OBJ/STL/OFF/COLLADA (Assimp), --up, their scene cache
occ_test(scene_formats_test unit LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/scene_formats_test.cpp)
# write_model: model files from --scene specs (big models for measurements), and the readers side by side
add_executable(write_model ${CMAKE_CURRENT_SOURCE_DIR}/write_model.cpp)
target_link_libraries(write_model PRIVATE occ_common)
