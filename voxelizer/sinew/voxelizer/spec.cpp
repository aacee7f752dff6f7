#include "sinew/voxelizer/spec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::voxelizer {

namespace {

constexpr NameTable<LengthUnit, 3> kLengthUnitNames{
    {{"m", LengthUnit::m}, {"cm", LengthUnit::cm}, {"mm", LengthUnit::mm}}};

// The spec's own reading rules on top of the shared YAML reader: lengths in the spec's unit, mesh
// paths relative to the spec's folder, and the composite values (meshes, boxes, selectors).
struct SpecReader {
  std::filesystem::path folder;
  LengthUnit units = LengthUnit::m;

  // A name or a path: text that must not be empty.
  static std::string name(const YamlNode& n) {
    if (!n.is_scalar() || n.text().empty()) throw n.error("expected a non-empty string");
    return n.text();
  }
  // A length in the spec's unit, returned in metres.
  double length(const YamlNode& n) const { return n.positive() * metres_per_unit(units); }
  static Vec3d vec3(const YamlNode& n, double scale = 1.0) {
    const auto v = n.vec3();
    return {v[0] * scale, v[1] * scale, v[2] * scale};
  }
  static LengthUnit unit(const YamlNode& n) { return n.choose(kLengthUnitNames, "unit"); }

  std::filesystem::path resolve(const std::string& p) const {
    std::filesystem::path path(p);
    if (path.is_relative()) path = folder / path;
    return path.lexically_normal();
  }

  // {min: [x, y, z], max: [x, y, z]} times `scale`, min < max in every axis.
  static std::pair<Vec3d, Vec3d> corners(const YamlNode& n, double scale) {
    n.allow_keys({"min", "max"});
    if (!n.has("min") || !n.has("max")) throw n.error("a box needs both min and max");
    const Vec3d lo = vec3(n.child("min"), scale), hi = vec3(n.child("max"), scale);
    if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z)) {
      throw n.error("min must be smaller than max in x, y and z");
    }
    return {lo, hi};
  }
  Box box(const YamlNode& n) const {
    const auto [lo, hi] = corners(n, metres_per_unit(units));
    return Box{lo, hi};
  }

  MeshSource mesh(const YamlNode& n) const {
    MeshSource m;
    m.field = n.path();
    m.transform.unit = units;
    if (n.is_scalar()) {
      m.path = resolve(name(n));
      return m;
    }
    n.allow_keys({"path", "sphere", "ellipsoid", "box", "cylinder", "subdivisions", "unit", "scale",
                  "rotate_deg", "translate"});
    int sources = 0;
    for (const char* k : {"path", "sphere", "ellipsoid", "box", "cylinder"})
      sources += n.has(k) ? 1 : 0;
    if (sources != 1) throw n.error("give exactly one of path, sphere, ellipsoid, box, cylinder");
    if (n.has("unit")) m.transform.unit = unit(n.child("unit"));
    if (n.has("path")) {
      m.path = resolve(name(n.child("path")));
    } else if (n.has("sphere") || n.has("ellipsoid")) {
      // A sphere is an ellipsoid given by one radius.
      const bool sphere = n.has("sphere");
      const auto e = n.child(sphere ? "sphere" : "ellipsoid");
      e.allow_keys({"centre", sphere ? "radius" : "radii"});
      m.kind = sphere ? MeshSource::Kind::sphere : MeshSource::Kind::ellipsoid;
      if (e.has("centre")) m.centre = vec3(e.child("centre"));
      if (sphere) {
        const double r = e.require("radius").positive();
        m.radii = {r, r, r};
      } else {
        m.radii = vec3(e.require("radii"));
        if (!(m.radii.x > 0 && m.radii.y > 0 && m.radii.z > 0)) throw e.error("radii must be > 0");
      }
    } else if (n.has("box")) {
      m.kind = MeshSource::Kind::box;
      std::tie(m.box_lo, m.box_hi) = corners(n.child("box"), 1.0);
    } else {
      const auto c = n.child("cylinder");
      c.allow_keys({"centre", "radius", "half_length"});
      m.kind = MeshSource::Kind::cylinder;
      if (c.has("centre")) m.centre = vec3(c.child("centre"));
      if (!c.has("radius") || !c.has("half_length")) throw c.error("needs radius and half_length");
      m.radii = {c.child("radius").positive(), c.child("half_length").positive(), 0};
    }
    if (n.has("subdivisions")) {
      const auto s = n.child("subdivisions");
      const auto v = s.integer();
      if (v < 0 || v > 8) throw s.error("must be in [0, 8]");
      m.subdivisions = static_cast<int>(v);
    }
    if (n.has("scale")) m.transform.scale = n.child("scale").positive();
    if (n.has("rotate_deg")) m.transform.rotate_deg = vec3(n.child("rotate_deg"));
    if (n.has("translate")) {
      m.transform.translate = vec3(n.child("translate"), metres_per_unit(m.transform.unit));
    }
    return m;
  }

  SurfaceRef surface(const YamlNode& n) const {
    SurfaceRef r;
    r.field = n.path();
    if (n.is_scalar()) {
      r.name = name(n);
    } else {
      r.mesh = mesh(n);
    }
    return r;
  }

  // A selector's keys (box, surface, distance), and `name` too when the selector is named.
  Selector selector(const YamlNode& n, bool named = false) const {
    std::vector<std::string_view> keys{"box", "surface", "distance"};
    if (named) keys.insert(keys.begin(), "name");
    n.allow_keys(keys);
    Selector s;
    s.field = n.path();
    if (n.has("box")) s.box = box(n.child("box"));
    if (n.has("surface")) {
      s.surface = surface(n.child("surface"));
      if (!n.has("distance")) throw n.error("a surface selector needs a distance");
      s.distance = length(n.child("distance"));
    } else if (n.has("distance")) {
      throw n.child("distance").error("distance needs a surface");
    }
    if (!s.box && !s.surface) throw n.error("give a box, a surface with a distance, or both");
    return s;
  }

  // A muscle's fibre field: constant, harmonic or circumferential (docs/voxelizer.md, fibres).
  FibreSpec fibres(const YamlNode& fb) const {
    fb.allow_keys({"type", "direction", "origin", "insertion", "centre", "axis", "major", "radii"});
    if (!fb.has("type"))
      throw fb.error("missing key 'type' (constant, harmonic or circumferential)");
    constexpr NameTable<FibreSpec::Kind, 3> kKinds{
        {{"constant", FibreSpec::Kind::constant},
         {"harmonic", FibreSpec::Kind::harmonic},
         {"circumferential", FibreSpec::Kind::circumferential}}};
    FibreSpec f;
    f.kind = fb.child("type").choose(kKinds, "fibre type");
    const char* kind_name = name_of(kKinds, f.kind);
    // Each type's own keys; any other is refused with the type's name.
    const std::vector<std::string> own =
        f.kind == FibreSpec::Kind::constant ? std::vector<std::string>{"direction"}
        : f.kind == FibreSpec::Kind::harmonic
            ? std::vector<std::string>{"origin", "insertion"}
            : std::vector<std::string>{"centre", "axis", "major", "radii"};
    for (const auto& k : fb.keys()) {
      if (k == "type") continue;
      if (std::find(own.begin(), own.end(), k) == own.end()) {
        throw fb.child(k).error(std::string("a ") + kind_name + " fibre field has no " + k);
      }
    }
    auto unit_vector = [&](const char* key) {
      const Vec3d d = vec3(fb.require(key));
      // Scaled by its largest component first: the length of (1e308, 1e308, 0) overflows, and
      // d / inf was a zero direction reported against the output file (issue 33).
      const double big = std::max({std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
      if (!(big > 0)) throw fb.child(key).error("must not be zero");
      const Vec3d scaled = (1.0 / big) * d;
      return (1.0 / norm(scaled)) * scaled;
    };
    if (f.kind == FibreSpec::Kind::constant) {
      f.direction = unit_vector("direction");
    } else if (f.kind == FibreSpec::Kind::harmonic) {
      if (!fb.has("origin") || !fb.has("insertion")) {
        throw fb.error("a harmonic fibre field needs origin and insertion");
      }
      f.origin = selector(fb.child("origin"));
      f.insertion = selector(fb.child("insertion"));
    } else {
      f.centre = vec3(fb.require("centre"), metres_per_unit(units));
      f.axis = unit_vector("axis");
      const Vec3d major = fb.has("major") ? unit_vector("major") : Vec3d{1, 0, 0};
      // The major axis made normal to the axis (Gram-Schmidt).
      const Vec3d m = major - dot(major, f.axis) * f.axis;
      if (!(norm(m) > 1e-6))
        throw fb.child(fb.has("major") ? "major" : "axis")
            .error("the major axis must not be parallel to the axis");
      f.major = (1.0 / norm(m)) * m;
      if (fb.has("radii")) {
        const auto rr = fb.child("radii");
        const auto items = rr.items();
        if (items.size() != 2) throw rr.error("expected [major, minor]");
        f.radius_major = items[0].positive();
        f.radius_minor = items[1].positive();
      }
    }
    return f;
  }
};

std::string list_of(const std::set<std::string>& names) {
  std::string list;
  for (const auto& n : names) list.append(list.empty() ? "" : ", ").append(n);
  return list;
}

void check_surface_names(const Spec& spec) {
  std::set<std::string> known{"outer"};
  if (spec.inner || spec.tissue_thickness) known.insert("inner");
  if (spec.glide_depth) known.insert("glide");
  for (const auto& m : spec.muscles) known.insert(m.name);
  for (const auto& t : spec.tendons)
    if (t.mesh) known.insert(t.name);
  for (const auto& g : spec.regions)
    if (g.mesh) known.insert(g.name);
  for_each_surface_ref(spec, [&](const SurfaceRef& ref) {
    if (ref.mesh || known.count(ref.name)) return;
    throw ConfigError(
        spec.file.string(), ref.field,
        "unknown surface or muscle name '" + ref.name + "' (known: " + list_of(known) + ")");
  });
}

}  // namespace

void for_each_surface_ref(const Spec& spec, const std::function<void(const SurfaceRef&)>& visit) {
  for (const auto& m : spec.muscles) {
    if (m.fibres.kind == FibreSpec::Kind::harmonic) {
      if (m.fibres.origin.surface) visit(*m.fibres.origin.surface);
      if (m.fibres.insertion.surface) visit(*m.fibres.insertion.surface);
    }
  }
  for (const auto& b : spec.boundary)
    if (b.has_surface) visit(b.surface);
  for (const auto& s : spec.node_sets)
    if (s.select.surface) visit(*s.select.surface);
  for (const auto& v : spec.visual) visit(v.surface);
}

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
    case Kind::generated:
      return generated ? generated->source : "generated";
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
  return parse_spec(read_text_file(path, "spec file"), path);
}

Spec parse_spec(const std::string& yaml_text, const std::filesystem::path& file) {
  SpecReader r;
  r.folder = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  const YamlNode root = parse_yaml(yaml_text, file.string());
  if (!root.is_map()) throw root.error("the spec must be a YAML map");
  root.allow_keys({"units", "output", "resolution", "weld_tolerance", "outer", "inner",
                   "tissue_thickness", "glide_depth", "layers", "materials", "muscles", "tendons",
                   "regions", "boundary", "node_sets", "crop", "visual", "rig"});
  Spec spec;
  spec.file = file;
  if (root.has("units")) r.units = SpecReader::unit(root.child("units"));
  spec.units = r.units;
  if (root.has("output")) spec.output = r.resolve(SpecReader::name(root.child("output")));

  // Resolution.
  {
    const auto n = root.child("resolution");
    if (!n.defined()) throw n.error("missing (give voxel_size or target_elements)");
    n.allow_keys(
        {"voxel_size", "target_elements", "max_subdivision", "min_fraction", "max_elements"});
    if (n.has("voxel_size")) spec.voxel_size = r.length(n.child("voxel_size"));
    if (n.has("target_elements")) {
      spec.target_elements = n.child("target_elements").integer();
      if (*spec.target_elements < 1) throw n.child("target_elements").error("must be >= 1");
    }
    if (spec.voxel_size.has_value() == spec.target_elements.has_value()) {
      throw n.error("give exactly one of voxel_size and target_elements");
    }
    if (n.has("max_elements")) {
      spec.max_elements = n.child("max_elements").integer();
      if (*spec.max_elements < 1) throw n.child("max_elements").error("must be >= 1");
    }
    if (n.has("max_subdivision")) {
      const auto l = n.child("max_subdivision").integer();
      if (l < 0 || l > 6) throw n.child("max_subdivision").error("must be in [0, 6]");
      spec.max_subdivision = static_cast<int>(l);
    }
    if (n.has("min_fraction")) {
      spec.min_fraction = n.child("min_fraction").number();
      if (spec.min_fraction < 0 || spec.min_fraction >= 1) {
        throw n.child("min_fraction").error("must be in [0, 1)");
      }
    }
  }
  if (root.has("weld_tolerance")) {
    spec.weld_tolerance = root.child("weld_tolerance").non_negative() * metres_per_unit(r.units);
  }

  // Surfaces.
  if (!root.has("outer")) throw root.child("outer").error("missing: the outer surface (skin) mesh");
  spec.outer = r.mesh(root.child("outer"));
  if (root.has("inner")) spec.inner = r.mesh(root.child("inner"));
  if (root.has("tissue_thickness"))
    spec.tissue_thickness = r.length(root.child("tissue_thickness"));
  if (spec.inner && spec.tissue_thickness) {
    throw root.child("tissue_thickness").error("give either inner or tissue_thickness, not both");
  }
  if (root.has("glide_depth")) {
    const auto n = root.child("glide_depth");
    spec.glide_depth = r.length(n);
    if (!spec.inner && !spec.tissue_thickness)
      throw n.error("a glide surface lies below the inner surface: give inner or tissue_thickness");
  }

  // Materials.
  if (root.has("materials")) {
    const auto n = root.child("materials");
    n.allow_keys({"preset", "table"});
    if (n.has("preset")) {
      using Preset = std::vector<MaterialSpec> (*)();
      spec.materials = n.child("preset").choose(
          NameTable<Preset, 1>{{{"warburton2013", &warburton2013_materials}}}, "preset")();
    }
    if (n.has("table")) {
      const auto t = n.child("table");
      if (!t.is_map()) throw t.error("expected a map of name: {...}");
      for (const auto& name : t.keys()) {
        const auto e = t.child(name);
        e.allow_keys({"youngs_modulus", "poisson_ratio", "density"});
        MaterialSpec m{name, e.require("youngs_modulus").positive(),
                       e.require("poisson_ratio").number(), e.require("density").positive()};
        if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5)) {
          throw e.child("poisson_ratio").error("must be in (-1, 0.5)");
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
  // The name of a material of the spec.
  auto material = [&](const YamlNode& n) {
    const std::string name = SpecReader::name(n);
    if (spec.find_material(name)) return name;
    std::set<std::string> known;
    for (const auto& m : spec.materials) known.insert(m.name);
    throw n.error("unknown material '" + name +
                  "' (known: " + (known.empty() ? "none" : list_of(known)) + ")");
  };

  // Layers.
  {
    const auto n = root.child("layers");
    if (!n.defined()) throw n.error("missing: at least one layer with a material");
    const auto items = n.items();
    if (items.empty()) throw n.error("at least one layer is needed");
    for (const auto& l : items) {
      l.allow_keys({"material", "thickness"});
      LayerSpec layer;
      layer.material = material(l.require("material"));
      if (l.has("thickness")) {
        layer.thickness = r.length(l.child("thickness"));
      } else if (&l != &items.back()) {
        throw l.child("thickness").error("missing: only the last layer may omit it (the rest)");
      }
      spec.layers.push_back(layer);
    }
  }

  // The rig's muscles are built when voxelizing (rig.hpp); its section is read on its own.
  if (root.has("rig")) {
    spec.rig = parse_rig_spec(root.child("rig"), r.folder, r.units);
    if (!spec.find_material(spec.rig->material)) {
      const auto rn = root.child("rig");
      throw(rn.has("material") ? rn.child("material") : rn)
          .error("unknown material '" + spec.rig->material +
                 "' for the rig's muscles (give materials: {preset: warburton2013} or a table "
                 "entry of that name)");
    }
  }

  // Muscles.
  for (const auto& m : root.child("muscles").items()) {
    m.allow_keys(
        {"name", "mesh", "material", "reference_stress", "optimal_stretch", "passive", "fibres"});
    MuscleSpec s;
    s.name = SpecReader::name(m.require("name"));
    s.mesh = r.mesh(m.require("mesh"));
    s.material = material(m.require("material"));
    if (m.has("reference_stress")) s.reference_stress = m.child("reference_stress").positive();
    if (m.has("optimal_stretch")) s.optimal_stretch = m.child("optimal_stretch").positive();
    if (m.has("passive")) {
      const auto p = m.child("passive");
      p.allow_keys({"p1", "p2", "linear_stretch"});
      if (p.has("p1")) s.passive_p1 = p.child("p1").non_negative();
      if (p.has("p2")) s.passive_p2 = p.child("p2").positive();
      if (p.has("linear_stretch")) {
        s.passive_linear_stretch = p.child("linear_stretch").positive();
        if (s.passive_linear_stretch <= 1) throw p.child("linear_stretch").error("must be > 1");
      }
      // The curve's slope where it turns linear, P1 P2 exp(P2 (x* − 1)) (physics/muscle.hpp),
      // sets the fibres' stiffness and so the stable step; one that overflows is no curve.
      const double slope =
          s.passive_p1 * s.passive_p2 * std::exp(s.passive_p2 * (s.passive_linear_stretch - 1));
      if (!std::isfinite(slope)) {
        throw p.error(
            fmt::format("the passive curve's slope at linear_stretch, p1 p2 "
                        "exp(p2 (x* - 1)) = {:.3g} x {:.3g} x exp({:.3g} x {:.3g}), "
                        "overflows: lower p1, p2 or linear_stretch",
                        s.passive_p1, s.passive_p2, s.passive_p2, s.passive_linear_stretch - 1));
      }
    }
    s.fibres = r.fibres(m.require("fibres"));
    for (const auto& other : spec.muscles) {
      if (other.name == s.name) {
        throw m.child("name").error("duplicate muscle name '" + s.name + "'");
      }
    }
    spec.muscles.push_back(std::move(s));
  }

  auto read_regions = [&](const char* key, bool allow_box, std::vector<RegionSpec>& out) {
    for (const auto& e : root.child(key).items()) {
      std::vector<std::string_view> keys{"name", "mesh", "material"};
      if (allow_box) keys.push_back("box");
      e.allow_keys(keys);
      RegionSpec g;
      if (!e.has("name") || !e.has("material")) throw e.error("needs a name and a material");
      g.name = SpecReader::name(e.child("name"));
      g.material = material(e.child("material"));
      if (e.has("mesh")) g.mesh = r.mesh(e.child("mesh"));
      if (allow_box && e.has("box")) g.box = r.box(e.child("box"));
      if (g.mesh.has_value() == g.box.has_value()) {
        throw e.error(allow_box ? "give exactly one of mesh and box" : "missing key 'mesh'");
      }
      out.push_back(std::move(g));
    }
  };
  read_regions("tendons", false, spec.tendons);
  read_regions("regions", true, spec.regions);
  {
    // Muscles, tendons and regions name surfaces: one name each, and not a reserved one.
    std::set<std::string> names{"outer", "inner", "glide"};
    auto unique = [&](const char* key, const auto& list) {
      for (std::size_t i = 0; i < list.size(); ++i) {
        if (!names.insert(list[i].name).second) {
          throw root.child(key).item(i).child("name").error(
              "name '" + list[i].name + "' is used twice (or is reserved: outer, inner)");
        }
      }
    };
    unique("muscles", spec.muscles);
    unique("tendons", spec.tendons);
    unique("regions", spec.regions);
  }

  // Boundary conditions.
  for (const auto& e : root.child("boundary").items()) {
    e.allow_keys({"type", "surface", "inside", "within", "box"});
    BoundarySpec b;
    b.field = e.path();
    if (!e.has("type")) throw e.error("missing key 'type' (rigid or sliding)");
    b.kind = e.child("type").choose(
        NameTable<BoundarySpec::Kind, 2>{
            {{"rigid", BoundarySpec::Kind::rigid}, {"sliding", BoundarySpec::Kind::sliding}}},
        "type");
    if (e.has("inside")) b.inside = e.child("inside").boolean();
    if (e.has("within")) b.within = r.length(e.child("within"));
    if (e.has("box")) b.box = r.box(e.child("box"));
    if (e.has("surface")) {
      b.surface = r.surface(e.child("surface"));
    } else {
      b.surface.name = "inner";
      b.surface.field = e.child("surface").path();
    }
    b.has_surface = b.inside || b.within.has_value();
    if (!b.has_surface && !b.box) throw e.error("select nodes with inside, within and/or box");
    if (b.kind == BoundarySpec::Kind::sliding && !b.has_surface) {
      throw e.error("a sliding condition needs a surface: give inside or within");
    }
    if (!b.has_surface && e.has("surface")) {
      throw e.child("surface").error("a surface needs inside or within");
    }
    spec.boundary.push_back(std::move(b));
  }

  if (root.has("crop")) {
    const auto n = root.child("crop");
    n.allow_keys({"box", "points", "distance"});
    CropSpec c;
    c.field = n.path();
    if (n.has("box")) c.box = r.box(n.child("box"));
    if (n.has("points")) {
      const auto pts = n.child("points");
      if (!pts.is_map() || pts.keys().empty())
        throw pts.error("expected a map of NAME: [x, y, z] (at least one)");
      for (const auto& name : pts.keys())
        c.points.emplace_back(name, SpecReader::vec3(pts.child(name), metres_per_unit(r.units)));
      if (!n.has("distance")) throw n.error("points need a distance (keep voxels within it)");
      c.distance = r.length(n.child("distance"));
    } else if (n.has("distance")) {
      throw n.child("distance").error("a distance needs points");
    }
    if (!c.box && c.points.empty()) throw n.error("give a box, points with a distance, or both");
    spec.crop = std::move(c);
  }

  for (const auto& e : root.child("node_sets").items()) {
    NodeSetSpec s;
    s.select = r.selector(e, true);
    s.name = SpecReader::name(e.require("name"));
    for (const auto& o : spec.node_sets) {
      if (o.name == s.name) throw e.child("name").error("duplicate node set '" + s.name + "'");
    }
    spec.node_sets.push_back(std::move(s));
  }

  for (const auto& e : root.child("visual").items()) {
    e.allow_keys({"name", "surface"});
    if (!e.has("name") || !e.has("surface")) throw e.error("needs a name and a surface");
    const std::string name = SpecReader::name(e.child("name"));
    for (const auto& other : spec.visual) {
      if (other.name == name) throw e.child("name").error("duplicate visual name '" + name + "'");
    }
    spec.visual.push_back({name, r.surface(e.child("surface"))});
  }
  if (!root.has("visual")) {
    spec.visual.push_back({"skin", SurfaceRef{"outer", std::nullopt, "visual"}});
  }

  check_surface_names(spec);
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
  if (m.kind == MeshSource::Kind::generated) {
    if (m.generated) {
      j["vertices"] = m.generated->vertices.size();
      j["triangles"] = m.generated->triangles.size();
    }
  } else if (m.kind != MeshSource::Kind::file) {
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
  if (spec.max_elements) j["max_elements"] = *spec.max_elements;
  j["max_subdivision"] = spec.max_subdivision;
  j["min_fraction"] = spec.min_fraction;
  j["weld_tolerance"] = spec.weld_tolerance;
  j["outer"] = mesh_json(spec.outer);
  if (spec.inner) j["inner"] = mesh_json(*spec.inner);
  if (spec.tissue_thickness) j["tissue_thickness"] = *spec.tissue_thickness;
  if (spec.glide_depth) j["glide_depth"] = *spec.glide_depth;
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
    } else if (m.fibres.kind == FibreSpec::Kind::harmonic) {
      mj["fibres"] = {{"type", "harmonic"},
                      {"origin", selector_json(m.fibres.origin)},
                      {"insertion", selector_json(m.fibres.insertion)}};
    } else {
      mj["fibres"] = {{"type", "circumferential"},
                      {"centre", vec_json(m.fibres.centre)},
                      {"axis", vec_json(m.fibres.axis)},
                      {"major", vec_json(m.fibres.major)},
                      {"radii", {m.fibres.radius_major, m.fibres.radius_minor}}};
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
  if (spec.crop) {
    nlohmann::json cj;
    if (spec.crop->box) cj["box"] = box_json(*spec.crop->box);
    for (const auto& [name, p] : spec.crop->points) cj["points"][name] = {p.x, p.y, p.z};
    if (!spec.crop->points.empty()) cj["distance"] = spec.crop->distance;
    j["crop"] = cj;
  }
  for (const auto& s : spec.node_sets) {
    j["node_sets"].push_back({{"name", s.name}, {"select", selector_json(s.select)}});
  }
  for (const auto& v : spec.visual) {
    j["visual"].push_back({{"name", v.name}, {"surface", ref_json(v.surface)}});
  }
  if (spec.rig) {
    j["rig"] = {{"landmarks", spec.rig->landmarks.string()},
                {"muscles", spec.rig->muscles},
                {"material", spec.rig->material},
                {"reference_stress", spec.rig->reference_stress},
                {"depth_scale", spec.rig->depth_scale},
                {"landmark_tolerance_m", spec.rig->landmark_tolerance},
                {"min_inside", spec.rig->min_inside},
                {"jaw", spec.rig->jaw}};
  }
  return j.dump();
}

}  // namespace sinew::voxelizer
