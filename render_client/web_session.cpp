#include "render_client/web_session.hpp"

#include <openssl/crypto.h>

#include <deque>
#include <iostream>
#include <optional>
#include <variant>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>

namespace occ {

namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;

enum class Role { none, drive, view };

// "/ws?token=T&x=1" -> path "/ws", token "T".
std::pair<std::string, std::string> split_target(std::string_view target) {
  const size_t q = target.find('?');
  std::string path(target.substr(0, q));
  std::string token;
  if (q == std::string_view::npos) return {path, token};
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view kv = query.substr(0, amp);
    if (kv.substr(0, 6) == "token=") token = std::string(kv.substr(6));
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
  }
  return {path, token};
}

bool same(const std::string& a, const std::string& b) {
  return a.size() == b.size() && !a.empty() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

Role role_of(const WebShared& sh, const std::string& token) {
  if (same(token, sh.drive_token)) return Role::drive;
  if (same(token, sh.view_token)) return Role::view;
  return Role::none;
}

template <class Stream>
class Session : public WebWatcher, public std::enable_shared_from_this<Session<Stream>> {
 public:
  Session(Stream stream, WebShared& sh, std::string peer) : stream_(std::move(stream)), sh_(sh), peer_(std::move(peer)) {}

  void start() {
    beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(10));
    if constexpr (std::is_same_v<Stream, beast::tcp_stream>) {
      read_request();
    } else {
      stream_.async_handshake(boost::asio::ssl::stream_base::server, [self = this->shared_from_this()](beast::error_code ec) {
        if (ec) return self->log("TLS handshake failed: " + ec.message());
        self->read_request();
      });
    }
  }

  void deliver(std::shared_ptr<const std::string> message) override {
    frame_ = std::move(message);
    write_next();
  }

 private:
  void log(const std::string& what) const { std::cerr << "render_client: web: " << peer_ << ": " << what << "\n"; }

  void read_request() {
    parser_.emplace();
    parser_->header_limit(8192);
    http::async_read(stream_, buf_, *parser_, [self = this->shared_from_this()](beast::error_code ec, size_t) {
      self->on_request(ec);
    });
  }

  void on_request(beast::error_code ec) {
    // A connection closed or idle before its first byte (a browser's spare one) is no bad request.
    if (ec == http::error::end_of_stream || (ec == beast::error::timeout && !parser_->got_some())) return;
    if (ec) return log("bad HTTP request (" + ec.message() + "): connection closed");
    const auto& req = parser_->get();
    const auto [path, token] = split_target(std::string_view(req.target().data(), req.target().size()));
    const Role role = role_of(sh_, token);
    if (role == Role::none) {
      log("refused " + path + ": no valid token (403)");
      return respond(http::status::forbidden, "text/plain", "403 forbidden: the URL's token is missing or wrong\n");
    }
    if (path == "/ws" && websocket::is_upgrade(req)) return upgrade(role);
    if (path == "/" && req.method() == http::verb::get) return respond(http::status::ok, "text/html; charset=utf-8", web_page());
    log("no such page " + path + " (404)");
    respond(http::status::not_found, "text/plain", "404 not found\n");
  }

  void respond(http::status status, const char* type, const std::string& body) {
    auto res = std::make_shared<http::response<http::string_body>>(status, parser_->get().version());
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    res->set("Referrer-Policy", "no-referrer");  // the URL carries the token
    res->keep_alive(false);
    res->body() = body;
    res->prepare_payload();
    http::async_write(stream_, *res, [self = this->shared_from_this(), res](beast::error_code, size_t) {
      beast::error_code ignored;
      beast::get_lowest_layer(self->stream_).socket().shutdown(tcp::socket::shutdown_send, ignored);
    });
  }

  void upgrade(Role role) {
    role_ = role;
    ws_.emplace(std::move(stream_));
    beast::get_lowest_layer(*ws_).expires_never();
    ws_->set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_->read_message_max(kMaxInputBytes);
    ws_->async_accept(parser_->get(), [self = this->shared_from_this()](beast::error_code ec) {
      if (ec) return self->log("WebSocket handshake failed: " + ec.message());
      self->on_open();
    });
  }

  void on_open() {
    sh_.watchers.push_back(this->shared_from_this());
    texts_.push_back(std::string("{\"role\":\"") + (role_ == Role::drive ? "drive" : "view") + "\"}");
    frame_ = sh_.last;
    write_next();
    read_input();
  }

  // One write at a time: text messages (the hello, pongs) first, in order, then the newest frame.
  void write_next() {
    if (!ws_ || writing_ || closed_) return;
    std::shared_ptr<const std::string> m;
    if (!texts_.empty()) {
      m = std::make_shared<const std::string>(std::move(texts_.front()));
      texts_.pop_front();
      ws_->text(true);
    } else if (frame_) {
      m = std::move(frame_);
      frame_.reset();
      ws_->binary(true);
    } else {
      return;
    }
    writing_ = true;
    ws_->async_write(boost::asio::buffer(*m), [self = this->shared_from_this(), m](beast::error_code ec, size_t) {
      self->writing_ = false;
      if (ec) {
        self->closed_ = true;
        return;
      }
      self->write_next();
    });
  }

  void read_input() {
    ws_->async_read(rbuf_, [self = this->shared_from_this()](beast::error_code ec, size_t) { self->on_input(ec); });
  }

  void on_input(beast::error_code ec) {
    if (ec == websocket::error::closed || ec == boost::asio::error::eof || ec == boost::asio::error::operation_aborted) {
      closed_ = true;
      return;
    }
    if (ec) {
      closed_ = true;
      if (ec == websocket::error::message_too_big)
        return log("input message longer than " + std::to_string(kMaxInputBytes) + " bytes: WebSocket closed");
      return log("WebSocket closed: " + ec.message());
    }
    const std::string text = beast::buffers_to_string(rbuf_.data());
    rbuf_.consume(rbuf_.size());
    if (!ws_->got_text()) return close("binary input message");
    auto parsed = parse_web_input(text);
    if (auto* why = std::get_if<std::string>(&parsed)) return close(*why);
    const WebInput& in = std::get<WebInput>(parsed);
    if (in.kind == WebInput::Kind::ping) {  // any page may measure its round trip
      if (texts_.size() >= kMaxPongs) return close("pings faster than they are answered");
      texts_.push_back("{\"pong\":" + std::to_string(in.seq) + "}");
      write_next();
    } else if (role_ == Role::drive && sh_.on_input) {
      sh_.on_input(in);
    }
    read_input();
  }

  void close(const std::string& why) {
    log(why + ": WebSocket closed");
    closed_ = true;
    ws_->async_close(websocket::close_code::policy_error, [self = this->shared_from_this()](beast::error_code) {});
  }

  Stream stream_;
  WebShared& sh_;
  std::string peer_;
  beast::flat_buffer buf_, rbuf_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  std::optional<websocket::stream<Stream>> ws_;
  Role role_ = Role::none;
  static constexpr size_t kMaxPongs = 64;
  std::deque<std::string> texts_;  // text messages to write before the next frame
  std::shared_ptr<const std::string> frame_;
  bool writing_ = false, closed_ = false;
};

std::string peer_name(const tcp::socket& s) {
  beast::error_code ec;
  const tcp::endpoint e = s.remote_endpoint(ec);
  return ec ? std::string("?") : e.address().to_string() + ":" + std::to_string(e.port());
}

}  // namespace

void start_web_session(tcp::socket socket, WebShared& shared, boost::asio::ssl::context* tls) {
  std::string peer = peer_name(socket);
  if (tls) {
    using S = beast::ssl_stream<beast::tcp_stream>;
    std::make_shared<Session<S>>(S(beast::tcp_stream(std::move(socket)), *tls), shared, std::move(peer))->start();
  } else {
    std::make_shared<Session<beast::tcp_stream>>(beast::tcp_stream(std::move(socket)), shared, std::move(peer))->start();
  }
}

}  // namespace occ
