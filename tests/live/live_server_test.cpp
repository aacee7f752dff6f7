// sinew-live's server against hostile or broken clients (issue #18): malformed JSON, unknown
// message types and muscles, NaN/Inf/out-of-range values, binary and oversized messages, a flood
// of 1,000 messages, clients that vanish mid-frame, two clients at once, missing or wrong tokens on
// a token-protected server, and path traversal in static-file requests. Each gets an error reply
// or is dropped; the server keeps serving; the engine stays finite; nothing outside the page's
// folder is served. And Ctrl-C on the tool while recording leaves a readable results file.
// Issue #33, a hostile page in the user's browser and other abuse: foreign Host and Origin
// headers, simultaneous handshakes against max_clients, weak tokens, the accept loop out of file
// descriptors, and recordings that would share a folder.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/sinks/ostream_sink.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "../simulator/sim_io_support.hpp"
#include "live_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/live/own_origin.hpp"
#include "sinew/live/server.hpp"
#include "sinew/live/session.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace sinew::live {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;
using simulator::testing::TempDir;

void receive_timeout(tcp::socket& s, int seconds) {
  timeval tv{seconds, 0};
  setsockopt(s.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
}

// The Host a browser sends for the page at http://127.0.0.1:port/ (the server answers to its own
// Host only), and the Origin of that page.
std::string own_host(unsigned short port) {
  return "127.0.0.1:" + std::to_string(port);
}
std::string own_origin(unsigned short port) {
  return "http://" + own_host(port);
}

// A client as the page is one: the server's own Host and Origin.
struct Client {
  net::io_context ioc;
  websocket::stream<tcp::socket> ws{ioc};
  explicit Client(unsigned short port, const std::string& target = "/ws") {
    ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    receive_timeout(ws.next_layer(), 20);
    ws.set_option(websocket::stream_base::decorator(
        [origin = own_origin(port)](websocket::request_type& req) {
          req.set(http::field::origin, origin);
        }));
    ws.handshake(own_host(port), target);
  }
  void send(const std::string& text) {
    ws.text(true);
    ws.write(net::buffer(text));
  }
  // The next message: (text, binary?).
  std::pair<std::string, bool> read() {
    beast::flat_buffer b;
    ws.read(b);
    return {beast::buffers_to_string(b.data()), !ws.got_text()};
  }
  // The next JSON message of this type (binary and other messages skipped).
  json next(const std::string& type, int limit = 5000) {
    for (int k = 0; k < limit; ++k) {
      auto [m, binary] = read();
      if (binary) continue;
      auto j = json::parse(m);
      if (j["type"] == type) return j;
    }
    throw std::runtime_error("no '" + type + "' message");
  }
  std::string error_for(const std::string& text) {
    send(text);
    return next("error")["message"].get<std::string>();
  }
};

// GET target: the status; auth an Authorization header, cookie a Cookie header ("" none);
// set_cookie receives the reply's Set-Cookie header; host the Host header ("" the server's own).
int get(unsigned short port, const std::string& target, const std::string& auth = "",
        const std::string& cookie = "", std::string* set_cookie = nullptr,
        const std::string& host = "") {
  net::io_context ioc;
  tcp::socket s(ioc);
  s.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  receive_timeout(s, 20);
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, host.empty() ? own_host(port) : host);
  if (!auth.empty()) req.set(http::field::authorization, auth);
  if (!cookie.empty()) req.set(http::field::cookie, cookie);
  http::write(s, req);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  if (set_cookie) *set_cookie = std::string(res[http::field::set_cookie]);
  return int(res.result_int());
}

// A WebSocket handshake written by hand on a connected socket: Host `host`, Origin `origin` (none
// when nullopt), target `target`.
void send_upgrade(tcp::socket& s, const std::string& host, const std::optional<std::string>& origin,
                  const std::string& target = "/ws") {
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, host);
  if (origin) req.set(http::field::origin, *origin);
  req.set(http::field::upgrade, "websocket");
  req.set(http::field::connection, "Upgrade");
  req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  req.set(http::field::sec_websocket_version, "13");
  http::write(s, req);
}

struct UpgradeReply {
  int status = 0;
  std::string content_type, body;
  std::string after;  // refused: what the server sent after the reply before it closed (nothing)
};

// The handshake's reply; for a refusal also whatever followed it (the server closes: EOF).
UpgradeReply upgrade(unsigned short port, const std::string& host,
                     const std::optional<std::string>& origin, const std::string& target = "/ws") {
  net::io_context ioc;
  tcp::socket s(ioc);
  s.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  receive_timeout(s, 20);
  send_upgrade(s, host, origin, target);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  UpgradeReply r{int(res.result_int()), std::string(res[http::field::content_type]), res.body(),
                 beast::buffers_to_string(b.data())};
  if (r.status == 101) return r;
  char chunk[4096];
  boost::system::error_code ec;
  while (!ec) r.after.append(chunk, s.read_some(net::buffer(chunk), ec));
  EXPECT_EQ(ec, net::error::eof) << "the server should close a refused handshake";
  return r;
}

class LiveServer : public ::testing::Test {
 protected:
  void start(const std::string& token = "") {
    ServerOptions so;
    so.token = token;
    start_with(so, {});
  }
  void start_with(ServerOptions so, SessionOptions session_options) {
    log::set_level(log::Level::error);
    testing::write_live_case(dir_.str());
    std::filesystem::create_directories(dir_ / "web");
    std::ofstream(dir_ / "web/index.html") << "<!doctype html><title>page</title>\n";
    std::ofstream(dir_ / "secret.txt") << "outside the page's folder\n";
    std::filesystem::create_symlink(dir_ / "secret.txt", dir_ / "web/leak.html");
    simulator::RunOptions o;
    o.scene_path = dir_ / "live_box.yaml";
    o.device = "cpu";
    o.threads = 1;
    session_ = std::make_unique<Session>(simulator::load_run(o, make_live_setup), session_options);
    so.port = 0;
    so.roots = {{"/", dir_ / "web"}};
    server_ = std::make_unique<Server>(*session_, so);
    port_ = server_->port();
    session_->start();
    io_ = std::thread([this] { server_->run(false); });
  }
  void TearDown() override {
    if (server_) server_->stop();
    if (io_.joinable()) io_.join();
    if (session_) session_->stop();
    server_.reset();
  }
  // The server still serves a new client, and the engine's state is finite.
  void expect_healthy() {
    Client c(port_);
    EXPECT_EQ(c.next("hello")["protocol"], kProtocolVersion);
    EXPECT_EQ(session_->last_error(), "");
    // The engine thread publishes its first frame at its own pace (on a loaded machine, after the
    // clients above have come and gone): wait for it, up to 10 s.
    auto f = session_->latest_frame();
    for (int k = 0; k < 1000 && !f; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      f = session_->latest_frame();
    }
    ASSERT_TRUE(f) << "no frame published";
    std::vector<float> v((f->size() - kFrameHeaderBytes) / 4);
    std::memcpy(v.data(), f->data() + kFrameHeaderBytes, v.size() * 4);
    for (float x : v) ASSERT_TRUE(std::isfinite(x));
  }
  TempDir dir_{"live_server"};
  std::unique_ptr<Session> session_;
  std::unique_ptr<Server> server_;
  std::thread io_;
  unsigned short port_ = 0;
};

TEST_F(LiveServer, GreetsAndStreamsFramesOfTheDocumentedSize) {
  start();
  Client c(port_);
  const json hello = c.next("hello", 1);
  EXPECT_EQ(hello["muscles"][0]["name"], "flexor");
  EXPECT_TRUE(hello["drag"].get<bool>());
  EXPECT_EQ(hello["up"], "z");  // the page's camera (sinew-live --up)
  auto [mesh, binary] = c.read();
  ASSERT_TRUE(binary);
  std::uint32_t h[4];
  std::memcpy(h, mesh.data(), 16);
  EXPECT_EQ(h[0], kTagMesh);
  EXPECT_EQ(mesh.size(), 16 + 12 * std::size_t(h[1]) + 12 * std::size_t(h[2]));
  EXPECT_TRUE(c.next("role")["steering"].get<bool>());
  int frames = 0;
  while (frames < 5) {
    auto [m, bin] = c.read();
    if (!bin) continue;
    std::memcpy(h + 1, m.data() + 4, 4);
    EXPECT_EQ(m.size(), kFrameHeaderBytes + 16 * std::size_t(h[1]));
    EXPECT_EQ(m.size(), hello["frame_bytes"].get<std::size_t>());
    ++frames;
  }
}

TEST_F(LiveServer, BadMessagesGetClearErrors) {
  start();
  Client c(port_);
  EXPECT_EQ(c.error_for("{this is not json"), "malformed JSON");
  EXPECT_NE(c.error_for(R"({"type": "teleport"})").find("unknown message type"), std::string::npos);
  EXPECT_NE(c.error_for(R"({"type": "activation", "muscle": "biceps", "value": 0.5})")
                .find("unknown muscle 'biceps'"),
            std::string::npos);
  EXPECT_EQ(c.error_for(R"({"type": "activation", "muscle": "flexor", "value": NaN})"),
            "malformed JSON");
  EXPECT_FALSE(
      c.error_for(R"({"type": "activation", "muscle": "flexor", "value": 1e999})").empty());
  EXPECT_NE(
      c.error_for(R"({"type": "activation", "muscle": "flexor", "value": 7})").find("outside"),
      std::string::npos);
  EXPECT_NE(
      c.error_for(R"({"type": "drag", "point": [9, 9, 9], "force": [0, 0, 1], "radius": 0.001})")
          .find("no node within"),
      std::string::npos);
  c.ws.binary(true);
  c.ws.write(net::buffer(std::string("\x01\x02\x03", 3)));
  EXPECT_NE(c.next("error")["message"].get<std::string>().find("binary"), std::string::npos);
  // A valid message after all that still works and its id comes back in the status.
  c.send(R"({"type": "pause", "id": 77})");
  for (int k = 0; k < 200; ++k) {
    const json s = c.next("status");
    if (s["last_id"] == 77) {
      EXPECT_TRUE(s["paused"].get<bool>());
      break;
    }
  }
  expect_healthy();
}

TEST_F(LiveServer, OversizedMessageDropsTheClientOnly) {
  start();
  Client c(port_);
  c.next("hello");
  c.send(R"({"type": "pause", "pad": ")" + std::string(10000, 'x') + "\"}");
  EXPECT_THROW(
      {
        for (int k = 0; k < 10000; ++k) c.read();
      },
      beast::system_error);
  EXPECT_EQ(c.ws.reason().code, websocket::close_code::too_big);
  expect_healthy();
}

TEST_F(LiveServer, AThousandMessagesInASecondAreThrottled) {
  start();
  Client c(port_);
  c.next("hello");
  for (int k = 0; k < 1000; ++k)
    c.send(k % 2 ? R"({"type": "field", "field": "jacobian"})"
                 : R"({"type": "field", "field": "displacement"})");
  EXPECT_NE(c.next("error")["message"].get<std::string>().find("messages per second"),
            std::string::npos);
  expect_healthy();
}

TEST_F(LiveServer, ClientsVanishingMidFrameDoNotHurt) {
  start();
  for (int k = 0; k < 20; ++k) {
    Client c(port_);
    c.read();                   // hello arrives; frames are being sent
    c.ws.next_layer().close();  // no close handshake, mid-stream
  }
  expect_healthy();
}

TEST_F(LiveServer, OneClientSteersTheOthersWatch) {
  start();
  auto a = std::make_unique<Client>(port_);
  EXPECT_TRUE(a->next("role")["steering"].get<bool>());
  Client b(port_);
  EXPECT_FALSE(b.next("role")["steering"].get<bool>());
  EXPECT_NE(b.error_for(R"({"type": "pause"})").find("another client steers"), std::string::npos);
  a->ws.close(websocket::close_code::normal);
  a.reset();
  EXPECT_TRUE(b.next("role")["steering"].get<bool>());
  b.send(R"({"type": "pause", "id": 5})");
  for (int k = 0; k < 200; ++k) {
    const json s = b.next("status");
    if (s["last_id"] == 5) {
      EXPECT_TRUE(s["paused"].get<bool>());
      break;
    }
  }
}

TEST_F(LiveServer, NothingOutsideThePageFolderIsServed) {
  start();
  EXPECT_EQ(get(port_, "/"), 200);
  EXPECT_EQ(get(port_, "/index.html"), 200);
  for (const char* t :
       {"/../secret.txt", "/%2e%2e/secret.txt", "/..%2fsecret.txt", "/web/../secret.txt",
        "/leak.html", "/.hidden", "//etc/passwd", "/index.html/../../secret.txt", "/nope.js"})
    EXPECT_EQ(get(port_, t), 404) << t;
  expect_healthy();
}

TEST_F(LiveServer, TokenIsCheckedOnEveryRequest) {
  start("s3cret-token-0123456");
  EXPECT_EQ(get(port_, "/"), 403);
  EXPECT_EQ(get(port_, "/?token=wrong"), 403);
  EXPECT_EQ(get(port_, "/?token=s3cret-token-0123456X"), 403);
  std::string cookie;
  EXPECT_EQ(get(port_, "/?token=s3cret-token-0123456", "", "", &cookie), 200);
  // The page's own requests (its scripts, three.js) carry the token by the cookie it was given.
  const std::string name = "sinew_live_" + std::to_string(port_);
  EXPECT_EQ(cookie, name + "=s3cret-token-0123456; Path=/; HttpOnly; SameSite=Strict");
  EXPECT_EQ(get(port_, "/index.html", "", "a=1; " + name + "=s3cret-token-0123456"), 200);
  EXPECT_EQ(get(port_, "/index.html", "", name + "=s3cret-token-012345X"), 403);
  EXPECT_EQ(get(port_, "/index.html", "", "sinew_live_1=s3cret-token-0123456"),
            403);  // another port's
  EXPECT_EQ(get(port_, "/index.html", "Bearer s3cret-token-0123456"), 200);
  EXPECT_EQ(get(port_, "/index.html", "Bearer nope"), 403);
  EXPECT_THROW(Client c(port_, "/ws"), beast::system_error);
  EXPECT_THROW(Client c(port_, "/ws?token=bad"), beast::system_error);
  Client ok(port_, "/ws?token=s3cret-token-0123456");
  EXPECT_EQ(ok.next("hello")["protocol"], kProtocolVersion);
}

// Issue #33: a page open in the user's browser may make it send anything to 127.0.0.1. The server
// answers only to its own names (DNS rebinding: a foreign Host) and its own page (a cross-origin
// WebSocket: a foreign Origin).
TEST(LiveOwnOrigin, HostAndOriginNameOnlyThisServer) {
  const OwnHost own{8080, "127.0.0.1", {"gpu-server.lan"}};
  for (const char* host : {"127.0.0.1:8080", "localhost:8080", "LocalHost:8080", "[::1]:8080",
                           "[0:0:0:0:0:0:0:1]:8080", "gpu-server.lan:8080", "GPU-Server.LAN:8080"})
    EXPECT_TRUE(is_own_host(host, own, "127.0.0.1")) << host;
  for (const char* host : {"evil.example",
                           "evil.example:8080",
                           "127.0.0.1.evil.example:8080",
                           "localhost.:8080",
                           "127.0.0.1",
                           "localhost",
                           "127.0.0.1:8081",
                           "127.0.0.1:08080",
                           "127.0.0.1:+8080",
                           "127.0.0.1:8080:8080",
                           "127.0.0.2:8080",
                           "127.1:8080",
                           "::1:8080",
                           "[::1]",
                           "[::1]8080",
                           "[localhost]:8080",
                           "[127.0.0.1]:8080",
                           "user@127.0.0.1:8080",
                           "",
                           ":8080",
                           "gpu-server.lan.evil.example:8080",
                           "10.0.0.5:8080"})
    EXPECT_FALSE(is_own_host(host, own, "127.0.0.1")) << host;
  for (const char* origin : {"http://127.0.0.1:8080", "http://localhost:8080", "http://[::1]:8080"})
    EXPECT_TRUE(is_own_origin(origin, own, "127.0.0.1")) << origin;
  for (const char* origin :
       {"null", "file://", "http://evil.example", "http://127.0.0.1.evil.example",
        "http://127.0.0.1.evil.example:8080", "https://127.0.0.1:8080", "ws://127.0.0.1:8080",
        "http://127.0.0.1:8080/", "http://127.0.0.1", "http://127.0.0.1:8081", "http://", ""})
    EXPECT_FALSE(is_own_origin(origin, own, "127.0.0.1")) << origin;
  // A wildcard bind: the machine's address the connection arrived at (an IP literal names no
  // attacker's domain), written as the browser does; no other address.
  const OwnHost any{8080, "0.0.0.0", {}};
  EXPECT_TRUE(is_own_host("192.168.1.5:8080", any, "::ffff:192.168.1.5"));
  EXPECT_TRUE(is_own_host("[fd00::5]:8080", any, "fd00:0::5"));
  EXPECT_FALSE(is_own_host("192.168.1.6:8080", any, "192.168.1.5"));
  EXPECT_FALSE(is_own_host("gpu-server.lan:8080", any, "192.168.1.5"));
  EXPECT_EQ(host_name_problem("gpu-server.lan"), "");
  for (const char* bad : {"", "gpu-server:8080", "[::1]", "10.0.0.5", "a b"})
    EXPECT_NE(host_name_problem(bad), "") << bad;
}

TEST_F(LiveServer, AForeignHostGets403) {
  start();
  const std::string port = std::to_string(port_);
  for (const std::string& host :
       std::vector<std::string>{"evil.example", "evil.example:" + port,
                                "127.0.0.1.evil.example:" + port, "127.0.0.1", "localhost"})
    EXPECT_EQ(get(port_, "/", "", "", nullptr, host), 403) << host;
  for (const std::string& host : {"127.0.0.1:" + port, "localhost:" + port})
    EXPECT_EQ(get(port_, "/", "", "", nullptr, host), 200) << host;
  // The WebSocket too, even with the server's own Origin.
  const auto r = upgrade(port_, "evil.example:" + port, own_origin(port_));
  EXPECT_EQ(r.status, 403);
  EXPECT_EQ(r.content_type, "text/plain; charset=utf-8");
  EXPECT_NE(r.body.find("wrong Host"), std::string::npos) << r.body;
  EXPECT_EQ(r.after, "");
  expect_healthy();
}

TEST_F(LiveServer, ACrossOriginWebSocketGetsNothing) {
  start();
  const std::string host = own_host(port_), port = std::to_string(port_);
  for (const std::optional<std::string>& origin :
       {std::optional<std::string>("null"), std::optional<std::string>("file://"),
        std::optional<std::string>("http://evil.example"),
        std::optional<std::string>("http://127.0.0.1.evil.example"),
        std::optional<std::string>("http://127.0.0.1.evil.example:" + port),
        std::optional<std::string>("http://127.0.0.1:1"),
        std::optional<std::string>("https://127.0.0.1:" + port),
        // No Origin: no browser sends that, and without a token nothing vouches for the client.
        std::optional<std::string>()}) {
    const auto r = upgrade(port_, host, origin);
    EXPECT_EQ(r.status, 403) << origin.value_or("(none)");
    EXPECT_NE(r.body.find("cross-origin WebSocket refused"), std::string::npos) << r.body;
    EXPECT_EQ(r.after, "") << "no hello, mesh or frame";
  }
  EXPECT_EQ(server_->client_count(), 0u);
  // The page's own origin, by any of the server's names, connects and steers (nobody else does).
  EXPECT_EQ(upgrade(port_, "localhost:" + port, "http://localhost:" + port).status, 101);
  Client page(port_);
  EXPECT_EQ(page.next("hello")["protocol"], kProtocolVersion);
  EXPECT_TRUE(page.next("role")["steering"].get<bool>());
}

TEST_F(LiveServer, WithATokenAProgramMayLeaveOutTheOriginButNotSendAForeignOne) {
  const std::string token = make_token();
  start(token);
  EXPECT_EQ(upgrade(port_, own_host(port_), std::nullopt, "/ws?token=" + token).status, 101);
  EXPECT_EQ(upgrade(port_, own_host(port_), std::nullopt, "/ws").status, 403);
  EXPECT_EQ(upgrade(port_, own_host(port_), "http://evil.example", "/ws?token=" + token).status,
            403);
}

TEST_F(LiveServer, SimultaneousHandshakesCannotPassMaxClients) {
  ServerOptions so;
  so.max_clients = 4;
  start_with(so, {});
  constexpr int kTries = 40;
  net::io_context ioc;
  std::vector<tcp::socket> sockets;
  for (int k = 0; k < kTries; ++k) {
    sockets.emplace_back(ioc);
    sockets.back().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port_));
    receive_timeout(sockets.back(), 20);
  }
  // Every handshake is written before any reply is read: the server reads them together.
  for (auto& s : sockets) send_upgrade(s, own_host(port_), own_origin(port_));
  int accepted = 0, refused = 0;
  for (auto& s : sockets) {
    beast::flat_buffer b;
    http::response<http::string_body> res;
    http::read(s, b, res);
    if (res.result() == http::status::switching_protocols) ++accepted;
    if (res.result() == http::status::service_unavailable && res.body() == "too many clients\n")
      ++refused;
  }
  EXPECT_EQ(accepted, 4);
  EXPECT_EQ(refused, kTries - 4);
  for (int k = 0; k < 500 && server_->client_count() != 4; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(server_->client_count(), 4u);
  // The slots come back when the clients leave: four connect again, a fifth is refused.
  sockets.clear();
  for (int k = 0; k < 500 && server_->client_count() != 0; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(server_->client_count(), 0u);
  std::vector<std::unique_ptr<Client>> four;
  for (int k = 0; k < 4; ++k) four.push_back(std::make_unique<Client>(port_));
  EXPECT_EQ(upgrade(port_, own_host(port_), own_origin(port_)).status, 503);
}

// The access token: at least 16 characters of the URL-safe kind, refused by the server and, before
// the model loads, by sinew-live's command line.
TEST(LiveServerToken, AWeakTokenIsRefused) {
  EXPECT_EQ(token_problem(make_token()), "");
  EXPECT_EQ(token_problem("abcdefghijklmnop"), "");
  for (const std::string& bad :
       std::vector<std::string>{"a", "s3cret-token", "abcdefghijklmno", "a token with spaces!",
                                "abcdefghijklmnop&x=1", std::string(257, 'a')})
    EXPECT_NE(token_problem(bad), "") << bad;
  EXPECT_NE(token_problem("abcdefghijklmno").find("at least 16"), std::string::npos);
}

TEST_F(LiveServer, TheServerRefusesAWeakToken) {
  start();
  ServerOptions so;
  so.port = 0;
  so.token = "a";
  EXPECT_THROW({ Server weak(*session_, so); }, ConfigError);
  so.token = "";
  so.allowed_hosts = {"gpu-server:8080"};
  EXPECT_THROW({ Server with_port(*session_, so); }, ConfigError);
}

TEST(LiveTool, AWeakTokenIsRefusedAtStartUp) {
  TempDir dir("live_tool_token");
  testing::write_live_case(dir.str());
  const std::string log = dir / "out.txt";
  // Without the check, sinew-live would serve until `timeout` ends it (exit 124).
  const std::string cmd = std::string("timeout 30 '") + SINEW_LIVE_TOOL + "' '" +
                          (dir / "live_box.yaml") +
                          "' --device cpu --port 0 --token short-token > '" + log + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);  // a bad command line
  const std::string out = simulator::testing::read_file(log);
  EXPECT_NE(out.find("an access token of 11 characters is guessed quickly: give at least 16"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("open http"), std::string::npos) << out;
}

// Out of file descriptors, accept() fails while the listening socket stays readable: retrying at
// once spun a core. The server waits and tries again, says so once, and serves the connection that
// waited once descriptors are free.
class DescriptorsUsedUp {
 public:
  DescriptorsUsedUp() {
    getrlimit(RLIMIT_NOFILE, &old_);
    int highest = 0;
    for (const auto& e : std::filesystem::directory_iterator("/proc/self/fd"))
      highest = std::max(highest, std::stoi(e.path().filename().string()));
    rlimit low = old_;
    low.rlim_cur = std::min<rlim_t>(old_.rlim_cur, rlim_t(highest) + 64);
    setrlimit(RLIMIT_NOFILE, &low);
    for (int fd; (fd = open("/dev/null", O_RDONLY)) >= 0;) fds_.push_back(fd);
    errno_ = errno;
  }
  ~DescriptorsUsedUp() {
    for (int fd : fds_) ::close(fd);
    setrlimit(RLIMIT_NOFILE, &old_);
  }
  int error() const { return errno_; }

 private:
  rlimit old_{};
  std::vector<int> fds_;
  int errno_ = 0;
};

double thread_cpu_seconds(std::thread& t) {
  clockid_t id{};
  pthread_getcpuclockid(t.native_handle(), &id);
  timespec ts{};
  clock_gettime(id, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

TEST_F(LiveServer, OutOfDescriptorsTheServerWaitsInsteadOfSpinning) {
  SessionOptions paused;  // an idle engine: the I/O thread's time is the server's alone
  paused.start_paused = true;
  start_with({}, paused);
  std::ostringstream warnings;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(warnings);
  log::logger().sinks().push_back(sink);
  log::set_level(log::Level::warn);
  net::io_context ioc;
  tcp::socket s(ioc);
  s.open(tcp::v4());  // its descriptor (and the io_context's) before they run out
  double cpu = 0;
  {
    DescriptorsUsedUp used_up;
    ASSERT_EQ(used_up.error(), EMFILE);
    s.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port_));  // no new descriptor
    const double t0 = thread_cpu_seconds(io_);
    std::this_thread::sleep_for(std::chrono::seconds(1));
    cpu = thread_cpu_seconds(io_) - t0;
  }
  log::logger().sinks().pop_back();
  log::set_level(log::Level::error);
  EXPECT_LT(cpu, 0.1) << "the I/O thread's CPU seconds in one second out of descriptors";
  const std::string said = warnings.str();
  std::size_t times = 0;
  for (auto at = said.find("cannot accept a connection"); at != std::string::npos;
       at = said.find("cannot accept a connection", at + 1))
    ++times;
  EXPECT_EQ(times, 1u) << said;
  // The connection that waited is served.
  receive_timeout(s, 20);
  http::request<http::empty_body> req(http::verb::get, "/", 11);
  req.set(http::field::host, own_host(port_));
  http::write(s, req);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  EXPECT_EQ(res.result_int(), 200u);
}

// The status of the client's session: the recording folder once it is (on) or is not (off).
std::string wait_for_recording(Client& c, bool on) {
  for (int k = 0; k < 2000; ++k) {
    const json s = c.next("status");
    if (on && !s["recording"].is_null()) return s["recording"].get<std::string>();
    if (!on && s["recording"].is_null()) return {};
  }
  throw std::runtime_error(on ? "no recording started" : "the recording did not stop");
}

void record(Client& c, bool on) {
  c.send(on ? R"({"type": "record", "on": true})" : R"({"type": "record", "on": false})");
}

TEST_F(LiveServer, ASecondRecordingGetsAFolderOfItsOwn) {
  SessionOptions so;
  so.record_dir = dir_ / "rec";  // sinew-live --record DIR: recording from the start
  start_with({}, so);
  Client c(port_);
  EXPECT_EQ(wait_for_recording(c, true), dir_ / "rec");
  record(c, false);
  wait_for_recording(c, false);
  record(c, true);
  EXPECT_EQ(wait_for_recording(c, true), dir_ / "rec-2");
  record(c, false);
  wait_for_recording(c, false);
  for (const char* rec : {"rec", "rec-2"}) {
    EXPECT_GE(postprocess::read_surface(dir_ / (std::string(rec) + "/results.h5")).frame_count(),
              1u)
        << rec;
    EXPECT_TRUE(std::filesystem::exists(dir_ / (std::string(rec) + "/scene.yaml"))) << rec;
  }
}

TEST_F(LiveServer, RecordingsStartedInOneSecondGetFoldersOfTheirOwn) {
  start();
  // The default folder is named by the second (sinew-live-recording-<unix time>) in the working
  // directory: the folders of the next seconds exist already, as another recording left them.
  const std::filesystem::path cwd = std::filesystem::current_path(), work = dir_ / "work";
  std::filesystem::create_directories(work);
  std::filesystem::current_path(work);
  struct Back {
    std::filesystem::path to;
    ~Back() { std::filesystem::current_path(to); }
  } back{cwd};
  const auto now = std::chrono::duration_cast<std::chrono::seconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
  std::vector<std::string> taken;
  for (auto t = now - 1; t <= now + 30; ++t) {
    taken.push_back(fmt::format("sinew-live-recording-{}", t));
    std::filesystem::create_directory(taken.back());
    std::ofstream(taken.back() + "/results.h5") << "another recording's\n";
  }
  Client c(port_);
  record(c, true);
  const std::string folder = wait_for_recording(c, true);
  record(c, false);
  wait_for_recording(c, false);
  EXPECT_EQ(std::find(taken.begin(), taken.end(), folder), taken.end()) << folder;
  EXPECT_EQ(folder.substr(folder.size() - 2), "-2") << folder;
  EXPECT_GE(postprocess::read_surface(folder + "/results.h5").frame_count(), 1u);
  for (const auto& t : taken)
    EXPECT_EQ(simulator::testing::read_file(t + "/results.h5"), "another recording's\n") << t;
}

TEST(LiveTool, MissingThreeJsSaysHowToInstallIt) {
  // scripts/install-deps has no --three option: the message names the script and sinew-live's
  // own --three separately, so that neither is mistaken for the other.
  TempDir dir("live_tool_three");
  testing::write_live_case(dir.str());
  const std::string log = dir / "out.txt", empty = dir / "no_three";
  std::filesystem::create_directories(empty);
  const std::string cmd = std::string("'") + SINEW_LIVE_TOOL + "' '" + (dir / "live_box.yaml") +
                          "' --device cpu --port 0 --three '" + empty + "' > '" + log + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string out = simulator::testing::read_file(log);
  // (The page and three.js are copied beside the built tool at build time: issue 34, item 8.)
  EXPECT_NE(out.find(empty + ": three.js is not there, nor beside the tool ("), std::string::npos)
      << out;
  EXPECT_NE(out.find("run scripts/install-deps (it puts three.js into .cache/three) and build "
                     "again (it copies it beside sinew-live), or point --three at a three.js "
                     "package folder"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("install-deps (--three)"), std::string::npos) << out;
}

TEST(LiveTool, CtrlCWhileRecordingLeavesAReadableResultsFile) {
  if (!std::filesystem::exists(std::string(SINEW_LIVE_THREE_DIR) + "/build/three.module.js"))
    GTEST_SKIP() << "three.js is not installed (scripts/install-deps puts it in .cache/three)";
  TempDir dir("live_tool");
  testing::write_live_case(dir.str());
  const std::string rec = dir / "rec", log = dir / "out.txt";
  const std::string cmd =
      std::string("exec '") + SINEW_LIVE_TOOL + "' '" + (dir / "live_box.yaml") +
      "' --device cpu --threads 1 --port 0 --record '" + rec + "' > '" + log + "' 2>&1";
  pid_t pid = 0;
  const char* argv[] = {"sh", "-c", cmd.c_str(), nullptr};
  ASSERT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  // Wait for the URL line, then for a few frames to be recorded.
  const auto t0 = std::chrono::steady_clock::now();
  while (simulator::testing::read_file(log).find("open http") == std::string::npos &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ASSERT_EQ(kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << simulator::testing::read_file(log);
  const auto anim = postprocess::read_surface(rec + "/results.h5");  // the volume boundary
  EXPECT_GE(anim.frame_count(), 2u);
  EXPECT_TRUE(std::filesystem::exists(rec + "/scene.yaml"));
}

}  // namespace
}  // namespace sinew::live
