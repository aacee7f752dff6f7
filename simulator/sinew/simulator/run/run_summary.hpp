#pragma once
// The run summary: <directory>/run_summary.json, rewritten (atomically) at every frame and at the
// end, so an interrupted or failed run still says how far it got and why it stopped.
// docs/results-format.md lists every key.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "sinew/simulator/engine/backend.hpp"

namespace sinew::simulator {

struct RunSummary {
  std::string status = "running";  // running | completed | unstable | interrupted | failed
  std::string message;             // why it stopped, when not completed
  std::string scene_file, model_file;
  std::string device;     // e.g. "cpu (OpenMP, 2 threads)"
  std::string precision;  // "float" | "double"
  int threads = 0;
  std::vector<std::string> effects;
  double duration = 0;  // s, scene time asked for
  double time_scaling = 1, mass_scaling = 1;
  double dt = 0;           // s, simulated time per step
  double dt_critical = 0;  // s, the model's estimate
  std::string dt_reason;
  std::int64_t steps_planned = 0;
  std::int64_t steps_done = 0;      // the engine's step index at the end
  std::int64_t steps_this_run = 0;  // steps computed by this process (after a restart: fewer)
  std::int64_t restart_step = -1;   // the checkpoint's step when resumed, −1 otherwise
  std::string restart_file;
  double simulated_time = 0;   // s, scene time reached
  double wall_time_s = 0;      // this process
  double time_per_step_s = 0;  // wall time of the step loop / steps_this_run
  double setup_s = 0;          // wall time before the step loop: model, plan, engine, writers
  // setup_s by stage (s), in this order: "model" (reading the scene and the model file, or taking
  // it from a ModelCache), "engine" (resolving the scene, the plan, the engine: on the GPU its
  // device arrays and graph capture), "outputs" (creating or reopening results.h5 and the probe
  // files, reading a checkpoint), "first_frame" (the first frame, probe row and this file).
  std::vector<std::pair<std::string, double>> setup_stages;
  // The step loop's start and end on the wall clock (s since 1970, UTC): where runs of one process
  // (sinew-sweep --concurrent) stepped at the same time. 0 before the loop started / ended.
  double loop_start_unix_s = 0, loop_end_unix_s = 0;
  // The step loop's wall time by stage (s, this process), in this order: "steps" (inside
  // Backend::step), "frames" (taking each frame: displacements and energies, and on the CPU its
  // fields and writing; on the GPU waiting for the frame thread when it falls behind), "probes",
  // "checkpoints" (with the wait for pending frames), "summary" (this file), "other" (progress,
  // the loop's own work).
  std::vector<std::pair<std::string, double>> loop_stages;
  // s spent writing frames (element fields, HDF5, indexes): on the GPU on the frame thread,
  // overlapped with the steps; on the CPU inside the "frames" stage.
  double frame_writing_s = 0;
  std::int64_t frames = 0;
  // The jaw (when the scene moves one): its nodes and the largest incisal opening its curves give
  // (m; scene_jaw.hpp incisal_opening over the run's steps).
  std::int64_t jaw_nodes = 0;
  double jaw_max_incisal_opening = 0;
  // The lips' pairs (a model whose jaw has them, with the effect `contact` on or off): their count
  // and the smallest gap across them over the frames (m, scene_jaw.hpp smallest_lip_gap;
  // negative: a lip through the other) and when (s).
  std::int64_t contact_pairs = 0;
  bool contact_on = false;
  double contact_min_gap = 0, contact_min_gap_time = 0;
  std::vector<Energies> energies;  // one per frame, simulated time
  std::vector<std::string> warnings;
};

// The JSON text of a summary (2-space indented).
std::string to_json(const RunSummary& summary);
// Writes it to `path` via a temporary file and rename (atomic_file.hpp). When that fails (a full
// disk) the summary already there is removed, so none is left describing an earlier state, and
// the write is tried once more. Throws IoError.
void write_run_summary(const std::string& path, const RunSummary& summary);
// The energy history of an existing summary; empty when the file is missing or unreadable (it is
// informational and never blocks a restart).
std::vector<Energies> read_energy_history(const std::string& path);

}  // namespace sinew::simulator
