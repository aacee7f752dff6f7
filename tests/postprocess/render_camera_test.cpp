// sinew-render's camera target, zoom and crop (aim_camera, crop, FrameRenderSettings): against the
// pinhole's closed form for a sphere's silhouette, the target's image shift, pixel-exact crops, and
// end to end through the tool on a results file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>

#include "export_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/postprocess/png_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/render_session.hpp"
#include "test_meshes.hpp"

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;

namespace {

constexpr double kPi = std::numbers::pi;

// Covered pixels (not background) and their mean column.
struct Footprint {
  long pixels = 0;
  double mean_x = 0;
};
Footprint footprint(const Image& img, Rgb background) {
  Footprint f;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.at(x, y) != background) {
        ++f.pixels;
        f.mean_x += x;
      }
  if (f.pixels) f.mean_x /= double(f.pixels);
  return f;
}

// Disc radius in pixels of a sphere of radius r at distance d (vertical fov in degrees, height H).
double disc_radius(double r, double d, double fov, int height) {
  return 0.5 * height * std::tan(std::asin(r / d)) / std::tan(fov * kPi / 360.0);
}

// A sphere r = 5 cm seen from 0.6 m; zoom 2 puts the camera at 0.3 m: each footprint matches the
// closed form within 3%, so the zoom enlarges it (tan(asin(r/0.3)) / tan(asin(r/0.6)))² ≈ 4.1 times.
TEST(RenderCamera, ZoomEnlargesTheFootprintAsThePinholeSays) {
  const double r = 0.05, fov = 30.0;
  const auto m = icosphere(4, r);
  RenderOptions o;
  o.width = 240;
  o.height = 200;
  o.camera.position = {0, 0, 0.6};
  o.camera.fov_y_deg = fov;
  const Footprint far = footprint(render(m.positions, m.triangles, o), o.shading.background);
  o.camera = aim_camera(o.camera, std::nullopt, 2.0);
  EXPECT_NEAR(o.camera.position[2], 0.3, 1e-15);
  const Footprint near = footprint(render(m.positions, m.triangles, o), o.shading.background);
  for (const auto& [f, d] : {std::pair{far, 0.6}, std::pair{near, 0.3}}) {
    const double rp = disc_radius(r, d, fov, o.height);
    EXPECT_NEAR(double(f.pixels) / (kPi * rp * rp), 1.0, 0.03) << d;
  }
  EXPECT_GT(double(near.pixels) / double(far.pixels), 3.9);
  EXPECT_THROW(aim_camera(o.camera, std::nullopt, 0.0), sinew::ConfigError);
  EXPECT_THROW(aim_camera(o.camera, std::nullopt, -1.0), sinew::ConfigError);
}

// Aiming at the sphere's right edge (0.05, 0, 0) keeps the distance and direction: the sphere's
// image moves left by r / (d tan(fov/2)) · H/2 pixels (to within a pixel), its size unchanged.
TEST(RenderCamera, TargetShiftsTheImage) {
  const double r = 0.05, d = 0.6, fov = 30.0;
  const auto m = icosphere(4, r);
  RenderOptions o;
  o.width = 240;
  o.height = 200;
  o.camera.position = {0, 0, d};
  o.camera.fov_y_deg = fov;
  const Footprint centred = footprint(render(m.positions, m.triangles, o), o.shading.background);
  o.camera = aim_camera(o.camera, Point{r, 0, 0}, 1.0);
  EXPECT_NEAR(o.camera.position[0], r, 1e-15);
  EXPECT_NEAR(o.camera.position[2], d, 1e-15);
  const Footprint moved = footprint(render(m.positions, m.triangles, o), o.shading.background);
  const double shift = r / (d * std::tan(fov * kPi / 360.0)) * o.height / 2;
  EXPECT_NEAR(centred.mean_x - moved.mean_x, shift, 1.0);
  EXPECT_NEAR(double(moved.pixels) / double(centred.pixels), 1.0, 0.02);
}

TEST(RenderCamera, CropKeepsExactlyThosePixels) {
  const auto a = stretching_sphere(3);
  FrameRenderSettings s;
  s.width = 160;
  s.height = 120;
  s.caption = false;
  const Image full = FrameRenderer(a, s).render(2);
  s.crop = std::array<int, 4>{40, 30, 80, 50};
  const Image part = FrameRenderer(a, s).render(2);
  ASSERT_EQ(part.width, 80);
  ASSERT_EQ(part.height, 50);
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < 80; ++x) ASSERT_EQ(part.at(x, y), full.at(40 + x, 30 + y)) << x << "," << y;
  EXPECT_THROW(crop(full, 100, 0, 80, 10), sinew::ConfigError);
  EXPECT_THROW(crop(full, 0, 0, 0, 10), sinew::ConfigError);
}

// Through the tool, on the framed front view of a results file's sphere: --zoom 0.5 quarters the
// footprint (the pinhole's 1/zoom², within 20% at this closeness), --zoom 2 enlarges it;
// --target at the sphere's top with --crop gives the cropped size with the sphere in its lower
// part; a crop outside the image exits 2.
TEST(RenderCamera, ToolOptions) {
  const auto dir = temp_dir("render_camera");
  const auto results = (dir / "r.h5").string();
  write_results(results, stretching_sphere(3));
  const std::string exe =
      std::string(SINEW_RENDER_EXE) + " " + results + " --size 200x160 --view front ";
  auto draw = [&](const std::string& options, const std::string& name) {
    const auto png = (dir / name).string();
    EXPECT_EQ(std::system((exe + options + " -o " + png + " > /dev/null").c_str()), 0) << options;
    return read_png(png);
  };
  const Rgb white{255, 255, 255};
  const Image plain = draw("", "plain.png"), half = draw("--zoom 0.5", "half.png"),
              twice = draw("--zoom 2", "twice.png"),
              top = draw("--target 0,0.05,0 --crop 20,10,160,120", "top.png");
  const double fp = double(footprint(plain, white).pixels);
  EXPECT_NEAR(double(footprint(half, white).pixels) / fp, 0.25, 0.05);
  EXPECT_GT(double(footprint(twice, white).pixels) / fp, 1.3);
  ASSERT_EQ(top.width, 160);
  ASSERT_EQ(top.height, 120);
  long upper = 0, lower = 0;
  for (int y = 0; y < top.height; ++y)
    for (int x = 0; x < top.width; ++x)
      if (top.at(x, y) != white) (y < top.height / 2 ? upper : lower) += 1;
  EXPECT_GT(lower, 2 * upper) << upper << " " << lower;
  const int bad = std::system((exe + "--crop 150,0,100,10 -o " + (dir / "bad.png").string() +
                               " > /dev/null 2> " + (dir / "err.txt").string())
                                  .c_str());
  EXPECT_EQ(WEXITSTATUS(bad), 2);
}

}  // namespace
