# Hard cases, label "hard" (scripts/test.sh and CI run every label; `scripts/test.sh -L hard`
# runs only these): numerical hard cases through the three real processes, translated scenes,
# extreme viewports, rotation drift, faults and bad input at the listening ports, and the
# depth-precision measurement (GL).
occ_test(hard_cases_test hard LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_cases_test.cpp)
add_dependencies(hard_cases_test switch_node render_client frame_diff)
occ_test(hard_translated_test hard LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_translated_test.cpp)
add_dependencies(hard_translated_test switch_node render_client frame_diff)
occ_test(hard_rotation_test hard LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_rotation_test.cpp)
add_dependencies(hard_rotation_test switch_node render_client frame_diff)
occ_test(hard_scenes_test hard LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_scenes_test.cpp)
occ_test(hard_depth_test hard LIBS occ_gl SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_depth_test.cpp)
occ_test(hard_faults_test hard LIBS occ_common occ_protocol SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_faults_test.cpp)
add_dependencies(hard_faults_test switch_node render_client frame_diff)
occ_test(hard_exit_test hard LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_exit_test.cpp)
add_dependencies(hard_exit_test switch_node render_client frame_diff)
# Every culling method against brute force, pixel for pixel, on the crack scenes and every shared
# scene (label "matrix": left out of the sanitizer suite, see scripts/test.sh).
occ_test(exactness_matrix_test matrix LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/exactness_matrix_test.cpp)
add_dependencies(exactness_matrix_test switch_node render_client occlusion_server frame_diff)
# A resync at every frame of a walk, replayed in one process with the nodes' cull frames (GL).
occ_test(hard_resync_test hard LIBS occ_cull_frame SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/hard_resync_test.cpp)
