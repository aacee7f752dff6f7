#pragma once
// One simulation run from a scene file: what `sinew-simulate` does, as a library call so tests can
// run it (and interrupt and resume it) without a process.
//
//   scene → parse → read model → resolve → engine (plan) → [explain] → step loop → outputs
//
// Outputs in the output directory (docs/results-format.md): results.h5 + results.xdmf (frames),
// probe_<name>.csv, run_summary.json, checkpoint.h5 (with checkpoint_every or on interruption).
// Frames: the first at t = 0, then one every output interval of scene time (at the first step at
// or after it), and the last step; probes likewise at their interval (default every step).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine.hpp"
#include "sinew/simulator/model_cache.hpp"
#include "sinew/simulator/plan.hpp"
#include "sinew/simulator/run_summary.hpp"
#include "sinew/simulator/scene.hpp"

namespace sinew::simulator {

struct RunOptions {
  std::string scene_path;
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

// The hourglass warning: at an output frame where the hourglass energy exceeds this share of the
// strain energy, the run logs one warning and lists it in run_summary.json's `warnings` (the
// usual 10% rule of explicit codes such as LS-DYNA). One-point elements can then be folded into
// hourglass patterns that no Jacobian check sees (docs/stability.md): refine, raise
// hourglass.kappa, or use modulus p_wave where bending does not matter.
inline constexpr double kHourglassWarningShare = 0.10;

// Runs (or explains) a scene. Throws ConfigError / FormatError / IoError / ResourceError before
// the loop starts. An instability during the loop is written to the summary (status "unstable")
// with every frame so far intact, and then rethrown as InstabilityError. SIGINT/SIGTERM during the
// loop stop it at the next step boundary with a checkpoint (status "interrupted").
RunResult run_scene(const RunOptions& options);

// Installs SIGINT/SIGTERM handlers that ask a running loop to stop (the tool calls it once).
// Every run_scene in flight, in any thread, stops at its next step boundary; the request stays
// set (interrupt_requested()) until clear_interrupt(), so a caller that runs scenes one after the
// other (sinew-sweep) sees it too.
void install_interrupt_handlers();
bool interrupt_requested();
void clear_interrupt();

}  // namespace sinew::simulator
