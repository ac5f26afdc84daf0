occ_test(core_test unit LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/core_math_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_hierarchy_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_path_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_culling_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_enclosure_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_occlusion_gate_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_cli_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_camera_buffer_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_hzb_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/core_depth_raster_test.cpp)
