# render_client --web: the input messages' parser (unit) and the page in a real browser (headless
# Debian chromium driven by puppeteer-core from tests/web/node_modules, scripts/setup.sh): it
# drives a cluster started by scripts/cluster.sh --web and compares the still frame with the
# reference renderer. Skipped (exit 77) only where /usr/bin/chromium is absent.
occ_test(web_input_test unit LIBS occ_web SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/web_input_test.cpp)
find_program(OCC_NODE node)
if(OCC_NODE)
  add_test(NAME Web.BrowserDrivesTheCluster
           COMMAND ${OCC_NODE} ${CMAKE_CURRENT_SOURCE_DIR}/web/browser_test.js ${PROJECT_SOURCE_DIR}
                   ${CMAKE_RUNTIME_OUTPUT_DIRECTORY})
  set_tests_properties(Web.BrowserDrivesTheCluster PROPERTIES LABELS integration SKIP_RETURN_CODE 77 TIMEOUT 600)
endif()
occ_test(web_frames_test unit LIBS occ_web SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/web_frames_test.cpp)
