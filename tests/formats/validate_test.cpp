// The validator on in-memory models: checks that are awkward to reach through a file, and the
// promise that every check names its dataset.
#include "sinew/formats/validate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "sinew/common/error.hpp"
#include "test_models.hpp"

namespace sinew::formats {
namespace {

// Applies `breakage` to a valid model and returns the validator's error.
FormatError broken(const std::function<void(Model&)>& breakage) {
  Model m = testing::every_feature_model();
  breakage(m);
  try {
    validate_model(m, "mem.h5");
  } catch (const FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "the validator accepted a broken model";
  return FormatError("", "", "");
}

// Expects `breakage` to make the validator name `dataset` and say `part`.
void expect_invalid(const std::function<void(Model&)>& breakage, const std::string& dataset,
                    const std::string& part) {
  const FormatError e = broken(breakage);
  EXPECT_EQ(e.file(), "mem.h5");
  EXPECT_EQ(e.field(), dataset) << e.what();
  EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
}

TEST(Validate, EveryFeatureModelIsValid) {
  EXPECT_NO_THROW(validate_model(testing::every_feature_model(), "mem.h5"));
}

TEST(Validate, GridAndLattice) {
  expect_invalid([](Model& m) { m.grid.voxel_size = 0; }, "/grid/voxel_size", "must be positive");
  expect_invalid([](Model& m) { m.grid.origin[1] = INFINITY; }, "/grid/origin", "not finite");
  expect_invalid([](Model& m) { m.grid.dims[2] = 2; }, "/elements/lattice",
                 "outside the grid of 4 × 3 × 2 voxels");
  expect_invalid([](Model& m) { std::swap(m.element_lattice[0], m.element_lattice[1]); },
                 "/elements/lattice",
                 "elements not sorted by (k, j, i) and unique: (0, 0, 0) follows (1, 0, 0)");
  expect_invalid(
      [](Model& m) {
        m.element_lattice.clear();
        m.element_nodes.clear();
      },
      "/elements/lattice", "the model has no elements");
  expect_invalid([](Model& m) { m.element_nodes.pop_back(); }, "/elements/nodes",
                 "has 35 rows, expected 36 (one row per element)");
  expect_invalid(
      [](Model& m) {
        m.node_lattice.push_back({4, 3, 4});
      },
      "/nodes/lattice", "node lattice point (4, 3, 4) outside the lattice");
  expect_invalid(
      [](Model& m) {
        // Drop the last element: its far corner (4, 3, 3) becomes an orphan node.
        m.element_lattice.pop_back();
        m.element_nodes.pop_back();
        m.material_offsets.pop_back();
      },
      "/nodes/lattice", "node (4, 3, 3) is not a corner of any element");
}

TEST(Validate, MaterialsAndFractions) {
  expect_invalid([](Model& m) { m.materials[1].name = "fat"; }, "/materials/name",
                 "duplicate material name 'fat'");
  expect_invalid([](Model& m) { m.materials[0].name.clear(); }, "/materials/name",
                 "material name is empty");
  expect_invalid([](Model& m) { m.materials[0].density = -1; }, "/materials/density",
                 "density must be positive");
  expect_invalid([](Model& m) { m.materials[0].bulk_modulus *= 1.001; }, "/materials/bulk_modulus",
                 "inconsistent with E/(3(1-2nu))");
  expect_invalid([](Model& m) { m.material_ids[13] = m.material_ids[12]; },
                 "/element_materials/material", "element 12: material 0 listed twice");
  expect_invalid([](Model& m) { m.material_offsets[0] = 1; }, "/element_materials/offsets",
                 "first offset must be 0");
  expect_invalid([](Model& m) { m.material_fractions.pop_back(); }, "/element_materials/fraction",
                 "has 47 rows, expected 48 (as many as /element_materials/material)");
  // Within the tolerance: a sum of 1 + 5e-7 passes (element 12 holds 0.5 fat + 0.5 tissue).
  Model m = testing::every_feature_model();
  m.material_fractions[13] = 0.5 + 5e-7;
  EXPECT_NO_THROW(validate_model(m, "mem.h5"));
}

TEST(Validate, Muscles) {
  expect_invalid([](Model& m) { m.muscles[1].name = m.muscles[0].name; }, "/muscles/name",
                 "duplicate muscle name");
  expect_invalid([](Model& m) { m.muscles[0].material = 2; }, "/muscles/material",
                 "material id 2 out of range [0, 2)");
  expect_invalid([](Model& m) { m.muscles[0].passive_linear_stretch = 1.0; },
                 "/muscles/passive_linear_stretch", "must be finite and > 1");
  expect_invalid([](Model& m) { m.muscles[0].optimal_stretch = 0; }, "/muscles/optimal_stretch",
                 "> 0");
  expect_invalid([](Model& m) { std::swap(m.muscles[1].elements[0], m.muscles[1].elements[1]); },
                 "/muscles/elements",
                 "muscle 'frontalis_right': element ids not sorted and unique");
  expect_invalid([](Model& m) { m.muscles[1].fibres.pop_back(); }, "/muscles/offsets",
                 "12 elements but 12 fractions and 11 fibres");
  // Within the tolerance: |f| = 1 + 5e-7 passes.
  Model m = testing::every_feature_model();
  m.muscles[0].fibres[0] = {0, 0, 1.0 + 5e-7};
  EXPECT_NO_THROW(validate_model(m, "mem.h5"));
}

TEST(Validate, SurfacesAndConstraints) {
  expect_invalid(
      [](Model& m) {
        m.surfaces[1].triangles[0] = {0, 0, 1};
      },
      "/surfaces/triangles", "triangle (0, 0, 1) repeats a vertex");
  expect_invalid([](Model& m) { m.surfaces[1].embedding_local.pop_back(); },
                 "/surfaces/embedding_offsets", "one per vertex expected");
  expect_invalid(
      [](Model& m) {
        m.surfaces[0].embedding_element = {0, 0, 0, 0};
      },
      "/surfaces/embedding_offsets", "only visual surfaces carry an embedding");
  expect_invalid([](Model& m) { m.surfaces[1].name = "skull"; }, "/surfaces/name",
                 "duplicate surface name 'skull'");
  expect_invalid(
      [](Model& m) {
        m.rigid_nodes.push_back(m.sliding[0].node);
        std::sort(m.rigid_nodes.begin(), m.rigid_nodes.end());
      },
      "/constraints/sliding_node", "is both rigid and sliding");
  expect_invalid([](Model& m) { std::swap(m.rigid_nodes[0], m.rigid_nodes[1]); },
                 "/constraints/rigid_nodes", "node ids not sorted and unique");
  expect_invalid([](Model& m) { m.sliding[1].node = m.sliding[0].node; },
                 "/constraints/sliding_node", "sliding nodes not sorted and unique");
  expect_invalid([](Model& m) { m.sliding[2].rest_distance = -1e-3; },
                 "/constraints/sliding_rest_distance", "must be finite and >= 0");
  // Texture coordinates (format version 2).
  expect_invalid([](Model& m) { m.surfaces[1].uv_triangles.pop_back(); },
                 "/surfaces/uv_triangle_offsets",
                 "surface 'skin': 23 rows of texture corners for 24 triangles");
  expect_invalid([](Model& m) { m.surfaces[1].uv_triangles[5][2] = 20; }, "/surfaces/uv_triangles",
                 "surface 'skin': texture coordinate id 20 out of range [0, 20)");
  expect_invalid([](Model& m) { m.surfaces[1].uvs[7][1] = std::nan(""); }, "/surfaces/uvs",
                 "texture coordinate (0.5, nan) is not finite");
  expect_invalid(
      [](Model& m) {
        m.surfaces[0].uvs = {{0.0, 0.0}};
      },
      "/surfaces/uv_offsets", "only visual surfaces carry texture coordinates");
  // Embedding on the boundary within the tolerance passes.
  Model m = testing::every_feature_model();
  m.surfaces[1].embedding_local[0][0] = -1.0 - 5e-10;
  EXPECT_NO_THROW(validate_model(m, "mem.h5"));
}

TEST(Validate, NamedSetsAndProvenance) {
  expect_invalid([](Model& m) { m.node_sets[0].name = "a/b"; }, "/node_sets",
                 "invalid set name 'a/b'");
  expect_invalid([](Model& m) { m.element_sets[1].name = "all"; }, "/element_sets",
                 "duplicate set name 'all'");
  expect_invalid([](Model& m) { m.provenance.inputs[0].sha256 = "abc"; },
                 "/provenance/input_sha256", "'abc' is not a SHA-256 digest");
  expect_invalid([](Model& m) { m.provenance.parameters_json = "{voxel_size: 1"; },
                 "/provenance/parameters_json", "not a valid JSON document");
  EXPECT_TRUE(is_valid_set_name("skull_contact"));
  EXPECT_TRUE(is_valid_set_name("frontalis left"));
  EXPECT_FALSE(is_valid_set_name(""));
  EXPECT_FALSE(is_valid_set_name("."));
  EXPECT_FALSE(is_valid_set_name("caf\xc3\xa9"));
}

}  // namespace
}  // namespace sinew::formats
