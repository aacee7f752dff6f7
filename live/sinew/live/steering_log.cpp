#include "sinew/live/steering_log.hpp"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/yaml_reader.hpp"
#include "sinew/simulator/engine/backend_core.hpp"

namespace sinew::live {

using nlohmann::json;

namespace {

// Curve time of step n: exactly what BackendCore::curve_time(time(n)) computes.
double knot_time(std::int64_t n, double dt, double s) {
  return (double(n) * dt) / s;
}

// The value BackendCore gives a muscle on its scene curve at step n (before T(·)).
double curve_value(const simulator::Curve& c, double t) {
  return simulator::BackendCore::clamped_activation(c, t);
}

// Appends knots so that steps [a, b] evaluate exactly as `c` does. first: nothing before step a
// is in the curve yet (a == 0); last: no knot follows (the curve holds to the end).
void add_original(std::vector<std::array<double, 2>>& k, const simulator::Curve& c, std::int64_t a,
                  std::int64_t b, double dt, double s, bool first, bool last) {
  const double ta = knot_time(a, dt, s), tb = knot_time(b, dt, s);
  if (c.points.empty()) {  // activation 0 throughout
    k.push_back({ta, 0.0});
    if (b > a) k.push_back({tb, 0.0});
    return;
  }
  const auto& p = c.points;
  // Original knots strictly inside (ta, tb), and the steps before the first and after the last
  // of them, which lie on cut segments.
  std::size_t lo = std::size_t(
      std::upper_bound(p.begin(), p.end(), ta, [](double x, const auto& q) { return x < q[0]; }) -
      p.begin());
  std::size_t hi = std::size_t(
      std::lower_bound(p.begin(), p.end(), tb, [](const auto& q, double x) { return q[0] < x; }) -
      p.begin());
  // Steps [from, to] that all lie on original segment j (between points j − 1 and j; j = 0 the
  // hold before the first point, j = size the hold after the last): a knot per step unless the
  // segment is flat (then its value is every step's, and two knots give it exactly).
  const auto steps_on_segment = [&](std::int64_t from, std::int64_t to, std::size_t j) {
    if (from > to) return;
    const bool flat = j == 0 || j >= p.size() || p[j - 1][1] == p[j][1];
    if (flat) {
      k.push_back({knot_time(from, dt, s), curve_value(c, knot_time(from, dt, s))});
      if (to > from) k.push_back({knot_time(to, dt, s), curve_value(c, knot_time(to, dt, s))});
      return;
    }
    for (std::int64_t n = from; n <= to; ++n)
      k.push_back({knot_time(n, dt, s), curve_value(c, knot_time(n, dt, s))});
  };
  // The last step before original knot q (steps are at knot_time(n)).
  const auto last_step_before = [&](double t) {
    std::int64_t n = std::int64_t(std::floor(t * s / dt));
    while (n >= a && knot_time(n, dt, s) >= t) --n;
    while (knot_time(n + 1, dt, s) < t) ++n;
    return n;
  };
  const auto first_step_after = [&](double t) {
    std::int64_t n = last_step_before(t) + 1;
    while (knot_time(n, dt, s) <= t) ++n;
    return n;
  };
  if (lo >= hi) {  // no original knot inside: one cut segment (or a hold)
    if (first && last) {
      k.insert(k.end(), p.begin(), p.end());
      return;
    }
    steps_on_segment(a, b, lo);
    return;
  }
  if (first) {
    k.insert(k.end(), p.begin(), p.begin() + std::ptrdiff_t(lo));
  } else {
    steps_on_segment(a, std::min(b, last_step_before(p[lo][0])), lo);
  }
  k.insert(k.end(), p.begin() + std::ptrdiff_t(lo), p.begin() + std::ptrdiff_t(hi));
  if (last) {
    k.insert(k.end(), p.begin() + std::ptrdiff_t(hi), p.end());
  } else {
    steps_on_segment(std::max(a, first_step_after(p[hi - 1][0])), b, hi);
  }
}

}  // namespace

std::vector<std::array<double, 2>> reproduce_activation(
    const simulator::Curve& original, const std::vector<ActivationChange>& changes, double dt,
    double s, std::int64_t end_step) {
  // Phases from their first step: the scene curve (phase 0), then each change: a ramp from the
  // value its step had to its target (or to the curve), as BackendCore sets and evaluates it.
  struct Phase {
    std::int64_t start;
    std::optional<double> target;
    double from;
  };
  const std::int64_t ramp = simulator::BackendCore::override_ramp_steps(dt);
  const auto curve_at = [&](std::int64_t n) { return curve_value(original, knot_time(n, dt, s)); };
  const auto value = [&](const Phase& p, std::int64_t n, bool scene) {
    if (scene) return curve_at(n);
    return simulator::BackendCore::ramped_activation(p.from, p.target ? *p.target : curve_at(n),
                                                     p.start, ramp, n);
  };
  std::vector<Phase> phases{{0, std::nullopt, 0.0}};
  for (const auto& c : changes) {
    if (c.step > end_step) break;
    const double from = value(phases.back(), c.step, phases.size() == 1);
    if (phases.size() > 1 && phases.back().start == c.step)
      phases.back().target =
          c.value;  // the later change of one step wins; its ramp starts the same
    else
      phases.push_back({c.step, c.value, from});
  }
  std::vector<std::array<double, 2>> k;
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const std::int64_t a = phases[i].start;
    const bool last = i + 1 == phases.size();
    const std::int64_t b = last ? end_step : phases[i + 1].start - 1;
    if (i == 0) {
      add_original(k, original, a, b, dt, s, true, last);
      continue;
    }
    // The ramp: a knot per step (each step's value exactly); then the target held, or the curve.
    const std::int64_t ramp_end = std::min(b, a + ramp - 1);
    for (std::int64_t n = a; n <= ramp_end; ++n)
      k.push_back({knot_time(n, dt, s), value(phases[i], n, false)});
    if (ramp_end >= b) continue;
    if (phases[i].target) {
      const double v = *phases[i].target;
      k.push_back({knot_time(ramp_end + 1, dt, s), v});
      if (b > ramp_end + 1) k.push_back({knot_time(b, dt, s), v});
    } else {
      add_original(k, original, ramp_end + 1, b, dt, s, false, last);
    }
  }
  // Knots must increase strictly: an original knot may coincide with a step's knot.
  std::vector<std::array<double, 2>> out;
  for (const auto& q : k) {
    if (!out.empty() && !(q[0] > out.back()[0])) {
      if (q[0] == out.back()[0] && q[1] == out.back()[1]) continue;
      continue;  // earlier knots win: they were placed for the steps they cover
    }
    out.push_back(q);
  }
  return out;
}

namespace {

// A YAML scene as JSON: maps, lists, and scalars as numbers, booleans or strings.
json to_json(const YamlNode& n) {
  if (n.is_map()) {
    json o = json::object();
    for (const auto& key : n.keys()) o[key] = to_json(n.child(key));
    return o;
  }
  if (n.is_sequence()) {
    json a = json::array();
    for (const auto& item : n.items()) a.push_back(to_json(item));
    return a;
  }
  if (!n.defined()) return nullptr;
  const std::string t = n.text();
  if (t == "true" || t == "false") return t == "true";
  try {
    return n.number();
  } catch (const Error&) {
    return t;
  }
}

}  // namespace

std::string reproduce_scene(const simulator::Scene& scene, const std::string& scene_text,
                            const std::vector<simulator::Curve>& activation_curves,
                            const std::vector<std::string>& muscle_names, double dt, double s,
                            std::int64_t end_step, const SteeringLog& log) {
  json j = to_json(parse_yaml(scene_text, scene.file));
  j["model"] = std::filesystem::absolute(scene.model_path).lexically_normal().string();
  j["duration"] = knot_time(end_step, dt, s);
  // The live run's Δt (planned for activations up to 1, Setup::activation_overrides), fixed.
  json ts = {{"mode", "fixed"}, {"value", dt}};
  if (scene.time_step.safety_factor) ts["safety_factor"] = *scene.time_step.safety_factor;
  if (scene.time_step.force) ts["force"] = true;
  j["time_step"] = ts;
  j["title"] = fmt::format("{} (reproduced live session, {} steps)",
                           scene.title.empty() ? scene.file : scene.title, end_step);
  for (std::size_t m = 0; m < muscle_names.size(); ++m) {
    std::vector<ActivationChange> mine;
    for (const auto& c : log.activations)
      if (c.muscle == m) mine.push_back(c);
    if (mine.empty()) continue;
    const simulator::Curve original =
        m < activation_curves.size() ? activation_curves[m] : simulator::Curve{};
    json knots = json::array();
    for (const auto& q : reproduce_activation(original, mine, dt, s, end_step))
      knots.push_back({q[0], q[1]});
    j["muscles"][muscle_names[m]] = knots;
  }
  for (std::size_t d = 0; d < log.drags.size(); ++d) {
    const auto& g = log.drags[d];
    if (g.start >= end_step) continue;
    const std::string set = fmt::format("live_drag_{}", d);
    j["node_sets"][set] = {{"nodes", g.nodes}};
    json curve = json::array();
    if (g.start > 0) curve.push_back({knot_time(g.start - 1, dt, s), 0.0});
    curve.push_back({knot_time(g.start, dt, s), 1.0});
    if (g.end >= 0 && g.end <= end_step) {
      if (g.end - 1 > g.start) curve.push_back({knot_time(g.end - 1, dt, s), 1.0});
      curve.push_back({knot_time(g.end, dt, s), 0.0});
    }
    // The total, spread as the live slot spread it (prepare_model: total · (1 / n) per node).
    j["boundary_conditions"].push_back(
        {{"type", "force"}, {"set", set}, {"value", g.total}, {"curve", curve}});
  }
  return j.dump(1) + "\n";
}

std::string steering_log_json(const SteeringLog& log, double dt, double s, std::int64_t end_step) {
  json j;
  j["format"] = "sinew-live steering log";
  j["version"] = 1;
  j["dt"] = dt;
  j["time_scaling"] = s;
  j["end_step"] = end_step;
  json ev = json::array();
  for (const auto& [step, what] : log.events)
    ev.push_back({{"step", step}, {"time", knot_time(step, dt, s)}, {"event", what}});
  j["events"] = ev;
  json drags = json::array();
  for (const auto& g : log.drags)
    drags.push_back({{"start_step", g.start},
                     {"end_step", g.end},
                     {"nodes", g.nodes.size()},
                     {"force", g.total}});
  j["drags"] = drags;
  return j.dump(1) + "\n";
}

}  // namespace sinew::live
