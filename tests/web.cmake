# render_client --web: the input messages' parser and the frames' encoders and header (unit), and
# the page in a real browser (headless Debian chromium driven by puppeteer-core from
# tests/web/node_modules, scripts/setup.sh): it drives a cluster started by scripts/cluster.sh
# --web and compares the still frame with the reference renderer. Skipped (exit 77) only where
# /usr/bin/chromium is absent.
occ_test(web_input_test unit LIBS occ_web SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/web_input_test.cpp)
occ_test(web_frames_test unit LIBS occ_web SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/web_frames_test.cpp)
find_program(OCC_NODE node)
if(OCC_NODE)
  add_test(NAME Web.BrowserDrivesTheCluster
           COMMAND ${OCC_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/web/browser_test.js ${PROJECT_SOURCE_DIR}
                   ${CMAKE_RUNTIME_OUTPUT_DIRECTORY})
else()  # node is a dependency (scripts/setup.sh): its absence fails, it does not skip
  add_test(NAME Web.BrowserDrivesTheCluster COMMAND sh -c "echo 'needs node (Debian nodejs: scripts/setup.sh)'; exit 1")
endif()
set_tests_properties(Web.BrowserDrivesTheCluster PROPERTIES LABELS integration SKIP_RETURN_CODE 77 TIMEOUT 600)
add_dependencies(web_frames_test render_client switch_node frame_diff)  # the browser test's binaries
