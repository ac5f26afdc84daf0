// What the transport tests share: the log lines of the connections a test configures.
#pragma once
#include <chrono>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "protocol/net/transport.hpp"

namespace occtest {

// Collects the log lines of the connections it configures (with `key`: a keyed, TLS connection).
struct LogCapture {
  std::mutex m;
  std::vector<std::string> lines;
  occ::net::ConnectionOptions options(occ::net::Millis linger = std::chrono::milliseconds(300),
                                      const occ::net::ClusterKey* key = nullptr) {
    occ::net::ConnectionOptions o = occ::net::keyed_options(key);
    o.close_linger = linger;
    o.log = [this](const std::string& line) {
      std::lock_guard lk(m);
      lines.push_back(line);
    };
    return o;
  }
  occ::net::ConnectionOptions options(const occ::net::ClusterKey* key) { return options(std::chrono::milliseconds(300), key); }
  std::vector<std::string> snapshot() {
    std::lock_guard lk(m);
    return lines;
  }
};

// Most transport tests start with a listener on a free port of 127.0.0.1 and a log for the
// connections they make.
class WithListener : public testing::Test {
 protected:
  void SetUp() override {
    auto l = occ::net::Listener::open(0);
    ASSERT_TRUE(l) << l.error();
    listener.emplace(std::move(*l));
  }
  LogCapture log;
  std::optional<occ::net::Listener> listener;
};

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace occtest
