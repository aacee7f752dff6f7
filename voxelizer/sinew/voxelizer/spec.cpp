#include "sinew/voxelizer/spec.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

namespace {

// Reading context: the file name for messages and the unit of lengths.
struct Reader {
  std::string file;
  std::filesystem::path folder;
  LengthUnit units = LengthUnit::m;

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw ConfigError(file, field, problem);
  }

  void check_keys(const YAML::Node& node, const std::string& field,
                  const std::set<std::string>& allowed) const {
    if (!node.IsMap()) fail(field, "expected a map");
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(join(field, key), "unknown key (allowed here: " + list + ")");
      }
    }
  }

  static std::string join(const std::string& field, const std::string& key) {
    return field.empty() ? key : field + "." + key;
  }
  static std::string at(const std::string& field, std::size_t i) {
    return field + "[" + std::to_string(i) + "]";
  }

  double number(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(field, "expected a number");
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(field, "expected a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(field, "must be finite, got '" + n.Scalar() + "'");
    return v;
  }
  double positive(const YAML::Node& n, const std::string& field) const {
    const double v = number(n, field);
    if (!(v > 0)) fail(field, "must be > 0, got " + n.Scalar());
    return v;
  }
  // A length in the spec's unit, returned in metres.
  double length(const YAML::Node& n, const std::string& field) const {
    return positive(n, field) * metres_per_unit(units);
  }
  std::int64_t integer(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(field, "expected an integer");
    try {
      return n.as<std::int64_t>();
    } catch (const YAML::Exception&) {
      fail(field, "expected an integer, got '" + n.Scalar() + "'");
    }
  }
  std::string text(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar() || n.Scalar().empty()) fail(field, "expected a non-empty string");
    return n.Scalar();
  }
  bool boolean(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(field, "expected true or false");
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(field, "expected true or false, got '" + n.Scalar() + "'");
    }
  }
  Vec3d vec3(const YAML::Node& n, const std::string& field, double scale = 1.0) const {
    if (!n.IsSequence() || n.size() != 3) fail(field, "expected a list of 3 numbers");
    return {number(n[0], at(field, 0)) * scale, number(n[1], at(field, 1)) * scale,
            number(n[2], at(field, 2)) * scale};
  }
  const YAML::Node sequence(const YAML::Node& n, const std::string& field) const {
    if (!n.IsSequence()) fail(field, "expected a list");
    return n;
  }

  Box box(const YAML::Node& n, const std::string& field) const {
    check_keys(n, field, {"min", "max"});
    if (!n["min"] || !n["max"]) fail(field, "a box needs both min and max");
    const double s = metres_per_unit(units);
    Box b{vec3(n["min"], join(field, "min"), s), vec3(n["max"], join(field, "max"), s)};
    if (!(b.lo.x < b.hi.x && b.lo.y < b.hi.y && b.lo.z < b.hi.z)) {
      fail(field, "min must be smaller than max in x, y and z");
    }
    return b;
  }

  MeshSource mesh(const YAML::Node& n, const std::string& field) const {
    MeshSource m;
    m.field = field;
    m.transform.unit = units;
    if (n.IsScalar()) {
      m.path = resolve(text(n, field));
      return m;
    }
    check_keys(n, field,
               {"path", "sphere", "ellipsoid", "box", "cylinder", "subdivisions", "unit", "scale",
                "rotate_deg", "translate"});
    int sources = 0;
    for (const char* k : {"path", "sphere", "ellipsoid", "box", "cylinder"})
      sources += n[k] ? 1 : 0;
    if (sources != 1) fail(field, "give exactly one of path, sphere, ellipsoid, box, cylinder");
    if (n["unit"]) m.transform.unit = parse_unit(n["unit"], join(field, "unit"));
    if (n["path"]) {
      m.path = resolve(text(n["path"], join(field, "path")));
    } else if (const auto s = n["sphere"]) {
      const std::string f = join(field, "sphere");
      check_keys(s, f, {"centre", "radius"});
      m.kind = MeshSource::Kind::sphere;
      if (s["centre"]) m.centre = vec3(s["centre"], join(f, "centre"));
      if (!s["radius"]) fail(f, "missing key 'radius'");
      const double r = positive(s["radius"], join(f, "radius"));
      m.radii = {r, r, r};
    } else if (const auto e = n["ellipsoid"]) {
      const std::string f = join(field, "ellipsoid");
      check_keys(e, f, {"centre", "radii"});
      m.kind = MeshSource::Kind::ellipsoid;
      if (e["centre"]) m.centre = vec3(e["centre"], join(f, "centre"));
      if (!e["radii"]) fail(f, "missing key 'radii'");
      m.radii = vec3(e["radii"], join(f, "radii"));
      if (!(m.radii.x > 0 && m.radii.y > 0 && m.radii.z > 0)) fail(f, "radii must be > 0");
    } else if (const auto b = n["box"]) {
      const std::string f = join(field, "box");
      check_keys(b, f, {"min", "max"});
      m.kind = MeshSource::Kind::box;
      if (!b["min"] || !b["max"]) fail(f, "a box needs both min and max");
      m.box_lo = vec3(b["min"], join(f, "min"));
      m.box_hi = vec3(b["max"], join(f, "max"));
      if (!(m.box_lo.x < m.box_hi.x && m.box_lo.y < m.box_hi.y && m.box_lo.z < m.box_hi.z)) {
        fail(f, "min must be smaller than max in x, y and z");
      }
    } else if (const auto c = n["cylinder"]) {
      const std::string f = join(field, "cylinder");
      check_keys(c, f, {"centre", "radius", "half_length"});
      m.kind = MeshSource::Kind::cylinder;
      if (c["centre"]) m.centre = vec3(c["centre"], join(f, "centre"));
      if (!c["radius"] || !c["half_length"]) fail(f, "needs radius and half_length");
      m.radii = {positive(c["radius"], join(f, "radius")),
                 positive(c["half_length"], join(f, "half_length")), 0};
    }
    if (n["subdivisions"]) {
      const auto s = integer(n["subdivisions"], join(field, "subdivisions"));
      if (s < 0 || s > 8) fail(join(field, "subdivisions"), "must be in [0, 8]");
      m.subdivisions = static_cast<int>(s);
    }
    if (n["scale"]) m.transform.scale = positive(n["scale"], join(field, "scale"));
    if (n["rotate_deg"]) m.transform.rotate_deg = vec3(n["rotate_deg"], join(field, "rotate_deg"));
    if (n["translate"]) {
      m.transform.translate =
          vec3(n["translate"], join(field, "translate"), metres_per_unit(m.transform.unit));
    }
    return m;
  }

  LengthUnit parse_unit(const YAML::Node& n, const std::string& field) const {
    const std::string u = text(n, field);
    if (u == "m") return LengthUnit::m;
    if (u == "cm") return LengthUnit::cm;
    if (u == "mm") return LengthUnit::mm;
    fail(field, "unknown unit '" + u + "' (known: m, cm, mm)");
  }

  std::filesystem::path resolve(const std::string& p) const {
    std::filesystem::path path(p);
    if (path.is_relative()) path = folder / path;
    return path.lexically_normal();
  }

  SurfaceRef surface(const YAML::Node& n, const std::string& field) const {
    SurfaceRef r;
    r.field = field;
    if (n.IsScalar()) {
      r.name = text(n, field);
    } else {
      r.mesh = mesh(n, field);
    }
    return r;
  }

  Selector selector(const YAML::Node& n, const std::string& field) const {
    check_keys(n, field, {"box", "surface", "distance"});
    Selector s;
    s.field = field;
    if (n["box"]) s.box = box(n["box"], join(field, "box"));
    if (n["surface"]) {
      s.surface = surface(n["surface"], join(field, "surface"));
      if (!n["distance"]) fail(field, "a surface selector needs a distance");
      s.distance = length(n["distance"], join(field, "distance"));
    } else if (n["distance"]) {
      fail(join(field, "distance"), "distance needs a surface");
    }
    if (!s.box && !s.surface) fail(field, "give a box, a surface with a distance, or both");
    return s;
  }
};

void check_surface_names(const Reader& r, const Spec& spec) {
  std::set<std::string> known{"outer"};
  if (spec.inner || spec.tissue_thickness) known.insert("inner");
  for (const auto& m : spec.muscles) known.insert(m.name);
  for (const auto& t : spec.tendons)
    if (t.mesh) known.insert(t.name);
  for (const auto& g : spec.regions)
    if (g.mesh) known.insert(g.name);
  auto check = [&](const SurfaceRef& ref) {
    if (ref.mesh || known.count(ref.name)) return;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    r.fail(ref.field, "unknown surface or muscle name '" + ref.name + "' (known: " + list + ")");
  };
  for (const auto& m : spec.muscles) {
    if (m.fibres.kind == FibreSpec::Kind::harmonic) {
      if (m.fibres.origin.surface) check(*m.fibres.origin.surface);
      if (m.fibres.insertion.surface) check(*m.fibres.insertion.surface);
    }
  }
  for (const auto& b : spec.boundary)
    if (b.has_surface) check(b.surface);
  for (const auto& s : spec.node_sets)
    if (s.select.surface) check(*s.select.surface);
  for (const auto& v : spec.visual) check(v.surface);
}

}  // namespace

std::string MeshSource::describe() const {
  std::ostringstream os;
  switch (kind) {
    case Kind::file:
      return path.string();
    case Kind::sphere:
      os << "sphere(r=" << radii.x << ")";
      break;
    case Kind::ellipsoid:
      os << "ellipsoid(" << radii.x << "," << radii.y << "," << radii.z << ")";
      break;
    case Kind::box:
      os << "box";
      break;
    case Kind::cylinder:
      os << "cylinder(r=" << radii.x << ",h=" << radii.y << ")";
      break;
  }
  return os.str();
}

std::vector<MaterialSpec> warburton2013_materials() {
  // Warburton & Maddock 2013, Table 1: E in MPa → Pa; ρ includes their mass scaling.
  return {{"stratum_corneum", 48e6, 0.49, 11000},
          {"dermis", 0.0814e6, 0.49, 11000},
          {"hypodermis", 0.034e6, 0.49, 11000},
          {"muscle", 0.5e6, 0.49, 11000},
          {"tendon", 24e6, 0.49, 11000}};
}

const MaterialSpec* Spec::find_material(const std::string& name) const {
  for (const auto& m : materials)
    if (m.name == name) return &m;
  return nullptr;
}

Spec read_spec(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path.string(), "", "cannot open the spec file");
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError(path.string(), "", "cannot read the spec file");
  return parse_spec(ss.str(), path);
}

Spec parse_spec(const std::string& yaml_text, const std::filesystem::path& file) {
  Reader r;
  r.file = file.string();
  r.folder = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(r.file, "", std::string("YAML syntax error: ") + e.what());
  }
  if (!root.IsMap()) r.fail("", "the spec must be a YAML map");
  r.check_keys(
      root, "",
      {"units", "output", "resolution", "weld_tolerance", "outer", "inner", "tissue_thickness",
       "layers", "materials", "muscles", "tendons", "regions", "boundary", "node_sets", "visual"});
  Spec spec;
  spec.file = file;
  if (root["units"]) r.units = r.parse_unit(root["units"], "units");
  spec.units = r.units;
  if (root["output"]) spec.output = r.resolve(r.text(root["output"], "output"));

  // Resolution.
  if (!root["resolution"]) r.fail("resolution", "missing (give voxel_size or target_elements)");
  {
    const auto n = root["resolution"];
    r.check_keys(n, "resolution",
                 {"voxel_size", "target_elements", "max_subdivision", "min_fraction"});
    if (n["voxel_size"]) spec.voxel_size = r.length(n["voxel_size"], "resolution.voxel_size");
    if (n["target_elements"]) {
      spec.target_elements = r.integer(n["target_elements"], "resolution.target_elements");
      if (*spec.target_elements < 1) r.fail("resolution.target_elements", "must be >= 1");
    }
    if (spec.voxel_size.has_value() == spec.target_elements.has_value()) {
      r.fail("resolution", "give exactly one of voxel_size and target_elements");
    }
    if (n["max_subdivision"]) {
      const auto l = r.integer(n["max_subdivision"], "resolution.max_subdivision");
      if (l < 0 || l > 6) r.fail("resolution.max_subdivision", "must be in [0, 6]");
      spec.max_subdivision = static_cast<int>(l);
    }
    if (n["min_fraction"]) {
      spec.min_fraction = r.number(n["min_fraction"], "resolution.min_fraction");
      if (spec.min_fraction < 0 || spec.min_fraction >= 1) {
        r.fail("resolution.min_fraction", "must be in [0, 1)");
      }
    }
  }
  if (root["weld_tolerance"]) {
    spec.weld_tolerance =
        r.number(root["weld_tolerance"], "weld_tolerance") * metres_per_unit(r.units);
    if (spec.weld_tolerance < 0) r.fail("weld_tolerance", "must be >= 0");
  }

  // Surfaces.
  if (!root["outer"]) r.fail("outer", "missing: the outer surface (skin) mesh");
  spec.outer = r.mesh(root["outer"], "outer");
  if (root["inner"]) spec.inner = r.mesh(root["inner"], "inner");
  if (root["tissue_thickness"]) {
    spec.tissue_thickness = r.length(root["tissue_thickness"], "tissue_thickness");
  }
  if (spec.inner && spec.tissue_thickness) {
    r.fail("tissue_thickness", "give either inner or tissue_thickness, not both");
  }

  // Materials.
  if (const auto n = root["materials"]) {
    r.check_keys(n, "materials", {"preset", "table"});
    if (n["preset"]) {
      const std::string p = r.text(n["preset"], "materials.preset");
      if (p != "warburton2013") {
        r.fail("materials.preset", "unknown preset '" + p + "' (known: warburton2013)");
      }
      spec.materials = warburton2013_materials();
    }
    if (const auto t = n["table"]) {
      if (!t.IsMap()) r.fail("materials.table", "expected a map of name: {...}");
      for (const auto& kv : t) {
        const std::string name = kv.first.as<std::string>();
        const std::string f = "materials.table." + name;
        r.check_keys(kv.second, f, {"youngs_modulus", "poisson_ratio", "density"});
        for (const char* k : {"youngs_modulus", "poisson_ratio", "density"}) {
          if (!kv.second[k]) r.fail(f, std::string("missing key '") + k + "'");
        }
        MaterialSpec m{name, r.positive(kv.second["youngs_modulus"], f + ".youngs_modulus"),
                       r.number(kv.second["poisson_ratio"], f + ".poisson_ratio"),
                       r.positive(kv.second["density"], f + ".density")};
        if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5)) {
          r.fail(f + ".poisson_ratio", "must be in (-1, 0.5)");
        }
        bool replaced = false;
        for (auto& old : spec.materials) {
          if (old.name == name) {
            old = m;  // a table entry overrides the preset's entry of that name
            replaced = true;
          }
        }
        if (!replaced) spec.materials.push_back(m);
      }
    }
  }
  auto need_material = [&](const std::string& name, const std::string& field) {
    if (spec.find_material(name)) return;
    std::string list;
    for (const auto& m : spec.materials) list += (list.empty() ? "" : ", ") + m.name;
    r.fail(field,
           "unknown material '" + name + "' (known: " + (list.empty() ? "none" : list) + ")");
  };

  // Layers.
  if (!root["layers"]) r.fail("layers", "missing: at least one layer with a material");
  {
    const auto n = r.sequence(root["layers"], "layers");
    if (n.size() == 0) r.fail("layers", "at least one layer is needed");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at("layers", i);
      r.check_keys(n[i], f, {"material", "thickness"});
      LayerSpec l;
      if (!n[i]["material"]) r.fail(f, "missing key 'material'");
      l.material = r.text(n[i]["material"], f + ".material");
      need_material(l.material, f + ".material");
      if (n[i]["thickness"]) {
        l.thickness = r.length(n[i]["thickness"], f + ".thickness");
      } else if (i + 1 != n.size()) {
        r.fail(f + ".thickness", "missing: only the last layer may omit it (the rest)");
      }
      spec.layers.push_back(l);
    }
  }

  // Muscles.
  if (const auto n = root["muscles"]) {
    r.sequence(n, "muscles");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at("muscles", i);
      const auto m = n[i];
      r.check_keys(
          m, f,
          {"name", "mesh", "material", "reference_stress", "optimal_stretch", "passive", "fibres"});
      for (const char* k : {"name", "mesh", "material", "fibres"}) {
        if (!m[k]) r.fail(f, std::string("missing key '") + k + "'");
      }
      MuscleSpec s;
      s.name = r.text(m["name"], f + ".name");
      s.mesh = r.mesh(m["mesh"], f + ".mesh");
      s.material = r.text(m["material"], f + ".material");
      need_material(s.material, f + ".material");
      if (m["reference_stress"]) {
        s.reference_stress = r.positive(m["reference_stress"], f + ".reference_stress");
      }
      if (m["optimal_stretch"]) {
        s.optimal_stretch = r.positive(m["optimal_stretch"], f + ".optimal_stretch");
      }
      if (const auto p = m["passive"]) {
        r.check_keys(p, f + ".passive", {"p1", "p2", "linear_stretch"});
        if (p["p1"]) s.passive_p1 = r.number(p["p1"], f + ".passive.p1");
        if (p["p2"]) s.passive_p2 = r.number(p["p2"], f + ".passive.p2");
        if (p["linear_stretch"]) {
          s.passive_linear_stretch = r.positive(p["linear_stretch"], f + ".passive.linear_stretch");
          if (s.passive_linear_stretch <= 1) r.fail(f + ".passive.linear_stretch", "must be > 1");
        }
      }
      const auto fb = m["fibres"];
      const std::string ff = f + ".fibres";
      r.check_keys(fb, ff, {"type", "direction", "origin", "insertion"});
      if (!fb["type"]) r.fail(ff, "missing key 'type' (constant or harmonic)");
      const std::string type = r.text(fb["type"], ff + ".type");
      if (type == "constant") {
        s.fibres.kind = FibreSpec::Kind::constant;
        if (!fb["direction"]) r.fail(ff, "a constant fibre field needs a direction");
        if (fb["origin"] || fb["insertion"]) r.fail(ff, "origin/insertion are for harmonic fibres");
        const Vec3d d = r.vec3(fb["direction"], ff + ".direction");
        const double len = norm(d);
        if (!(len > 0)) r.fail(ff + ".direction", "must not be zero");
        s.fibres.direction = (1.0 / len) * d;
      } else if (type == "harmonic") {
        s.fibres.kind = FibreSpec::Kind::harmonic;
        if (fb["direction"]) r.fail(ff + ".direction", "a harmonic fibre field has no direction");
        if (!fb["origin"] || !fb["insertion"]) {
          r.fail(ff, "a harmonic fibre field needs origin and insertion");
        }
        s.fibres.origin = r.selector(fb["origin"], ff + ".origin");
        s.fibres.insertion = r.selector(fb["insertion"], ff + ".insertion");
      } else {
        r.fail(ff + ".type", "unknown fibre type '" + type + "' (known: constant, harmonic)");
      }
      for (const auto& other : spec.muscles) {
        if (other.name == s.name) r.fail(f + ".name", "duplicate muscle name '" + s.name + "'");
      }
      spec.muscles.push_back(std::move(s));
    }
  }

  auto read_regions = [&](const char* key, bool allow_box, std::vector<RegionSpec>& out) {
    const auto n = root[key];
    if (!n) return;
    r.sequence(n, key);
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at(key, i);
      if (allow_box) {
        r.check_keys(n[i], f, {"name", "mesh", "box", "material"});
      } else {
        r.check_keys(n[i], f, {"name", "mesh", "material"});
      }
      RegionSpec g;
      if (!n[i]["name"] || !n[i]["material"]) r.fail(f, "needs a name and a material");
      g.name = r.text(n[i]["name"], f + ".name");
      g.material = r.text(n[i]["material"], f + ".material");
      need_material(g.material, f + ".material");
      if (n[i]["mesh"]) g.mesh = r.mesh(n[i]["mesh"], f + ".mesh");
      if (allow_box && n[i]["box"]) g.box = r.box(n[i]["box"], f + ".box");
      if (g.mesh.has_value() == g.box.has_value()) {
        r.fail(f, allow_box ? "give exactly one of mesh and box" : "missing key 'mesh'");
      }
      out.push_back(std::move(g));
    }
  };
  read_regions("tendons", false, spec.tendons);
  read_regions("regions", true, spec.regions);
  {
    std::set<std::string> names{"outer", "inner"};
    auto unique = [&](const std::string& name, const std::string& field) {
      if (!names.insert(name).second) {
        r.fail(field, "name '" + name + "' is used twice (or is reserved: outer, inner)");
      }
    };
    for (std::size_t i = 0; i < spec.muscles.size(); ++i)
      unique(spec.muscles[i].name, Reader::at("muscles", i) + ".name");
    for (std::size_t i = 0; i < spec.tendons.size(); ++i)
      unique(spec.tendons[i].name, Reader::at("tendons", i) + ".name");
    for (std::size_t i = 0; i < spec.regions.size(); ++i)
      unique(spec.regions[i].name, Reader::at("regions", i) + ".name");
  }

  // Boundary conditions.
  if (const auto n = root["boundary"]) {
    r.sequence(n, "boundary");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at("boundary", i);
      r.check_keys(n[i], f, {"type", "surface", "inside", "within", "box"});
      BoundarySpec b;
      b.field = f;
      if (!n[i]["type"]) r.fail(f, "missing key 'type' (rigid or sliding)");
      const std::string type = r.text(n[i]["type"], f + ".type");
      if (type == "rigid") {
        b.kind = BoundarySpec::Kind::rigid;
      } else if (type == "sliding") {
        b.kind = BoundarySpec::Kind::sliding;
      } else {
        r.fail(f + ".type", "unknown type '" + type + "' (known: rigid, sliding)");
      }
      if (n[i]["inside"]) b.inside = r.boolean(n[i]["inside"], f + ".inside");
      if (n[i]["within"]) b.within = r.length(n[i]["within"], f + ".within");
      if (n[i]["box"]) b.box = r.box(n[i]["box"], f + ".box");
      if (n[i]["surface"]) {
        b.surface = r.surface(n[i]["surface"], f + ".surface");
      } else {
        b.surface.name = "inner";
        b.surface.field = f + ".surface";
      }
      b.has_surface = b.inside || b.within.has_value();
      if (!b.has_surface && !b.box) {
        r.fail(f, "select nodes with inside, within and/or box");
      }
      if (b.kind == BoundarySpec::Kind::sliding && !b.has_surface) {
        r.fail(f, "a sliding condition needs a surface: give inside or within");
      }
      if (!b.has_surface && n[i]["surface"]) {
        r.fail(f + ".surface", "a surface needs inside or within");
      }
      spec.boundary.push_back(std::move(b));
    }
  }

  if (const auto n = root["node_sets"]) {
    r.sequence(n, "node_sets");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at("node_sets", i);
      r.check_keys(n[i], f, {"name", "box", "surface", "distance"});
      if (!n[i]["name"]) r.fail(f, "missing key 'name'");
      NodeSetSpec s;
      s.name = r.text(n[i]["name"], f + ".name");
      YAML::Node sel = YAML::Clone(n[i]);
      sel.remove("name");
      s.select = r.selector(sel, f);
      for (const auto& o : spec.node_sets) {
        if (o.name == s.name) r.fail(f + ".name", "duplicate node set '" + s.name + "'");
      }
      spec.node_sets.push_back(std::move(s));
    }
  }

  if (const auto n = root["visual"]) {
    r.sequence(n, "visual");
    for (std::size_t i = 0; i < n.size(); ++i) {
      const std::string f = Reader::at("visual", i);
      r.check_keys(n[i], f, {"name", "surface"});
      if (!n[i]["name"] || !n[i]["surface"]) r.fail(f, "needs a name and a surface");
      VisualSpec v{r.text(n[i]["name"], f + ".name"), r.surface(n[i]["surface"], f + ".surface")};
      spec.visual.push_back(std::move(v));
    }
  } else {
    spec.visual.push_back({"skin", SurfaceRef{"outer", std::nullopt, "visual"}});
  }

  check_surface_names(r, spec);
  return spec;
}

namespace {
nlohmann::json vec_json(const Vec3d& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}
nlohmann::json box_json(const Box& b) {
  return {{"min", vec_json(b.lo)}, {"max", vec_json(b.hi)}};
}
nlohmann::json mesh_json(const MeshSource& m) {
  nlohmann::json j;
  j["source"] = m.describe();
  if (m.kind != MeshSource::Kind::file) {
    j["centre"] = vec_json(m.centre);
    j["radii"] = vec_json(m.radii);
    j["box_min"] = vec_json(m.box_lo);
    j["box_max"] = vec_json(m.box_hi);
    j["subdivisions"] = m.subdivisions;
  }
  j["unit"] = to_string(m.transform.unit);
  j["scale"] = m.transform.scale;
  j["rotate_deg"] = vec_json(m.transform.rotate_deg);
  j["translate_m"] = vec_json(m.transform.translate);
  return j;
}
nlohmann::json ref_json(const SurfaceRef& s) {
  return s.mesh ? mesh_json(*s.mesh) : nlohmann::json(s.name);
}
nlohmann::json selector_json(const Selector& s) {
  nlohmann::json j = nlohmann::json::object();
  if (s.box) j["box"] = box_json(*s.box);
  if (s.surface) {
    j["surface"] = ref_json(*s.surface);
    j["distance"] = s.distance;
  }
  return j;
}
}  // namespace

std::string spec_to_json(const Spec& spec) {
  nlohmann::json j;
  j["units_in_spec"] = to_string(spec.units);
  if (spec.voxel_size) j["voxel_size"] = *spec.voxel_size;
  if (spec.target_elements) j["target_elements"] = *spec.target_elements;
  j["max_subdivision"] = spec.max_subdivision;
  j["min_fraction"] = spec.min_fraction;
  j["weld_tolerance"] = spec.weld_tolerance;
  j["outer"] = mesh_json(spec.outer);
  if (spec.inner) j["inner"] = mesh_json(*spec.inner);
  if (spec.tissue_thickness) j["tissue_thickness"] = *spec.tissue_thickness;
  for (const auto& l : spec.layers) {
    nlohmann::json lj{{"material", l.material}};
    if (l.thickness) lj["thickness"] = *l.thickness;
    j["layers"].push_back(lj);
  }
  for (const auto& m : spec.materials) {
    j["materials"][m.name] = {{"youngs_modulus", m.youngs_modulus},
                              {"poisson_ratio", m.poisson_ratio},
                              {"density", m.density}};
  }
  for (const auto& m : spec.muscles) {
    nlohmann::json mj{{"name", m.name},
                      {"mesh", mesh_json(m.mesh)},
                      {"material", m.material},
                      {"reference_stress", m.reference_stress},
                      {"optimal_stretch", m.optimal_stretch},
                      {"passive",
                       {{"p1", m.passive_p1},
                        {"p2", m.passive_p2},
                        {"linear_stretch", m.passive_linear_stretch}}}};
    if (m.fibres.kind == FibreSpec::Kind::constant) {
      mj["fibres"] = {{"type", "constant"}, {"direction", vec_json(m.fibres.direction)}};
    } else {
      mj["fibres"] = {{"type", "harmonic"},
                      {"origin", selector_json(m.fibres.origin)},
                      {"insertion", selector_json(m.fibres.insertion)}};
    }
    j["muscles"].push_back(mj);
  }
  auto regions = [&](const char* key, const std::vector<RegionSpec>& v) {
    for (const auto& g : v) {
      nlohmann::json gj{{"name", g.name}, {"material", g.material}};
      if (g.mesh) gj["mesh"] = mesh_json(*g.mesh);
      if (g.box) gj["box"] = box_json(*g.box);
      j[key].push_back(gj);
    }
  };
  regions("tendons", spec.tendons);
  regions("regions", spec.regions);
  for (const auto& b : spec.boundary) {
    nlohmann::json bj{{"type", b.kind == BoundarySpec::Kind::rigid ? "rigid" : "sliding"},
                      {"inside", b.inside}};
    if (b.has_surface) bj["surface"] = ref_json(b.surface);
    if (b.within) bj["within"] = *b.within;
    if (b.box) bj["box"] = box_json(*b.box);
    j["boundary"].push_back(bj);
  }
  for (const auto& s : spec.node_sets) {
    j["node_sets"].push_back({{"name", s.name}, {"select", selector_json(s.select)}});
  }
  for (const auto& v : spec.visual) {
    j["visual"].push_back({{"name", v.name}, {"surface", ref_json(v.surface)}});
  }
  return j.dump();
}

}  // namespace sinew::voxelizer
