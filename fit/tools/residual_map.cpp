#include "residual_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "sinew/formats/model_file.hpp"
#include "sinew/postprocess/model_preview.hpp"
#include "sinew/postprocess/rasterizer.hpp"

namespace sinew::fit {
namespace {

double distance2(const std::array<double, 3>& a, const float* b) {
  double s = 0;
  for (int d = 0; d < 3; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
  return s;
}

}  // namespace

postprocess::Image draw_residual_map(const FitResult& r) {
  using namespace postprocess;
  const formats::Model model = formats::read_model(r.model_path);
  const ModelPreview preview = make_model_preview(model, r.surface, 3, 0.25);
  const auto& skin = preview.skin;
  const std::size_t nv = skin.positions.size() / 3;
  const auto& res = r.worst_frame_residual_mm;

  // The markers seen in the worst frame and the radius of their influence.
  std::vector<std::size_t> seen;
  for (std::size_t m = 0; m < res.size(); ++m)
    if (!std::isnan(res[m])) seen.push_back(m);
  std::vector<double> nearest;
  for (const auto a : seen) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto b : seen) {
      if (a == b) continue;
      double s = 0;
      for (int d = 0; d < 3; ++d)
        s += (r.marker_rest[a][d] - r.marker_rest[b][d]) *
             (r.marker_rest[a][d] - r.marker_rest[b][d]);
      best = std::min(best, s);
    }
    if (std::isfinite(best)) nearest.push_back(std::sqrt(best));
  }
  double radius = 0.01;  // m, for a single marker
  if (!nearest.empty()) {
    std::nth_element(nearest.begin(),
                     nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2),
                     nearest.end());
    radius = 1.5 * nearest[nearest.size() / 2];
  }
  ScalarColoring coloring;
  coloring.values.assign(nv, std::numeric_limits<float>::quiet_NaN());
  for (std::size_t v = 0; v < nv; ++v) {
    double sw = 0, swd = 0;
    for (const auto m : seen) {
      const double d2 = distance2(r.marker_rest[m], &skin.positions[3 * v]);
      if (d2 > radius * radius) continue;
      const double fade = 1 - std::sqrt(d2) / radius;  // → 0 at R: no seam there
      const double w = fade * fade / std::max(d2, 1e-12);
      sw += w;
      swd += w * res[m];
    }
    if (sw > 0) coloring.values[v] = static_cast<float>(swd / sw);
  }
  double top = 0;
  for (const auto m : seen) top = std::max(top, res[m]);
  coloring.min = 0;
  coloring.max = static_cast<float>(top > 0 ? top : 1e-3);
  coloring.label = "mm";

  RenderOptions o;
  o.width = 900;
  o.height = 720;
  const int viewport = o.width - color_bar_strip_width(o.width);
  o.camera = frame_view(skin.positions, View::front, static_cast<double>(viewport) / o.height);
  o.shading.base = {200, 200, 200};
  o.coloring = &coloring;
  const auto f = static_cast<std::size_t>(std::max(r.worst_frame, 0));
  if (r.worst_frame >= 0)
    o.caption = fmt::format("t = {:.4g} s: RMS {:.3f}, max {:.3f} mm", r.frame_times[f],
                            r.frame_rms_mm[f], r.frame_max_mm[f]);
  Image img = render(skin.positions, skin.triangles, o);

  // The markers as discs of their own residual, on top; those on skin facing away from the
  // camera (the normal of their nearest skin vertex) are left out.
  const auto normals = vertex_normals(skin.positions, skin.triangles);
  const int rad = 5;
  for (const auto m : seen) {
    std::size_t near = 0;
    for (std::size_t v = 1; v < nv; ++v)
      if (distance2(r.marker_rest[m], &skin.positions[3 * v]) <
          distance2(r.marker_rest[m], &skin.positions[3 * near]))
        near = v;
    double facing = 0;
    for (int d = 0; d < 3; ++d)
      facing += normals[3 * near + d] * (o.camera.position[d] - r.marker_rest[m][d]);
    if (nv > 0 && facing < 0) continue;
    double px = 0, py = 0;
    if (!project_point(o.camera, viewport, o.height,
                       {r.marker_rest[m][0], r.marker_rest[m][1], r.marker_rest[m][2]}, px, py))
      continue;
    const double t = res[m] / coloring.max;
    const Rgb c = map_color(ColorMap::viridis, t);
    const Rgb rim = t < 0.5 ? Rgb{255, 255, 255} : Rgb{40, 40, 40};  // seen on either end
    for (int dy = -rad - 1; dy <= rad + 1; ++dy)
      for (int dx = -rad - 1; dx <= rad + 1; ++dx) {
        const int d2 = dx * dx + dy * dy;
        if (d2 > (rad + 1) * (rad + 1)) continue;
        img.set(static_cast<int>(px) + dx, static_cast<int>(py) + dy, d2 > rad * rad ? rim : c);
      }
  }
  return img;
}

}  // namespace sinew::fit
