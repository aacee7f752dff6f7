// The model summary (text and JSON) on the every-feature model, against numbers worked out by hand.
#include "sinew/formats/summary.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_models.hpp"

namespace sinew::formats {
namespace {

// every_feature_model(): 4 × 3 × 3 voxels of 1 mm at (0.01, −0.02, 0.005); fat below 1.5 mm,
// muscle tissue above; element 0 (fat only) is half full.
constexpr double kH3 = 1e-9;

TEST(Summary, NumbersOfTheEveryFeatureModel) {
  const auto s = summarize(testing::every_feature_model());
  EXPECT_EQ(s.nodes, 80u);
  EXPECT_EQ(s.elements, 36u);
  EXPECT_NEAR(s.bbox_min[0], 0.01, 1e-15);
  EXPECT_NEAR(s.bbox_min[1], -0.02, 1e-15);
  EXPECT_NEAR(s.bbox_min[2], 0.005, 1e-15);
  EXPECT_NEAR(s.bbox_max[0], 0.014, 1e-15);
  EXPECT_NEAR(s.bbox_max[1], -0.017, 1e-15);
  EXPECT_NEAR(s.bbox_max[2], 0.008, 1e-15);
  EXPECT_NEAR(s.voxel_volume, 36 * kH3, 1e-21);
  // fat: 12 voxels × 1.5 layers minus half of element 0; muscle tissue: 12 × 1.5.
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].name, "fat");
  EXPECT_NEAR(s.materials[0].volume, (18 - 0.5) * kH3, 1e-21);
  EXPECT_EQ(s.materials[0].elements, 24u);
  EXPECT_NEAR(s.materials[1].volume, 18 * kH3, 1e-21);
  EXPECT_EQ(s.materials[1].elements, 24u);
  EXPECT_NEAR(s.tissue_volume, 35.5 * kH3, 1e-21);
  ASSERT_EQ(s.muscles.size(), 2u);
  EXPECT_NEAR(s.muscles[0].volume, 12 * kH3, 1e-21);
  EXPECT_NEAR(s.muscles[1].volume, 12 * 0.6 * kH3, 1e-21);
  EXPECT_EQ(s.muscles[1].elements, 12u);
  EXPECT_EQ(s.rigid_nodes, 20u);    // z_min: 5 × 4
  EXPECT_EQ(s.sliding_nodes, 12u);  // x_min without its bottom row: 4 × 3
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.surfaces[0].sliding_nodes, 12u);
  EXPECT_FALSE(s.surfaces[0].embedded);
  EXPECT_EQ(s.surfaces[1].vertices, 20u);
  EXPECT_EQ(s.surfaces[1].triangles, 24u);
  EXPECT_TRUE(s.surfaces[1].embedded);
  EXPECT_EQ(s.node_sets.size(), 7u);
  EXPECT_EQ(s.element_sets.back().name, "corner");
}

TEST(Summary, TextNamesEverything) {
  const std::string text = summary_text(summarize(testing::every_feature_model()));
  for (const char* part :
       {"grid: 4 x 3 x 3 voxels of 0.001 m, origin (0.01, -0.02, 0.005) m",
        "nodes: 80, elements: 36", "bounding box: (0.01, -0.02, 0.005) to (0.014, -0.017, 0.008) m",
        "  fat: 1.75e-08 m^3 in 24 elements", "  frontalis_right: 7.2e-09 m^3 in 12 elements",
        "constraints: 20 rigid nodes, 12 sliding nodes, 12 jaw nodes",
        "  skull (sliding): 4 vertices, 2 triangles, 12 sliding nodes",
        "  skin (visual): 20 vertices, 24 triangles, embedded", "x_min (16)", "corner (3)",
        "provenance: tool 'formats test' version '0.1.0', created '2026-11-21T06:49:00Z'",
        "  input meshes/skin.obj sha256 ", "parameters {\"voxel_size\":0.001"}) {
    EXPECT_NE(text.find(part), std::string::npos) << "missing '" << part << "' in\n" << text;
  }
}

TEST(Summary, JsonCarriesTheSameNumbers) {
  const auto j = nlohmann::json::parse(summary_json(summarize(testing::every_feature_model())));
  EXPECT_EQ(j["format"], "sinew-model");
  EXPECT_EQ(j["format_version"], 3);
  EXPECT_EQ(j["jaw_nodes"], 12);
  EXPECT_EQ(j["nodes"], 80);
  EXPECT_EQ(j["elements"], 36);
  EXPECT_EQ(j["grid"]["dims"], nlohmann::json::array({4, 3, 3}));
  EXPECT_NEAR(j["materials"][0]["volume"].get<double>(), 17.5e-9, 1e-21);
  EXPECT_EQ(j["muscles"][1]["name"], "frontalis_right");
  EXPECT_EQ(j["rigid_nodes"], 20);
  EXPECT_EQ(j["sliding_nodes"], 12);
  EXPECT_EQ(j["surfaces"][1]["role"], "visual");
  EXPECT_EQ(j["node_sets"]["skull_contact"], 12);
  EXPECT_EQ(j["provenance"]["inputs"][1]["path"], "meshes/skull.obj");
  EXPECT_EQ(j["provenance"]["parameters"]["note"], "every feature");
  EXPECT_NEAR(j["bounding_box"]["max"][2].get<double>(), 0.008, 1e-15);
}

// A name that is not UTF-8 (bytes from a damaged file) prints as U+FFFD, not as JSON's exception.
TEST(Summary, JsonOfANameThatIsNotUtf8) {
  auto model = testing::every_feature_model();
  model.muscles[1].name = "bad\xff";
  const auto j = nlohmann::json::parse(summary_json(summarize(model)));
  EXPECT_EQ(j["muscles"][1]["name"], "bad\xef\xbf\xbd");
}

}  // namespace
}  // namespace sinew::formats
