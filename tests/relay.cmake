# link emulator tests: occ_relay in-process behind loopback echo servers, and the link_relay binary
# (flags, port files, control port). 127.0.0.1 and port 0 only; the suite takes a few seconds.
occ_test(relay_test integration LIBS occ_relay occ_net SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/relay_test.cpp)
add_dependencies(relay_test link_relay)
