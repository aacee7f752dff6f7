#include "sinew/postprocess/frame_timing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "sinew/common/error.hpp"

namespace sinew::postprocess {
namespace {

// The median spacing of the frame times: robust to the last interval, which is shorter when the
// scene's duration is not a whole number of output intervals.
double median_interval(const std::vector<double>& times) {
  std::vector<double> d;
  for (std::size_t k = 1; k < times.size(); ++k) d.push_back(times[k] - times[k - 1]);
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// How far x is from the nearest whole number ≥ 1, relative to it.
double off_whole(double x) {
  const double n = std::max(1.0, std::round(x));
  return std::abs(x - n) / n;
}

}  // namespace

double default_fps(const std::vector<double>& times, double time_scale) {
  if (times.size() < 2) return 24.0;
  const double dt = median_interval(times);
  if (!(dt > 0) || !std::isfinite(dt)) return 24.0;
  auto factor = [&](double fps) {
    return time_scale > 0 ? dt * time_scale * fps : 1.0 / (dt * fps);
  };
  // A relative tolerance so that float-rounded output intervals still tie (200 Hz: 8.33 vs 6.67).
  return off_whole(factor(30.0)) < off_whole(factor(24.0)) - 1e-9 ? 30.0 : 24.0;
}

float key_time(std::int64_t frame, double fps) {
  const double exact = static_cast<double>(frame) / fps;
  float t = static_cast<float>(exact);
  while (t > 0.0f && static_cast<double>(t) * fps > static_cast<double>(frame)) {
    t = std::nextafter(t, 0.0f);
  }
  return t;
}

namespace {

// frame_timing at a given positive fps.
FrameTiming timing_at(const std::vector<double>& times, double fps, double time_scale) {
  FrameTiming out;
  out.fps = fps;
  for (std::size_t k = 0; k < times.size(); ++k) {
    std::int64_t n = static_cast<std::int64_t>(k);
    if (time_scale > 0) {
      const double f = std::round((times[k] - times[0]) * time_scale * fps);
      if (!(f < 1e15)) {
        throw ConfigError("", "--time-scale",
                          fmt::format("{} puts results frame {} past frame 10^15", time_scale, k));
      }
      n = static_cast<std::int64_t>(f);
      if (k > 0 && n <= out.frame.back()) {
        throw ConfigError(
            "", "--time-scale",
            fmt::format("{} at {} fps puts results frames {} (t = {:.9g} s) and {} (t = {:.9g} s) "
                        "on the same frame {}: raise --time-scale or --fps, or leave --time-scale "
                        "out (one results frame per frame)",
                        time_scale, fps, k - 1, times[k - 1], k, times[k], n));
      }
    }
    out.frame.push_back(n);
    out.time.push_back(key_time(n, fps));
  }
  return out;
}

}  // namespace

FrameTiming frame_timing(const std::vector<double>& times, const FrameTimingOptions& o) {
  if (!(o.time_scale >= 0) || !std::isfinite(o.time_scale)) {
    throw ConfigError("", "--time-scale", fmt::format("must be positive, not {}", o.time_scale));
  }
  if (o.fps != 0.0) {
    if (!(o.fps > 0) || !std::isfinite(o.fps)) {
      throw ConfigError("", "--fps", fmt::format("must be a positive frame rate, not {}", o.fps));
    }
    return timing_at(times, o.fps, o.time_scale);
  }
  const double fps = default_fps(times, o.time_scale);
  try {
    return timing_at(times, fps, o.time_scale);
  } catch (const ConfigError&) {
    // The default's other rate when it gives every results frame its own frame (30 fps for
    // 40 ms at 24 fps: 0.96 frames apart, 1.2 at 30).
    if (o.time_scale == 0) throw;
    try {
      return timing_at(times, fps == 24.0 ? 30.0 : 24.0, o.time_scale);
    } catch (const ConfigError&) {
    }
    throw;
  }
}

}  // namespace sinew::postprocess
