#pragma once
// What a caller asks of one run (RunOptions: sinew-simulate's options) and what it gets back
// (RunResult): the arguments of run_scene (runner.hpp), also read by the run's set-up
// (run_setup.hpp). Apart from runner.hpp so that the set-up, which the runner calls, does not
// include the runner.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/model_cache.hpp"
#include "sinew/simulator/engine/plan.hpp"
#include "sinew/simulator/run/run_summary.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::simulator {

struct RunOptions {
  std::string scene_path;
  // The scene itself, when it is not read from scene_path (the Python module's scenes made from a
  // dict or edited in memory): scene_path then only names it in messages and the summary, and
  // scene_directory resolves its relative model path. Empty: scene_path is read.
  std::string scene_text;
  std::string scene_directory;
  std::string output_dir;              // created when missing
  std::string device = "auto";         // cpu | cuda | auto
  std::optional<Precision> precision;  // overrides the scene's
  int threads = 0;                     // 0: OpenMP's default
  int cuda_device = 0;                 // the CUDA device the run uses (cuda or auto)
  bool quiet = false;                  // no progress bar
  bool explain = false;                // print the plan first
  bool run = true;                     // false: stop after the plan
  bool force = false;   // run past the step, frame and probe-row limits (run_limits.hpp)
  std::string restart;  // checkpoint to resume from ("" none)
  std::int64_t checkpoint_every = 0;  // steps between checkpoints (0: none)
  // Stop once this step is reached, writing a checkpoint there, as an interruption would (tests
  // use it to cut a run in two); −1: run to the end.
  std::int64_t stop_at_step = -1;
  // Receives the plan text (default: stdout).
  std::function<void(const std::string&)> print;
  // With `explain`: more text appended to the plan from the model and plan (sinew-simulate --parts
  // prints the partition of sinew::partition this way; the simulator does not depend on it).
  std::function<std::string(const formats::Model&, const Plan&)> explain_more;
  // The engine to run instead of --device's (sinew-simulate-parts: the partitioned engine under
  // mpirun, whose every call is collective); null: make_cpu_backend or make_cuda_backend.
  std::function<std::unique_ptr<Backend>(const formats::Model&, const Setup&)> make_backend;
  // Where the model file is read: null, read here (sinew-simulate); else from this cache, read
  // once per process and shared with the other runs that use it (sinew-sweep). Not owned; it must
  // outlive the run. The same checks and errors either way.
  ModelCache* models = nullptr;
};

struct RunResult {
  RunSummary summary;
  std::string output_dir;
  bool ran = false;  // false when only the plan was printed
};

}  // namespace sinew::simulator
