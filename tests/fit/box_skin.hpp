#pragma once
// A small procedural model for the target-shape tests (tests/fit): a block of 10 × 6 × 3 voxels
// of 2 mm (20 × 12 × 6 mm, x along the block) of muscle-like tissue (E = 0.5 MPa, ν = 0.49,
// ρ = 11,000 kg/m³ mass-scaled, as data/scenes/muscle_block.yaml), with two muscles in its top
// two layers, fibres along x: "left" over y ∈ [0, 6] mm and "right" over y ∈ [6, 12] mm. Its
// visual surface "skin" covers the top face (z = 6 mm): a grid of 21 × 13 vertices 1 mm apart,
// vertex (a, b) at (a, b, 6) mm with id a + 21 b, two triangles per cell, counter-clockwise seen
// from +z, each vertex embedded in the top element that holds it (ζ = 1).
#include <cmath>
#include <string>

#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model.hpp"

namespace sinew::fit::testing {

inline constexpr int kSkinColumns = 21, kSkinRows = 13;  // vertices along x and y

inline formats::Model box_with_skin() {
  formats::BoxSpec spec;
  spec.dims = {10, 6, 3};
  spec.voxel_size = 0.002;
  spec.materials = {formats::make_neo_hookean_material("tissue", 500000, 0.49, 11000)};
  for (int half = 0; half < 2; ++half) {
    formats::BoxMuscleSpec m;
    m.name = half == 0 ? "left" : "right";
    m.element_min = {0, 3 * half, 1};
    m.element_max = {10, 3 * half + 3, 3};
    m.fibre = {1, 0, 0};
    spec.muscles.push_back(m);
  }
  spec.created = "2026-01-01T00:00:00Z";
  formats::Model model = formats::make_box_model(spec);
  formats::Surface skin;
  skin.name = "skin";
  skin.role = formats::SurfaceRole::visual;
  const double h = spec.voxel_size;
  for (int b = 0; b < kSkinRows; ++b)
    for (int a = 0; a < kSkinColumns; ++a) {
      const double x = 0.001 * a, y = 0.001 * b, z = 0.006;
      skin.vertices.push_back({x, y, z});
      const int i = std::min(static_cast<int>(std::floor(x / h)), 9);
      const int j = std::min(static_cast<int>(std::floor(y / h)), 5);
      const formats::Lattice base{i, j, 2};
      formats::Index element = -1;
      for (std::size_t e = 0; e < model.element_lattice.size(); ++e)
        if (model.element_lattice[e] == base) element = static_cast<formats::Index>(e);
      skin.embedding_element.push_back(element);
      skin.embedding_local.push_back({2 * (x / h - i) - 1, 2 * (y / h - j) - 1, 1.0});
    }
  for (int b = 0; b + 1 < kSkinRows; ++b)
    for (int a = 0; a + 1 < kSkinColumns; ++a) {
      const formats::Index v = a + kSkinColumns * b;
      skin.triangles.push_back({v, v + 1, v + 1 + kSkinColumns});
      skin.triangles.push_back({v, v + 1 + kSkinColumns, v + kSkinColumns});
    }
  model.surfaces.push_back(skin);
  return model;
}

// The surface as OBJ text (m), with `positions` in place of the rest vertices when given.
inline std::string skin_obj(const formats::Surface& s,
                            const std::vector<formats::Point>& positions = {}) {
  std::string text = "# the box's skin\n";
  const auto& v = positions.empty() ? s.vertices : positions;
  for (const auto& p : v)
    text += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) +
            "\n";
  for (const auto& t : s.triangles)
    text += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
            std::to_string(t[2] + 1) + "\n";
  return text;
}

}  // namespace sinew::fit::testing
