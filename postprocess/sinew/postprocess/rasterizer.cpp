#include "sinew/postprocess/rasterizer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "sinew/common/error.hpp"

namespace sinew::postprocess {
namespace {

Point sub(const Point& a, const Point& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Point add(const Point& a, const Point& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
Point scale(const Point& a, double s) {
  return {a[0] * s, a[1] * s, a[2] * s};
}
double dot(const Point& a, const Point& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Point normalize(const Point& a) {
  const double n = std::sqrt(dot(a, a));
  return n > 0 ? scale(a, 1.0 / n) : a;
}
Point vertex(const std::vector<float>& p, std::size_t i) {
  return {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
}
std::uint8_t to_byte(double v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

// Short labels for the colour bar: 3 significant digits, no exponent for ordinary ranges.
std::string number_label(double v) {
  const double a = std::abs(v);
  if (a == 0.0) return "0";
  if (a >= 1e4 || a < 1e-3) return fmt::format("{:.2e}", v);
  if (a >= 100) return fmt::format("{:.0f}", v);
  if (a >= 10) return fmt::format("{:.1f}", v);
  if (a >= 1) return fmt::format("{:.2f}", v);
  return fmt::format("{:.3f}", v);
}

void draw_color_bar(Image& img, const ScalarColoring& c, int strip, Rgb ink) {
  const int w = img.width, h = img.height;
  const int font = std::max(1, h / 240);
  const int bar_w = std::max(6, strip / 5);
  const int top = std::max(h / 8, 4 * text_height(font)), bottom = h - top;
  const int x0 = w - strip + std::max(4, strip / 8);
  for (int y = top; y < bottom; ++y) {
    const double t = 1.0 - static_cast<double>(y - top) / std::max(1, bottom - top - 1);
    img.fill_rect(x0, y, bar_w, 1, map_color(c.map, t));
  }
  // Frame.
  img.fill_rect(x0 - 1, top - 1, bar_w + 2, 1, ink);
  img.fill_rect(x0 - 1, bottom, bar_w + 2, 1, ink);
  img.fill_rect(x0 - 1, top - 1, 1, bottom - top + 2, ink);
  img.fill_rect(x0 + bar_w, top - 1, 1, bottom - top + 2, ink);
  const int tx = x0 + bar_w + 3 * font;
  const int th = text_height(font);
  draw_text(img, tx, top - th / 2, number_label(c.max * c.label_scale), ink, font);
  draw_text(img, tx, bottom - th / 2, number_label(c.min * c.label_scale), ink, font);
  if (!c.label.empty()) {
    // Above the bar, kept inside the image when the strip is narrower than the label.
    const int lx = std::max(w - strip, std::min(x0, w - 2 - text_width(c.label, font)));
    draw_text(img, lx, top - 3 * th, c.label, ink, font);
  }
}

}  // namespace

View parse_view(const std::string& text, const std::string& field) {
  if (text == "front") return View::front;
  if (text == "side") return View::side;
  if (text == "top") return View::top;
  if (text == "three-quarter" || text == "three_quarter") return View::three_quarter;
  throw ConfigError("", field,
                    fmt::format("unknown view \"{}\" (front, side, top, three-quarter)", text));
}

UpAxis parse_up_axis(const std::string& text, const std::string& field) {
  if (text == "y") return UpAxis::y;
  if (text == "z") return UpAxis::z;
  throw ConfigError("", field, fmt::format("unknown up axis \"{}\" (y or z)", text));
}

ColorMap parse_color_map(const std::string& text, const std::string& field) {
  if (text == "viridis") return ColorMap::viridis;
  if (text == "blue-red" || text == "blue_red") return ColorMap::blue_red;
  throw ConfigError("", field, fmt::format("unknown colour map \"{}\" (viridis, blue-red)", text));
}

Rgb map_color(ColorMap map, double t) {
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  if (map == ColorMap::viridis) {
    // viridis(9): #440154 #472D7B #3B528B #2C728E #21908C #27AD81 #5DC863 #AADC32 #FDE725.
    static constexpr std::uint8_t kTable[9][3] = {{68, 1, 84},    {71, 45, 123},  {59, 82, 139},
                                                  {44, 114, 142}, {33, 144, 140}, {39, 173, 129},
                                                  {93, 200, 99},  {170, 220, 50}, {253, 231, 37}};
    const double s = t * 8.0;
    const int i = std::min(7, static_cast<int>(s));
    const double f = s - i;
    auto lerp = [&](int k) {
      return static_cast<std::uint8_t>(std::lround(kTable[i][k] * (1 - f) + kTable[i + 1][k] * f));
    };
    return {lerp(0), lerp(1), lerp(2)};
  }
  // Blue (59, 76, 192) – white (240, 240, 240) – red (180, 4, 38), as in cool–warm maps.
  static constexpr double kBlue[3] = {59, 76, 192}, kWhite[3] = {240, 240, 240},
                          kRed[3] = {180, 4, 38};
  const double* a = t < 0.5 ? kBlue : kWhite;
  const double* b = t < 0.5 ? kWhite : kRed;
  const double f = t < 0.5 ? 2 * t : 2 * t - 1;
  auto lerp = [&](int k) {
    return static_cast<std::uint8_t>(std::lround(a[k] * (1 - f) + b[k] * f));
  };
  return {lerp(0), lerp(1), lerp(2)};
}

Camera aim_camera(const Camera& camera, const std::optional<Point>& target, double zoom) {
  if (!(zoom > 0) || !std::isfinite(zoom))
    throw ConfigError("", "--zoom", fmt::format("{} is not a positive number", zoom));
  Camera c = camera;
  if (target) c.target = *target;
  for (int k = 0; k < 3; ++k) {
    const auto i = std::size_t(k);
    c.position[i] = c.target[i] + (camera.position[i] - camera.target[i]) / zoom;
  }
  return c;
}

bool project_point(const Camera& cam, int width, int height, const Point& p, double& px,
                   double& py) {
  const Point f = normalize(sub(cam.target, cam.position));
  const Point r = normalize(cross(f, cam.up));
  const Point u = cross(r, f);
  const double ty = std::tan(cam.fov_y_deg * std::numbers::pi / 360.0);
  const double tx = ty * static_cast<double>(width) / height;
  const Point d = sub(p, cam.position);
  const double x = dot(d, r), y = dot(d, u), z = dot(d, f);
  if (!(z > 0)) return false;
  px = (0.5 + x / (2 * z * tx)) * width;
  py = (0.5 - y / (2 * z * ty)) * height;
  return true;
}

Camera frame_view(const std::vector<float>& positions, View view, double aspect, UpAxis up,
                  double fov_y_deg) {
  Point lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
           std::numeric_limits<double>::max()};
  Point hi = scale(lo, -1.0);
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], static_cast<double>(positions[i + k]));
      hi[k] = std::max(hi[k], static_cast<double>(positions[i + k]));
    }
  }
  if (positions.size() < 3) lo = hi = {0, 0, 0};
  const Point center = scale(add(lo, hi), 0.5);
  double radius = 0.5 * std::sqrt(dot(sub(hi, lo), sub(hi, lo)));
  if (!(radius > 0)) radius = 1.0;
  // Directions in a y-up frame: front +z, side +x, top +y; mapped to z-up (front −y) below.
  Point dir, cam_up{0, 1, 0};
  const double az = std::numbers::pi / 4, el = 20.0 * std::numbers::pi / 180.0;
  switch (view) {
    case View::front:
      dir = {0, 0, 1};
      break;
    case View::side:
      dir = {1, 0, 0};
      break;
    case View::top:
      dir = {0, 1, 0};
      cam_up = {0, 0, -1};
      break;
    case View::three_quarter:
      dir = {std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)};
      break;
  }
  if (up == UpAxis::z) {  // (x, y, z)_yup -> (x, -z, y)_zup
    auto to_z = [](const Point& p) { return Point{p[0], -p[2], p[1]}; };
    dir = to_z(dir);
    cam_up = to_z(cam_up);
  }
  // The nearest distance at which all 8 box corners project inside 95 % of each half field:
  // a corner at (x, y) across and z towards the camera from the centre needs
  // d ≥ |x| / (0.95 tan(fov_x/2)) + z, likewise for y.
  const double tan_y = 0.95 * std::tan(fov_y_deg * std::numbers::pi / 360.0);
  const double tan_x = tan_y * aspect;
  const Point right = normalize(cross(scale(dir, -1.0), cam_up));
  const Point upward = cross(right, scale(dir, -1.0));
  double distance = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Point corner = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]};
    const Point d = sub(corner, center);
    const double z = dot(d, dir);
    distance = std::max(
        {distance, std::abs(dot(d, right)) / tan_x + z, std::abs(dot(d, upward)) / tan_y + z});
  }
  // Keep the camera outside the box's sphere whatever its shape.
  distance = std::max(distance, 1.01 * radius);
  Camera cam;
  cam.position = add(center, scale(dir, distance));
  cam.target = center;
  cam.up = cam_up;
  cam.fov_y_deg = fov_y_deg;
  return cam;
}

int color_bar_strip_width(int width) {
  return std::max(48, width / 6);
}

std::vector<float> vertex_normals(const std::vector<float>& positions,
                                  const std::vector<std::int32_t>& triangles) {
  std::vector<double> acc(positions.size(), 0.0);
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const auto a = static_cast<std::size_t>(triangles[t]),
               b = static_cast<std::size_t>(triangles[t + 1]),
               c = static_cast<std::size_t>(triangles[t + 2]);
    // |cross| = 2 × area: summing the unnormalised face normals weights them by area.
    const Point n = cross(sub(vertex(positions, b), vertex(positions, a)),
                          sub(vertex(positions, c), vertex(positions, a)));
    for (auto v : {a, b, c}) {
      for (int k = 0; k < 3; ++k) acc[3 * v + k] += n[k];
    }
  }
  std::vector<float> out(positions.size(), 0.0f);
  for (std::size_t v = 0; v + 2 < acc.size(); v += 3) {
    const Point n = normalize({acc[v], acc[v + 1], acc[v + 2]});
    for (int k = 0; k < 3; ++k) out[v + k] = static_cast<float>(n[k]);
  }
  return out;
}

Image render(const std::vector<float>& positions, const std::vector<std::int32_t>& triangles,
             const RenderOptions& o) {
  if (o.width < 8 || o.height < 8 || o.width > 16384 || o.height > 16384) {
    throw ConfigError("", "size",
                      fmt::format("image size {}x{} out of range [8, 16384]", o.width, o.height));
  }
  if (o.supersample < 1 || o.supersample > 4) {
    throw ConfigError("", "supersample", "supersampling must be 1 to 4");
  }
  const std::size_t nv = positions.size() / 3;
  if (o.coloring && o.coloring->values.size() != nv) {
    throw ConfigError(
        "", "scalar",
        fmt::format("{} scalar values for {} vertices", o.coloring->values.size(), nv));
  }
  for (auto id : triangles) {
    if (id < 0 || static_cast<std::size_t>(id) >= nv) {
      throw ConfigError("", "triangles", fmt::format("vertex id {} out of range [0, {})", id, nv));
    }
  }
  const bool bar = o.coloring && o.coloring->bar;
  const int strip = bar ? color_bar_strip_width(o.width) : 0;
  const int ss = o.supersample;
  const int vw = (o.width - strip) * ss, vh = o.height * ss;  // the mesh's viewport, samples
  const int W = o.width * ss, H = o.height * ss;

  // Camera basis.
  const Camera& cam = o.camera;
  const Point f = normalize(sub(cam.target, cam.position));
  const Point r = normalize(cross(f, cam.up));
  const Point u = cross(r, f);
  const double ty = std::tan(cam.fov_y_deg * std::numbers::pi / 360.0);
  const double tx = ty * static_cast<double>(vw) / vh;
  // Light direction (towards the light): from the camera, above and to the left.
  const Point light = normalize(add(add(scale(f, -1.0), scale(u, 0.6)), scale(r, -0.4)));

  // Project every vertex.
  std::vector<double> sx(nv), sy(nv), zc(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const Point d = sub(vertex(positions, i), cam.position);
    const double x = dot(d, r), y = dot(d, u), z = dot(d, f);
    zc[i] = z;
    sx[i] = z > 0 ? (0.5 + x / (2 * z * tx)) * vw : 0;
    sy[i] = z > 0 ? (0.5 - y / (2 * z * ty)) * vh : 0;
  }
  const auto normals = vertex_normals(positions, triangles);

  std::vector<float> color(static_cast<std::size_t>(W) * H * 3);
  for (std::size_t i = 0; i < color.size(); i += 3) {
    color[i] = o.shading.background.r / 255.0f;
    color[i + 1] = o.shading.background.g / 255.0f;
    color[i + 2] = o.shading.background.b / 255.0f;
  }
  std::vector<double> inv_depth(static_cast<std::size_t>(W) * H, 0.0);  // 1/z_c; 0 = empty
  const double range = o.coloring ? static_cast<double>(o.coloring->max) - o.coloring->min : 1.0;

  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::size_t a = static_cast<std::size_t>(triangles[t]),
                      b = static_cast<std::size_t>(triangles[t + 1]),
                      c = static_cast<std::size_t>(triangles[t + 2]);
    if (zc[a] <= 0 || zc[b] <= 0 || zc[c] <= 0) continue;
    const double area = (sx[b] - sx[a]) * (sy[c] - sy[a]) - (sx[c] - sx[a]) * (sy[b] - sy[a]);
    if (area == 0.0) continue;
    const int x_lo = std::max(0, static_cast<int>(std::floor(std::min({sx[a], sx[b], sx[c]}))));
    const int x_hi = std::min(vw - 1, static_cast<int>(std::ceil(std::max({sx[a], sx[b], sx[c]}))));
    const int y_lo = std::max(0, static_cast<int>(std::floor(std::min({sy[a], sy[b], sy[c]}))));
    const int y_hi = std::min(vh - 1, static_cast<int>(std::ceil(std::max({sy[a], sy[b], sy[c]}))));
    for (int py = y_lo; py <= y_hi; ++py) {
      const double y = py + 0.5;
      for (int px = x_lo; px <= x_hi; ++px) {
        const double x = px + 0.5;
        // Barycentrics from edge functions, sign-normalised by the triangle's orientation.
        const double w0 = ((sx[b] - x) * (sy[c] - y) - (sx[c] - x) * (sy[b] - y)) / area;
        const double w1 = ((sx[c] - x) * (sy[a] - y) - (sx[a] - x) * (sy[c] - y)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const double iz = w0 / zc[a] + w1 / zc[b] + w2 / zc[c];
        const std::size_t pix = static_cast<std::size_t>(py) * W + px;
        if (iz <= inv_depth[pix]) continue;
        inv_depth[pix] = iz;
        // Perspective-correct weights.
        const double p0 = w0 / zc[a] / iz, p1 = w1 / zc[b] / iz, p2 = w2 / zc[c] / iz;
        Point n{0, 0, 0}, pos{0, 0, 0};
        for (int k = 0; k < 3; ++k) {
          n[k] = p0 * normals[3 * a + k] + p1 * normals[3 * b + k] + p2 * normals[3 * c + k];
          pos[k] =
              p0 * positions[3 * a + k] + p1 * positions[3 * b + k] + p2 * positions[3 * c + k];
        }
        const Point view = normalize(sub(cam.position, pos));
        n = normalize(n);
        if (dot(n, view) < 0) n = scale(n, -1.0);
        Rgb base = o.shading.base;
        if (o.coloring) {
          const auto& v = o.coloring->values;
          const double s = p0 * v[a] + p1 * v[b] + p2 * v[c];
          // A NaN value (no data at a corner) keeps the surface's own colour.
          if (!std::isnan(s))
            base = map_color(o.coloring->map, range > 0 ? (s - o.coloring->min) / range : 0.0);
        }
        const double diffuse = std::max(0.0, dot(n, light));
        const Point half = normalize(add(light, view));
        const double spec =
            o.shading.specular * std::pow(std::max(0.0, dot(n, half)), o.shading.shininess);
        const double k = o.shading.ambient + o.shading.diffuse * diffuse;
        float* out = &color[pix * 3];
        out[0] = static_cast<float>(base.r / 255.0 * k + spec);
        out[1] = static_cast<float>(base.g / 255.0 * k + spec);
        out[2] = static_cast<float>(base.b / 255.0 * k + spec);
      }
    }
  }

  // Box filter down to the output size.
  Image img(o.width, o.height, o.shading.background);
  const double norm = 1.0 / (ss * ss);
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width - strip; ++x) {
      double sum[3] = {0, 0, 0};
      for (int j = 0; j < ss; ++j) {
        for (int i = 0; i < ss; ++i) {
          const std::size_t s = (static_cast<std::size_t>(y * ss + j) * W + x * ss + i) * 3;
          for (int k = 0; k < 3; ++k) sum[k] += std::clamp(color[s + k], 0.0f, 1.0f);
        }
      }
      img.set(x, y, {to_byte(sum[0] * norm), to_byte(sum[1] * norm), to_byte(sum[2] * norm)});
    }
  }
  const double lum =
      0.3 * o.shading.background.r + 0.59 * o.shading.background.g + 0.11 * o.shading.background.b;
  const Rgb ink = lum > 128 ? Rgb{20, 20, 20} : Rgb{235, 235, 235};
  if (bar) draw_color_bar(img, *o.coloring, strip, ink);
  if (!o.caption.empty()) {
    const int font = std::max(1, o.height / 240);
    draw_text(img, 4 * font, o.height - text_height(font) - 4 * font, o.caption, ink, font);
  }
  return img;
}

}  // namespace sinew::postprocess
