#pragma once
// The real scenes through the runner, as users run them (`sinew-simulate SCENE`), beside the engine
// step alone on the same model and setup: the figure users see next to the figure the kernel
// benchmarks report (docs/performance.md). Shared by cuda_bench and simulator_cpu_bench:
//   --scene FILE (repeatable) [--precision float|double] [--out DIR]
// For each scene: the whole run (everything the scene writes, into DIR/<scene name>), its wall time
// per step and the run summary's split by stage (run_summary.json: loop_stages_s), then the step
// alone: the same backend stepped without outputs (CUDA: median of timed graph launches after
// warm-up, CUDA events; CPU: median of 5 timed calls of 20 steps after 3 warm-up steps).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::bench {

struct SceneTimingOptions {
  std::vector<std::string> scenes;
  std::string device = "cpu";  // cpu | cuda
  std::optional<simulator::Precision> precision;
  std::string out = "scene_bench_results";
  int threads = 0;
};

// Takes argv[k] (and its value) when it is a scene option: --scene FILE, --precision float|double,
// --out DIR. Returns false for any other argument; throws std::invalid_argument on a bad value.
inline bool parse_scene_option(int& k, int argc, char** argv, SceneTimingOptions& o) {
  const std::string a = argv[k];
  if (a != "--scene" && a != "--precision" && a != "--out") return false;
  if (k + 1 >= argc) throw std::invalid_argument(a + " needs a value");
  const std::string v = argv[++k];
  if (a == "--scene") {
    o.scenes.push_back(v);
  } else if (a == "--out") {
    o.out = v;
  } else if (v == "float" || v == "double") {
    o.precision = v == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  } else {
    throw std::invalid_argument("--precision takes float or double, got '" + v + "'");
  }
  return true;
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// ms per step of the engine alone on the scene's model and setup.
inline double engine_step_ms(const std::string& scene_path, const SceneTimingOptions& o) {
  using namespace simulator;
  const Scene scene = parse_scene(scene_path);
  const formats::Model model = formats::read_model(scene.model_path);
  ResolveOptions ro;
  ro.precision = o.precision;
  ro.threads = o.threads;
  const ResolvedScene resolved = resolve_scene(scene, model, ro);
  if (o.device == "cuda") {
    auto backend = make_cuda_backend(model, resolved.setup);
    auto* timing = dynamic_cast<CudaTiming*>(backend.get());
    timing->timed_graph_launches(3);  // warm-up
    const auto ms = timing->timed_graph_launches(10);
    return median(std::vector<double>(ms.begin(), ms.end())) / timing->graph_steps();
  }
  auto backend = make_cpu_backend(model, resolved.setup);
  backend->step(3);
  std::vector<double> ms;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    backend->step(20);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
        20);
  }
  return median(ms);
}

// Runs every scene and prints one block each and a table; returns 0, or 1 when a scene failed.
inline int run_scene_timing(const SceneTimingOptions& o) {
  using namespace simulator;
  std::printf("scenes through the runner (device %s); the step alone on the same model and setup\n",
              o.device.c_str());
  std::vector<std::string> table;
  int status = 0;
  for (const auto& path : o.scenes) {
    try {
      RunOptions ro;
      ro.scene_path = path;
      ro.output_dir = (std::filesystem::path(o.out) / std::filesystem::path(path).stem()).string();
      ro.device = o.device;
      ro.precision = o.precision;
      ro.threads = o.threads;
      ro.quiet = true;
      const RunResult r = run_scene(ro);
      const RunSummary& s = r.summary;
      const double run_ms = s.time_per_step_s * 1e3;
      const double alone_ms = engine_step_ms(path, o);
      std::printf("== %s: %lld steps, %s, %s\n", path.c_str(), (long long)s.steps_this_run,
                  s.precision.c_str(), s.device.c_str());
      std::printf(
          "  run: %.4f ms/step (wall %.2f s, setup %.2f s); step alone %.4f ms; ratio %.2f\n",
          run_ms, s.wall_time_s, s.setup_s, alone_ms, run_ms / alone_ms);
      for (const auto& [stage, seconds] : s.loop_stages)
        std::printf("  stage %-12s %9.4f ms/step  %5.1f%%\n", stage.c_str(),
                    s.steps_this_run > 0 ? 1e3 * seconds / double(s.steps_this_run) : 0.0,
                    run_ms > 0 ? 100 * 1e3 * seconds / double(s.steps_this_run) / run_ms : 0.0);
      std::printf(
          "  frames: %lld, written in %.3f s (on the frame thread where the backend steps "
          "on the GPU)\n",
          (long long)s.frames, s.frame_writing_s);
      const double simulated_per_wall =
          s.wall_time_s > 0 ? s.simulated_time / s.wall_time_s : 0.0;  // scene time
      char line[512];
      std::snprintf(line, sizeof line, "| %s | %s | %lld | %.4f | %.4f | %.2f | %.3g |",
                    std::filesystem::path(path).filename().c_str(), s.precision.c_str(),
                    (long long)s.steps_this_run, run_ms, alone_ms, run_ms / alone_ms,
                    simulated_per_wall);
      table.push_back(line);
    } catch (const std::exception& e) {
      std::printf("== %s failed: %s\n", path.c_str(), e.what());
      status = 1;
    }
  }
  std::printf(
      "\n| scene | precision | steps | run ms/step | step alone ms | ratio | simulated s per wall "
      "s "
      "|\n|---|---|---|---|---|---|---|\n");
  for (const auto& l : table) std::printf("%s\n", l.c_str());
  return status;
}

}  // namespace sinew::bench
