#pragma once
// Sane limits on how much a run computes and writes, checked before anything is written: a
// scene value that is valid on its own (a long `duration`, a tiny `output.interval` or
// `output.probe_interval`) can ask for more steps, frames or probe rows than any machine can
// finish or store. Each count is checked against its limit with a message naming the scene key;
// `sinew-simulate --force` (RunOptions::force) runs anyway. The plan (--explain) prints the
// counts and the estimated output size (describe_outputs).
//
// Counts that do not fit in 64 bits at all (duration / Δt overflowing) are refused by make_plan
// itself, --force or not (plan.hpp).
#include <cstdint>
#include <string>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/plan.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::simulator {

// Above these a run is refused without --force. A billion steps is weeks of wall time even on
// small models; 100,000 frames or 100 million probe rows is far past what anyone inspects, and
// usually a sign of an interval given in the wrong unit.
inline constexpr double kMaxSteps = 1e9;
inline constexpr double kMaxFrames = 1e5;
inline constexpr double kMaxProbeRows = 1e8;  // per probe

// What a run will produce, counted in double so absurd scenes cannot overflow.
struct OutputCounts {
  double steps = 0;
  double frames = 0;        // frames in results.h5: the first, one per interval (at most one per
                            // step), the last
  double probe_rows = 0;    // rows per probe CSV (at most one per step)
  std::size_t probes = 0;   // probe count
  double frame_bytes = 0;   // bytes of one results frame (the fields asked for)
  double output_bytes = 0;  // results.h5 frames + probe CSVs, estimated
};

OutputCounts count_outputs(const formats::Model& model, const Plan& plan,
                           const ResolvedScene& scene);

// Throws ConfigError(scene_file, key, problem) for the first count over its limit, naming the
// scene key that sets it (`duration` or `time_scaling`, `output.interval`,
// `output.probe_interval`), the count, the limit and the way out (--force). Does nothing when
// `force`.
void check_output_limits(const OutputCounts& counts, const ResolvedScene& scene,
                         const std::string& scene_file, bool force);

// The plan's lines on outputs: frame count, probe rows, estimated output size.
std::string describe_outputs(const OutputCounts& counts);

}  // namespace sinew::simulator
