#pragma once
// The run's wall time estimated before it starts (`sinew-simulate --explain`): a short warm-up on
// the engine itself, rewound afterwards (Backend::state / restore: the run then continues from the
// same bits as without the warm-up), times the steps; one frame's and one probe row's host work are
// timed too. Estimate = steps × step time + frames × frame time + rows × row time. It leaves out
// file writing (HDF5, CSV) and a step rate that changes through the scene (e.g. sliding nodes that
// search more as the motion grows): docs/performance.md compares estimates with runs.
#include <string>

#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/run/run_limits.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::simulator {

struct RunEstimate {
  std::int64_t warmup_steps = 0;
  double step_s = 0;              // s of wall time per step (the warm-up's second half)
  double frame_s = 0, row_s = 0;  // s per frame (displacements, fields, energies), per probe row
  double frames = 0, rows = 0;    // how many the run writes (count_outputs: rows per probe file)
  double total_s = 0;
  std::string failure;  // the warm-up's instability message, when it failed (no estimate)
};

// `counts`: the run's frames and probe rows (count_outputs); `fields`: whether frames carry
// element fields. The backend is back at its starting state on return, also when the warm-up
// failed.
RunEstimate estimate_run(Backend& backend, const ResolvedScene& resolved,
                         const OutputCounts& counts, bool fields);
// One line for the plan: "Estimated wall time: ..." (or why there is none).
std::string describe(const RunEstimate& e);

}  // namespace sinew::simulator
