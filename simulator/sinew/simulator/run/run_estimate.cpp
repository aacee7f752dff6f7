#include "sinew/simulator/run/run_estimate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/simulator/output/probes.hpp"

namespace sinew::simulator {
namespace {

template <typename F>
double seconds_of(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

RunEstimate estimate_run(Backend& backend, const ResolvedScene& resolved,
                         const OutputCounts& counts, bool fields) {
  RunEstimate e;
  const Plan& plan = backend.plan();
  e.frames = counts.frames;
  e.rows = counts.probe_rows;
  // A probe row as the runner writes it: the probed nodes' displacements, each reaction set.
  const std::vector<Index> probed = displacement_probe_nodes(resolved.probes);
  // Two calls of the backend's preferred length: the first warms up (first graph launches,
  // caches, lists), the second is timed.
  const std::int64_t half =
      std::max<std::int64_t>(1, std::min(plan.steps / 2, backend.preferred_step_count()));
  const State start = backend.state();
  try {
    backend.step(half);
    e.step_s = seconds_of([&] { backend.step(half); }) / double(half);
    e.warmup_steps = 2 * half;
    // A frame as the runner takes it; its fields are computed here too, as they are on the step
    // loop's thread where frames are not written in the background (the CPU).
    e.frame_s = seconds_of([&] {
      Frame frame = backend.frame(fields);
      if (frame.fields && !backend.host_idle_while_stepping()) frame.fields();
    });
    if (!resolved.probes.empty())
      e.row_s = seconds_of([&] {
        backend.displacements(probed);
        for (const auto& p : resolved.probes)
          if (p.kind == SceneProbe::Kind::reaction) backend.reaction(p.nodes);
      });
    e.total_s = double(plan.steps) * e.step_s + e.frames * e.frame_s + e.rows * e.row_s;
  } catch (const InstabilityError& ex) {
    e.failure = ex.what();
  }
  backend.restore(start);
  return e;
}

std::string describe(const RunEstimate& e) {
  if (!e.failure.empty())
    return fmt::format("Estimated wall time: none, the warm-up went unstable: {}\n", e.failure);
  return fmt::format(
      "Estimated wall time: {:.3g} s (steps {:.3g} ms each, measured over {} warm-up steps; {:.0f} "
      "frames at {:.3g} ms; {:.0f} rows per probe at {:.3g} ms; file writing not included)\n",
      e.total_s, e.step_s * 1e3, e.warmup_steps, e.frames, e.frame_s * 1e3, e.rows, e.row_s * 1e3);
}

}  // namespace sinew::simulator
