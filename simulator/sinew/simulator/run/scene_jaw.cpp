#include "sinew/simulator/run/scene_jaw.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/simulator/physics/jaw.hpp"
#include "sinew/simulator/run/scene_curve.hpp"

namespace sinew::simulator {

namespace {

SceneCurve ranged_curve(const YamlNode& n, double lo, double hi, const char* unit,
                        const char* what) {
  SceneCurve c = parse_curve(n);
  for (std::size_t i = 0; i < c.curve.points.size(); ++i) {
    const double v = c.curve.points[i][1];
    if (!(v >= lo && v <= hi)) {
      throw n.error(
          fmt::format("{} must lie in [{}, {}] {} (the range of healthy adults, "
                      "docs/faces.md \"The jaw\"); point {} has {}",
                      what, lo, hi, unit, i, v));
    }
  }
  return c;
}

Curve scaled(const std::optional<SceneCurve>& c, double factor) {
  Curve out;
  if (!c) return out;  // empty: 0 (JawMotion::pose)
  out = c->curve;
  for (auto& p : out.points) p[1] *= factor;
  return out;
}

}  // namespace

SceneJaw parse_scene_jaw(const YamlNode& n) {
  n.expect_map();
  n.allow_keys({"opening_deg", "protrusion_mm", "lateral_mm"});
  if (n.size() == 0) throw n.error("give at least one of opening_deg, protrusion_mm, lateral_mm");
  SceneJaw jaw;
  jaw.key = n.path();
  if (n.has("opening_deg"))
    jaw.opening_deg = ranged_curve(n.child("opening_deg"), kJawOpeningMinDegrees,
                                   kJawOpeningMaxDegrees, "degrees", "the jaw's opening");
  if (n.has("protrusion_mm"))
    jaw.protrusion_mm = ranged_curve(n.child("protrusion_mm"), kJawProtrusionMinMm,
                                     kJawProtrusionMaxMm, "mm", "the jaw's protrusion");
  if (n.has("lateral_mm"))
    jaw.lateral_mm = ranged_curve(n.child("lateral_mm"), -kJawLateralMaxMm, kJawLateralMaxMm, "mm",
                                  "the jaw's lateral shift");
  return jaw;
}

void resolve_scene_jaw(const std::optional<SceneJaw>& jaw, const std::string& scene_file,
                       const formats::Model& model, Setup& s) {
  if (!model.jaw) {
    if (jaw) {
      throw ConfigError(scene_file, jaw->key,
                        "the model has no jaw (voxelize it with `rig: {jaw: true}` on a head with "
                        "a skull: docs/faces.md \"The jaw\")");
    }
    return;
  }
  const formats::Jaw& mj = *model.jaw;
  if (!jaw) {
    // The jaw closed: its nodes are held as the skull's are.
    std::vector<Index> rigid;
    std::set_union(s.rigid_nodes.begin(), s.rigid_nodes.end(), mj.nodes.begin(), mj.nodes.end(),
                   std::back_inserter(rigid));
    s.rigid_nodes = std::move(rigid);
    return;
  }
  const auto on_jaw = [&](const std::vector<Index>& nodes) {
    return std::count_if(nodes.begin(), nodes.end(), [&](Index nd) {
      return std::binary_search(mj.nodes.begin(), mj.nodes.end(), nd);
    });
  };
  const auto refuse = [&](std::size_t count, const std::string& what) {
    throw ConfigError(scene_file, jaw->key,
                      fmt::format("{} nodes of the jaw are also {}: a jaw node moves with the jaw "
                                  "only (remove them from that condition)",
                                  count, what));
  };
  if (const auto k = on_jaw(s.rigid_nodes)) refuse(std::size_t(k), "fixed by boundary_conditions");
  for (const auto& p : s.prescribed)
    if (const auto k = on_jaw(p.nodes)) refuse(std::size_t(k), "prescribed by " + p.label);
  for (const auto& p : s.sliding_planes)
    if (const auto k = on_jaw(p.nodes)) refuse(std::size_t(k), "held on a plane by " + p.label);

  JawMotion j;
  j.nodes = mj.nodes;
  j.pivot = mj.pivot;
  j.axis = mj.axis;
  j.forward = mj.forward;
  j.incisal = mj.incisal;
  j.opening = scaled(jaw->opening_deg, std::numbers::pi / 180.0);
  j.protrusion = scaled(jaw->protrusion_mm, 1e-3);
  j.lateral = scaled(jaw->lateral_mm, 1e-3);
  s.jaw = std::move(j);
}

double incisal_opening(const JawMotion& jaw, double t) {
  double map[physics::kJawMapSize];
  jaw.map(t, map);
  const Vec3<double> x{jaw.incisal[0], jaw.incisal[1], jaw.incisal[2]};
  const Vec3<double> u = physics::jaw_displacement(map, x);
  return std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
}

std::optional<LipContact> lip_contact_of(const formats::Model& model) {
  if (!model.jaw || model.jaw->lip_pairs.empty()) return std::nullopt;
  const auto& f = model.jaw->forward;
  const auto& a = model.jaw->axis;
  LipContact c;
  c.pairs = model.jaw->lip_pairs;
  c.up = {f[1] * a[2] - f[2] * a[1], f[2] * a[0] - f[0] * a[2], f[0] * a[1] - f[1] * a[0]};
  return c;
}

double smallest_lip_gap(const LipContact& contact, const formats::Model& model,
                        const std::vector<double>& u) {
  double gap = std::numeric_limits<double>::infinity();
  for (const auto& [upper, lower] : contact.pairs) {
    const auto pu = model.node_position(upper), pl = model.node_position(lower);
    double g = 0;
    for (std::size_t k = 0; k < 3; ++k)
      g += (pu[k] + u[3 * std::size_t(upper) + k] - pl[k] - u[3 * std::size_t(lower) + k]) *
           contact.up[k];
    gap = std::min(gap, g);
  }
  return gap;
}

double max_incisal_opening(const Setup& setup, double dt, std::int64_t steps) {
  if (!setup.jaw) return 0;
  const JawMotion& j = *setup.jaw;
  const double end = double(steps) * dt / setup.time_scaling;  // scene (curve) time
  std::vector<double> times;
  const int samples = 4096;
  for (int k = 0; k <= samples; ++k) times.push_back(end * k / samples);
  for (const Curve* c : {&j.opening, &j.protrusion, &j.lateral})
    for (const auto& p : c->points)
      if (p[0] <= end) times.push_back(p[0]);
  double most = 0;
  for (double t : times) most = std::max(most, incisal_opening(j, t));
  return most;
}

}  // namespace sinew::simulator
