#include "sinew/simulator/run/run_limits.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "sinew/common/error.hpp"

namespace sinew::simulator {

namespace {

// A probe row is "time,step,x,y,z" in %.9g-ish text: about 80 bytes.
constexpr double kProbeRowBytes = 80;

// Events every `interval` over `duration` (both scene time) on a run of `steps` steps: one per
// interval but at most one per step, plus the first and (when it is not one already) the last.
double event_count(double duration, double interval, double steps) {
  if (!(interval > 0)) return steps + 1;  // every step
  return std::min(steps, std::ceil(duration / interval)) + 1;
}

std::string bytes_text(double b) {
  if (b >= 0x1p40) return fmt::format("{:.3g} TiB", b / 0x1p40);
  if (b >= 0x1p30) return fmt::format("{:.3g} GiB", b / 0x1p30);
  if (b >= 0x1p20) return fmt::format("{:.3g} MiB", b / 0x1p20);
  if (b >= 0x1p10) return fmt::format("{:.3g} KiB", b / 0x1p10);
  return fmt::format("{:.0f} B", b);
}

}  // namespace

OutputCounts count_outputs(const formats::Model& model, const Plan& plan,
                           const ResolvedScene& scene) {
  OutputCounts c;
  const double duration = scene.setup.duration / scene.setup.time_scaling;  // scene time
  c.steps = double(plan.steps);
  // Without an interval only the first and the last frame are written.
  c.frames = scene.output_interval > 0 ? event_count(duration, scene.output_interval, c.steps)
                                       : std::min(c.steps, 1.0) + 1;
  c.probes = scene.probes.size();
  c.probe_rows = c.probes > 0 ? event_count(duration, scene.probe_interval, c.steps) : 0;

  // results.h5 stores float64 throughout (docs/results-format.md).
  const double nodes = double(model.node_count()), elements = double(model.element_count());
  c.frame_bytes = 16;  // time, step
  for (auto f : scene.fields) {
    switch (f) {
      case OutputField::displacement:
        c.frame_bytes += nodes * 3 * 8;
        break;
      case OutputField::stress:
      case OutputField::jacobian:
      case OutputField::energy_density:
        c.frame_bytes += elements * 8;
        break;
      case OutputField::surfaces:
        for (const auto& s : model.surfaces) {
          if (s.role == formats::SurfaceRole::visual)
            c.frame_bytes += double(s.vertices.size()) * 24;
        }
        break;
    }
  }
  c.output_bytes = c.frames * c.frame_bytes + c.probe_rows * double(c.probes) * kProbeRowBytes;
  return c;
}

void check_output_limits(const OutputCounts& c, const ResolvedScene& scene,
                         const std::string& scene_file, bool force) {
  if (force) return;
  const char* way_out = "pass --force to run it anyway";
  if (c.steps > kMaxSteps) {
    const double s = scene.setup.time_scaling;
    const std::string key = s != 1 ? "time_scaling" : "duration";
    throw ConfigError(
        scene_file, key,
        fmt::format("duration {:.6g} s{} at Δt = {:.3g} s is {:.3g} steps, more than the {:.0e} a "
                    "run may take; shorten it or {}",
                    scene.setup.duration / s,
                    s != 1 ? fmt::format(" × time_scaling {:.6g}", s) : "",
                    scene.setup.duration / c.steps, c.steps, kMaxSteps, way_out));
  }
  if (c.frames > kMaxFrames) {
    throw ConfigError(
        scene_file, "output.interval",
        fmt::format("an interval of {:.6g} s gives {:.4g} frames (about {} of results), more "
                    "than the {:.0e} a run may write; raise output.interval or {}",
                    scene.output_interval, c.frames, bytes_text(c.frames * c.frame_bytes),
                    kMaxFrames, way_out));
  }
  if (c.probe_rows > kMaxProbeRows) {
    throw ConfigError(
        scene_file, "output.probe_interval",
        fmt::format(
            "{} gives {:.4g} rows per probe, more than the {:.0e} a run may write; "
            "{} or {}",
            scene.probe_interval > 0 ? fmt::format("an interval of {:.6g} s", scene.probe_interval)
                                     : std::string("a row every step (no probe_interval)"),
            c.probe_rows, kMaxProbeRows,
            scene.probe_interval > 0 ? "raise output.probe_interval" : "set output.probe_interval",
            way_out));
  }
}

std::string describe_outputs(const OutputCounts& c) {
  std::string text = fmt::format("  {:.0f} frames of {} each", c.frames, bytes_text(c.frame_bytes));
  if (c.probes > 0) text += fmt::format(", {:.0f} rows per probe", c.probe_rows);
  text += fmt::format("; about {} in all\n", bytes_text(c.output_bytes));
  return text;
}

}  // namespace sinew::simulator
