#pragma once
// The voxelizer spec: what sinew-voxelize builds, read from a YAML file. docs/voxelizer.md
// documents every key with examples; data/specs/ holds runnable examples.
//
// Units: every length in this struct is in metres (the file's lengths are in its `units`, default
// m, and are converted on reading). Elastic moduli and stresses in Pa, densities in kg/m³.
// Unknown keys, wrong types and out-of-range values throw ConfigError naming the file, the key
// path (e.g. "muscles[1].fibres.origin.box.min") and the line (common's yaml_reader.hpp).
#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/rig_spec.hpp"

namespace sinew::voxelizer {

// Axis-aligned box, m. lo < hi componentwise.
struct Box {
  Vec3d lo{0, 0, 0}, hi{0, 0, 0};
  bool contains(const Vec3d& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};

// Where a mesh comes from: a file (any format assimp reads) or a generated primitive (for examples
// and tests; see primitives.hpp), or a mesh built in memory (the rig's muscles: `generated`, in
// metres, the transform left at identity). The transform applies to all (unit, scale, rotate,
// translate).
struct MeshSource {
  enum class Kind { file, sphere, ellipsoid, box, cylinder, generated };
  Kind kind = Kind::file;
  std::filesystem::path path;  // Kind::file, resolved against the spec's folder
  // Primitives, in the mesh's own unit before the transform: centre, radii (sphere: x only;
  // cylinder: x = radius, y = half-length, along z), box lo/hi; subdivisions = mesh fineness.
  Vec3d centre{0, 0, 0};
  Vec3d radii{0, 0, 0};
  Vec3d box_lo{0, 0, 0}, box_hi{0, 0, 0};
  int subdivisions = 4;
  std::shared_ptr<const TriangleMesh> generated;  // Kind::generated
  MeshTransform transform;
  std::string field;             // key path in the spec, for messages
  std::string describe() const;  // the path, or e.g. "sphere(r=0.01)"
};

// A reference to a surface: one of the named surfaces ("outer", "inner", or the name of a muscle,
// tendon or region that has a mesh), or a mesh of its own.
struct SurfaceRef {
  std::string name;  // empty when `mesh` is set
  std::optional<MeshSource> mesh;
  std::string field;
};

// Selects points (voxel centres, nodes) by a box, or by unsigned distance <= `distance` from a
// surface, or both (both must hold).
struct Selector {
  std::optional<Box> box;
  std::optional<SurfaceRef> surface;
  double distance = 0;  // m, used with surface
  std::string field;
};

struct MaterialSpec {
  std::string name;
  double youngs_modulus = 0;  // Pa
  double poisson_ratio = 0;   // 1, in (-1, 0.5)
  double density = 0;         // kg/m³
};

// The materials of Warburton & Maddock 2013, Table 1 (physics-notes §6): stratum_corneum, dermis,
// hypodermis, muscle, tendon; ρ = 11,000 kg/m³ (mass-scaled), ν = 0.49.
std::vector<MaterialSpec> warburton2013_materials();

// A layer of tissue by depth below the outer surface. thickness: m; empty = the rest (last only).
struct LayerSpec {
  std::string material;
  std::optional<double> thickness;
};

struct FibreSpec {
  enum class Kind { constant, harmonic, circumferential };
  Kind kind = Kind::constant;
  Vec3d direction{1, 0, 0};    // constant: unit after reading
  Selector origin, insertion;  // harmonic: Dirichlet 0 and 1 regions (voxel centres)
  // circumferential (sphincters; fibres.hpp): around `axis` through `centre` (m), tangent to the
  // ellipses of semi-axes proportional to radii (major along `major`, minor along axis × major).
  Vec3d centre{0, 0, 0}, axis{0, 0, 1}, major{1, 0, 0};  // axis, major: unit, orthogonal
  double radius_major = 1, radius_minor = 1;             // only their ratio matters
};

struct MuscleSpec {
  std::string name;
  MeshSource mesh;
  std::string material;
  double reference_stress = 5e6;  // Pa, σref
  double optimal_stretch = 1.0;   // λopt
  double passive_p1 = 0.05, passive_p2 = 6.6, passive_linear_stretch = 1.4;
  FibreSpec fibres;
};

// A tendon / aponeurosis, or a generic region: a closed mesh or a box with a material.
struct RegionSpec {
  std::string name;
  std::optional<MeshSource> mesh;
  std::optional<Box> box;
  std::string material;
};

struct BoundarySpec {
  enum class Kind { rigid, sliding };
  Kind kind = Kind::rigid;
  SurfaceRef surface;  // default "inner"; unused for a box-only rigid condition
  bool has_surface = true;
  bool inside = false;           // nodes inside the surface (winding number ≥ 1/2)
  std::optional<double> within;  // nodes at unsigned distance ≤ within (m)
  std::optional<Box> box;        // restricts the condition to nodes in this box
  std::string field;
};

// The region of interest (crop.hpp): voxels whose centre lies in `box` (when given) and within
// `distance` of at least one of `points` (when given; both must hold) are kept; the nodes on the
// cut are held rigid. Lengths in m.
struct CropSpec {
  std::optional<Box> box;
  std::vector<std::pair<std::string, Vec3d>> points;  // named points, m
  double distance = 0;                                // m, with points
  std::string field;
};

struct NodeSetSpec {
  std::string name;
  Selector select;
};

struct VisualSpec {
  std::string name;
  SurfaceRef surface;
};

struct Spec {
  std::filesystem::path file;  // the spec file itself ("" when parsed from a string)
  std::filesystem::path output;
  LengthUnit units = LengthUnit::m;

  // Resolution: exactly one of voxel_size (m) and target_elements.
  std::optional<double> voxel_size;
  std::optional<std::int64_t> target_elements;
  int max_subdivision = 1;  // levels of adaptive subdivision of a boundary voxel
  // The most elements the meshes may make (expected from their volume and area, checked before the
  // fractions are computed); empty: kDefaultMaxElements (mesh_bounds.hpp). --force goes past it.
  std::optional<std::int64_t> max_elements;
  double min_fraction = 0.0;    // voxels whose tissue fraction is ≤ this are dropped
  double weld_tolerance = 0.0;  // m, for clean_mesh

  MeshSource outer;
  std::optional<MeshSource> inner;
  std::optional<double> tissue_thickness;  // m, derive the inner surface from the outer one
  // m: derive the glide surface "glide", this far below the inner surface (given or derived): the
  // surface the deep layer slides on when the nodes of the voxels the skull cuts lie inside the
  // skull (docs/voxelizer.md, "Safe constraints").
  std::optional<double> glide_depth;

  std::vector<LayerSpec> layers;
  std::vector<MaterialSpec> materials;
  std::vector<MuscleSpec> muscles;
  std::vector<RegionSpec> tendons;
  std::vector<RegionSpec> regions;
  std::vector<BoundarySpec> boundary;
  std::vector<NodeSetSpec> node_sets;
  std::optional<CropSpec> crop;
  std::vector<VisualSpec> visual;  // default: [{name: skin, surface: outer}]
  std::optional<RigSpec> rig;      // muscles built from landmarks (rig.hpp), added when voxelizing

  const MaterialSpec* find_material(const std::string& name) const;
};

// Reads and checks a spec. Throws IoError (unreadable), ConfigError (syntax, unknown keys, wrong
// types, ranges, unknown material / surface names).
Spec read_spec(const std::filesystem::path& path);
// The same from text; `file` is used for messages and to resolve relative mesh paths.
Spec parse_spec(const std::string& yaml_text, const std::filesystem::path& file);

// Calls `visit` for every surface reference of the spec that names or gives a surface: harmonic
// fibres' origin and insertion, boundary conditions that use a surface, node sets, visual surfaces.
void for_each_surface_ref(const Spec& spec, const std::function<void(const SurfaceRef&)>& visit);

// The spec as one JSON document (every parameter, SI units), for the model's provenance.
std::string spec_to_json(const Spec& spec);

}  // namespace sinew::voxelizer
