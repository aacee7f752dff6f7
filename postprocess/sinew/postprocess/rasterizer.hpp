#pragma once
// A small software rasteriser: no window, no GPU. Draws a triangle mesh z-buffered, shaded with
// per-vertex normals, into an RGB Image, optionally colour-mapped by a per-vertex scalar with a
// colour bar.
//
// Camera: a pinhole at `position` looking at `target`, `up` giving the image's vertical, vertical
// field of view `fov_y_deg`. A point p maps to camera coordinates (x_c, y_c, z_c) = ((p − position)
// · r, (p − position) · u, (p − position) · f) with f = normalize(target − position),
// r = normalize(f × up), u = r × f, and to the pixel
//   px = (1/2 + x_c / (2 z_c tan(fov_x/2))) W,  py = (1/2 − y_c / (2 z_c tan(fov_y/2))) H,
// tan(fov_x/2) = tan(fov_y/2) W/H (W × H: the mesh's viewport). Triangles with a vertex at
// z_c ≤ 0 (behind the camera) are skipped.
//
// Shading (Blinn–Phong, two-sided, a head light above-left of the camera):
//   c = base (k_a + k_d max(0, n·l)) + k_s max(0, n·h)^shininess (white),  h = normalize(l + v),
// n the perspective-correct interpolated vertex normal (area-weighted average of the adjacent
// faces' normals), flipped to face the viewer. Antialiasing: the image is drawn at
// `supersample` × the size and box-filtered down.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/postprocess/image.hpp"

namespace sinew::postprocess {

using Point = std::array<double, 3>;

struct Camera {
  Point position{0, 0, 1};
  Point target{0, 0, 0};
  Point up{0, 1, 0};
  double fov_y_deg = 30.0;
};

// Named views for automatic framing. With up axis +y the front camera sits on +z (looking
// along −z), side on +x, top on +y (the front at the bottom of the image), three-quarter at
// azimuth 45° between front and side, 20° above. With up axis +z (Blender's convention) the front
// camera sits on −y, side on +x, top on +z.
enum class View { front, side, top, three_quarter };
enum class UpAxis { y, z };
// Parses "front", "side", "top", "three-quarter"; throws ConfigError naming `field`.
View parse_view(const std::string& text, const std::string& field = "--view");
UpAxis parse_up_axis(const std::string& text, const std::string& field = "--up");

// A camera that frames the axis-aligned bounding box of `positions` (V × 3) from `view`: it
// looks at the box's centre from the nearest distance at which all 8 corners fall inside 95 %
// of both fields of view. `aspect` = viewport width / height.
Camera frame_view(const std::vector<float>& positions, View view, double aspect,
                  UpAxis up = UpAxis::y, double fov_y_deg = 30.0);

// The camera aimed at `target` (m, when given: moved by target − camera.target, so the view
// direction and the distance are kept) and dollied towards it by `zoom` > 0:
//   position' = target' + (position − target) / zoom.
// A sphere of radius r at the target, seen from distance d, fills a disc of radius
// (H/2) tan(asin(r/d)) / tan(fov_y/2) pixels, so its footprint grows about zoom² times (exactly in
// the limit r ≪ d). Throws ConfigError (field "--zoom") for a zoom that is not a positive number.
Camera aim_camera(const Camera& camera, const std::optional<Point>& target, double zoom);

// The pixel (px, py) of point p in a width × height viewport through `camera` (the formula at the
// top); false when p lies behind the camera (z_c ≤ 0).
bool project_point(const Camera& camera, int width, int height, const Point& p, double& px,
                   double& py);

// What an image shows and how large, shared by results frames (FrameRenderSettings) and model
// previews (PreviewSettings): size, automatic framing from a view, the camera aimed and zoomed
// (aim_camera) and the image cut to `crop` = {x, y, w, h} pixels of the width × height render.
struct ViewSettings {
  int width = 800, height = 600;
  View view = View::three_quarter;
  UpAxis up = UpAxis::y;
  std::optional<Point> target;  // m
  double zoom = 1.0;
  std::optional<std::array<int, 4>> crop;
};

enum class ColorMap { viridis, blue_red };
ColorMap parse_color_map(const std::string& text, const std::string& field = "--colormap");
// The colour of t ∈ [0, 1] (clamped): viridis (matplotlib's, 9 samples, linear between them) or
// a diverging blue–white–red map (blue at 0, white at 1/2, red at 1).
Rgb map_color(ColorMap map, double t);

// A per-vertex scalar shown through a colour map: values[i] of vertex i; the map spans
// [min, max]. A triangle with a NaN value at a corner keeps Shading::base (no data there). The colour bar (on the right, when `bar`) is labelled with min × label_scale and
// max × label_scale and `label` (e.g. values in m, label_scale 1000, label "mm").
struct ScalarColoring {
  std::vector<float> values;
  float min = 0.0f, max = 1.0f;
  ColorMap map = ColorMap::viridis;
  bool bar = true;
  std::string label;
  double label_scale = 1.0;
};

struct Shading {
  Rgb base{214, 176, 150};  // surface colour when no scalar colouring
  Rgb background{255, 255, 255};
  double ambient = 0.18, diffuse = 0.72, specular = 0.22, shininess = 40.0;
};

struct RenderOptions {
  int width = 800, height = 600;  // output size, pixels
  int supersample = 2;            // samples per pixel along each axis (1 = no antialiasing)
  Camera camera;
  Shading shading;
  const ScalarColoring* coloring = nullptr;  // not owned; nullptr: plain shading
  std::string caption;                       // drawn at the bottom left when not empty
};

// Width of the colour bar's strip on the right of an image of `width` pixels (the mesh's
// viewport is what is left); frame_view should be given the viewport's aspect.
int color_bar_strip_width(int width);

// Renders the mesh (positions V × 3, triangles T × 3 vertex ids). Throws ConfigError on a bad size
// or a scalar whose count is not V.
Image render(const std::vector<float>& positions, const std::vector<std::int32_t>& triangles,
             const RenderOptions& options);

// Area-weighted vertex normals (unit length; zero for vertices of no non-degenerate triangle).
std::vector<float> vertex_normals(const std::vector<float>& positions,
                                  const std::vector<std::int32_t>& triangles);

}  // namespace sinew::postprocess
