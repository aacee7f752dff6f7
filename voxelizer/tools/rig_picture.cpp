#include "rig_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "sinew/postprocess/png_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/voxelizer/rig_spec.hpp"

namespace sinew::voxelizer {
namespace {

using postprocess::Image;
using postprocess::Rgb;

void append(const TriangleMesh& m, std::vector<float>& pos, std::vector<std::int32_t>& tri) {
  const auto base = static_cast<std::int32_t>(pos.size() / 3);
  for (const auto& v : m.vertices) {
    pos.push_back(static_cast<float>(v.x));
    pos.push_back(static_cast<float>(v.y));
    pos.push_back(static_cast<float>(v.z));
  }
  for (const auto& t : m.triangles)
    for (auto i : t) tri.push_back(base + i);
}

// The pixel of p seen by camera c in a viewport of w × h (the rasteriser's pinhole model,
// rasterizer.hpp); false when p is behind the camera.
bool project(const postprocess::Camera& c, int w, int h, const Vec3d& p, double& px, double& py) {
  const Vec3d pos{c.position[0], c.position[1], c.position[2]};
  const Vec3d tgt{c.target[0], c.target[1], c.target[2]}, up{c.up[0], c.up[1], c.up[2]};
  const Vec3d f = (1.0 / norm(tgt - pos)) * (tgt - pos);
  Vec3d r = cross(f, up);
  r = (1.0 / norm(r)) * r;
  const Vec3d u = cross(r, f);
  const Vec3d d = p - pos;
  const double zc = dot(d, f);
  if (zc <= 0) return false;
  const double ty = std::tan(c.fov_y_deg * M_PI / 360.0), tx = ty * w / h;
  px = (0.5 + dot(d, r) / (2 * zc * tx)) * w;
  py = (0.5 - dot(d, u) / (2 * zc * ty)) * h;
  return true;
}

}  // namespace

void write_rig_picture(const std::string& path, const TriangleMesh& skin,
                       const Landmarks& landmarks, const std::vector<PictureMuscle>& muscles,
                       bool numbered_landmarks) {
  const int legend = numbered_landmarks ? 490 : 0, w = 900, h = 1000;
  // Frame on the landmarks (the face), with a margin: the box of the landmarks widened by 25%.
  std::vector<float> box;
  Vec3d lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
  for (const auto& [n, p] : landmarks.points) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  const Vec3d mid = 0.5 * (lo + hi), half = 0.625 * (hi - lo);
  for (int k = 0; k < 8; ++k) {
    box.push_back(static_cast<float>(mid.x + ((k & 1) ? half.x : -half.x)));
    box.push_back(static_cast<float>(mid.y + ((k & 2) ? half.y : -half.y)));
    box.push_back(static_cast<float>(mid.z + ((k & 4) ? half.z : -half.z)));
  }
  postprocess::RenderOptions o;
  o.width = w;
  o.height = h;
  o.camera = postprocess::frame_view(box, postprocess::View::front, double(w) / h);
  std::vector<float> pos;
  std::vector<std::int32_t> tri;
  append(skin, pos, tri);
  Image img = postprocess::render(pos, tri, o);
  if (!muscles.empty()) {
    // Muscles on a dark background, each its colour, then the skin blended over them.
    const std::vector<Rgb> palette{{200, 40, 40},  {40, 120, 200}, {40, 160, 70},  {200, 140, 30},
                                   {150, 60, 170}, {30, 160, 160}, {220, 90, 140}, {120, 120, 40},
                                   {90, 90, 200},  {180, 80, 40}};
    Image under(w, h, {255, 255, 255});
    for (std::size_t i = 0; i < muscles.size(); ++i) {
      std::vector<float> mp;
      std::vector<std::int32_t> mt;
      append(*muscles[i].mesh, mp, mt);
      auto mo = o;
      // The muscle's own pass; its pixels (not background) are copied over.
      // One colour per muscle, both sides alike: by the base name's place in the rig's list.
      std::string base = muscles[i].name;
      for (const char* side : {"_left", "_right"})
        if (base.size() > 6 && base.ends_with(side)) base.resize(base.size() - std::strlen(side));
      const auto& all = rig_muscle_names();
      const auto at =
          static_cast<std::size_t>(std::find(all.begin(), all.end(), base) - all.begin());
      mo.shading.base = palette[at % palette.size()];
      mo.shading.background = {1, 2, 3};
      const Image m = postprocess::render(mp, mt, mo);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          if (!(m.at(x, y) == Rgb{1, 2, 3})) under.set(x, y, m.at(x, y));
    }
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const Rgb a = img.at(x, y), b = under.at(x, y);
        auto mix = [](int s, int m) { return static_cast<std::uint8_t>((45 * s + 55 * m) / 100); };
        img.set(x, y, {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)});
      }
    }
  }
  Image out(w + legend, h, {255, 255, 255});
  out.blit(img, 0, 0);
  if (numbered_landmarks) {
    const auto& names = landmark_names();
    for (std::size_t i = 0; i < names.size(); ++i) {
      double px = 0, py = 0;
      if (!project(o.camera, w, h, landmarks.at(names[i]), px, py)) continue;
      const int x = static_cast<int>(std::lround(px)), y = static_cast<int>(std::lround(py));
      out.fill_rect(x - 4, y - 4, 9, 9, {200, 0, 0});
      out.fill_rect(x - 2, y - 2, 5, 5, {255, 255, 255});
      const std::string label = std::to_string(i + 1);
      out.fill_rect(x + 6, y - 9, postprocess::text_width(label, 2) + 4, 18, {255, 255, 255});
      postprocess::draw_text(out, x + 8, y - 7, label, {160, 0, 0}, 2);
      // Each point's x and y in mm beside its name: with the dots they scale the picture, so
      // that a point in the wrong place can be moved by the right amount (docs/landmarks.md).
      const Vec3d& p = landmarks.at(names[i]);
      char xy[48];
      std::snprintf(xy, sizeof xy, "%7.1f %7.1f", 1e3 * p.x, 1e3 * p.y);
      const int row = 44 + static_cast<int>(i) * 24;
      postprocess::draw_text(out, w + 10, row, std::to_string(i + 1) + " " + names[i], {0, 0, 0},
                             2);
      postprocess::draw_text(out, w + 10 + 23 * 12, row, xy, {0, 0, 0}, 2);
    }
    postprocess::draw_text(out, w + 10 + 23 * 12, 20, "  X MM  Y MM", {0, 0, 0}, 2);
  }
  postprocess::write_png(path, out);
}

}  // namespace sinew::voxelizer
