// Many runs at once on one device (docs/performance.md, Sweeps): a scene run K times through
// sinew-sweep's runner with the K runs at once (threads; on a GPU each engine has its own streams),
// against one run alone. Two figures per K:
//  - whole runs: wall time of the sweep, element-steps per second (Σ elements × steps / wall), the
//    ratio to K = 1, and on the GPU the achieved bandwidth (the engine's minimum bytes per step ×
//    steps / wall) against the measured device-to-device copy bandwidth;
//  - steady state: the same over the stretch where all K runs were stepping (from each run's step
//    loop start and end in its run_summary.json: the latest start to the earliest end), each run's
//    steps in it counted at its own loop's steps/s: what the engines get out of the GPU once set
//    up, apart from the set-ups (printed too: median and maximum by stage, setup_stages_s).
// Before the runs it prints the steps per run and, on the GPU, one engine's step alone (graph
// launches, CUDA events) and the time all K need if running at once gained nothing.
//
//   sweep_bench --scene SCENE --model MODEL [--device cuda|cpu] [--concurrent 1,16,64]
//               [--duration S] [--precision float|double] [--out DIR] [--keep-outputs]
//               [--gpu-wait auto|spin|block]
//
// The runs write only their first and last frame (displacements) and no probe rows unless
// --keep-outputs: the figure is the engines', not the writers'. --gpu-wait: how the runs' threads
// wait for the GPU (SweepOptions::gpu_wait; auto: asleep when K is above the cores). The runs are the same scene with a
// different title each (`list: [{title: run 0}, ...]`), so each does the whole work.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/scene.hpp"
#include "sinew/sweep/run_sweep.hpp"
#include "sinew/sweep/sweep_file.hpp"

namespace fs = std::filesystem;
using namespace sinew;

namespace {

struct Options {
  std::string scene, model, device = "cuda", precision, out = "sweep_bench_results";
  std::string gpu_wait = "auto";
  std::vector<int> concurrent{1, 16, 64};
  double duration = 0;
  bool keep_outputs = false;
};

std::vector<int> int_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

// The sweep file of `runs` runs of the scene, written into dir.
std::string write_sweep(const Options& o, int runs, const fs::path& dir) {
  std::string text =
      fmt::format("version: 1\nscene: '{}'\nlist:\n", fs::absolute(o.scene).string());
  for (int r = 0; r < runs; ++r)
    text +=
        fmt::format("  - {{title: 'run {}', model: '{}'}}\n", r, fs::absolute(o.model).string());
  std::string grid;
  if (o.duration > 0) grid += fmt::format("  duration: [{}]\n", o.duration);
  if (!o.keep_outputs)
    grid += "  output: [{interval: 0, fields: [displacement]}]\n  probes: [[]]\n";
  if (!grid.empty()) text.append("grid:\n").append(grid);
  const auto path = dir / fmt::format("sweep_{}.yaml", runs);
  fs::create_directories(dir);
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace

// One run's set-up and step loop, from its run_summary.json.
struct RunTimes {
  double setup = 0, loop_start = 0, loop_end = 0, steps = 0;
  std::vector<std::pair<std::string, double>> setup_stages;
};

RunTimes read_times(const std::string& summary_path) {
  std::ifstream in(summary_path);
  if (!in) throw std::runtime_error("cannot read " + summary_path);
  const auto j = nlohmann::ordered_json::parse(in);  // set-up stages in their order
  RunTimes t;
  t.setup = j.at("setup_s").get<double>();
  t.loop_start = j.at("loop_start_unix_s").get<double>();
  t.loop_end = j.at("loop_end_unix_s").get<double>();
  t.steps = double(j.at("steps_this_run").get<std::int64_t>());
  for (const auto& [name, seconds] : j.at("setup_stages_s").items())
    t.setup_stages.emplace_back(name, seconds.get<double>());
  return t;
}

// The stretch where every run was stepping and the steps per second of all runs in it, each run
// at its own loop's average rate (a run that stepped alone for a while before the others joined
// averaged a little faster than it stepped beside them: the figure leans high by that much).
struct Steady {
  double seconds = 0;        // the latest loop start to the earliest loop end; 0: none
  double steps_per_s = 0;    // Σ over runs of steps / loop time
  double share_of_loop = 0;  // seconds / the mean loop time of the runs
};

Steady steady_state(const std::vector<RunTimes>& runs) {
  Steady s;
  if (runs.empty()) return s;
  double start = runs[0].loop_start, end = runs[0].loop_end, loops = 0;
  for (const auto& r : runs) {
    start = std::max(start, r.loop_start);
    end = std::min(end, r.loop_end);
    const double loop = r.loop_end - r.loop_start;
    loops += loop;
    if (loop > 0) s.steps_per_s += r.steps / loop;
  }
  s.seconds = std::max(0.0, end - start);
  s.share_of_loop = loops > 0 ? s.seconds / (loops / double(runs.size())) : 0;
  return s;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5))];
}

// "0.07/0.08: model 0.01/0.02, engine ...": median / maximum over the runs of the set-up and of
// each of its stages, s.
std::string setup_text(const std::vector<RunTimes>& runs) {
  if (runs.empty()) return "";
  std::vector<double> total;
  for (const auto& r : runs) total.push_back(r.setup);
  std::string text = fmt::format("{:.3f}/{:.3f}:", percentile(total, 0.5), percentile(total, 1.0));
  for (std::size_t k = 0; k < runs[0].setup_stages.size(); ++k) {
    std::vector<double> v;
    for (const auto& r : runs)
      if (k < r.setup_stages.size()) v.push_back(r.setup_stages[k].second);
    text += fmt::format("{} {} {:.3f}/{:.3f}", k ? "," : "", runs[0].setup_stages[k].first,
                        percentile(v, 0.5), percentile(v, 1.0));
  }
  return text;
}

int main(int argc, char** argv) try {
  Options o;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    const auto value = [&]() -> std::string {
      if (k + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++k];
    };
    if (a == "--scene")
      o.scene = value();
    else if (a == "--model")
      o.model = value();
    else if (a == "--device")
      o.device = value();
    else if (a == "--concurrent")
      o.concurrent = int_list(value());
    else if (a == "--duration")
      o.duration = std::stod(value());
    else if (a == "--precision")
      o.precision = value();
    else if (a == "--out")
      o.out = value();
    else if (a == "--keep-outputs")
      o.keep_outputs = true;
    else if (a == "--gpu-wait")
      o.gpu_wait = value();
    else
      throw std::invalid_argument("unknown argument " + a + " (see the header of sweep_bench.cpp)");
  }
  if (o.scene.empty() || o.model.empty())
    throw std::invalid_argument("--scene and --model are needed");
  if (o.gpu_wait != "auto" && o.gpu_wait != "spin" && o.gpu_wait != "block")
    throw std::invalid_argument("--gpu-wait takes auto, spin or block, got '" + o.gpu_wait + "'");

  const auto model = formats::read_model(o.model);
  const double elements = double(model.element_count());
  auto scene = simulator::parse_scene(o.scene);
  if (o.duration > 0) scene.duration = o.duration;
  simulator::ResolveOptions ro;
  if (!o.precision.empty())
    ro.precision =
        o.precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
  const auto resolved = simulator::resolve_scene(scene, model, ro);
  double bytes_per_step = 0, copy_bw = 0, step_alone_s = 0;
  std::int64_t steps_per_run = 0;
  double dt = 0;
  if (o.device == "cuda") {
    // The engine's minimum traffic per step on this model and scene (CudaTiming), one engine's
    // step alone (median of timed graph launches after warm-up), and the copy bandwidth as the
    // ceiling.
    auto backend = simulator::make_cuda_backend(model, resolved.setup);
    steps_per_run = backend->plan().steps;
    dt = backend->plan().dt;
    auto& timing = dynamic_cast<simulator::CudaTiming&>(*backend);
    bytes_per_step = timing.bytes_per_step();
    timing.timed_graph_launches(3);
    auto ms = timing.timed_graph_launches(10);
    std::sort(ms.begin(), ms.end());
    step_alone_s = 1e-3 * ms[ms.size() / 2] / timing.graph_steps();
    copy_bw = simulator::measure_copy_bandwidth(std::size_t(1) << 30);
    std::printf(
        "device %s: copy bandwidth %.0f GB/s; %.0f elements, %.3g MB per step at least; "
        "one engine's step alone %.4f ms (%.0f GB/s)\n",
        simulator::cuda_device_name().c_str(), copy_bw / 1e9, elements, bytes_per_step / 1e6,
        1e3 * step_alone_s, bytes_per_step / step_alone_s / 1e9);
  } else {
    const auto backend = simulator::make_cpu_backend(model, resolved.setup);
    steps_per_run = backend->plan().steps;
    dt = backend->plan().dt;
    std::printf("device cpu: %.0f elements\n", elements);
  }
  std::printf("%lld steps per run (dt %.4g s, duration %.4g s)\n", (long long)steps_per_run, dt,
              scene.duration);
  if (step_alone_s > 0) {
    double all = 0;
    for (const int k : o.concurrent) all += double(k) * double(steps_per_run) * step_alone_s;
    std::printf("steps of all runs one after another: %.1f s (running at once should need less)\n",
                all);
  }
  std::fflush(stdout);

  std::vector<std::string> whole_rows, steady_rows;
  double single = 0, single_steady = 0;
  for (const int k : o.concurrent) {
    const fs::path dir = fs::path(o.out) / fmt::format("k{}", k);
    fs::remove_all(dir);
    const auto sweep = sweep::parse_sweep(write_sweep(o, k, dir));
    sweep::SweepOptions so;
    so.output_dir = (dir / "results").string();
    so.settings.device = o.device;
    so.settings.concurrent = k;
    if (!o.precision.empty()) so.settings.precision = o.precision;
    so.quiet = true;
    so.gpu_wait = o.gpu_wait;
    const auto t0 = std::chrono::steady_clock::now();
    const auto report = sweep::run_sweep(sweep, so);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double steps = 0;
    std::size_t failed = 0;
    std::vector<RunTimes> times;
    for (const auto& r : report.rows) {
      failed += r.status != "completed";
      steps += r.figures[r.figures.size() - 2].value_or(0);  // steps_done
      if (r.status == "completed")
        times.push_back(
            read_times((fs::path(so.output_dir) / r.name / "run_summary.json").string()));
    }
    const auto bandwidth = [&](double steps_per_s) {
      const double bw = bytes_per_step * steps_per_s;
      return copy_bw > 0 ? fmt::format("{:.0f} | {:.0f}%", bw / 1e9, 100 * bw / copy_bw)
                         : std::string("- | -");
    };
    const double rate = elements * steps / wall;
    if (single == 0) single = rate;
    whole_rows.push_back(fmt::format(
        "| {} | {} | {:.2f} | {:.0f} | {:.3g} | {:.2f} | {} |{}", k, report.rows.size(), wall,
        steps / double(report.rows.size()), rate, rate / single, bandwidth(steps / wall),
        failed ? fmt::format(" {} runs did not complete", failed) : ""));
    const Steady st = steady_state(times);
    const double steady_rate = elements * st.steps_per_s;
    if (single_steady == 0) single_steady = steady_rate;
    steady_rows.push_back(
        st.seconds > 0
            ? fmt::format("| {} | {:.2f} | {:.0f}% | {:.3g} | {:.2f} | {} | {} |", k, st.seconds,
                          100 * st.share_of_loop, steady_rate, steady_rate / single_steady,
                          bandwidth(st.steps_per_s), setup_text(times))
            : fmt::format("| {} | 0 | 0% | - | - | - | - | {} (never all stepping at once) |", k,
                          setup_text(times)));
    std::printf("K = %d: whole runs %s\n       steady state %s\n", k, whole_rows.back().c_str(),
                steady_rows.back().c_str());
    std::fflush(stdout);
  }
  std::printf(
      "\nWhole runs (set-up, first and last frame, summary; the first row is the reference):\n\n"
      "| runs at once | runs | wall s | steps per run | element-steps/s | vs first row | "
      "bandwidth GB/s | share of copy |\n|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : whole_rows) std::printf("%s\n", r.c_str());
  std::printf(
      "\nSteady state (while all runs of the row were stepping; each run's steps at its loop's "
      "average rate):\n\n"
      "| runs at once | all stepping s | of a run's loop | element-steps/s | vs first row | "
      "bandwidth GB/s | share of copy | set-up s, median/max "
      "|\n|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : steady_rows) std::printf("%s\n", r.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "sweep_bench: %s\n", e.what());
  return 1;
}
