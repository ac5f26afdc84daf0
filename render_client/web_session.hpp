// One connection of the --web server (web_server.hpp): HTTP request, then either one response
// (the page, 403, 404) or a WebSocket. Everything here runs on the server's thread.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>

#include "render_client/web_server.hpp"

namespace occ {

// A WebSocket watcher, as the server sees it.
class WebWatcher {
 public:
  virtual ~WebWatcher() = default;
  // Queue `message` (binary) for this watcher, replacing one not yet being written.
  virtual void deliver(std::shared_ptr<const std::string> message) = 0;
};

// What every session shares with the server; used on the server's thread only.
struct WebShared {
  std::string drive_token, view_token;
  WebServer::InputHandler on_input;
  std::vector<std::weak_ptr<WebWatcher>> watchers;  // expired ones are dropped by the server
  std::shared_ptr<const std::string> last;          // the last message published (for new watchers)
};

// Serves one accepted connection; `tls` null for plain HTTP. The session keeps itself alive
// until its connection closes.
void start_web_session(boost::asio::ip::tcp::socket socket, WebShared& shared, boost::asio::ssl::context* tls);

// The page, as built into the binary (web_page.cpp, from render_client/web/index.html).
const std::string& web_page();

}  // namespace occ
