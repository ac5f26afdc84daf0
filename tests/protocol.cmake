# protocol tests: decoders and visible-set algebra (unit), loopback transport (integration)
occ_test(protocol_test unit LIBS occ_protocol SOURCES
  protocol_samples.cpp protocol_wire_test.cpp protocol_fuzz_test.cpp protocol_visible_set_test.cpp)
# the cluster key: key files and the HMAC proofs (unit); over loopback in net_transport_test
occ_test(net_auth_test unit LIBS occ_net OpenSSL::Crypto SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/net_auth_test.cpp)
occ_test(net_transport_test integration LIBS occ_net Boost::system SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/net_transport_test.cpp)
# what the three processes share (protocol/cluster): diff sender, typed config, endpoints
occ_test(switch_step_test unit LIBS occ_cluster SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/switch_step_test.cpp)
# TLS links with a cluster key (protocol/net/tls.hpp): confidentiality, refusals, integrity
occ_test(net_tls_test integration LIBS occ_net Boost::system OpenSSL::SSL SOURCES
  ${CMAKE_CURRENT_SOURCE_DIR}/net_tls_test.cpp)
