#pragma once
// Models and file helpers shared by the tests of formats/.
#include <hdf5.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/formats/sha256.hpp"

namespace sinew::formats::testing {

// 4 × 3 × 3 voxels of 1 mm; two layers (fat below 1.5 mm, muscle tissue above: the k = 1 row is
// cut in half), two muscles, rigid bottom face, one partly filled element, a sliding plane
// ("skull") next to the x_min face with its bindings, a jaw (the x_max face above the bottom), a
// visual surface ("skin") on the top face embedded in the top elements, extra node/element sets
// and provenance with an input file.
inline Model every_feature_model() {
  BoxSpec spec;
  spec.dims = {4, 3, 3};
  spec.voxel_size = 1e-3;
  spec.origin = {0.01, -0.02, 0.005};
  spec.materials = {make_neo_hookean_material("fat", 3000, 0.49, 900),
                    make_neo_hookean_material("muscle_tissue", 11000, 0.45, 1060)};
  spec.layer_boundaries = {1.5e-3};
  // Two muscles over material 1, the left one with the generator's defaults.
  auto muscle = [](const char* name, Lattice element_min, Lattice element_max, Point fibre) {
    BoxMuscleSpec m;
    m.name = name;
    m.material = 1;
    m.element_min = element_min;
    m.element_max = element_max;
    m.fibre = fibre;
    return m;
  };
  const BoxMuscleSpec left = muscle("frontalis_left", {0, 0, 1}, {2, 3, 3}, {0, 0, 2});
  BoxMuscleSpec right = muscle("frontalis_right", {2, 0, 1}, {4, 3, 3}, {1, 1, 0});
  right.fraction = 0.6;
  right.reference_stress = 3e5;
  right.optimal_stretch = 1.1;
  spec.muscles = {left, right};
  spec.rigid_faces = {"z_min"};
  spec.created = "2026-11-21T06:49:00Z";
  Model m = make_box_model(spec);

  // Element 0 is only partly tissue.
  for (auto i = m.material_offsets[0]; i < m.material_offsets[1]; ++i) {
    m.material_fractions[static_cast<std::size_t>(i)] *= 0.5;
  }

  const double h = spec.voxel_size;
  const auto& o = spec.origin;
  const std::int32_t nx = 4, ny = 3, nz = 3;

  // Sliding plane x = x0 − 0.5 mm, a square in (y, z) with a margin of 1 mm, split along its
  // diagonal into triangle 0 (below: z' <= y') and triangle 1.
  Surface skull;
  skull.name = "skull";
  skull.role = SurfaceRole::sliding;
  const double xs = o[0] - 0.5e-3, y0 = o[1] - 1e-3, y1 = o[1] + (ny + 1) * h, z0 = o[2] - 1e-3,
               z1 = o[2] + (nz + 1) * h;
  skull.vertices = {{xs, y0, z0}, {xs, y1, z0}, {xs, y1, z1}, {xs, y0, z1}};
  skull.triangles = {{0, 2, 1}, {0, 3, 2}};
  m.surfaces.push_back(skull);
  NamedSet contact{"skull_contact", {}};
  for (std::size_t n = 0; n < m.node_lattice.size(); ++n) {
    const auto& l = m.node_lattice[n];
    if (l[0] != 0 || l[2] == 0) continue;  // x_min face, not the rigid bottom
    const auto p = m.node_position(static_cast<Index>(n));
    const double u = (p[1] - y0) / (y1 - y0), v = (p[2] - z0) / (z1 - z0);
    m.sliding.push_back({static_cast<Index>(n), 0, 0.5e-3, v <= u ? 0 : 1});
    contact.ids.push_back(static_cast<Index>(n));
  }

  // Skin: the top face, one vertex per top lattice point, embedded with ζ = 1.
  Surface skin;
  skin.name = "skin";
  skin.role = SurfaceRole::visual;
  for (std::int32_t j = 0; j <= ny; ++j) {
    for (std::int32_t i = 0; i <= nx; ++i) {
      skin.vertices.push_back({o[0] + i * h, o[1] + j * h, o[2] + nz * h});
      const std::int32_t ei = std::min(i, nx - 1), ej = std::min(j, ny - 1);
      skin.embedding_element.push_back(ei + nx * (ej + ny * (nz - 1)));
      skin.embedding_local.push_back({i == ei ? -1.0 : 1.0, j == ej ? -1.0 : 1.0, 1.0});
      skin.uvs.push_back({double(i) / nx, double(j) / ny});
    }
  }
  for (std::int32_t j = 0; j < ny; ++j) {
    for (std::int32_t i = 0; i < nx; ++i) {
      const Index a = i + (nx + 1) * j, b = a + 1, c = a + (nx + 1) + 1, d = a + (nx + 1);
      skin.triangles.push_back({a, b, c});
      skin.triangles.push_back({a, c, d});
    }
  }
  skin.uv_triangles = skin.triangles;  // texture coordinates: the top face mapped onto [0, 1]²
  m.surfaces.push_back(skin);

  // A jaw: the x_max face above the rigid bottom, hinged about a line along y beside it.
  Jaw jaw;
  for (std::size_t n = 0; n < m.node_lattice.size(); ++n) {
    const auto& l = m.node_lattice[n];
    if (l[0] == nx && l[2] > 0) jaw.nodes.push_back(static_cast<Index>(n));
  }
  jaw.pivot = {o[0] + (nx + 1) * h, o[1], o[2] + nz * h};
  jaw.axis = {0, 1, 0};
  jaw.forward = {1, 0, 0};
  jaw.incisal = {o[0] + nx * h, o[1] + h, o[2]};
  m.jaw = jaw;

  m.node_sets.push_back(contact);
  m.element_sets.push_back({"corner", {0, 5, 35}});
  m.provenance.tool = "formats test";
  m.provenance.tool_version = "0.1.0";
  m.provenance.inputs = {{"meshes/skin.obj", sha256_hex("skin")},
                         {"meshes/skull.obj", sha256_hex("skull")}};
  m.provenance.parameters_json = R"({"voxel_size":0.001,"note":"every feature"})";
  return m;
}

// A fresh path in the test temp folder, named after the running test.
inline std::string temp_path(const std::string& suffix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string name = std::string(info->test_suite_name()) + "_" + info->name() + "_" + suffix;
  std::string clean;
  for (const char c : name)
    clean.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '.' ? c : '_');
  const auto path = std::filesystem::path(::testing::TempDir()) / ("sinew_" + clean);
  std::filesystem::remove(path);
  return path.string();
}

inline std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace sinew::formats::testing
