# parser fuzz harnesses (common/fuzz/): the checked-in seeds of tests/fuzz/ and fixed-seed
# mutations of them, in every build (the libFuzzer runs: common/fuzz/CMakeLists.txt)
occ_test(fuzz_parsers_test unit LIBS occ_fuzz_targets SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_parsers_test.cpp)
