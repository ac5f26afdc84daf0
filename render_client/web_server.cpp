#include "render_client/web_server.hpp"

#include <openssl/rand.h>

#include <iostream>
#include <optional>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include "common/error.hpp"
#include "protocol/net/endpoint.hpp"
#include "render_client/web_session.hpp"
#include "render_client/web_tls.hpp"

namespace occ {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

namespace {

// 128 random bits, hex.
std::string random_token() {
  unsigned char b[16];
  if (RAND_bytes(b, sizeof b) != 1) throw std::runtime_error("--web: no random bytes for the token");
  static const char* hex = "0123456789abcdef";
  std::string s;
  for (unsigned char c : b) s += {hex[c >> 4], hex[c & 15]};
  return s;
}

}  // namespace

WebOptions parse_web_options(const std::string& web, const std::string& tls) {
  const net::Endpoint e = net::parse_endpoint("web", web);
  WebOptions o;
  o.address = e.host;
  o.port = e.port;
  o.tls = tls;
  if (!tls.empty() && tls != "self-signed" && tls.find(':') == std::string::npos)
    throw InputError("--web ,tls='" + tls + "': expected CERT.pem:KEY.pem or self-signed");
  return o;
}

struct WebServer::Impl {
  WebShared shared;  // before the io_context: sessions refer to it until they are destroyed
  asio::io_context ioc;
  tcp::acceptor acceptor{ioc};
  std::optional<asio::ssl::context> tls;
  std::string address;
  std::thread thread;

  void accept() {
    acceptor.async_accept([this](boost::system::error_code ec, tcp::socket s) {
      if (!ec) start_web_session(std::move(s), shared, tls ? &*tls : nullptr);
      if (acceptor.is_open()) accept();
    });
  }
};

WebServer::WebServer(const WebOptions& o, InputHandler on_input) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.shared.drive_token = random_token();
  m.shared.view_token = random_token();
  m.shared.on_input = std::move(on_input);
  m.address = o.address;
  if (!o.tls.empty()) m.tls.emplace(make_tls_context(o.tls));
  boost::system::error_code ec;
  const auto addr = asio::ip::make_address(o.address, ec);
  if (ec) throw InputError("--web '" + o.address + "': not an IP address");
  const tcp::endpoint ep(addr, o.port);
  m.acceptor.open(ep.protocol(), ec);
  if (!ec) m.acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) m.acceptor.bind(ep, ec);
  if (!ec) m.acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec)
    throw InputError("--web '" + o.address + ":" + std::to_string(o.port) + "': cannot listen: " + ec.message());
  m.accept();
  m.thread = std::thread([&m] { m.ioc.run(); });
  std::cerr << "render_client: web viewer (drive): " << url(true) << "\n"
            << "render_client: web viewer (view only): " << url(false) << "\n";
}

WebServer::~WebServer() {
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

void WebServer::publish(std::shared_ptr<const std::string> message) {
  asio::post(impl_->ioc, [this, message] {
    WebShared& sh = impl_->shared;
    sh.last = message;
    std::erase_if(sh.watchers, [](const std::weak_ptr<WebWatcher>& w) { return w.expired(); });
    for (const auto& w : sh.watchers)
      if (auto s = w.lock()) s->deliver(message);
  });
}

uint16_t WebServer::port() const {
  boost::system::error_code ec;
  return impl_->acceptor.local_endpoint(ec).port();
}

std::string WebServer::url(bool drive) const {
  const std::string host = impl_->address.find(':') != std::string::npos ? "[" + impl_->address + "]" : impl_->address;
  return std::string(impl_->tls ? "https" : "http") + "://" + host + ":" + std::to_string(port()) +
         "/?token=" + (drive ? impl_->shared.drive_token : impl_->shared.view_token);
}

}  // namespace occ
