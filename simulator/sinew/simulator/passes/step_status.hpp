#pragma once
// What a step reports besides its results, shared by both engines (backend_core.hpp turns it into
// messages). The GPU fills one StepStatus per graph launch and the host reads it at sync points;
// the CPU checks the same conditions as it goes.
namespace sinew::simulator {

struct StepStatus {
  int bad_jacobian;      // some element had J ≤ 0 or NaN
  int bad_displacement;  // some node got a NaN/Inf displacement
  int blowup;            // kinetic energy above the blow-up bound at a checked step
  int slide_miss;        // a sliding node left its (ahead-refreshed) list: replay the batch
};

// The blow-up bound without the external work (which the engine accumulates): kinetic energy >
// factor × (base + |W|) is a blow-up (docs/physics.md, "Instability").
struct BlowupBound {
  double base;  // J, max(0, initial energy) + active-muscle bound + round-off floor
  double factor;
};

}  // namespace sinew::simulator
