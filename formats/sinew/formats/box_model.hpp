#pragma once
// A generated model: a block of nx × ny × nz cubic voxels of side h, every voxel present. Used by
// simulator tests, GPU benchmarks and verification runs (sinew-generate box).
//
//  - Materials: one, or a stack of layers along z. Layer L spans heights [b(L−1), b(L)] above the
//    bottom face (b(−1) = 0, b(last) = nz·h); boundaries may cut voxels, and a cut voxel gets each
//    layer's share as its volume fraction (overlap length / h). Every voxel is full: Σ = 1.
//  - Muscles (optional, any number): a sub-box of elements [element_min, element_max) (lattice
//    coordinates of base corners, half-open), one constant unit fibre direction, one fraction.
//  - Node sets "x_min", "x_max", "y_min", "y_max", "z_min", "z_max": the nodes on each face.
//    Element sets "all", "material_<name>" (elements with a share of that material) and
//    "muscle_<name>".
//  - Rigid nodes: the union of the faces named in rigid_faces.
// Node and element numbering follow model.hpp: element (i, j, k) is i + nx (j + ny k), node
// (i, j, k) is i + (nx+1) (j + (ny+1) k).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"

namespace sinew::formats {

struct BoxMuscleSpec {
  std::string name = "muscle";
  Index material = 0;             // its passive tissue, an index into BoxSpec::materials
  Lattice element_min{0, 0, 0};   // first element (i, j, k) of the sub-box
  Lattice element_max{0, 0, 0};   // one past the last, per axis
  Point fibre{1, 0, 0};           // normalised by the generator; must be non-zero
  double fraction = 1.0;          // muscle volume fraction in each of its elements
  double reference_stress = 5e6;  // Pa
  double optimal_stretch = 1.0;
  double passive_p1 = 0.05;
  double passive_p2 = 6.6;
  double passive_linear_stretch = 1.4;
};

struct BoxSpec {
  std::array<std::int32_t, 3> dims{8, 8, 8};  // voxels along x, y, z
  double voxel_size = 1e-3;                   // m
  Point origin{0, 0, 0};                      // m
  std::vector<Material> materials;            // one per layer, from the bottom (z min) up
  std::vector<double> layer_boundaries;       // m above the bottom face, materials.size() − 1,
                                              // strictly increasing inside (0, nz·h)
  std::vector<BoxMuscleSpec> muscles;
  std::vector<std::string> rigid_faces;  // any of x_min, x_max, y_min, y_max, z_min, z_max
  std::string created;                   // provenance time; empty: now (UTC)
};

// The six face names in the order of the node sets.
inline constexpr std::array<const char*, 6> kBoxFaces = {"x_min", "x_max", "y_min",
                                                         "y_max", "z_min", "z_max"};

// Builds the model; throws ConfigError (field = the spec item) for an impossible spec. The model's
// provenance records the tool "sinew::formats::make_box_model" and every spec value as JSON.
Model make_box_model(const BoxSpec& spec);

// A TLED neo-Hookean material stated by its shear modulus μ (Pa), as in physics-notes §7, rather
// than by E as make_neo_hookean_material takes it: E = 2μ(1+ν), κ = E / (3(1−2ν)), μ kept exactly
// as given.
Material make_neo_hookean_material_from_shear(std::string name, double shear_modulus,
                                              double poisson_ratio, double density);

}  // namespace sinew::formats
