# The binaries start with only EGL (no OSMesa, LLVM or Xlib linked; each loaded when
# asked for), and the prepared GPU run (scripts/gpu_bundle.sh + run_gpu.sh) end to end on llvmpipe.
occ_test(gpu_start_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/gpu_start_test.cpp)
add_dependencies(gpu_start_test render_client switch_node occlusion_server frame_diff cull_overview link_relay)
