#pragma once
// The in-memory form of a sinew model file (format version 3; version 1 files, which have no
// texture coordinates, and version 2 files, which have no jaw, are still read). docs/model-format.md documents the
// file dataset by dataset; this struct mirrors it one to one. SI units throughout: metres,
// kilograms, seconds, pascals.
//
// Lattice conventions (paper §6.4, physics-notes §1):
//  - The grid has `dims` = (nx, ny, nz) voxels of side `voxel_size`; its node lattice has
//    (nx+1, ny+1, nz+1) points. Lattice point (i, j, k) sits at origin + voxel_size * (i, j, k).
//  - Present nodes are listed in lexicographic order with i fastest (sorted by k, then j, then i),
//    so two present nodes (i, j, k) and (i+1, j, k) always have consecutive ids.
//  - Present elements are listed in the same order by their base corner (the lattice point with the
//    smallest i, j, k). Element e covers lattice points base + {0,1}³.
//  - element_nodes[e] lists its 8 node ids in the VTK / hex8 order:
//      0:(0,0,0) 1:(1,0,0) 2:(1,1,0) 3:(0,1,0) 4:(0,0,1) 5:(1,0,1) 6:(1,1,1) 7:(0,1,1)
//    so node a has natural-coordinate signs (ξa, ηa, ζa) = (2·di−1, 2·dj−1, 2·dk−1), and
//    element_nodes[e][1] == element_nodes[e][0] + 1 (likewise 2 = 3+1, 5 = 4+1, 6 = 7+1).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sinew::formats {

inline constexpr int kModelFormatVersion = 3;
// The oldest version the reader accepts: version 1 lacks the surfaces' texture coordinates and
// versions 1 and 2 the jaw (they are read as models without one).
inline constexpr int kModelFormatOldestVersion = 1;
inline constexpr const char* kModelFormatName = "sinew-model";

using Index = std::int32_t;   // node, element, triangle, material ids
using Offset = std::int64_t;  // CSR offsets
using Lattice = std::array<std::int32_t, 3>;
using Point = std::array<double, 3>;
// Texture coordinates (u, v) in OBJ's (and assimp's) convention: (0, 0) is the image's bottom-left
// corner, v grows upward. glTF puts (0, 0) at the top-left: its exporter writes (u, 1 − v).
using TexCoord = std::array<double, 2>;

// Natural-coordinate offsets (di, dj, dk) of the 8 element nodes in hex8 order.
inline constexpr std::array<std::array<int, 3>, 8> kHexCorner = {
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};

struct VoxelGrid {
  Point origin{0, 0, 0};                      // m, position of lattice point (0,0,0)
  double voxel_size = 0;                      // m, side of every (cubic) voxel
  std::array<std::int32_t, 3> dims{0, 0, 0};  // voxels along x, y, z
  bool operator==(const VoxelGrid&) const = default;
};

// Constitutive laws the format can name. Stored in the file as its string name.
enum class MaterialLaw { neo_hookean_tled };
const char* to_string(MaterialLaw law);
// Throws FormatError (no file or field: callers add them) for unknown names.
MaterialLaw material_law_from_string(const std::string& name);

struct Material {
  std::string name;
  MaterialLaw law = MaterialLaw::neo_hookean_tled;
  double youngs_modulus = 0;  // Pa
  double poisson_ratio = 0;   // 1
  double shear_modulus = 0;   // Pa, μ = E / (2(1+ν))
  double bulk_modulus = 0;    // Pa, κ = E / (3(1−2ν))
  double density = 0;         // kg/m³
  bool operator==(const Material&) const = default;
};

// The shear modulus μ and bulk modulus κ (both Pa) of an isotropic elastic material from Young's
// modulus E (Pa) and Poisson's ratio ν (1):
//   μ = E / (2(1+ν)),   κ = E / (3(1−2ν)).
// Finite and positive for E > 0 and ν in (−1, 0.5). Source: the standard conversion formulae for
// isotropic linear elasticity, e.g. A. F. Bower, Applied Mechanics of Solids (CRC Press, 2009),
// §3.2.3. The one place sinew computes them: the voxelizer, make_neo_hookean_material() and the
// validator's consistency check all call it.
struct ShearAndBulkModulus {
  double shear_modulus = 0;  // Pa, μ
  double bulk_modulus = 0;   // Pa, κ
};
ShearAndBulkModulus shear_and_bulk_modulus(double youngs_modulus, double poisson_ratio);

// A TLED neo-Hookean material from E (Pa), ν and ρ (kg/m³), with μ and κ from
// shear_and_bulk_modulus(), as the validator checks them.
Material make_neo_hookean_material(std::string name, double youngs_modulus, double poisson_ratio,
                                   double density);

// Active force-length curves a muscle can name.
enum class ForceLengthCurve { blemker2005 };
const char* to_string(ForceLengthCurve curve);
ForceLengthCurve force_length_curve_from_string(const std::string& name);

struct Muscle {
  std::string name;
  Index material = -1;            // its passive isotropic tissue, an index into materials
  double reference_stress = 5e6;  // Pa, σref
  double optimal_stretch = 1.0;   // λopt
  ForceLengthCurve force_length = ForceLengthCurve::blemker2005;
  double passive_p1 = 0.05;  // fp(x) = p1 (exp(p2 (x−1)) − 1) for 1 < x < x*
  double passive_p2 = 6.6;
  double passive_linear_stretch = 1.4;  // x*, linear continuation beyond it
  // Per element: the elements this muscle overlaps, its volume fraction there and the unit fibre
  // direction (reference configuration). Sorted by element id.
  std::vector<Index> elements;
  std::vector<double> fractions;
  std::vector<Point> fibres;
  bool operator==(const Muscle&) const = default;
};

enum class SurfaceRole { sliding, visual };
const char* to_string(SurfaceRole role);
SurfaceRole surface_role_from_string(const std::string& name);

struct Surface {
  std::string name;
  SurfaceRole role = SurfaceRole::visual;
  std::vector<Point> vertices;                  // m
  std::vector<std::array<Index, 3>> triangles;  // counter-clockwise seen from outside
  // Visual surfaces only (empty otherwise): per vertex the element that holds it and its natural
  // coordinates (ξ, η, ζ) ∈ [−1, 1]³ in that element.
  std::vector<Index> embedding_element;
  std::vector<Point> embedding_local;
  // Visual surfaces only, optional: the artist's texture coordinates, indexed per triangle corner
  // (as in OBJ's `f v/vt`): uv_triangles is empty (no UVs) or has one row per triangle, whose
  // corner k has coordinates uvs[uv_triangles[t][k]]. Per corner because one position can carry
  // several (u, v) along a texture seam. Finite; any range (textures may repeat).
  std::vector<TexCoord> uvs;
  std::vector<std::array<Index, 3>> uv_triangles;
  bool operator==(const Surface&) const = default;
};

struct SlidingBinding {
  Index node = -1;
  Index surface = -1;        // index into surfaces; that surface has role sliding
  double rest_distance = 0;  // m, distance from the surface kept during the run
  Index rest_triangle = -1;  // nearest triangle at rest, the warm start of the closest-point search
  bool operator==(const SlidingBinding&) const = default;
};

struct NamedSet {
  std::string name;
  std::vector<Index> ids;  // sorted, unique
  bool operator==(const NamedSet&) const = default;
};

// The mandible as a rigid body apart from the skull (docs/model-format.md "/jaw", docs/faces.md
// "The jaw"): its nodes move as one rigid body that a scene drives (rotation about the
// temporomandibular axis, protrusion, lateral shift); without a scene's `jaw:` they are held like
// rigid nodes (the jaw closed). Frame: `axis` (unit, the subject's left: the hinge), `forward` (unit,
// normal to axis: protrusion), up = forward × axis. Opening by θ rotates about +axis through
// `pivot`, so the chin moves down and back.
struct Jaw {
  std::vector<Index> nodes;  // sorted, unique; neither rigid nor sliding
  Point pivot{0, 0, 0};      // m, on the temporomandibular axis (midway between the condyles)
  Point axis{1, 0, 0};       // unit
  Point forward{0, 0, 1};    // unit, normal to axis
  Point incisal{0, 0, 0};    // m, the incisal point at rest (where the opening is measured)
  // The faces of the cut between the lips (docs/faces.md "Lips and teeth"): per pair the node of
  // the upper side (the upper lip, the cheek above the teeth) and the node straight below it across
  // the cut. Each node in at most one pair. Optional (empty: no contact between the lips).
  std::vector<std::array<Index, 2>> lip_pairs;
  bool operator==(const Jaw&) const = default;
};

struct InputFile {
  std::string path;
  std::string sha256;  // lowercase hex
  bool operator==(const InputFile&) const = default;
};

struct Provenance {
  std::string tool;  // e.g. "sinew-voxelize"
  std::string tool_version;
  std::string created;  // ISO 8601 UTC, e.g. 2026-11-21T06:49:00Z
  std::vector<InputFile> inputs;
  std::string parameters_json;  // every parameter used, as one JSON document
  bool operator==(const Provenance&) const = default;
};

struct Model {
  VoxelGrid grid;
  std::vector<Lattice> node_lattice;                // N, lattice coordinates of present nodes
  std::vector<Lattice> element_lattice;             // E, base corner of present elements
  std::vector<std::array<Index, 8>> element_nodes;  // E × 8, hex8 order (see above)

  std::vector<Material> materials;
  // Element material fractions, CSR over elements: the entries of element e are
  // [material_offsets[e], material_offsets[e+1]). Sum per element = tissue fraction ≤ 1.
  std::vector<Offset> material_offsets;    // E + 1
  std::vector<Index> material_ids;         // K
  std::vector<double> material_fractions;  // K, in (0, 1]

  std::vector<Muscle> muscles;
  std::vector<Index> rigid_nodes;       // sorted, unique
  std::vector<SlidingBinding> sliding;  // sorted by node, one binding per node
  std::optional<Jaw> jaw;               // since version 3; none: no jaw
  std::vector<Surface> surfaces;
  std::vector<NamedSet> node_sets;
  std::vector<NamedSet> element_sets;
  Provenance provenance;

  std::size_t node_count() const { return node_lattice.size(); }
  std::size_t element_count() const { return element_lattice.size(); }
  // Rest position of node n, m.
  Point node_position(Index n) const {
    const auto& l = node_lattice[static_cast<std::size_t>(n)];
    return {grid.origin[0] + grid.voxel_size * l[0], grid.origin[1] + grid.voxel_size * l[1],
            grid.origin[2] + grid.voxel_size * l[2]};
  }
  bool operator==(const Model&) const = default;
};

// Lexicographic order of lattice points with i fastest: by k, then j, then i. Node and element
// lists are sorted by it.
bool lattice_less(const Lattice& a, const Lattice& b);

// Fills node_lattice (every corner of every element, sorted lexicographically by k, j, i) and
// element_nodes from element_lattice, which must already be sorted the same way and unique
// (throws FormatError otherwise). Used by the voxelizer and by generators; the validator
// checks the same invariants on files.
void build_lattice_topology(Model& model);

}  // namespace sinew::formats
