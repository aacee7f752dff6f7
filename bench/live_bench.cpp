// live_bench: sinew-live's figures (docs/performance.md, "Live"). For one scene:
//  1. batch: the engine of the live plan stepped alone (preferred step counts) for --seconds;
//  2. live: the same engine in a Session behind the Server, a WebSocket client receiving every
//     frame (--frame-rate), for --seconds: simulated seconds per wall second, steps/s, frames/s
//     received, and the ratio live / batch;
//  3. latency: meanwhile the client moves the first muscle's slider every 100 ms (alternating
//     values, each message with an id); the time from sending it to the first frame whose header
//     carries that id (the engine applied it, stepped, and the frame arrived): median and 99th
//     percentile.
//
//   live_bench SCENE [--device cpu|cuda|auto] [--precision float|double] [--seconds S]
//              [--frame-rate F] [--threads N]
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "sinew/common/log.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/live/server.hpp"
#include "sinew/live/session.hpp"

namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(p * double(v.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace sinew;
  CLI::App app{"live_bench: sinew-live's speed against the batch engine, and steering latency"};
  simulator::RunOptions opt;
  std::string precision;
  double seconds = 20, frame_rate = 30;
  app.add_option("scene", opt.scene_path, "Scene file")->required()->check(CLI::ExistingFile);
  app.add_option("--device", opt.device, "cpu, cuda or auto")->default_val("auto");
  app.add_option("--precision", precision, "float or double (default: the scene's)");
  app.add_option("--seconds", seconds, "Wall seconds of each measurement")->default_val(20);
  app.add_option("--frame-rate", frame_rate, "Frames per second streamed")->default_val(30);
  app.add_option("--threads", opt.threads, "OpenMP threads of the CPU backend");
  CLI11_PARSE(app, argc, argv);
  if (!precision.empty())
    opt.precision =
        precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  log::set_level(log::Level::warn);
  return tool::run("live_bench", [&] {
    auto run = simulator::load_run(opt, live::make_live_setup);
    auto& backend = *run.backend;
    const double s = run.resolved.setup.time_scaling, dt = backend.dt();
    fmt::print("scene {}\ndevice {}\nprecision {}\ndt {:.6g} s, {} nodes\n", opt.scene_path,
               run.summary.device, run.summary.precision, dt, run.model->node_count());

    // 1. Batch.
    const auto initial = backend.state();
    backend.step(backend.preferred_step_count());  // warm-up
    auto t0 = Clock::now();
    const std::int64_t b0 = backend.step_index();
    while (since(t0) < seconds) backend.step(backend.preferred_step_count());
    const double batch_wall = since(t0);
    const double batch_sps = double(backend.step_index() - b0) / batch_wall;
    backend.restore(initial);
    fmt::print("batch: {:.1f} steps/s, {:.4g} simulated s per wall s\n", batch_sps,
               batch_sps * dt / s);

    // 2. + 3. Live with a client.
    const std::string muscle = run.model->muscles.empty() ? "" : run.model->muscles[0].name;
    live::SessionOptions so;
    so.frame_rate = frame_rate;
    so.pause_at_end = false;  // measure past the scene's duration too
    live::Session session(std::move(run), so);
    std::uint32_t vertices = 0;
    std::memcpy(&vertices, session.mesh_message()->data() + 4, 4);
    live::ServerOptions sv;
    sv.port = 0;
    sv.max_messages_per_second = 1000;
    live::Server server(session, sv);
    std::thread io([&] { server.run(false); });
    session.start();

    net::io_context ioc;
    websocket::stream<tcp::socket> ws(ioc);
    ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), server.port()));
    ws.handshake("127.0.0.1", "/ws");
    std::mutex m;
    std::vector<Clock::time_point> sent(1, Clock::now());
    std::vector<double> latency;
    std::atomic<std::int64_t> frames{0};
    std::atomic<bool> done{false};
    std::uint32_t last_seen = 0;
    std::thread reader([&] {
      beast::flat_buffer b;
      while (!done) {
        beast::error_code ec;
        ws.read(b, ec);
        if (ec) break;
        if (!ws.got_text() && b.size() >= live::kFrameHeaderBytes) {
          std::uint32_t h[4];
          std::memcpy(h, static_cast<const char*>(b.data().data()), 16);
          if (h[0] == live::kTagFrame) {
            ++frames;
            std::lock_guard lock(m);
            if (h[3] > last_seen && h[3] < sent.size()) {
              for (std::uint32_t id = last_seen + 1; id <= h[3]; ++id)
                latency.push_back(std::chrono::duration<double>(Clock::now() - sent[id]).count());
              last_seen = h[3];
            }
          }
        }
        b.consume(b.size());
      }
    });
    std::this_thread::sleep_for(std::chrono::seconds(1));  // warm-up
    const std::int64_t l0 = session.step_index(), f0 = frames;
    t0 = Clock::now();
    std::uint32_t id = 0;
    while (since(t0) < seconds) {
      if (!muscle.empty()) {
        ++id;
        {
          std::lock_guard lock(m);
          sent.push_back(Clock::now());
        }
        ws.text(true);
        ws.write(net::buffer(
            fmt::format(R"({{"type": "activation", "muscle": "{}", "value": {}, "id": {}}})",
                        muscle, id % 2 ? 0.35 : 0.3, id)));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    const double live_wall = since(t0);
    const double live_sps = double(session.step_index() - l0) / live_wall;
    const double fps = double(frames - f0) / live_wall;
    done = true;
    beast::error_code ec;
    ws.next_layer().close(ec);
    reader.join();
    server.stop();
    io.join();
    session.stop();
    std::lock_guard lock(m);
    fmt::print(
        "live: {:.1f} steps/s, {:.4g} simulated s per wall s, {:.1f} frames/s received "
        "({} frame bytes), live/batch {:.3f}\n",
        live_sps, live_sps * dt / s, fps, live::kFrameHeaderBytes + 16 * std::size_t(vertices),
        live_sps / batch_sps);
    fmt::print(
        "slider -> first frame reflecting it: median {:.1f} ms, p99 {:.1f} ms ({} samples)\n",
        1e3 * percentile(latency, 0.5), 1e3 * percentile(latency, 0.99), latency.size());
    return tool::kExitOk;
  });
}
