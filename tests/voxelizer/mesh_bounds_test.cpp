// Bounds on what a spec's meshes may make (mesh_bounds.hpp; issue 33): a mesh far larger than the
// spec's units allow, more elements than resolution.max_elements, an inside-out mesh that cannot
// be flipped. Each is an error naming the file (or the spec), and a warning with --force.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "pipeline_test_util.hpp"
#include "sinew/common/error.hpp"
#include "sinew/voxelizer/mesh_bounds.hpp"
#include "sinew/voxelizer/primitives.hpp"

namespace sinew::voxelizer {
namespace {

using testing::TempDir;

std::string spec_with(const std::string& outer, const std::string& resolution = "voxel_size: 5",
                      const std::string& units = "mm") {
  return "units: " + units + "\nresolution: {" + resolution + "}\nouter: " + outer +
         "\nmaterials: {preset: warburton2013}\nlayers: [{material: dermis}]\n";
}

// The GeometryError voxelize throws for the spec.
std::string geometry_error(const std::string& yaml, const std::filesystem::path& file) {
  return testing::expect_error<GeometryError>(yaml, file);
}

VoxelizeResult forced(const std::string& yaml, const std::filesystem::path& file) {
  VoxelizeOptions o;
  o.force = true;
  return voxelize(parse_spec(yaml, file), o);
}

bool has_warning(const Summary& s, const std::string& text) {
  return std::any_of(s.warnings.begin(), s.warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

// A 2.2 m long mesh in a spec in mm (a damaged STL made one): refused with the file, the extent
// and the units; in a spec in metres the same numbers are 2.2 mm and pass.
TEST(MeshBounds, AMeshSpanningMoreThanAThousandOfTheSpecsUnitsIsRefused) {
  TempDir dir;
  testing::write_obj(make_box({0, 0, 0}, {2200, 10, 10}, 0), dir / "long.obj");
  const std::string what = geometry_error(spec_with("long.obj"), dir / "s.yaml");
  EXPECT_NE(what.find("long.obj"), std::string::npos) << what;
  EXPECT_NE(what.find("spans 2200 mm along x"), std::string::npos) << what;
  EXPECT_NE(what.find("more than 1000 mm (the spec's units)"), std::string::npos) << what;
  const auto r = forced(spec_with("long.obj"), dir / "s.yaml");
  EXPECT_GT(r.summary.elements, 0);
  EXPECT_TRUE(has_warning(r.summary, "going on (--force)"));
  // The same file read in mm inside a spec in metres: 2.2 m, within 1000 m.
  EXPECT_NO_THROW(voxelize(parse_spec(
      spec_with("{path: long.obj, unit: mm}", "voxel_size: 0.005", "m"), dir / "s.yaml")));
}

TEST(MeshBounds, MoreElementsThanTheLimitAreRefusedBeforeTheFractions) {
  TempDir dir;
  const std::string yaml = spec_with("{sphere: {radius: 10}}", "voxel_size: 1, max_elements: 500");
  const std::string what = geometry_error(yaml, dir / "s.yaml");
  EXPECT_NE(what.find("s.yaml: resolution:"), std::string::npos) << what;
  EXPECT_NE(what.find("more than resolution.max_elements (500)"), std::string::npos) << what;
  EXPECT_GT(forced(yaml, dir / "s.yaml").summary.elements, 500);
  EXPECT_EQ(kDefaultMaxElements, 10'000'000);
}

// Inside out with a hole: not closed, so it cannot be flipped, and its winding number is -1
// inside. A closed mesh pointing inward is still flipped with a warning.
TEST(MeshBounds, AnInsideOutMeshThatCannotBeFlippedIsRefused) {
  TempDir dir;
  TriangleMesh box = make_box({0, 0, 0}, {20, 20, 20}, 1);
  flip_orientation(box);
  testing::write_obj(box, dir / "inward.obj");
  const auto closed = voxelize(parse_spec(spec_with("inward.obj"), dir / "s.yaml"));
  EXPECT_TRUE(has_warning(closed.summary, "oriented inward; triangles flipped"));
  box.triangles.pop_back();
  testing::write_obj(box, dir / "holed.obj");
  const std::string what = geometry_error(spec_with("holed.obj"), dir / "s.yaml");
  EXPECT_NE(what.find("holed.obj"), std::string::npos) << what;
  EXPECT_NE(what.find("negative volume"), std::string::npos) << what;
  // Forced past the bound, the winding number (-1 inside) finds no tissue.
  try {
    forced(spec_with("holed.obj"), dir / "s.yaml");
    ADD_FAILURE() << "no error";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("no tissue"), std::string::npos) << e.what();
  }
}

TEST(MeshBounds, MessagesGiveLengthsInTheSpecsUnits) {
  EXPECT_EQ(format_length(2.2, LengthUnit::mm), "2200 mm");
  EXPECT_EQ(format_length(0.015, LengthUnit::cm), "1.5 cm");
  TriangleMesh m = make_box({0, 0, 0}, {0.5, 0.2, 0.1}, 0);
  EXPECT_FALSE(extent_problem(m, LengthUnit::mm));
  m = make_box({0, 0, 0}, {0.5, 1.5, 0.1}, 0);
  ASSERT_TRUE(extent_problem(m, LengthUnit::mm));
  EXPECT_NE(extent_problem(m, LengthUnit::mm)->find("1500 mm along y"), std::string::npos);
  EXPECT_FALSE(extent_problem(m, LengthUnit::cm));
}

}  // namespace
}  // namespace sinew::voxelizer
