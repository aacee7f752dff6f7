#pragma once
// A scene's curves (docs/scene-format.md, "Curves"): a list of [t, value] points (t strictly
// increasing), the ramp/hold/release shorthand ({start, ramp, hold, release, peak}), or one number
// (a constant). Values are returned as written (the caller converts units and checks ranges).
#include <string>

#include "sinew/simulator/engine/curve.hpp"

namespace sinew {
class YamlNode;
}

namespace sinew::simulator {

// A piecewise-linear curve (curve.hpp) as written in the scene, after shorthand expansion, with
// its key path for messages. t strictly increasing, at least one point.
struct SceneCurve {
  Curve curve;
  std::string key;
};

// Throws ConfigError naming the key path and line (a curve not monotone in t names the point).
SceneCurve parse_curve(const YamlNode& c);

}  // namespace sinew::simulator
