# render_client --window: the navigator (unit) and a windowed cluster under Xvfb + xdotool.
occ_test(navigator_test unit LIBS occ_navigator SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/navigator_test.cpp)
occ_test(window_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/window_test.cpp)
# sends WM_DELETE_WINDOW like a window manager, through render_client/x11_lib.hpp (dlopen, no link)
target_link_libraries(window_test PRIVATE ${CMAKE_DL_LIBS})
target_include_directories(window_test PRIVATE ${X11_INCLUDE_DIR})
add_dependencies(window_test switch_node render_client)
# Conventions: --version, script --help, scripts/video.sh.
occ_test(conventions_test integration LIBS occ_common SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/conventions_test.cpp)
add_dependencies(conventions_test render_client switch_node occlusion_server frame_diff cull_overview link_relay)
