#pragma once
// What a run does before its step loop, shared by sinew-simulate (runner.cpp) and sinew-live
// (live/): pick the device, read the scene and the model, resolve the scene, build the engine
// (the plan), fill the summary's header and, on request, explain the plan. One path, so a live
// session simulates exactly what sinew-simulate would.
#include <functional>
#include <memory>
#include <string>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "sinew/simulator/run/run_limits.hpp"
#include "sinew/simulator/run/run_options.hpp"
#include "sinew/simulator/run/run_summary.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::simulator {

struct LoadedRun {
  std::string scene_text;  // the scene file's bytes (the checkpoint digest)
  Scene scene;
  std::shared_ptr<const formats::Model> model;  // never null after load_run
  std::string model_sha256;  // the model file's SHA-256 when the ModelCache read it; else ""
  ResolvedScene resolved;
  std::unique_ptr<Backend> backend;
  bool cuda = false;
  int threads = 1;      // OpenMP threads of the CPU backend
  RunSummary summary;   // header filled: files, device, precision, effects, plan, warnings
  OutputCounts counts;  // count_outputs of the plan
  // Wall time (s) of reading the scene and the model, and of resolving and building the engine.
  double model_s = 0, engine_s = 0;
};

// Loads and plans options.scene_path on options.device. `adjust`, when given, may change the
// resolved Setup before the engine is built (sinew-live adds its force slots). Throws ConfigError /
// FormatError / IoError / ResourceError naming the file and key.
LoadedRun load_run(const RunOptions& options, const std::function<void(Setup&)>& adjust = nullptr);

// The plan, device, outputs (into options.output_dir), probes, warnings and run estimate as
// `--explain` prints them, and options.explain_more's text.
std::string explain_run(LoadedRun& run, const RunOptions& options);

// The results writer's options for the scene's output fields.
ResultsOptions results_options(const Scene& scene, const std::string& scene_path);

// The scene file's text. Throws IoError.
std::string read_scene_text(const std::string& path);

}  // namespace sinew::simulator
