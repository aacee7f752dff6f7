// live_bench: sinew-live's figures (docs/performance.md, "Live"). For one scene, both parts looping
// over the scene as a user replaying it does (back to step 0 whenever the scene's duration is
// passed, so the model only ever sees the states of its own scene):
//  1. batch: the engine of the live plan stepped alone (preferred step counts) for --seconds, the
//     scene's own curves; the restores at the scene's end are not timed;
//  2. live: the same engine in a Session behind the Server, a WebSocket client receiving every
//     frame (--frame-rate), for --seconds. The client steers like a user: every 100 ms of wall
//     time, and no sooner than --slider-sim-period of simulated time since its last move (a user
//     watching a slow model moves the slider as slowly in the model's time), it moves the first
//     muscle's slider, alternating between its curve's peak and half of it (inside the
//     activation range the scene itself plans for: the live plan would accept up to 1, but one
//     muscle held above its scene's peak long past the scene's end inverted an element of the
//     1 mm forehead, and the bench measures speed, not how far the model can be pushed), and
//     when a frame's scene time passes the duration it sends "reset" (step 0, overrides cleared).
//     Reported: steps/s and simulated seconds per wall second over the whole measurement (resets,
//     commands and frames included) and over the engine's step calls alone, frames/s received,
//     the resets (count, message → first frame after it), and the ratio live / batch;
//  3. latency: the time from sending a slider message to the first frame whose header carries its
//     id (the engine applied it, stepped, and the frame arrived): median and 99th percentile.
// An instability in either part stops the bench with the engine's message (exit status 3).
//
//   live_bench SCENE [--device cpu|cuda|auto] [--precision float|double] [--seconds S]
//              [--frame-rate F] [--slider-sim-period S] [--threads N]
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

#include "sinew/common/error.hpp"
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

// What the client sent, by message id (ids count from 1).
struct Sent {
  Clock::time_point at;
  bool reset = false;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace sinew;
  CLI::App app{"live_bench: sinew-live's speed against the batch engine, and steering latency"};
  simulator::RunOptions opt;
  std::string precision;
  double seconds = 20, frame_rate = 30, slider_sim_period = 0.02;
  app.add_option("scene", opt.scene_path, "Scene file")->required()->check(CLI::ExistingFile);
  app.add_option("--device", opt.device, "cpu, cuda or auto")->default_val("auto");
  app.add_option("--precision", precision, "float or double (default: the scene's)")
      ->check(CLI::IsMember({"float", "double"}));
  app.add_option("--seconds", seconds, "Wall seconds of each measurement")
      ->default_val(20)
      ->check(CLI::PositiveNumber);
  app.add_option("--frame-rate", frame_rate, "Frames per second streamed")
      ->default_val(30)
      ->check(CLI::PositiveNumber);
  app.add_option("--slider-sim-period", slider_sim_period,
                 "Simulated seconds at least between slider moves (0: every 100 ms of wall time; "
                 "at 0.5 mm a move every 100 ms of wall time is a step every 2-3 ms of the "
                 "model's time, which inverts elements)")
      ->default_val(0.02)
      ->check(CLI::NonNegativeNumber);
  app.add_option("--threads", opt.threads, "OpenMP threads of the CPU backend");
  CLI11_PARSE(app, argc, argv);
  if (!precision.empty())
    opt.precision =
        precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  log::set_level(log::Level::warn);
  tool::ExitCodes codes;
  codes.instability = tool::kExitUnstable;
  return tool::run("live_bench", codes, [&] {
    auto run = simulator::load_run(opt, live::make_live_setup);
    auto& backend = *run.backend;
    const double s = run.resolved.setup.time_scaling, dt = backend.dt();
    const double duration = run.scene.duration;
    const std::int64_t scene_steps = backend.plan().steps;
    fmt::print(
        "scene {}\ndevice {}\nprecision {}\ndt {:.6g} s, {} nodes, {} steps per scene ({} s)\n",
        opt.scene_path, run.summary.device, run.summary.precision, dt, run.model->node_count(),
        scene_steps, duration);

    // 1. Batch, looping over the scene.
    const auto initial = backend.state();
    backend.step(backend.preferred_step_count());  // warm-up
    backend.restore(initial);
    std::int64_t batch_steps = 0, batch_loops = 0;
    double batch_wall = 0;
    while (batch_wall < seconds) {
      const auto t0 = Clock::now();
      const std::int64_t n = backend.step_index();
      backend.step(backend.preferred_step_count());
      batch_wall += since(t0);
      batch_steps += backend.step_index() - n;
      if (backend.step_index() >= scene_steps) {
        backend.restore(initial);
        ++batch_loops;
      }
    }
    backend.restore(initial);
    const double batch_sps = double(batch_steps) / batch_wall;
    fmt::print("batch: {:.1f} steps/s, {:.4g} simulated s per wall s ({} scene loops)\n", batch_sps,
               batch_sps * dt / s, batch_loops);

    // 2. + 3. Live with a client.
    const std::string muscle = run.model->muscles.empty() ? "" : run.model->muscles[0].name;
    const auto& curves = run.resolved.setup.activation;
    const double peak = !curves.empty() && !curves[0].points.empty()
                            ? std::clamp(curves[0].max_value(), 0.0, 1.0)
                            : 0.0;
    live::SessionOptions so;
    so.frame_rate = frame_rate;
    so.pause_at_end = false;  // the client resets at the scene's end
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
    // The server answers to its own Host and Origin only (docs/live.md, "Threat model").
    const std::string own = fmt::format("127.0.0.1:{}", server.port());
    ws.set_option(websocket::stream_base::decorator([own](websocket::request_type& req) {
      req.set(boost::beast::http::field::origin, "http://" + own);
    }));
    ws.handshake(own, "/ws");
    std::mutex m;  // guards sent, latency, reset_latency, last_seen, pending_reset, max_time
    std::vector<Sent> sent(1);
    std::vector<double> latency, reset_latency;
    std::uint32_t last_seen = 0, pending_reset = 0;
    double max_time = 0;
    std::atomic<double> shown_time{0};  // the latest frame's scene time
    std::atomic<std::int64_t> frames{0};
    std::atomic<bool> done{false}, want_reset{false};
    std::thread reader([&] {
      beast::flat_buffer b;
      while (!done) {
        beast::error_code ec;
        ws.read(b, ec);
        if (ec) break;
        if (!ws.got_text() && b.size() >= live::kFrameHeaderBytes) {
          const char* p = static_cast<const char*>(b.data().data());
          std::uint32_t h[4];
          double time = 0;
          std::memcpy(h, p, 16);
          std::memcpy(&time, p + 24, 8);
          if (h[0] == live::kTagFrame) {
            ++frames;
            const auto now = Clock::now();
            std::lock_guard lock(m);
            if (h[3] > last_seen && h[3] < sent.size()) {
              for (std::uint32_t id = last_seen + 1; id <= h[3]; ++id)
                (sent[id].reset ? reset_latency : latency)
                    .push_back(std::chrono::duration<double>(now - sent[id].at).count());
              last_seen = h[3];
            }
            max_time = std::max(max_time, time);
            shown_time = time;
            // Past the scene's end and no reset on its way: replay the scene.
            if (time >= duration && pending_reset <= last_seen) want_reset = true;
          }
        }
        b.consume(b.size());
      }
    });
    const auto send = [&](const std::string& json_without_id, bool reset) {
      std::uint32_t id = 0;
      {
        std::lock_guard lock(m);
        id = std::uint32_t(sent.size());
        sent.push_back({Clock::now(), reset});
        if (reset) pending_reset = id;
      }
      ws.text(true);
      ws.write(net::buffer(fmt::format(R"({{{}, "id": {}}})", json_without_id, id)));
    };
    std::this_thread::sleep_for(std::chrono::seconds(1));  // warm-up
    const std::int64_t l0 = session.steps_run(), f0 = frames;
    const double e0 = session.stepping_seconds();
    const auto t0 = Clock::now();
    auto next_slider = t0;
    int slider = 0;
    double last_move_time = -1e300;  // scene time of the last slider move
    std::string error;
    while (since(t0) < seconds) {
      if (want_reset.exchange(false)) send(R"("type": "reset")", true);
      const double shown = shown_time;
      if (shown < last_move_time) last_move_time = -1e300;  // a reset went back to step 0
      if (!muscle.empty() && Clock::now() >= next_slider &&
          shown - last_move_time >= slider_sim_period) {
        last_move_time = shown;
        send(fmt::format(R"("type": "activation", "muscle": "{}", "value": {:.17g})", muscle,
                         slider++ % 2 ? 0.5 * peak : peak),
             false);
        next_slider = Clock::now() + std::chrono::milliseconds(100);
      }
      error = session.last_error();
      if (!error.empty()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const double live_wall = since(t0);
    const std::int64_t live_steps = session.steps_run() - l0;
    const double stepping = session.stepping_seconds() - e0;
    const double fps = double(frames - f0) / live_wall;
    done = true;
    beast::error_code ec;
    ws.next_layer().close(ec);
    reader.join();
    server.stop();
    io.join();
    session.stop();
    if (!error.empty())
      throw InstabilityError(
          opt.scene_path, "live session",
          fmt::format("{} (after {:.1f} s of the live measurement)", error, live_wall));
    std::lock_guard lock(m);
    const double live_sps = double(live_steps) / live_wall;
    fmt::print(
        "live: {:.1f} steps/s, {:.4g} simulated s per wall s ({:.4g} over the engine's step calls "
        "alone: {:.1f} of {:.1f} s), {:.1f} frames/s received ({} frame bytes), live/batch "
        "{:.3f}\n",
        live_sps, live_sps * dt / s, double(live_steps) * dt / s / stepping, stepping, live_wall,
        fps, live::kFrameHeaderBytes + 16 * std::size_t(vertices), live_sps / batch_sps);
    fmt::print(
        "resets at the scene's end: {}, reset -> first frame after it: median {:.1f} ms, max "
        "{:.1f} ms; latest scene time shown {:.4g} s\n",
        reset_latency.size(), 1e3 * percentile(reset_latency, 0.5),
        1e3 * percentile(reset_latency, 1.0), max_time);
    fmt::print(
        "slider ({} between {:.3g} and {:.3g}) -> first frame reflecting it: median {:.1f} ms, "
        "p99 {:.1f} ms ({} samples)\n",
        muscle, 0.5 * peak, peak, 1e3 * percentile(latency, 0.5), 1e3 * percentile(latency, 0.99),
        latency.size());
    return tool::kExitOk;
  });
}
