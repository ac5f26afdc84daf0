# GL tests (label gl): need an OpenGL 4.5 core context through EGL or OSMesa (llvmpipe is fine).
occ_test(gl_test gl LIBS occ_gl SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/gl_context_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/gl_render_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/gl_material_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/gl_stream_test.cpp)

# PNG files and the frame_diff tool (no GL).
occ_test(image_test unit LIBS occ_common SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/image_png_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/image_frame_diff_test.cpp)
add_dependencies(image_test frame_diff)

# The HC depth pyramid on the GPU against occlusion queries and the switch step.
occ_test(gl_hzb_test gl LIBS occ_gl occ_cluster SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/gl_hzb_test.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/gl_depth_raster_test.cpp)
# The tau checker's arithmetic (frame_diff --items, render_client/tools/item_diff.hpp).
occ_test(item_diff_test unit LIBS occ_item_diff SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/image_item_diff_test.cpp)
# The tau bound end to end (label integration): the tau > 0 promise (0 objects missing, displacement
# <= tau + 1) on the item buffers of the reference and the cluster
occ_test(tau_bound_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/lod_tau_bound_test.cpp)
add_dependencies(tau_bound_test switch_node render_client frame_diff)
