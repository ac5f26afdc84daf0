#include "protocol/net/endpoint.hpp"

#include "common/error.hpp"

namespace occ::net {

Endpoint parse_endpoint(const std::string& flag, const std::string& text, EndpointRules rules) {
  Endpoint e{"127.0.0.1", 0};
  std::string port = text;
  const auto colon = text.rfind(':');
  if (colon != std::string::npos) {
    e.host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (e.host.empty() && !rules.host_required) throw InputError("--" + flag + " '" + text + "': empty host");
  }
  size_t used = 0;
  long p = -1;
  try {
    p = std::stol(port, &used);
  } catch (...) {
    used = 0;
  }
  const bool host_missing = rules.host_required && (colon == std::string::npos || e.host.empty());
  if (host_missing || used == 0 || used != port.size() || p < rules.min_port || p > 65535)
    throw InputError("--" + flag + " '" + text + "': expected HOST:PORT with PORT " + std::to_string(rules.min_port) +
                     "..65535");
  e.port = uint16_t(p);
  return e;
}

}  // namespace occ::net
