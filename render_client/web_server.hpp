// render_client --web: an HTTP and WebSocket server (Boost.Beast) on a thread of its own. It
// serves one page (render_client/web/index.html, built into the binary) and, at /ws, a
// WebSocket that carries frames to the page and the page's input back.
//
// Access: two random tokens made at start and printed in the URLs; a request without one of
// them gets 403 and nothing else. The drive token's pages steer the camera; the view token's
// only watch (their input is read, checked and dropped). A bad HTTP request, a WebSocket
// message that is binary, longer than kMaxInputBytes or not a valid input (web_input.hpp) closes
// that connection with one log line on stderr; the server and the rendering go on.
//
// Frames: publish() hands one message to every watcher; a watcher still busy with an earlier one
// gets only the newest (slow links skip frames, they do not queue them). A watcher that joins
// gets the last message published first.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "common/web_input.hpp"

namespace occ {

struct WebOptions {
  std::string address = "127.0.0.1";
  uint16_t port = 0;  // 0: a free port, named in the printed URLs
  std::string tls;    // empty (http), "self-signed", or "CERT.pem:KEY.pem"
};

// --web [ADDR:]PORT and --web's tls=; throws InputError naming the flag.
WebOptions parse_web_options(const std::string& web, const std::string& tls);

class WebServer {
 public:
  // Called on the server's thread for each valid input of a drive page.
  using InputHandler = std::function<void(const WebInput&)>;

  // Binds (throws InputError naming --web when it cannot, --web's tls= for a bad pair), starts the
  // server thread and prints both URLs on stderr.
  WebServer(const WebOptions& o, InputHandler on_input);
  ~WebServer();  // stops the thread; every connection is closed
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // Sends `message` (a binary WebSocket message) to every watcher. Any thread.
  void publish(std::shared_ptr<const std::string> message);
  uint16_t port() const;
  // "http[s]://ADDR:PORT/?token=T" with the drive (true) or view token.
  std::string url(bool drive) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace occ
