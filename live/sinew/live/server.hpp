#pragma once
// The HTTP + WebSocket endpoint of sinew-live (Boost.Beast over Boost.Asio, one I/O thread;
// docs/live.md explains the choice). GET serves the page's static files (static_files.hpp);
// /ws upgrades to the WebSocket of the protocol (protocol.hpp). Every request must carry the
// access token (?token=…, "Authorization: Bearer …", or the cookie sinew_live_<port> that every
// file served sets, so the page's scripts and styles load too) when one is set: sinew-live sets one
// for any bind that is not a loopback address.
//
// Clients: the first connected steers, the others watch (their control messages are refused);
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
  std::string token;                     // "" none
  double max_messages_per_second = 200;  // per client; the rest are dropped with one error reply
  std::size_t max_clients = 16;
  std::size_t max_queued = 256;
};

// Whether a host string names a loopback address (127.0.0.0/8, ::1, localhost).
bool is_loopback_host(const std::string& host);
// 32 hex digits from std::random_device.
std::string make_token();

class Server {
 public:
  // Binds at once (throws IoError naming host:port when it cannot).
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
