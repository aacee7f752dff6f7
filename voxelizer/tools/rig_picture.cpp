#include "rig_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "sinew/postprocess/png_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/voxelizer/jaw.hpp"
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

struct ColouredMesh {
  const TriangleMesh* mesh;
  Rgb colour;
};

// The meshes drawn each in its colour on white (nearest wins, pass by pass), then `skin` (already
// rendered with `o`) blended over them at 45% opacity.
void blend_over(Image& skin, const postprocess::RenderOptions& o,
                const std::vector<ColouredMesh>& meshes) {
  const int w = o.width, h = o.height;
  Image under(w, h, {255, 255, 255});
  for (const auto& cm : meshes) {
    std::vector<float> mp;
    std::vector<std::int32_t> mt;
    append(*cm.mesh, mp, mt);
    if (mt.empty()) continue;
    auto mo = o;
    mo.shading.base = cm.colour;
    mo.shading.background = {1, 2, 3};
    const Image m = postprocess::render(mp, mt, mo);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (!(m.at(x, y) == Rgb{1, 2, 3})) under.set(x, y, m.at(x, y));
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Rgb a = skin.at(x, y), b = under.at(x, y);
      auto mix = [](int s, int m) { return static_cast<std::uint8_t>((45 * s + 55 * m) / 100); };
      skin.set(x, y, {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)});
    }
  }
}

// A box of the landmarks widened by 25% (8 corners, V × 3): the face's frame for frame_view.
std::vector<float> landmark_box(const Landmarks& landmarks) {
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
  return box;
}

}  // namespace

void write_rig_picture(const std::string& path, const TriangleMesh& skin,
                       const Landmarks& landmarks, const std::vector<PictureMuscle>& muscles,
                       bool numbered_landmarks) {
  const int legend = numbered_landmarks ? 490 : 0, w = 900, h = 1000;
  // Frame on the landmarks (the face), with a margin.
  const std::vector<float> box = landmark_box(landmarks);
  postprocess::RenderOptions o;
  o.width = w;
  o.height = h;
  o.camera = postprocess::frame_view(box, postprocess::View::front, double(w) / h);
  std::vector<float> pos;
  std::vector<std::int32_t> tri;
  append(skin, pos, tri);
  Image img = postprocess::render(pos, tri, o);
  if (!muscles.empty()) {
    // One colour per muscle, both sides alike: by the base name's place in the rig's list.
    const std::vector<Rgb> palette{{200, 40, 40},  {40, 120, 200}, {40, 160, 70},  {200, 140, 30},
                                   {150, 60, 170}, {30, 160, 160}, {220, 90, 140}, {120, 120, 40},
                                   {90, 90, 200},  {180, 80, 40}};
    std::vector<ColouredMesh> coloured;
    for (const auto& m : muscles) {
      std::string base = m.name;
      for (const char* side : {"_left", "_right"})
        if (base.size() > 6 && base.ends_with(side)) base.resize(base.size() - std::strlen(side));
      const auto& all = rig_muscle_names();
      const auto at =
          static_cast<std::size_t>(std::find(all.begin(), all.end(), base) - all.begin());
      coloured.push_back({m.mesh, palette[at % palette.size()]});
    }
    blend_over(img, o, coloured);
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

void write_jaw_picture(const std::string& path, const TriangleMesh& skin, const TriangleMesh& skull,
                       const Landmarks& landmarks) {
  const JawGeometry jaw = jaw_geometry(landmarks);
  const int legend = 560, w = 900, h = 1000;
  postprocess::RenderOptions o;
  o.width = w;
  o.height = h;
  // Framed on the skull and the landmarks: the whole side of the head, the joint and the chin.
  std::vector<float> box = landmark_box(landmarks);
  for (const auto& v : skull.vertices) {
    box.push_back(static_cast<float>(v.x));
    box.push_back(static_cast<float>(v.y));
    box.push_back(static_cast<float>(v.z));
  }
  o.camera = postprocess::frame_view(box, postprocess::View::side, double(w) / h);
  std::vector<float> pos;
  std::vector<std::int32_t> tri;
  append(skin, pos, tri);
  Image img = postprocess::render(pos, tri, o);
  // The skull split as the voxelizer splits its held nodes: a triangle whose three corners lie in
  // the mandible's region is the mandible's.
  TriangleMesh mandible, rest;
  mandible.vertices = rest.vertices = skull.vertices;
  for (const auto& t : skull.triangles) {
    const bool in = in_mandible(jaw, skull.vertices[std::size_t(t[0])]) &&
                    in_mandible(jaw, skull.vertices[std::size_t(t[1])]) &&
                    in_mandible(jaw, skull.vertices[std::size_t(t[2])]);
    (in ? mandible : rest).triangles.push_back(t);
  }
  blend_over(img, o, {{&rest, {170, 170, 160}}, {&mandible, {220, 120, 30}}});
  Image out(w + legend, h, {255, 255, 255});
  out.blit(img, 0, 0);
  const auto mark = [&](const Vec3d& p, Rgb colour, int size) {
    double px = 0, py = 0;
    if (!project(o.camera, w, h, p, px, py)) return;
    const int x = static_cast<int>(std::lround(px)), y = static_cast<int>(std::lround(py));
    out.fill_rect(x - size, y - size, 2 * size + 1, 2 * size + 1, colour);
  };
  // The occlusal plane seen edge on: dots along forward through the stomion, from the pivot's
  // depth to the lips.
  const double reach = dot(jaw.stomion - jaw.pivot, jaw.forward);
  for (int k = 0; k <= 120; ++k) {
    const double d = reach * (k / 120.0 - 1.0) + 0.01;
    mark(jaw.stomion + d * jaw.forward, {40, 90, 200}, 1);
  }
  mark(jaw.pivot, {200, 0, 0}, 7);  // the hinge axis, end on
  mark(jaw.pivot, {255, 255, 255}, 3);
  mark(jaw.incisal, {40, 90, 200}, 5);
  char line[160];
  int row = 30;
  const auto text = [&](const std::string& t, Rgb colour) {
    postprocess::draw_text(out, w + 10, row, t, colour, 2);
    row += 26;
  };
  text("THE JAW, SEEN FROM THE LEFT", {0, 0, 0});
  row += 10;
  text("ORANGE: THE MANDIBLE", {220, 120, 30});
  text("RED DOT: THE HINGE AXIS, END ON", {200, 0, 0});
  std::snprintf(line, sizeof line, "  PIVOT %.1f %.1f %.1f MM", 1e3 * jaw.pivot.x,
                1e3 * jaw.pivot.y, 1e3 * jaw.pivot.z);
  text(line, {0, 0, 0});
  std::snprintf(line, sizeof line, "  AXIS %.3f %.3f %.3f", jaw.axis.x, jaw.axis.y, jaw.axis.z);
  text(line, {0, 0, 0});
  text("BLUE LINE: THE OCCLUSAL PLANE", {40, 90, 200});
  text("BLUE DOT: THE INCISAL POINT", {40, 90, 200});
  std::snprintf(line, sizeof line, "  %.1f MM BELOW, %.1f MM AHEAD OF",
                1e3 * -dot(jaw.incisal - jaw.pivot, jaw.up),
                1e3 * dot(jaw.incisal - jaw.pivot, jaw.forward));
  text(line, {0, 0, 0});
  text("  THE PIVOT", {0, 0, 0});
  std::snprintf(line, sizeof line, "CONDYLES %.1f MM APART", 2e3 * jaw.half_condyles);
  text(line, {0, 0, 0});
  postprocess::write_png(path, out);
}

}  // namespace sinew::voxelizer
