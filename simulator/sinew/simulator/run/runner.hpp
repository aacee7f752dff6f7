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
#include <cstddef>
#include <vector>

#include "sinew/simulator/run/run_options.hpp"

namespace sinew::simulator {

// The hourglass warning. One-point elements can be folded into hourglass patterns that no Jacobian
// check sees (docs/stability.md): refine, raise hourglass.kappa, or use modulus p_wave where bending
// does not matter. Explicit codes (LS-DYNA, Abaqus) flag a hourglass energy above 10% of the
// internal energy; here the yardstick is the elastic energy (Energies::elastic: neo-Hookean +
// passive muscle, the energy stored in the material), not the strain energy, whose active muscle
// term is negative while a muscle contracts (docs/physics.md §8). A frame is hourglass-dominated
// when its hourglass energy exceeds kHourglassWarningShare of its elastic energy, the latter taken
// as at least kHourglassFloorShare of the largest elastic energy of the run's frames: at the onset
// of a load both energies are tiny and their ratio says nothing about the run (the forehead's
// brow raise: 12% at t = 5 ms, when the hourglass energy is 0.08% of the run's largest elastic
// energy; docs/stability.md). The run is judged when it ends (completed, interrupted or unstable):
// one warning naming the first such frame, in the log and in run_summary.json's `warnings`.
inline constexpr double kHourglassWarningShare = 0.10;
inline constexpr double kHourglassFloorShare = 0.10;

// The index of the first hourglass-dominated frame of `energies` (one per frame, in order), or
// energies.size() when there is none. Frames whose energies are not finite are skipped.
std::size_t first_hourglass_dominated(const std::vector<Energies>& energies);

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
// Asks every run in flight to stop as SIGINT would (the Python module, whose own SIGINT handler
// Python keeps, calls it on Ctrl-C while a run_scene works on another thread).
void request_interrupt();
void clear_interrupt();

}  // namespace sinew::simulator
