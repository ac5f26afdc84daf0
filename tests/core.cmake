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
# Source comments cite no issue number and no measured timing (reads the source tree only).
occ_test(comment_conventions_test unit SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/comment_conventions_test.cpp)
