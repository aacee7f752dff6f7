// sinew-inspect --element / --node (describe.hpp): on a generated two-layer box with a muscle, a
// rigid face and one sliding node on a plane under the box, every fact the text states is the
// model's: lattice, centre, material fractions (the layer boundary cuts the element in 0.5 / 0.5),
// the muscle's fraction and fibre, the corners' constraints (the sliding node's side of its
// surface), neighbours (absent past the box's faces), sets and out-of-range ids.
#include "sinew/formats/describe.hpp"

#include <gtest/gtest.h>

#include <string>

#include "sinew/common/error.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/formats/validate.hpp"

namespace sinew::formats {
namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

Model sample() {
  BoxSpec spec;
  spec.dims = {3, 3, 2};
  spec.voxel_size = 1e-3;
  spec.materials = {make_neo_hookean_material("soft", 3000, 0.49, 1000),
                    make_neo_hookean_material("firm", 30000, 0.45, 1100)};
  spec.layer_boundaries = {0.5e-3};  // cuts the bottom layer of elements in half
  BoxMuscleSpec mu;
  mu.name = "band";
  mu.material = 1;
  mu.element_min = {0, 0, 1};
  mu.element_max = {3, 3, 2};
  mu.fibre = {0, 1, 0};
  mu.fraction = 0.75;
  spec.muscles = {mu};
  spec.rigid_faces = {"x_min"};
  spec.created = "2026-01-01T00:00:00Z";
  Model m = make_box_model(spec);
  // Node 1 (lattice (1, 0, 0)) slides on a plane 0.25 mm ABOVE it (normal +z): it lies behind it.
  Surface plane;
  plane.name = "floor";
  plane.role = SurfaceRole::sliding;
  plane.vertices = {{-1e-3, -1e-3, 0.25e-3}, {4e-3, -1e-3, 0.25e-3}, {4e-3, 4e-3, 0.25e-3}};
  plane.triangles = {{0, 1, 2}};
  m.surfaces.push_back(plane);
  m.sliding.push_back({1, Index(m.surfaces.size() - 1), 0.25e-3, 0});
  return m;
}

TEST(Describe, ElementStatesItsMaterialsMusclesCornersAndNeighbours) {
  const Model m = sample();
  ASSERT_NO_THROW(validate_model(m, "sample"));
  // Element 0: lattice (0, 0, 0), centre (0.5, 0.5, 0.5) mm, soft 0.5 and firm 0.5, no muscle.
  const std::string e0 = describe_element(m, 0);
  EXPECT_TRUE(contains(e0, "element 0 of 18")) << e0;
  EXPECT_TRUE(contains(e0, "lattice      (0, 0, 0)")) << e0;
  EXPECT_TRUE(contains(e0, "centre       (0.5, 0.5, 0.5) mm")) << e0;
  EXPECT_TRUE(contains(e0, "soft                 fraction 0.5000")) << e0;
  EXPECT_TRUE(contains(e0, "firm                 fraction 0.5000")) << e0;
  EXPECT_TRUE(contains(e0, "tissue fraction 1.0000")) << e0;
  EXPECT_TRUE(contains(e0, "muscles\n    none")) << e0;
  EXPECT_TRUE(contains(e0, "0 node 0         (0, 0, 0) mm  rigid")) << e0;
  EXPECT_TRUE(contains(e0,
                       "1 node 1         (1, 0, 0) mm  sliding on 'floor' (rest distance 0.25 "
                       "mm, rest triangle 0, behind its plane by 0.25 mm: the simulator moves "
                       "it out to the surface's outer side)"))
      << e0;
  EXPECT_TRUE(contains(e0, "2 node 5         (1, 1, 0) mm  free")) << e0;
  // Element (i, j, k) is i + 3 (j + 3 k): +x 1, +y 3, +z 9; nothing at -x, -y, -z.
  EXPECT_TRUE(contains(e0, "neighbours   -x none, +x 1, -y none, +y 3, -z none, +z 9")) << e0;
  EXPECT_TRUE(contains(e0, "element sets all, material_soft, material_firm")) << e0;
  // Element 13 = (1, 1, 1): all firm (its passive tissue), the muscle at 0.75 along y.
  const std::string e13 = describe_element(m, 13);
  EXPECT_TRUE(contains(e13, "firm                 fraction 1.0000")) << e13;
  EXPECT_TRUE(contains(e13, "band                 fraction 0.7500, fibre (0.0000, 1.0000, 0.0000)"))
      << e13;
  EXPECT_TRUE(contains(e13, "neighbours   -x 12, +x 14, -y 10, +y 16, -z 4, +z none")) << e13;
  EXPECT_THROW(describe_element(m, 18), ConfigError);
  EXPECT_THROW(describe_element(m, -1), ConfigError);
}

TEST(Describe, NodeStatesItsConstraintSetsAndElements) {
  const Model m = sample();
  // Node 21 = (1, 1, 1): interior, free, corner of 8 elements; node (i, j, k) = i + 4 (j + 4 k).
  const std::string n21 = describe_node(m, 21);
  EXPECT_TRUE(contains(n21, "position     (1, 1, 1) mm")) << n21;
  EXPECT_TRUE(contains(n21, "constraint   free")) << n21;
  EXPECT_TRUE(contains(n21, "node sets    none")) << n21;
  // Corner 6 (1, 1, 1) of element 0; corner 0 of element 13 (muscle band, firm).
  EXPECT_TRUE(contains(n21, "6: element 0         soft 0.5000, muscles: none")) << n21;
  EXPECT_TRUE(contains(n21, "0: element 13        firm 1.0000, muscles: band")) << n21;
  EXPECT_TRUE(contains(n21, "neighbours   -x 20, +x 22, -y 17, +y 25, -z 5, +z 37")) << n21;
  const std::string n0 = describe_node(m, 0);
  EXPECT_TRUE(contains(n0, "constraint   rigid")) << n0;
  EXPECT_TRUE(contains(n0, "node sets    x_min, y_min, z_min")) << n0;
  EXPECT_TRUE(contains(n0, "neighbours   -x none, +x 1, -y none, +y 4, -z none, +z 16")) << n0;
  try {
    describe_node(m, 48, "box.h5");
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(contains(e.what(), "box.h5: --node: node 48 out of range [0, 48)")) << e.what();
  }
}

}  // namespace
}  // namespace sinew::formats
