// The stream a Connection's bytes go through (transport.cpp, and TLS over it: tls.hpp): its TCP
// socket, counting what crosses it, so the connection knows its bytes on the wire (the messages,
// plus TLS records and handshake with a key). The io thread only; the counters are atomic so
// that stats() may read them from other threads.
#pragma once
#include <atomic>
#include <cstdint>
#include <utility>

#include "protocol/net/asio_names.hpp"

namespace occ::net {

class CountedSocket {
 public:
  using executor_type = asio_names::tcp::socket::executor_type;
  using lowest_layer_type = asio_names::tcp::socket::lowest_layer_type;

  CountedSocket(asio_names::tcp::socket& s, std::atomic<uint64_t>& in, std::atomic<uint64_t>& out)
      : s_(s), in_(in), out_(out) {}

  executor_type get_executor() { return s_.get_executor(); }
  lowest_layer_type& lowest_layer() { return s_.lowest_layer(); }
  const lowest_layer_type& lowest_layer() const { return s_.lowest_layer(); }

  template <class Buffers, class Handler>
  void async_read_some(const Buffers& b, Handler&& h) {
    s_.async_read_some(b, [this, h = std::forward<Handler>(h)](asio_names::error_code ec, size_t n) mutable {
      in_ += n;
      std::move(h)(ec, n);
    });
  }
  template <class Buffers, class Handler>
  void async_write_some(const Buffers& b, Handler&& h) {
    s_.async_write_some(b, [this, h = std::forward<Handler>(h)](asio_names::error_code ec, size_t n) mutable {
      out_ += n;
      std::move(h)(ec, n);
    });
  }

 private:
  asio_names::tcp::socket& s_;
  std::atomic<uint64_t>& in_;
  std::atomic<uint64_t>& out_;
};

}  // namespace occ::net
