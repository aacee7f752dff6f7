// The jaw's geometry from landmarks (jaw.hpp, docs/faces.md "The jaw"): the sample head's axis,
// pivot and incisal point; the mandible's region and the cut; landmark sets that cannot make a
// mandible refused with the file and the landmark named.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/jaw.hpp"
#include "sinew/voxelizer/landmarks.hpp"

namespace sinew::voxelizer {
namespace {

const std::filesystem::path kSource = SINEW_SOURCE_DIR;

Landmarks sample_head() {
  return read_landmarks(kSource / "data/landmarks/sample_head.yaml");
}

TEST(JawGeometry, TheSampleHeadsAxisPivotAndIncisalPoint) {
  const JawGeometry j = jaw_geometry(sample_head());
  // Tragi (±74.773, 3.490, 6.623) mm; forward (0, −0.0391, 0.9992) from the face's frame.
  EXPECT_NEAR(j.axis.x, 1, 1e-12);
  EXPECT_NEAR(j.pivot.x, 0, 1e-12);
  EXPECT_NEAR(j.pivot.y, 3.0205e-3, 1e-7);
  EXPECT_NEAR(j.pivot.z, 18.6138e-3, 1e-7);
  EXPECT_NEAR(j.incisal.y, -70.9165e-3, 1e-7);
  EXPECT_NEAR(j.incisal.z, 84.4742e-3, 1e-7);
  EXPECT_NEAR(j.half_condyles, 74.773e-3, 1e-9);
  EXPECT_NEAR(j.half_mouth, 27.329e-3, 1e-6);
  // The chin below the lips is the mandible's; the nose's base and the skull behind the joint
  // are not.
  EXPECT_TRUE(in_mandible(j, {0, -95e-3, 60e-3}));
  EXPECT_FALSE(in_mandible(j, {0, -34e-3, 85e-3}));
  EXPECT_FALSE(in_mandible(j, {0, -80e-3, -20e-3}));
  // A voxel between the lips is cut (skin and all), one in the lower lip a voxel below is not;
  // one in the cheek beside the teeth is cut only next to the skull and well under the skin;
  // none behind the last molars (45 mm behind the incisal point).
  const double h = 3e-3;
  const Vec3d between = j.stomion - 3e-3 * j.forward;
  EXPECT_TRUE(in_jaw_cut(j, between, h, -8e-3, 1e-3));
  EXPECT_FALSE(in_jaw_cut(j, between - h * j.up, h, -8e-3, 1e-3));
  const Vec3d cheek = j.stomion + 40e-3 * j.axis - 30e-3 * j.forward;
  EXPECT_FALSE(in_jaw_cut(j, cheek, h, -8e-3, 5e-3));  // far from the bone
  EXPECT_TRUE(in_jaw_cut(j, cheek, h, -1e-3, 5e-3));   // next to it
  EXPECT_FALSE(in_jaw_cut(j, cheek, h, -1e-3, 4e-3));  // next to it, but the skin is near
  const Vec3d behind = j.stomion + 60e-3 * j.axis - 62e-3 * j.forward;
  EXPECT_FALSE(in_jaw_cut(j, behind, h, -1e-3, 5e-3));
}

void expect_refused(Landmarks l, const std::string& landmark, const std::string& problem) {
  l.file = "face_landmarks.yaml";
  try {
    jaw_geometry(l);
    FAIL() << "expected a ConfigError naming " << landmark;
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "face_landmarks.yaml");
    EXPECT_EQ(e.field(), "landmarks." + landmark);
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  }
}

TEST(JawGeometry, LandmarksThatCannotMakeAMandibleAreRefused) {
  {
    Landmarks l = sample_head();
    std::swap(l.points["upper_lip"], l.points["lower_lip"]);
    expect_refused(l, "lower_lip", "the lower lip is not below the upper lip");
  }
  {
    Landmarks l = sample_head();
    std::swap(l.points["mouth_corner_left"], l.points["mouth_corner_right"]);
    expect_refused(l, "mouth_corner_left", "not either side of the lips' middle");
  }
  {
    Landmarks l = sample_head();  // the lips at the tragi's height
    l.points["upper_lip"].y = 10e-3;
    l.points["lower_lip"].y = 0;
    expect_refused(l, "upper_lip", "not at least 20 mm below the tragi");
  }
}

}  // namespace
}  // namespace sinew::voxelizer
