#pragma once
// When a run writes its frames and probe rows: event k of a stream every `interval` of scene time
// falls on the first step at or after k · interval (scaled by time_scaling, in steps of Δt). A
// function of k alone, so a resumed run, a live run (sinew-live) and the scene that reproduces it
// pick the same steps.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sinew::simulator {

// The step of event k for events every `interval` of scene time; the int64 maximum (never) when
// that step is past 2^62, as for any k ≥ 1 with an interval of 1e308 s.
inline std::int64_t event_step(std::int64_t k, double interval, double time_scaling, double dt) {
  const double x = double(k) * interval * time_scaling / dt;
  // Casting an infinite or out-of-range double to int64 is undefined (INT64_MIN on x86, which made
  // next_after() count k up for ever: scripts/fuzz_inputs.py found the hang).
  if (!(x < 0x1p62)) return std::numeric_limits<std::int64_t>::max();
  return static_cast<std::int64_t>(std::ceil(x - 1e-9 * std::max(1.0, x)));
}

// Iterates the event steps of one output stream (frames or probe rows) past a given step.
class OutputSchedule {
 public:
  OutputSchedule(double interval, double time_scaling, double dt, std::int64_t last_step,
                 bool every_step)
      : interval_(interval),
        scaling_(time_scaling),
        dt_(dt),
        last_(last_step),
        every_(every_step) {}
  // The first event step strictly after `step` (last_step when none before it; the int64 maximum
  // at or past last_step).
  std::int64_t next_after(std::int64_t step) {
    if (step >= last_) return std::numeric_limits<std::int64_t>::max();
    if (every_) return step + 1;
    if (!(interval_ > 0)) return last_;
    // Events at most one step apart (interval · scaling ≤ Δt) fall on every step: the ceiling of a
    // sequence rising by at most 1 takes every integer. Said outright because the jump below
    // stops at k = 2^62, short of step · Δt / interval for an interval of 1e-308 s, from where
    // counting k up one at a time never ended (scripts/fuzz_inputs.py).
    if (interval_ * scaling_ <= dt_) return std::min(step + 1, last_);
    // Jump to the events of this step first: with an interval far below Δt, counting up one
    // event at a time would take interval/Δt iterations per step.
    const double first = std::min(double(step) * dt_ / (interval_ * scaling_), 0x1p62);
    k_ = std::max(k_, static_cast<std::int64_t>(first) - 1);
    while (event_step(k_, interval_, scaling_, dt_) <= step) ++k_;
    return std::min(event_step(k_, interval_, scaling_, dt_), last_);
  }

 private:
  double interval_, scaling_, dt_;
  std::int64_t last_;
  bool every_;
  std::int64_t k_ = 0;
};

}  // namespace sinew::simulator
