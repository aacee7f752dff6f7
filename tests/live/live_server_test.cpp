// sinew-live's server against hostile or broken clients (issue #18): malformed JSON, unknown
// message types and muscles, NaN/Inf/out-of-range values, binary and oversized messages, a flood
// of 1,000 messages, clients that vanish mid-frame, two clients at once, missing or wrong tokens on
// a token-protected server, and path traversal in static-file requests. Each gets an error reply
// or is dropped; the server keeps serving; the engine stays finite; nothing outside the page's
// folder is served. And Ctrl-C on the tool while recording leaves a readable results file.
#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "../simulator/sim_io_support.hpp"
#include "live_support.hpp"
#include "sinew/common/log.hpp"
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

struct Client {
  net::io_context ioc;
  websocket::stream<tcp::socket> ws{ioc};
  explicit Client(unsigned short port, const std::string& target = "/ws") {
    ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    receive_timeout(ws.next_layer(), 20);
    ws.handshake("127.0.0.1", target);
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

// GET target with optional extra header; the status code.
// GET target: the status; auth an Authorization header, cookie a Cookie header ("" none);
// set_cookie receives the reply's Set-Cookie header.
int get(unsigned short port, const std::string& target, const std::string& auth = "",
        const std::string& cookie = "", std::string* set_cookie = nullptr) {
  net::io_context ioc;
  tcp::socket s(ioc);
  s.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  receive_timeout(s, 20);
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, "127.0.0.1");
  if (!auth.empty()) req.set(http::field::authorization, auth);
  if (!cookie.empty()) req.set(http::field::cookie, cookie);
  http::write(s, req);
  beast::flat_buffer b;
  http::response<http::string_body> res;
  http::read(s, b, res);
  if (set_cookie) *set_cookie = std::string(res[http::field::set_cookie]);
  return int(res.result_int());
}

class LiveServer : public ::testing::Test {
 protected:
  void start(const std::string& token = "") {
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
    session_ = std::make_unique<Session>(simulator::load_run(o, make_live_setup), SessionOptions{});
    ServerOptions so;
    so.port = 0;
    so.token = token;
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
  start("s3cret-token");
  EXPECT_EQ(get(port_, "/"), 403);
  EXPECT_EQ(get(port_, "/?token=wrong"), 403);
  EXPECT_EQ(get(port_, "/?token=s3cret-tokenX"), 403);
  std::string cookie;
  EXPECT_EQ(get(port_, "/?token=s3cret-token", "", "", &cookie), 200);
  // The page's own requests (its scripts, three.js) carry the token by the cookie it was given.
  const std::string name = "sinew_live_" + std::to_string(port_);
  EXPECT_EQ(cookie, name + "=s3cret-token; Path=/; HttpOnly; SameSite=Strict");
  EXPECT_EQ(get(port_, "/index.html", "", "a=1; " + name + "=s3cret-token"), 200);
  EXPECT_EQ(get(port_, "/index.html", "", name + "=s3cret-tokeN"), 403);
  EXPECT_EQ(get(port_, "/index.html", "", "sinew_live_1=s3cret-token"), 403);  // another port's
  EXPECT_EQ(get(port_, "/index.html", "Bearer s3cret-token"), 200);
  EXPECT_EQ(get(port_, "/index.html", "Bearer nope"), 403);
  EXPECT_THROW(Client c(port_, "/ws"), beast::system_error);
  EXPECT_THROW(Client c(port_, "/ws?token=bad"), beast::system_error);
  Client ok(port_, "/ws?token=s3cret-token");
  EXPECT_EQ(ok.next("hello")["protocol"], kProtocolVersion);
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
  EXPECT_NE(out.find(empty + ": three.js is not installed there: run scripts/install-deps (it puts "
                             "three.js into .cache/three), or point --three at a three.js "
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
