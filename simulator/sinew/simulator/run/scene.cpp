#include "sinew/simulator/run/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::simulator {

namespace {

// The names the scene file uses, for reading and for writing (to_string and friends).
constexpr NameTable<Effect, 8> kEffectNames{{{"elasticity", Effect::elasticity},
                                             {"hourglass", Effect::hourglass},
                                             {"damping", Effect::damping},
                                             {"gravity", Effect::gravity},
                                             {"muscles", Effect::muscles},
                                             {"sliding", Effect::sliding},
                                             {"loads", Effect::loads},
                                             {"contact", Effect::contact}}};
constexpr NameTable<HourglassModulus, 2> kHourglassModulusNames{
    {{"shear", HourglassModulus::shear}, {"p_wave", HourglassModulus::p_wave}}};
constexpr NameTable<Precision, 2> kPrecisionNames{
    {{"float", Precision::float32}, {"double", Precision::float64}}};
constexpr NameTable<OutputField, 5> kOutputFieldNames{
    {{"displacement", OutputField::displacement},
     {"stress", OutputField::stress},
     {"J", OutputField::jacobian},
     {"energy_density", OutputField::energy_density},
     {"surfaces", OutputField::surfaces}}};

}  // namespace

const char* to_string(Effect effect) {
  return name_of(kEffectNames, effect);
}

const char* hourglass_modulus_name(HourglassModulus modulus) {
  return name_of(kHourglassModulusNames, modulus);
}

const char* precision_name(Precision precision) {
  return name_of(kPrecisionNames, precision);
}

const char* to_string(OutputField field) {
  return name_of(kOutputFieldNames, field);
}

bool SceneOutput::has(OutputField f) const {
  return std::find(fields.begin(), fields.end(), f) != fields.end();
}

bool Scene::has(Effect e) const {
  return std::find(effects.begin(), effects.end(), e) != effects.end();
}

namespace {

// A length, or a vector of lengths (or of velocities or accelerations), in the scene's units,
// returned in SI.
std::array<double, 3> length3(const YamlNode& c, const Scene& scene) {
  auto v = c.vec3();
  for (double& x : v) x *= scene.length_unit;
  return v;
}

std::array<double, 3> unit_vec3(const YamlNode& c) {
  auto v = c.vec3();
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(n > 0)) throw c.error("the normal must not be the zero vector");
  for (auto& x : v) x /= n;
  return v;
}

std::array<bool, 3> parse_components(const YamlNode& c) {
  std::array<bool, 3> out{false, false, false};
  const auto one = [&](const YamlNode& s) {
    const auto comp = s.choose(NameTable<int, 3>{{{"x", 0}, {"y", 1}, {"z", 2}}});
    if (out[static_cast<std::size_t>(comp)]) throw s.error("component listed twice");
    out[static_cast<std::size_t>(comp)] = true;
  };
  if (c.is_scalar()) {
    one(c);
  } else {
    const auto items = c.items();
    if (items.empty()) throw c.error("list at least one component (x, y, z)");
    for (const auto& item : items) one(item);
  }
  return out;
}

std::string check_name(const YamlNode& c, const std::string& s) {
  if (s.empty()) throw c.error("the name must not be empty");
  for (char ch : s) {
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.')) {
      throw c.error(fmt::format("name '{}' may only contain letters, digits, '_', '-' and '.'", s));
    }
  }
  return s;
}

std::string parse_name(const YamlNode& c) {
  return check_name(c, c.text());
}

void parse_time_step(const YamlNode& c, Scene& scene) {
  auto& ts = scene.time_step;
  if (c.is_scalar()) {
    if (c.text() == "auto") return;
    ts.automatic = false;
    ts.value = c.positive();
    return;
  }
  c.allow_keys({"mode", "safety_factor", "value", "force"});
  const bool automatic =
      c.has("mode") ? c.child("mode").choose(NameTable<bool, 2>{{{"auto", true}, {"fixed", false}}})
                    : !c.has("value");
  if (c.has("safety_factor")) {
    ts.safety_factor = c.child("safety_factor").positive();
    if (*ts.safety_factor > 1) throw c.child("safety_factor").error("must be in (0, 1]");
  }
  if (automatic) {
    if (c.has("value")) throw c.child("value").error("'value' needs mode: fixed");
    if (c.has("force")) throw c.child("force").error("'force' only applies to mode: fixed");
  } else {
    if (!c.has("value")) throw c.error("mode: fixed needs 'value' (s)");
    ts.automatic = false;
    ts.value = c.child("value").positive();
    if (c.has("force")) ts.force = c.child("force").boolean();
  }
}

void parse_node_sets(const YamlNode& c, Scene& scene) {
  for (const auto& name : c.keys()) {
    const auto s = c.child(name);
    SceneNodeSet set;
    set.name = check_name(s, name);
    if (set.name == "all")
      throw s.error("'all' is the built-in set of every node; choose another name");
    set.key = s.path();
    s.allow_keys({"model", "box", "plane", "nodes", "tolerance"});
    int kinds = 0;
    for (const auto* k : {"model", "box", "plane", "nodes"}) kinds += s.has(k) ? 1 : 0;
    if (kinds != 1) throw s.error("define the set by exactly one of: model, box, plane, nodes");
    if (s.has("tolerance") && !s.has("plane"))
      throw s.child("tolerance").error("'tolerance' only applies to a plane");
    if (s.has("model")) {
      set.kind = SceneNodeSet::Kind::model;
      set.model_set = s.child("model").text();
    } else if (s.has("box")) {
      set.kind = SceneNodeSet::Kind::box;
      const auto b = s.child("box");
      b.allow_keys({"min", "max"});
      if (!b.has("min") || !b.has("max"))
        throw b.error("a box needs 'min' and 'max' corners (lengths in the scene's units)");
      set.min = length3(b.child("min"), scene);
      set.max = length3(b.child("max"), scene);
      for (int i = 0; i < 3; ++i) {
        if (set.min[static_cast<std::size_t>(i)] > set.max[static_cast<std::size_t>(i)]) {
          throw b.child("max").error(fmt::format("max is below min along {}", "xyz"[i]));
        }
      }
    } else if (s.has("plane")) {
      set.kind = SceneNodeSet::Kind::plane;
      const auto p = s.child("plane");
      p.allow_keys({"point", "normal"});
      if (!p.has("point") || !p.has("normal"))
        throw p.error("a plane needs 'point' (a length in the scene's units) and 'normal'");
      set.point = length3(p.child("point"), scene);
      set.normal = unit_vec3(p.child("normal"));
      if (s.has("tolerance")) set.tolerance = s.child("tolerance").positive() * scene.length_unit;
    } else {
      set.kind = SceneNodeSet::Kind::nodes;
      const auto n = s.child("nodes");
      const auto items = n.items();
      if (items.empty()) throw n.error("list at least one node id");
      for (const auto& item : items) {
        const auto id = item.integer();
        if (id < 0) throw item.error("node ids are >= 0");
        set.ids.push_back(id);
      }
    }
    scene.node_sets.push_back(std::move(set));
  }
}

void parse_boundary(const YamlNode& c, Scene& scene) {
  for (const auto& b : c.items()) {
    b.expect_map();
    if (!b.has("type"))
      throw b.error("each boundary condition needs 'type' (fixed, plane, displacement, force)");
    SceneBoundary bc;
    bc.key = b.path();
    bc.kind = b.child("type").choose(
        NameTable<SceneBoundary::Kind, 4>{{{"fixed", SceneBoundary::Kind::fixed},
                                           {"plane", SceneBoundary::Kind::plane},
                                           {"displacement", SceneBoundary::Kind::displacement},
                                           {"force", SceneBoundary::Kind::force}}});
    switch (bc.kind) {
      case SceneBoundary::Kind::fixed:
        b.allow_keys({"type", "set", "components"});
        break;
      case SceneBoundary::Kind::plane:
        b.allow_keys({"type", "set", "normal"});
        break;
      case SceneBoundary::Kind::displacement:
        b.allow_keys({"type", "set", "components", "value", "curve"});
        break;
      case SceneBoundary::Kind::force:
        b.allow_keys({"type", "set", "value", "per_node", "curve"});
        break;
    }
    if (!b.has("set")) throw b.error("needs 'set' (a node set name, or 'all')");
    bc.set = b.child("set").text();
    if (b.has("components")) bc.components = parse_components(b.child("components"));
    if (bc.kind == SceneBoundary::Kind::plane) {
      if (!b.has("normal")) throw b.error("a plane condition needs 'normal'");
      bc.normal = unit_vec3(b.child("normal"));
    }
    if (bc.kind == SceneBoundary::Kind::displacement || bc.kind == SceneBoundary::Kind::force) {
      if (!b.has("value"))
        throw b.error(bc.kind == SceneBoundary::Kind::force
                          ? "needs 'value' [fx, fy, fz] (N)"
                          : "needs 'value' [ux, uy, uz] (lengths in the scene's units)");
      // A displacement is a length; a force stays in N.
      bc.value = bc.kind == SceneBoundary::Kind::force ? b.child("value").vec3()
                                                       : length3(b.child("value"), scene);
      if (b.has("curve")) bc.curve = parse_curve(b.child("curve"));
      if (!scene.has(Effect::loads)) {
        throw b.error("prescribed displacements and forces need the 'loads' effect in 'effects'");
      }
    }
    if (b.has("per_node")) bc.per_node = b.child("per_node").boolean();
    scene.boundary.push_back(std::move(bc));
  }
}

void parse_initial_velocity(const YamlNode& c, Scene& scene) {
  if (c.is_sequence() && c.size() == 3 && c.item(0).is_scalar()) {
    scene.initial_velocity.push_back({"all", length3(c, scene), c.path()});
    return;
  }
  for (const auto& v : c.items()) {
    v.allow_keys({"set", "value"});
    if (!v.has("set") || !v.has("value"))
      throw v.error("needs 'set' and 'value' [vx, vy, vz] (m/s)");
    scene.initial_velocity.push_back(
        {v.child("set").text(), length3(v.child("value"), scene), v.path()});
  }
}

void parse_output(const YamlNode& c, Scene& scene) {
  c.allow_keys({"interval", "fields", "probe_interval"});
  auto& out = scene.output;
  if (c.has("interval")) out.interval = c.child("interval").non_negative();
  if (c.has("probe_interval")) out.probe_interval = c.child("probe_interval").positive();
  if (c.has("fields")) {
    const auto f = c.child("fields");
    out.fields = {OutputField::displacement};
    for (const auto& item : f.items()) {
      const auto field = item.choose(kOutputFieldNames);
      if (field == OutputField::displacement) continue;
      if (out.has(field)) throw item.error("field listed twice");
      out.fields.push_back(field);
    }
  }
}

void parse_probes(const YamlNode& c, Scene& scene) {
  std::set<std::string> names;
  for (const auto& p : c.items()) {
    p.expect_map();
    SceneProbe probe;
    probe.key = p.path();
    if (!p.has("name")) throw p.error("each probe needs a 'name' (it names the CSV file)");
    if (!p.has("type")) throw p.error("each probe needs 'type' (displacement or reaction)");
    probe.name = parse_name(p.child("name"));
    if (!names.insert(probe.name).second)
      throw p.child("name").error(fmt::format("probe name '{}' used twice", probe.name));
    probe.kind = p.child("type").choose(
        NameTable<SceneProbe::Kind, 2>{{{"displacement", SceneProbe::Kind::displacement},
                                        {"reaction", SceneProbe::Kind::reaction}}});
    if (probe.kind == SceneProbe::Kind::displacement) {
      p.allow_keys({"name", "type", "node", "point"});
      if (p.has("node") == p.has("point"))
        throw p.error("a displacement probe needs exactly one of 'node' or 'point'");
      if (p.has("node")) {
        probe.node = p.child("node").integer();
        if (*probe.node < 0) throw p.child("node").error("node ids are >= 0");
      } else {
        probe.point = length3(p.child("point"), scene);
      }
    } else {
      p.allow_keys({"name", "type", "set"});
      if (!p.has("set")) throw p.error("a reaction probe needs 'set' (a node set name)");
      probe.set = p.child("set").text();
    }
    scene.probes.push_back(std::move(probe));
  }
}

}  // namespace

Scene parse_scene_text(const std::string& text, const std::string& file,
                       const std::string& directory) {
  Scene scene;
  scene.file = file;
  scene.directory = directory;
  const YamlNode c = parse_yaml(text, file);
  if (!c.is_map())
    throw ConfigError(file, "", "a scene is a mapping of keys (model:, effects:, duration:, ...)");
  c.allow_keys({"title", "units", "model", "effects", "duration", "time_step", "damping",
                "mass_scaling", "time_scaling", "hourglass", "precision", "gravity", "muscles",
                "node_sets", "boundary_conditions", "initial_velocity", "output", "probes", "jaw"});

  if (c.has("title")) scene.title = c.child("title").text();
  if (c.has("units")) {
    scene.length_unit = c.child("units").choose(
        NameTable<double, 3>{{{"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}}}, "units");
  }
  if (!c.has("model"))
    throw ConfigError(file, "model", "missing: the model file (path relative to the scene file)");
  scene.model = c.child("model").text();
  if (scene.model.empty()) throw c.child("model").error("the model path must not be empty");
  {
    const std::filesystem::path p(scene.model);
    scene.model_path = p.is_absolute() || directory.empty()
                           ? p.string()
                           : (std::filesystem::path(directory) / p).string();
  }

  if (!c.has("effects")) {
    throw ConfigError(file, "effects",
                      "missing: list the effects to simulate (elasticity, hourglass, damping, "
                      "gravity, muscles, sliding, loads, contact)");
  }
  {
    const auto e = c.child("effects");
    for (const auto& item : e.items()) {
      const auto effect = item.choose(kEffectNames);
      if (scene.has(effect))
        throw item.error(fmt::format("effect '{}' listed twice", to_string(effect)));
      scene.effects.push_back(effect);
    }
    if (!scene.has(Effect::elasticity)) {
      throw e.error("'elasticity' is required: without it the body has no stiffness");
    }
  }

  if (!c.has("duration")) throw ConfigError(file, "duration", "missing: the simulated time (s)");
  scene.duration = c.child("duration").number();
  if (!(scene.duration > 0))
    throw c.child("duration").error(fmt::format("must be > 0 s, got {}", scene.duration));

  if (c.has("time_step")) parse_time_step(c.child("time_step"), scene);

  if (c.has("damping")) {
    if (!scene.has(Effect::damping))
      throw c.child("damping").error("'damping' is given but 'damping' is not in effects");
    scene.damping = c.child("damping").positive();
  } else if (scene.has(Effect::damping)) {
    throw ConfigError(
        file, "damping",
        "missing: the effect 'damping' needs the mass-proportional coefficient α (1/s)");
  }
  if (c.has("mass_scaling")) {
    scene.mass_scaling = c.child("mass_scaling").number();
    if (!(scene.mass_scaling >= 1))
      throw c.child("mass_scaling").error(fmt::format("must be >= 1, got {}", scene.mass_scaling));
  }
  if (c.has("time_scaling")) {
    scene.time_scaling = c.child("time_scaling").number();
    if (!(scene.time_scaling >= 1))
      throw c.child("time_scaling").error(fmt::format("must be >= 1, got {}", scene.time_scaling));
  }
  if (c.has("hourglass")) {
    const auto h = c.child("hourglass");
    if (!scene.has(Effect::hourglass))
      throw h.error("'hourglass' is given but 'hourglass' is not in effects");
    h.allow_keys({"kappa", "modulus"});
    if (h.has("kappa")) scene.hourglass.kappa = h.child("kappa").positive();
    if (h.has("modulus"))
      scene.hourglass.modulus = h.child("modulus").choose(kHourglassModulusNames);
  }
  if (c.has("precision")) {
    scene.precision = c.child("precision").choose(kPrecisionNames);
  }
  if (c.has("gravity")) {
    if (!scene.has(Effect::gravity))
      throw c.child("gravity").error("'gravity' is given but 'gravity' is not in effects");
    scene.gravity = length3(c.child("gravity"), scene);
  }
  if (c.has("muscles")) {
    const auto m = c.child("muscles");
    if (!scene.has(Effect::muscles))
      throw m.error("activation curves are given but 'muscles' is not in effects");
    for (const auto& name : m.keys()) {
      const auto a = m.child(name);
      SceneActivation act;
      act.muscle = name;
      act.key = a.path();
      act.curve = parse_curve(a);
      for (std::size_t i = 0; i < act.curve.curve.points.size(); ++i) {
        const double v = act.curve.curve.points[i][1];
        if (!(v >= 0 && v <= 1))
          throw a.error(fmt::format("activation must lie in [0, 1]; point {} has {}", i, v));
      }
      scene.activations.push_back(std::move(act));
    }
  }
  if (c.has("node_sets")) parse_node_sets(c.child("node_sets"), scene);
  if (c.has("boundary_conditions")) parse_boundary(c.child("boundary_conditions"), scene);
  if (c.has("initial_velocity")) parse_initial_velocity(c.child("initial_velocity"), scene);
  if (c.has("output")) parse_output(c.child("output"), scene);
  if (c.has("probes")) parse_probes(c.child("probes"), scene);
  if (c.has("jaw")) scene.jaw = parse_scene_jaw(c.child("jaw"));
  return scene;
}

Scene parse_scene(const std::string& path) {
  const auto text = read_text_file(path, "scene file");
  return parse_scene_text(text, path, std::filesystem::path(path).parent_path().string());
}

}  // namespace sinew::simulator

// ---- resolution against a model ----

namespace sinew::simulator {

namespace {

std::string set_names(const Scene& scene, const formats::Model& model) {
  std::string s = "all";
  for (const auto& set : scene.node_sets) s += ", " + set.name;
  for (const auto& set : model.node_sets) s += ", " + set.name;
  return s;
}

std::vector<Index> select_nodes(const Scene& scene, const formats::Model& model,
                                const SceneNodeSet& set) {
  std::vector<Index> ids;
  const auto n = static_cast<Index>(model.node_count());
  const double h = model.grid.voxel_size;
  switch (set.kind) {
    case SceneNodeSet::Kind::model: {
      const auto it =
          std::find_if(model.node_sets.begin(), model.node_sets.end(),
                       [&](const formats::NamedSet& s) { return s.name == set.model_set; });
      if (it == model.node_sets.end()) {
        std::string known;
        for (const auto& s : model.node_sets) known += (known.empty() ? "" : ", ") + s.name;
        throw ConfigError(scene.file, set.key + ".model",
                          fmt::format("the model has no node set '{}' (it has: {})", set.model_set,
                                      known.empty() ? "none" : known));
      }
      ids = it->ids;
      break;
    }
    case SceneNodeSet::Kind::box: {
      // A node on the box's face belongs to it: rest positions carry round-off of origin + h·i.
      const double eps = 1e-6 * h;
      for (Index i = 0; i < n; ++i) {
        const auto p = model.node_position(i);
        bool inside = true;
        for (std::size_t k = 0; k < 3; ++k)
          inside = inside && p[k] >= set.min[k] - eps && p[k] <= set.max[k] + eps;
        if (inside) ids.push_back(i);
      }
      break;
    }
    case SceneNodeSet::Kind::plane: {
      const double tol = set.tolerance ? *set.tolerance : 1e-3 * h;
      for (Index i = 0; i < n; ++i) {
        const auto p = model.node_position(i);
        double d = 0;
        for (std::size_t k = 0; k < 3; ++k) d += (p[k] - set.point[k]) * set.normal[k];
        if (std::abs(d) <= tol) ids.push_back(i);
      }
      break;
    }
    case SceneNodeSet::Kind::nodes: {
      for (std::size_t k = 0; k < set.ids.size(); ++k) {
        if (set.ids[k] >= n) {
          throw ConfigError(
              scene.file, fmt::format("{}.nodes[{}]", set.key, k),
              fmt::format("node id {} out of range: the model has {} nodes", set.ids[k], n));
        }
        ids.push_back(static_cast<Index>(set.ids[k]));
      }
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      break;
    }
  }
  if (ids.empty()) {
    throw ConfigError(scene.file, set.key,
                      fmt::format("node set '{}' selects no node of the model", set.name));
  }
  return ids;
}

Index nearest_node(const formats::Model& model, const std::array<double, 3>& point,
                   double& distance) {
  Index best = -1;
  double best_d2 = 0;
  for (Index i = 0; i < static_cast<Index>(model.node_count()); ++i) {
    const auto p = model.node_position(i);
    const double d2 = (p[0] - point[0]) * (p[0] - point[0]) +
                      (p[1] - point[1]) * (p[1] - point[1]) + (p[2] - point[2]) * (p[2] - point[2]);
    if (best < 0 || d2 < best_d2) {
      best = i;
      best_d2 = d2;
    }
  }
  distance = std::sqrt(best_d2);
  return best;
}

}  // namespace

std::vector<Index> resolve_node_set(const Scene& scene, const formats::Model& model,
                                    const std::string& name, const std::string& key) {
  if (name == "all") {
    std::vector<Index> ids(model.node_count());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<Index>(i);
    return ids;
  }
  for (const auto& set : scene.node_sets) {
    if (set.name == name) return select_nodes(scene, model, set);
  }
  for (const auto& set : model.node_sets) {
    if (set.name == name) {
      if (set.ids.empty())
        throw ConfigError(scene.file, key, fmt::format("the model's node set '{}' is empty", name));
      return set.ids;
    }
  }
  throw ConfigError(
      scene.file, key,
      fmt::format("unknown node set '{}' (known: {})", name, set_names(scene, model)));
}

namespace {

// The model's sliding bindings and muscles that the scene's effects leave out (ResolvedScene::
// left_out). Rigid nodes need no entry: they are always held.
std::vector<std::string> left_out_effects(const Scene& scene, const formats::Model& model) {
  std::vector<std::string> notes;
  if (!scene.has(Effect::sliding) && !model.sliding.empty()) {
    std::vector<std::string> surfaces;
    for (const auto& b : model.sliding) {
      const auto& name = model.surfaces.at(static_cast<std::size_t>(b.surface)).name;
      if (std::find(surfaces.begin(), surfaces.end(), name) == surfaces.end())
        surfaces.push_back(name);
    }
    notes.push_back(fmt::format(
        "the model binds {} nodes to the sliding surface{} '{}', but the scene's effects leave "
        "out 'sliding': those nodes move freely instead of gliding (add sliding to effects)",
        model.sliding.size(), surfaces.size() == 1 ? "" : "s", fmt::join(surfaces, "', '")));
  }
  if (!scene.has(Effect::contact) && model.jaw && !model.jaw->lip_pairs.empty()) {
    notes.push_back(fmt::format(
        "the model has {} contact pairs across the cut between the lips, but the scene's effects "
        "leave out 'contact': the lips can pass through each other (add contact to effects)",
        model.jaw->lip_pairs.size()));
  }
  if (!scene.has(Effect::muscles) && !model.muscles.empty()) {
    notes.push_back(fmt::format(
        "the model has {} muscle{}, but the scene's effects leave out 'muscles': their fibres add "
        "no stress, active or passive (add muscles to effects)",
        model.muscles.size(), model.muscles.size() == 1 ? "" : "s"));
  }
  return notes;
}

}  // namespace

ResolvedScene resolve_scene(const Scene& scene, const formats::Model& model,
                            const ResolveOptions& options) {
  if (model.node_count() == 0 || model.element_count() == 0) {
    throw ConfigError(scene.file, "model",
                      fmt::format("the model '{}' has no elements", scene.model_path));
  }
  for (const auto& set : scene.node_sets) {
    for (const auto& m : model.node_sets) {
      if (m.name == set.name) {
        throw ConfigError(
            scene.file, set.key,
            fmt::format("the model already has a node set '{}'; give the scene's set another name",
                        set.name));
      }
    }
  }
  ResolvedScene out;
  auto& s = out.setup;
  s.effects.elasticity = scene.has(Effect::elasticity);
  s.effects.hourglass = scene.has(Effect::hourglass);
  s.effects.damping = scene.has(Effect::damping);
  s.effects.gravity = scene.has(Effect::gravity);
  s.effects.muscles = scene.has(Effect::muscles);
  s.effects.sliding = scene.has(Effect::sliding);
  s.effects.loads = scene.has(Effect::loads);
  s.effects.contact = scene.has(Effect::contact);
  for (const auto e : scene.effects) out.effects.push_back(to_string(e));

  if (s.effects.sliding && model.sliding.empty()) {
    throw ConfigError(scene.file, "effects",
                      "'sliding' is listed but the model has no sliding nodes (remove it from "
                      "effects, or give the model's spec a sliding condition: docs/voxelizer.md)");
  }
  if (s.effects.muscles && model.muscles.empty()) {
    throw ConfigError(scene.file, "effects", "'muscles' is listed but the model has no muscles");
  }
  if (s.effects.contact && !(model.jaw && !model.jaw->lip_pairs.empty())) {
    throw ConfigError(scene.file, "effects",
                      "'contact' is listed but the model has no contact pairs (the lips' pairs "
                      "come with the jaw: voxelize the head with `rig: {jaw: true}`, "
                      "docs/faces.md \"Lips and teeth\")");
  }
  if (s.effects.contact) s.lip_contact = lip_contact_of(model);
  out.left_out = left_out_effects(scene, model);

  s.precision = options.precision ? *options.precision : scene.precision;
  s.threads = options.threads;
  s.time_scaling = scene.time_scaling;
  s.duration = scene.duration * scene.time_scaling;
  if (scene.time_step.automatic) {
    s.time_step.policy = TimeStepPolicy::automatic;
  } else {
    s.time_step.policy = scene.time_step.force ? TimeStepPolicy::forced : TimeStepPolicy::user;
    s.time_step.user_dt = scene.time_step.value;
  }
  if (scene.time_step.safety_factor) s.time_step.safety_factor = *scene.time_step.safety_factor;
  s.damping_alpha = s.effects.damping ? scene.damping : 0.0;
  s.mass_scaling = scene.mass_scaling;
  s.hourglass = scene.hourglass;
  s.gravity = scene.gravity;

  // Activation curves, indexed like the model's muscles.
  s.activation.assign(s.effects.muscles ? model.muscles.size() : 0, Curve::constant(0.0));
  for (const auto& act : scene.activations) {
    const auto it = std::find_if(model.muscles.begin(), model.muscles.end(),
                                 [&](const formats::Muscle& m) { return m.name == act.muscle; });
    if (it == model.muscles.end()) {
      std::string known;
      for (const auto& m : model.muscles) known += (known.empty() ? "" : ", ") + m.name;
      throw ConfigError(scene.file, act.key,
                        fmt::format("unknown muscle '{}' (the model has: {})", act.muscle,
                                    known.empty() ? "none" : known));
    }
    s.activation[static_cast<std::size_t>(it - model.muscles.begin())] = act.curve.curve;
  }

  // Rigid nodes: the model's, plus every node fixed in all three components.
  std::vector<Index> rigid = model.rigid_nodes;
  for (const auto& bc : scene.boundary) {
    const auto nodes = resolve_node_set(scene, model, bc.set, bc.key + ".set");
    const auto label = [&](const char* what) {
      return fmt::format("{} ({} of set '{}')", bc.key, what, bc.set);
    };
    switch (bc.kind) {
      case SceneBoundary::Kind::fixed:
        if (bc.components[0] && bc.components[1] && bc.components[2]) {
          rigid.insert(rigid.end(), nodes.begin(), nodes.end());
        } else {
          // Holding one component at zero is a symmetry plane along that axis; the engine honours
          // planes with or without the loads effect.
          for (std::size_t k = 0; k < 3; ++k) {
            if (!bc.components[k]) continue;
            SlidingPlane plane;
            plane.nodes = nodes;
            plane.normal = {0, 0, 0};
            plane.normal[k] = 1;
            plane.label = label("fixed component");
            s.sliding_planes.push_back(std::move(plane));
          }
        }
        break;
      case SceneBoundary::Kind::plane:
        s.sliding_planes.push_back({nodes, bc.normal, label("plane")});
        break;
      case SceneBoundary::Kind::displacement: {
        PrescribedDisplacement p;
        p.nodes = nodes;
        p.components = bc.components;
        p.value = bc.value;
        if (bc.curve) p.curve = bc.curve->curve;
        p.label = label("displacement");
        s.prescribed.push_back(std::move(p));
        break;
      }
      case SceneBoundary::Kind::force: {
        NodalForce f;
        f.nodes = nodes;
        const double n = bc.per_node ? static_cast<double>(nodes.size()) : 1.0;
        f.total = {bc.value[0] * n, bc.value[1] * n, bc.value[2] * n};
        if (bc.curve) f.curve = bc.curve->curve;
        f.label = label("force");
        s.forces.push_back(std::move(f));
        break;
      }
    }
  }
  std::sort(rigid.begin(), rigid.end());
  rigid.erase(std::unique(rigid.begin(), rigid.end()), rigid.end());
  s.rigid_nodes = std::move(rigid);
  resolve_scene_jaw(scene.jaw, scene.file, model, s);

  for (const auto& v : scene.initial_velocity) {
    s.initial_velocities.push_back(
        {resolve_node_set(scene, model, v.set, v.key + ".set"), v.value});
  }

  out.output_interval = scene.output.interval;
  out.probe_interval = scene.output.probe_interval ? *scene.output.probe_interval : 0.0;
  out.fields = scene.output.fields;
  s.output_interval = scene.output.interval * scene.time_scaling;
  if (scene.output.has(OutputField::surfaces)) {
    const bool any = std::any_of(
        model.surfaces.begin(), model.surfaces.end(),
        [](const formats::Surface& f) { return f.role == formats::SurfaceRole::visual; });
    if (!any)
      throw ConfigError(scene.file, "output.fields",
                        "'surfaces' is requested but the model has no visual surface");
  }

  for (const auto& p : scene.probes) {
    ResolvedProbe r;
    r.kind = p.kind;
    r.name = p.name;
    if (p.kind == SceneProbe::Kind::reaction) {
      r.nodes = resolve_node_set(scene, model, p.set, p.key + ".set");
      r.description =
          fmt::format("reaction force on node set '{}' ({} nodes)", p.set, r.nodes.size());
    } else if (p.node) {
      if (*p.node >= static_cast<std::int64_t>(model.node_count())) {
        throw ConfigError(scene.file, p.key + ".node",
                          fmt::format("node id {} out of range: the model has {} nodes", *p.node,
                                      model.node_count()));
      }
      r.nodes = {static_cast<Index>(*p.node)};
      r.description = fmt::format("displacement of node {}", *p.node);
    } else {
      const auto node = nearest_node(model, *p.point, r.distance);
      r.nodes = {node};
      const auto& q = *p.point;
      r.description =
          fmt::format("displacement of node {} (nearest to [{}, {}, {}], {:.6g} m away)", node,
                      q[0], q[1], q[2], r.distance);
    }
    out.probes.push_back(std::move(r));
  }
  return out;
}

}  // namespace sinew::simulator
