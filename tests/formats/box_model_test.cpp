// The box generator: counts, numbering, face sets, layer fractions and volumes, muscles, rigid
// faces, and its errors.
#include "sinew/formats/box_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "sinew/common/error.hpp"
#include "sinew/formats/summary.hpp"
#include "sinew/formats/validate.hpp"

namespace sinew::formats {
namespace {

BoxSpec basic_spec() {
  BoxSpec spec;
  spec.dims = {5, 4, 3};
  spec.voxel_size = 2e-3;
  spec.origin = {0.1, 0.2, 0.3};
  spec.materials = {make_neo_hookean_material("gel", 3000, 0.45, 1000)};
  spec.created = "2026-01-01T00:00:00Z";
  return spec;
}

// By value: a reference return with a temporary name argument trips g++ 13's -Wdangling-reference.
NamedSet find_set(const std::vector<NamedSet>& sets, const std::string& name) {
  for (const auto& s : sets) {
    if (s.name == name) return s;
  }
  throw std::runtime_error("no set " + name);
}

TEST(BoxModel, CountsNumberingAndValidity) {
  const Model m = make_box_model(basic_spec());
  EXPECT_EQ(m.node_count(), 6u * 5u * 4u);
  EXPECT_EQ(m.element_count(), 5u * 4u * 3u);
  EXPECT_NO_THROW(validate_model(m, "<memory>"));
  // Element (i, j, k) = i + nx (j + ny k); node (i, j, k) = i + (nx+1) (j + (ny+1) k).
  const std::size_t e = 2 + 5 * (1 + 4 * 2);
  EXPECT_EQ(m.element_lattice[e], (Lattice{2, 1, 2}));
  EXPECT_EQ(m.element_nodes[e][0], 2 + 6 * (1 + 5 * 2));
  EXPECT_EQ(m.element_nodes[e][1], m.element_nodes[e][0] + 1);
  EXPECT_EQ(m.element_nodes[e][3], m.element_nodes[e][0] + 6);
  EXPECT_EQ(m.element_nodes[e][4], m.element_nodes[e][0] + 30);
  EXPECT_EQ(m.element_nodes[e][6], m.element_nodes[e][0] + 37);
  const auto p = m.node_position(m.element_nodes[e][6]);
  EXPECT_DOUBLE_EQ(p[0], 0.1 + 3 * 2e-3);
  EXPECT_DOUBLE_EQ(p[1], 0.2 + 2 * 2e-3);
  EXPECT_DOUBLE_EQ(p[2], 0.3 + 3 * 2e-3);
  // Single material, every voxel full.
  EXPECT_EQ(m.material_ids.size(), m.element_count());
  for (const double f : m.material_fractions) EXPECT_EQ(f, 1.0);
  EXPECT_TRUE(m.rigid_nodes.empty());
  EXPECT_TRUE(m.muscles.empty());
  EXPECT_EQ(m.provenance.tool, "sinew::formats::make_box_model");
  EXPECT_EQ(m.provenance.created, "2026-01-01T00:00:00Z");
  const auto params = nlohmann::json::parse(m.provenance.parameters_json);
  EXPECT_EQ(params["dims"], nlohmann::json::array({5, 4, 3}));
  EXPECT_EQ(params["voxel_size"], 2e-3);
}

TEST(BoxModel, FaceNodeSets) {
  const Model m = make_box_model(basic_spec());
  const std::array<std::size_t, 6> sizes = {5 * 4, 5 * 4, 6 * 4, 6 * 4, 6 * 5, 6 * 5};
  ASSERT_GE(m.node_sets.size(), 6u);
  for (std::size_t f = 0; f < 6; ++f) {
    const auto& set = m.node_sets[f];
    EXPECT_EQ(set.name, kBoxFaces[f]);
    EXPECT_EQ(set.ids.size(), sizes[f]) << set.name;
    const std::size_t axis = f / 2;
    const double h = 2e-3;
    const double expected =
        basic_spec().origin[axis] + (f % 2 == 0 ? 0.0 : basic_spec().dims[axis] * h);
    for (const Index n : set.ids)
      EXPECT_NEAR(m.node_position(n)[axis], expected, 1e-15) << set.name;
  }
  const auto& all = find_set(m.element_sets, "all");
  EXPECT_EQ(all.ids.size(), m.element_count());
  EXPECT_EQ(find_set(m.element_sets, "material_gel").ids.size(), m.element_count());
}

TEST(BoxModel, FractionalLayersAndTheirVolumes) {
  BoxSpec spec = basic_spec();
  spec.dims = {2, 2, 4};
  spec.voxel_size = 1e-3;
  spec.materials = {make_neo_hookean_material("bone", 1e9, 0.3, 1900),
                    make_neo_hookean_material("fat", 3000, 0.49, 900),
                    make_neo_hookean_material("skin", 5e4, 0.49, 1100)};
  spec.layer_boundaries = {0.7e-3, 3e-3};  // bone 0.7 voxel, fat 2.3 voxels, skin 1 voxel
  const Model m = make_box_model(spec);
  EXPECT_NO_THROW(validate_model(m, "<memory>"));
  // Row k = 0: bone 0.7 + fat 0.3; rows 1, 2: fat; row 3: skin (boundary 3 mm is a voxel face).
  const auto row = [&](std::size_t e) {
    std::vector<std::pair<Index, double>> r;
    for (auto i = m.material_offsets[e]; i < m.material_offsets[e + 1]; ++i) {
      r.emplace_back(m.material_ids[static_cast<std::size_t>(i)],
                     m.material_fractions[static_cast<std::size_t>(i)]);
    }
    return r;
  };
  const auto r0 = row(0);
  ASSERT_EQ(r0.size(), 2u);
  EXPECT_EQ(r0[0].first, 0);
  EXPECT_NEAR(r0[0].second, 0.7, 1e-12);
  EXPECT_EQ(r0[1].first, 1);
  EXPECT_NEAR(r0[1].second, 0.3, 1e-12);
  EXPECT_EQ(row(4 * 1).size(), 1u);
  const auto r3 = row(4 * 3);
  ASSERT_EQ(r3.size(), 1u) << "a boundary on a voxel face leaves no sliver";
  EXPECT_EQ(r3[0].first, 2);
  EXPECT_EQ(r3[0].second, 1.0);
  for (std::size_t e = 0; e < m.element_count(); ++e) {
    double sum = 0;
    for (const auto& [id, f] : row(e)) sum += f;
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  // Volumes: cross-section 2 mm × 2 mm times each layer's thickness.
  const auto s = summarize(m);
  const double area = 4e-6;
  EXPECT_NEAR(s.materials[0].volume, area * 0.7e-3, 1e-20);
  EXPECT_NEAR(s.materials[1].volume, area * 2.3e-3, 1e-20);
  EXPECT_NEAR(s.materials[2].volume, area * 1.0e-3, 1e-20);
  EXPECT_NEAR(s.tissue_volume, area * 4e-3, 1e-20);
  EXPECT_EQ(s.materials[0].elements, 4u);
  EXPECT_EQ(s.materials[1].elements, 12u);
  EXPECT_EQ(find_set(m.element_sets, "material_fat").ids.size(), 12u);
}

TEST(BoxModel, MuscleSubBoxAndRigidFaces) {
  BoxSpec spec = basic_spec();
  BoxMuscleSpec mu;
  mu.name = "zygomaticus";
  mu.element_min = {1, 0, 1};
  mu.element_max = {4, 2, 3};
  mu.fibre = {3, 4, 0};
  mu.fraction = 0.8;
  spec.muscles = {mu};
  spec.rigid_faces = {"z_min", "x_min"};
  const Model m = make_box_model(spec);
  ASSERT_EQ(m.muscles.size(), 1u);
  const auto& muscle = m.muscles[0];
  EXPECT_EQ(muscle.elements.size(), 3u * 2u * 2u);
  EXPECT_EQ(muscle.elements.front(), 1 + 5 * (0 + 4 * 1));
  EXPECT_EQ(muscle.elements.back(), 3 + 5 * (1 + 4 * 2));
  for (const auto& f : muscle.fibres) {
    EXPECT_DOUBLE_EQ(f[0], 0.6);
    EXPECT_DOUBLE_EQ(f[1], 0.8);
    EXPECT_EQ(f[2], 0.0);
  }
  for (const double f : muscle.fractions) EXPECT_EQ(f, 0.8);
  EXPECT_EQ(find_set(m.element_sets, "muscle_zygomaticus").ids, muscle.elements);
  // z_min (6 × 5) ∪ x_min (5 × 4) share the edge i = 0, k = 0 (5 nodes).
  EXPECT_EQ(m.rigid_nodes.size(), 30u + 20u - 5u);
  const auto s = summarize(m);
  EXPECT_NEAR(s.muscles[0].volume, 12 * 0.8 * 8e-9, 1e-20);
}

TEST(BoxModel, BadSpecsAreConfigErrors) {
  auto expect_error = [](const BoxSpec& spec, const std::string& field, const std::string& part) {
    try {
      (void)make_box_model(spec);
      ADD_FAILURE() << "no error for " << field;
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.field(), field);
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  BoxSpec s = basic_spec();
  s.dims = {0, 1, 1};
  expect_error(s, "dims", "at least 1");
  s = basic_spec();
  s.voxel_size = -1;
  expect_error(s, "voxel_size", "must be positive");
  s = basic_spec();
  s.materials.push_back(make_neo_hookean_material("b", 1, 0.3, 1));
  expect_error(s, "layer_boundaries", "2 materials need 1 layer boundaries, got 0");
  s.layer_boundaries = {6e-3};  // nz h = 6 mm
  expect_error(s, "layer_boundaries", "must increase strictly inside");
  s = basic_spec();
  BoxMuscleSpec mu;
  mu.element_min = {0, 0, 0};
  mu.element_max = {6, 1, 1};
  s.muscles = {mu};
  expect_error(s, "muscles[0]", "outside [0, 5)");
  s.muscles[0].element_max = {1, 1, 1};
  s.muscles[0].fibre = {0, 0, 0};
  expect_error(s, "muscles[0]", "fibre direction is zero");
  s = basic_spec();
  s.rigid_faces = {"top"};
  expect_error(s, "rigid_faces", "unknown face 'top'");
  s = basic_spec();
  s.materials[0] = make_neo_hookean_material("gel", 3000, 0.5, 1000);
  expect_error(s, "/materials/poisson_ratio",
               "[0]: material 'gel': Poisson ratio 0.5 outside (-1, 0.5)");
}

}  // namespace
}  // namespace sinew::formats
