#pragma once
// The complete dynamic state of a run, for checkpoint and restart (sim-io writes it) and for tests.
// Restoring it into an engine built from the same Model and Setup continues bit-identically: time
// is recomputed as step · Δt, everything else the step loop reads is in here.
// Displacements are stored as double whatever the precision (float -> double -> float is exact).
#include <cstdint>
#include <vector>

#include "sinew/formats/model.hpp"

namespace sinew::simulator {

// How far a state's time may be from step · Δt, relative (BackendCore::check_state). The engines
// compute time as double(step) · Δt, so a state they wrote agrees exactly; the tolerance only
// leaves room for a time computed another way (a sum of steps) and refuses any other step.
inline constexpr double kStateTimeTolerance = 1e-9;

struct State {
  std::int64_t step = 0;       // n: u holds u(n)
  double time = 0;             // s, n · Δt (restore checks it against step · Δt)
  double dt = 0;               // s, the Δt of the run that wrote it (restore checks it)
  std::vector<double> u;       // N × 3, m, u(n), node-major (x, y, z per node)
  std::vector<double> u_prev;  // N × 3, m, u(n−1)
  std::vector<formats::Index> sliding_triangle;  // per model sliding binding: last closest triangle
  double external_work = 0;     // J, accumulated external work (forces, gravity, prescribed)
  double energy_reference = 0;  // J, the blow-up test's running reference
};

}  // namespace sinew::simulator
