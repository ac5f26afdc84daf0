// HOST:PORT on the command line: the one parser every binary uses (--listen, --peer, --connect,
// the relay's --target).
#pragma once
#include <cstdint>
#include <string>

namespace occ::net {

struct Endpoint {
  std::string host;
  uint16_t port = 0;
};

struct EndpointRules {
  bool host_required = false;  // false: "PORT" alone means 127.0.0.1:PORT
  uint16_t min_port = 0;       // 0 allows "pick a free port" (listening)
};

// Parses "HOST:PORT" (or "PORT" unless rules.host_required). Throws occ::InputError naming the
// flag: "--peer 'x:99999': expected HOST:PORT with PORT 0..65535", "--listen ':1': empty host".
Endpoint parse_endpoint(const std::string& flag, const std::string& text, EndpointRules rules = {});

}  // namespace occ::net
