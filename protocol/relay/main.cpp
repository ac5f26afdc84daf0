// link_relay: user-space link emulator between two cluster processes (the kernel here has no
// netem). Model and control commands: protocol/relay/relay.hpp.
#include <signal.h>

#include <iostream>
#include <sstream>
#include <stdexcept>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "protocol/net/endpoint.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/relay/relay.hpp"

namespace {

// An override of -1 means "same as the symmetric flag".
occ::relay::LinkParams direction(double delay, double jitter, double rate, double d, double j, double r) {
  return {d >= 0 ? d : delay, j >= 0 ? j : jitter, r >= 0 ? r : rate};
}

std::string describe(const occ::relay::LinkParams& p) {
  std::ostringstream s;
  s << "delay " << p.delay_ms << " ms, jitter " << p.jitter_ms << " ms, rate ";
  if (p.rate_mbit > 0)
    s << p.rate_mbit << " Mbit/s";
  else
    s << "unlimited";
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  return occ::run_main([&] {
    std::string listen = "127.0.0.1:0", port_file, target, control_port_file;
    double delay = 0, jitter = 0, rate = 0;
    double up_delay = -1, down_delay = -1, up_jitter = -1, down_jitter = -1, up_rate = -1, down_rate = -1;
    uint32_t seed = 1;
    int timeout_ms = 10000, queue_mib = 8;
    constexpr double kMaxMs = 600000, kMaxMbit = 100000;
    occ::Cli cli("link_relay", "--target HOST:PORT [options]",
                 "TCP relay that emulates a network link: forwards every accepted connection to the target and\n"
                 "adds, per direction, a one-way delay, jitter (never reordering bytes) and a bandwidth cap.\n"
                 "up = client -> target, down = target -> client. Per-direction flags default to -1 = the\n"
                 "symmetric value. Control (with --control-port-file): connect to that port on 127.0.0.1 and\n"
                 "send lines 'stall', 'resume', 'cut', 'flip' (alter one byte from the target) or 'stats';\n"
                 "each gets a one-line answer. Logs one line per connection opened / closed (bytes per\n"
                 "direction) to stderr. SIGINT/SIGTERM: exit 0.");
    cli.option("listen", &listen, "ADDR:PORT", "where to listen (port 0 = pick a free one)");
    cli.option("port-file", &port_file, "FILE", "write the listening port here (atomically)");
    cli.option("target", &target, "HOST:PORT", "where to forward each connection (required)");
    cli.option("delay-ms", &delay, 0, kMaxMs, "one-way delay, each direction");
    cli.option("jitter-ms", &jitter, 0, kMaxMs, "uniform +- jitter added to the delay, each direction");
    cli.option("rate-mbit", &rate, 0, kMaxMbit, "bandwidth cap in Mbit/s, each direction (0 = unlimited)");
    cli.option("up-delay-ms", &up_delay, -1, kMaxMs, "client -> target delay");
    cli.option("down-delay-ms", &down_delay, -1, kMaxMs, "target -> client delay");
    cli.option("up-jitter-ms", &up_jitter, -1, kMaxMs, "client -> target jitter");
    cli.option("down-jitter-ms", &down_jitter, -1, kMaxMs, "target -> client jitter");
    cli.option("up-rate-mbit", &up_rate, -1, kMaxMbit, "client -> target cap");
    cli.option("down-rate-mbit", &down_rate, -1, kMaxMbit, "target -> client cap");
    cli.option("control-port-file", &control_port_file, "FILE", "open the control port, write its port here");
    cli.option("seed", &seed, 0, 4294967295L, "jitter random seed");
    cli.option("timeout-ms", &timeout_ms, 0, 3600000, "how long to retry connecting to the target, per connection");
    cli.option("queue-mib", &queue_mib, 1, 1024, "per direction: stop reading the sender above this many MiB queued");
    if (!cli.parse(argc, argv)) return 0;
    if (target.empty()) throw occ::InputError("--target HOST:PORT is required (see link_relay --help)");

    occ::relay::RelayOptions o;
    const occ::net::Endpoint l = occ::net::parse_endpoint("listen", listen, {true, 0}),
                             t = occ::net::parse_endpoint("target", target, {true, 1});
    o.listen_address = l.host;
    o.listen_port = l.port;
    o.target_host = t.host;
    o.target_port = t.port;
    o.up = direction(delay, jitter, rate, up_delay, up_jitter, up_rate);
    o.down = direction(delay, jitter, rate, down_delay, down_jitter, down_rate);
    const std::string links = "up: " + describe(o.up) + "; down: " + describe(o.down);
    o.seed = seed;
    o.connect_timeout = occ::relay::Millis(timeout_ms);
    o.max_queued_bytes = size_t(queue_mib) << 20;
    o.control = !control_port_file.empty();
    o.log = [](const std::string& line) { std::cerr << "link_relay: " << line << std::endl; };

    // Block the stop signals before the relay's thread starts (it inherits the mask); sigwait below.
    sigset_t stop;
    sigemptyset(&stop);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop, nullptr);

    auto relay = occ::relay::Relay::start(std::move(o));
    if (!relay) throw std::runtime_error(relay.error());
    if (!port_file.empty())
      if (auto err = occ::net::write_port_file(port_file, relay->port())) throw std::runtime_error(*err);
    if (!control_port_file.empty())
      if (auto err = occ::net::write_port_file(control_port_file, relay->control_port()))
        throw std::runtime_error(*err);
    std::cerr << "link_relay: " << l.host << ":" << relay->port() << " -> " << target << "; " << links;
    if (relay->control_port()) std::cerr << "; control port " << relay->control_port();
    std::cerr << std::endl;

    int sig = 0;
    sigwait(&stop, &sig);
    return 0;  // ~Relay closes the open connections ("relay stopped")
  });
}
