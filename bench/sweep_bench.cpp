// Many runs at once on one device (docs/performance.md, Sweeps): a scene run N times through
// sinew-sweep's runner with K runs at once (threads; on a GPU each engine has its own streams),
// against one run alone. Prints per K: wall time, element-steps per second (Σ elements × steps /
// wall), the ratio to one run, and on the GPU the achieved bandwidth (the engine's minimum bytes per
// step × steps / wall) against the measured device-to-device copy bandwidth.
//
//   sweep_bench --scene SCENE --model MODEL [--device cuda|cpu] [--concurrent 1,16,64]
//               [--duration S] [--precision float|double] [--out DIR] [--keep-outputs]
//
// The runs write only their first and last frame (displacements) and no probe rows unless
// --keep-outputs: the figure is the engines', not the writers'. The runs are the same scene with a
// different title each (`list: [{title: run 0}, ...]`), so each does the whole work.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/cuda_backend.hpp"
#include "sinew/simulator/scene.hpp"
#include "sinew/sweep/run_sweep.hpp"
#include "sinew/sweep/sweep_file.hpp"

namespace fs = std::filesystem;
using namespace sinew;

namespace {

struct Options {
  std::string scene, model, device = "cuda", precision, out = "sweep_bench_results";
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
    else
      throw std::invalid_argument("unknown argument " + a + " (see the header of sweep_bench.cpp)");
  }
  if (o.scene.empty() || o.model.empty())
    throw std::invalid_argument("--scene and --model are needed");

  const auto model = formats::read_model(o.model);
  const double elements = double(model.element_count());
  double bytes_per_step = 0, copy_bw = 0;
  if (o.device == "cuda") {
    // The engine's minimum traffic per step on this model and scene (CudaTiming), and the copy
    // bandwidth as the ceiling.
    auto scene = simulator::parse_scene(o.scene);
    simulator::ResolveOptions ro;
    if (!o.precision.empty())
      ro.precision =
          o.precision == "float" ? simulator::Precision::float32 : simulator::Precision::float64;
    const auto resolved = simulator::resolve_scene(scene, model, ro);
    auto backend = simulator::make_cuda_backend(model, resolved.setup);
    bytes_per_step = dynamic_cast<simulator::CudaTiming&>(*backend).bytes_per_step();
    copy_bw = simulator::measure_copy_bandwidth(std::size_t(1) << 30);
    std::printf("device %s: copy bandwidth %.0f GB/s; %.0f elements, %.3g MB per step at least\n",
                simulator::cuda_device_name().c_str(), copy_bw / 1e9, elements,
                bytes_per_step / 1e6);
  } else {
    std::printf("device cpu: %.0f elements\n", elements);
  }

  std::printf(
      "\n| runs at once | runs | wall s | steps per run | element-steps/s | vs one run | "
      "bandwidth GB/s | share of copy |\n|---|---|---|---|---|---|---|---|\n");
  double single = 0;
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
    const auto t0 = std::chrono::steady_clock::now();
    const auto report = sweep::run_sweep(sweep, so);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double steps = 0;
    std::size_t failed = 0;
    for (const auto& r : report.rows) {
      failed += r.status != "completed";
      steps += r.figures[r.figures.size() - 2].value_or(0);  // steps_done
    }
    const double rate = elements * steps / wall;
    if (single == 0) single = rate;
    const double bw = bytes_per_step * steps / wall;
    const std::string bandwidth =
        copy_bw > 0 ? fmt::format("{:.0f} | {:.0f}%", bw / 1e9, 100 * bw / copy_bw) : "- | -";
    std::printf("%s\n", fmt::format("| {} | {} | {:.2f} | {:.0f} | {:.3g} | {:.2f} | {} |{}", k,
                                    report.rows.size(), wall, steps / double(report.rows.size()),
                                    rate, rate / single, bandwidth,
                                    failed ? fmt::format(" {} runs did not complete", failed) : "")
                            .c_str());
    std::fflush(stdout);
  }
  std::printf(
      "\n(element-steps/s counts whole runs: set-up, the first and last frame, the summary; "
      "the first row is the reference)\n");
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "sweep_bench: %s\n", e.what());
  return 1;
}
