# parser fuzz harnesses (common/fuzz/): the checked-in seeds of tests/fuzz/ and fixed-seed
# mutations of them, in every build (the libFuzzer runs: common/fuzz/CMakeLists.txt)
occ_test(fuzz_parsers_test unit LIBS occ_fuzz_targets SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_parsers_test.cpp)
# make_fuzz_seeds DIR: writes the seeds of tests/fuzz/ with the repository's own writers (the glTF
# exporter of scene_export, save_camera_path, the cache writers)
add_executable(make_fuzz_seeds ${CMAKE_CURRENT_SOURCE_DIR}/make_fuzz_seeds.cpp ${PROJECT_SOURCE_DIR}/render_client/tools/scene_export.cpp)
target_link_libraries(make_fuzz_seeds PRIVATE occ_fuzz_targets)
