// The preview of a model file (model_preview.hpp, sinew-render MODEL.h5): on a generated block with
// a muscle sub-box whose fibres run along y, the muscle's mesh is exactly its box, every fibre
// streamline runs along y through the muscle from end to end, the muscle shows red through the
// translucent skin (and not through an opaque one), the streamlines are drawn over it along y, and
// the tool writes the preview and refuses frame options on a model.
#include "sinew/postprocess/model_preview.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "export_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/postprocess/png_writer.hpp"

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;

namespace {

constexpr double kH = 1e-3;

// 10 × 10 × 4 voxels of 1 mm; the muscle fills elements x 3..6, y 2..7, z 1..2 (a 4 × 6 × 2 mm box
// from (3, 2, 1) mm), fibres along y.
sinew::formats::Model block_with_muscle() {
  sinew::formats::BoxSpec spec;
  spec.dims = {10, 10, 4};
  spec.voxel_size = kH;
  spec.materials = {sinew::formats::make_neo_hookean_material("soft", 3000, 0.45, 1000)};
  sinew::formats::BoxMuscleSpec mu;
  mu.name = "band";
  mu.element_min = {3, 2, 1};
  mu.element_max = {7, 8, 3};
  mu.fibre = {0, 1, 0};
  spec.muscles = {mu};
  spec.created = "2026-01-01T00:00:00Z";
  return sinew::formats::make_box_model(spec);
}

bool reddish(Rgb c) {
  return c.r > c.g + 40 && c.r > c.b + 40;
}

TEST(ModelPreview, MuscleMeshAndStreamlinesFollowTheModel) {
  const auto m = block_with_muscle();
  const auto p = make_model_preview(m, "", 2);
  EXPECT_EQ(p.skin.name, "elements");  // no visual surface: the elements' boundary
  ASSERT_EQ(p.muscles.size(), 1u);
  const auto& mesh = p.muscles[0];
  // Boundary of a 4 × 6 × 2 box of voxels: 2 (4·6 + 4·2 + 6·2) faces, two triangles each.
  EXPECT_EQ(mesh.triangles.size(), 3u * 2u * 88u);
  float lo[3] = {1, 1, 1}, hi[3] = {-1, -1, -1};
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], mesh.positions[i]);
    hi[i % 3] = std::max(hi[i % 3], mesh.positions[i]);
  }
  const float want_lo[3] = {3e-3f, 2e-3f, 1e-3f}, want_hi[3] = {7e-3f, 8e-3f, 3e-3f};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(lo[k], want_lo[k], 1e-9);
    EXPECT_NEAR(hi[k], want_hi[k], 1e-9);
  }
  // Seeds every 2 elements: x ∈ {4, 6}, y ∈ {2, 4, 6}, z = 2; each line along y spans the muscle
  // to within a step (h/2) of its ends.
  ASSERT_EQ(p.streamlines.size(), 6u);
  for (const auto& s : p.streamlines) {
    double ymin = 1, ymax = -1;
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      EXPECT_NEAR(s.points[k][0], s.points[0][0], 1e-12);
      EXPECT_NEAR(s.points[k][2], s.points[0][2], 1e-12);
      ymin = std::min(ymin, s.points[k][1]);
      ymax = std::max(ymax, s.points[k][1]);
    }
    EXPECT_LT(ymin, 2e-3 + kH / 2);
    EXPECT_GT(ymax, 8e-3 - kH / 2);
  }
  EXPECT_THROW(make_model_preview(m, "skin"), sinew::ConfigError);
}

TEST(ModelPreview, MuscleShowsThroughTheTranslucentSkinWithItsFibres) {
  const auto m = block_with_muscle();
  const auto p = make_model_preview(m, "", 2);
  PreviewSettings s;
  s.width = 300;
  s.height = 300;
  s.view = View::front;  // looking along −z at the block's top face, the muscle under it
  s.fibres = false;
  // The camera the preview uses, to find the muscle's centre (5, 5, 2) mm on the image.
  std::vector<float> all = p.skin.positions;
  all.insert(all.end(), p.muscles[0].positions.begin(), p.muscles[0].positions.end());
  const Camera cam = frame_view(all, s.view, 1.0, s.up);
  double cx, cy, ex, ey;
  ASSERT_TRUE(project_point(cam, 300, 300, {5e-3, 5e-3, 4e-3}, cx, cy));
  ASSERT_TRUE(project_point(cam, 300, 300, {1e-3, 5e-3, 4e-3}, ex, ey));  // skin, no muscle below
  const Image plain = render_model_preview(p, s);
  EXPECT_TRUE(reddish(plain.at(int(cx), int(cy))));
  EXPECT_FALSE(reddish(plain.at(int(ex), int(ey))));
  s.skin_opacity = 1;
  EXPECT_FALSE(reddish(render_model_preview(p, s).at(int(cx), int(cy))));
  // Fibres: the pixels they change lie over the muscle and run along its length (y: vertical).
  s.skin_opacity = 0.35;
  s.fibres = true;
  const Image lined = render_model_preview(p, s);
  double top, bottom, left, right;
  project_point(cam, 300, 300, {3e-3, 8e-3, 3e-3}, left, top);
  project_point(cam, 300, 300, {7e-3, 2e-3, 3e-3}, right, bottom);
  int changed = 0, ylo = 300, yhi = -1;
  for (int y = 0; y < 300; ++y)
    for (int x = 0; x < 300; ++x)
      if (!(lined.at(x, y) == plain.at(x, y))) {
        ++changed;
        EXPECT_GE(x, int(left) - 2);
        EXPECT_LE(x, int(right) + 2);
        ylo = std::min(ylo, y);
        yhi = std::max(yhi, y);
      }
  EXPECT_GT(changed, 50);
  EXPECT_GT(yhi - ylo, 0.8 * (bottom - top)) << ylo << " " << yhi << " " << top << " " << bottom;
}

TEST(ModelPreview, ToolDrawsAModelAndRefusesFrameOptions) {
  const auto dir = temp_dir("model_preview");
  const auto model = (dir / "block.h5").string();
  sinew::formats::write_model(block_with_muscle(), model);
  EXPECT_TRUE(is_model_file(model));
  const std::string exe = SINEW_RENDER_EXE;
  const auto png = (dir / "preview.png").string();
  ASSERT_EQ(
      std::system(
          (exe + " " + model + " --view front --size 240x200 -o " + png + " > /dev/null").c_str()),
      0);
  const Image img = read_png(png);
  EXPECT_EQ(img.width, 240);
  int red = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) red += reddish(img.at(x, y)) ? 1 : 0;
  EXPECT_GT(red, 100);
  const int rc = std::system((exe + " " + model + " --sequence " + (dir / "seq").string() +
                              " > /dev/null 2> " + (dir / "err.txt").string())
                                 .c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  std::ifstream err(dir / "err.txt");
  const std::string text((std::istreambuf_iterator<char>(err)), {});
  EXPECT_NE(text.find("this is a model file: it has no frames"), std::string::npos) << text;
}

}  // namespace
