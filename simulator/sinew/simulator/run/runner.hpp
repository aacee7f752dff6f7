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
#include "sinew/simulator/run/run_options.hpp"

namespace sinew::simulator {

// The hourglass warning: at an output frame where the hourglass energy exceeds this share of the
// elastic energy (Energies::elastic: neo-Hookean + passive muscle, the energy stored in the
// material), the run logs one warning and lists it in run_summary.json's `warnings` (the usual 10%
// rule of explicit codes such as LS-DYNA). One-point elements can then be folded into hourglass
// patterns that no Jacobian check sees (docs/stability.md): refine, raise hourglass.kappa, or use
// modulus p_wave where bending does not matter. The strain energy is no yardstick in a muscle run:
// its active term is negative while a muscle contracts (docs/physics.md §8).
inline constexpr double kHourglassWarningShare = 0.10;

// Whether the energies of a frame call for the hourglass warning.
inline bool hourglass_dominated(const Energies& e) {
  return e.elastic > 0 && e.hourglass > kHourglassWarningShare * e.elastic;
}

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
