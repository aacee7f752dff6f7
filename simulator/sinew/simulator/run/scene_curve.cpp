// Curves as a scene writes them (docs/scene-format.md, "Curves").
#include "sinew/simulator/run/scene_curve.hpp"

#include <fmt/format.h>

#include "sinew/common/yaml_reader.hpp"

namespace sinew::simulator {

namespace {

void check_monotone(const YamlNode& c, const std::vector<std::array<double, 2>>& points) {
  // Error text names the offending point; Curve::valid() is the same rule.
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (!(points[i][0] > points[i - 1][0])) {
      throw c.error(fmt::format("curve not monotone in t: point {} has t = {} after t = {}", i,
                                points[i][0], points[i - 1][0]));
    }
  }
}

}  // namespace

// A curve: a list of [t, value] points, or the ramp/hold/release shorthand, or a single number
// (constant).
SceneCurve parse_curve(const YamlNode& c) {
  SceneCurve out;
  out.key = c.path();
  auto& curve = out.curve;
  if (c.is_scalar()) {
    curve.points.push_back({0.0, c.number()});
    return out;
  }
  if (c.is_sequence()) {
    if (c.size() == 0) throw c.error("a curve needs at least one [t, value] point");
    for (const auto& p : c.items()) {
      if (!p.is_sequence() || p.size() != 2) throw p.error("expected a point [t, value]");
      curve.points.push_back({p.item(0).number(), p.item(1).number()});
    }
    check_monotone(c, curve.points);
    return out;
  }
  c.allow_keys({"points", "start", "ramp", "hold", "release", "peak"});
  if (c.has("points")) {
    for (const auto* k : {"start", "ramp", "hold", "release", "peak"}) {
      if (c.has(k))
        throw c.child(k).error("give either 'points' or the ramp/hold/release shorthand, not both");
    }
    return parse_curve(c.child("points"));
  }
  if (!c.has("ramp"))
    throw c.error("a curve needs 'points' or 'ramp' (with optional start, hold, release, peak)");
  const double start = c.has("start") ? c.child("start").non_negative() : 0.0;
  const double ramp = c.child("ramp").positive();
  const double peak = c.has("peak") ? c.child("peak").number() : 1.0;
  curve.points.push_back({start, 0.0});
  curve.points.push_back({start + ramp, peak});
  if (c.has("release")) {
    const double hold = c.has("hold") ? c.child("hold").non_negative() : 0.0;
    const double release = c.child("release").positive();
    if (hold > 0) curve.points.push_back({start + ramp + hold, peak});
    curve.points.push_back({start + ramp + hold + release, 0.0});
  } else if (c.has("hold")) {
    throw c.child("hold").error(
        "'hold' needs 'release' (without release the peak is held to the end)");
  }
  if (start > 0) curve.points.insert(curve.points.begin(), {0.0, 0.0});
  return out;
}

}  // namespace sinew::simulator
