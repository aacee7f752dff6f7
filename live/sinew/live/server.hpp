#pragma once
// The HTTP + WebSocket endpoint of sinew-live (Boost.Beast over Boost.Asio, one I/O thread;
// docs/live.md explains the choice). GET serves the page's static files (static_files.hpp);
// /ws upgrades to the WebSocket of the protocol (protocol.hpp). Every request must carry the
// access token (?token=…, "Authorization: Bearer …", or the cookie sinew_live_<port> that every
// file served sets, so the page's scripts and styles load too) when one is set: sinew-live sets one
// for any bind that is not a loopback address.
//
// Before the token: a request whose Host is not one of the server's own names and port (DNS
// rebinding) gets 403, and so does a WebSocket handshake whose Origin is not the server's own page
// (own_origin.hpp). A handshake without an Origin (no browser sends one) is accepted only when a
// token is set, i.e. from a client that proved it has the token. docs/live.md, "Threat model".
//
// Clients: at most max_clients, counted from the moment a handshake is admitted (before its 101 is
// sent), so simultaneous handshakes cannot pass the limit together; the rest get 503. The first
// connected steers, the others watch (their control messages are refused);
// when the steering client leaves, the oldest remaining one steers. Each client has its own send
// queue: control and status messages in order (a client more than kMaxQueued behind is dropped),
// and one slot for the newest frame, replaced while the previous is still being sent, so a slow
// client gets fewer frames and nothing waits for it.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "sinew/live/session.hpp"
#include "sinew/live/static_files.hpp"

namespace sinew::live {

struct ServerOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;  // 0: any free port (port() tells which)
  std::vector<StaticRoot> roots;
  std::string token;                       // "" none; else as token_problem() allows
  std::vector<std::string> allowed_hosts;  // names besides loopback and the bound address
  double max_messages_per_second = 200;    // per client; the rest are dropped with one error reply
  std::size_t max_clients = 16;
  std::size_t max_queued = 256;
};

// Whether a host string names a loopback address (127.0.0.0/8, ::1, localhost).
bool is_loopback_host(const std::string& host);
// 32 hex digits from std::random_device.
std::string make_token();
// Why `token` cannot be an access token, or "" when it can: at least kMinTokenLength characters
// (a short one is guessed: nothing limits how fast a client tries), at most 256, and only the
// characters a URL's query and a cookie carry as they are (letters, digits, '-', '.', '_', '~').
inline constexpr std::size_t kMinTokenLength = 16;
std::string token_problem(const std::string& token);

class Server {
 public:
  // Binds at once (throws IoError naming host:port when it cannot; ConfigError for a token that
  // token_problem() refuses or a bad allowed host name).
  Server(Session& session, ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  unsigned short port() const;
  // Runs the I/O loop in the calling thread until stop() or SIGINT/SIGTERM (with_signals).
  void run(bool with_signals);
  void stop();  // thread-safe
  std::size_t client_count() const;

  struct Impl;  // the I/O state (server.cpp)

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace sinew::live
