#include "sinew/postprocess/pc2_writer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/postprocess/rasterizer.hpp"

namespace sinew::postprocess {
namespace {

static_assert(std::endian::native == std::endian::little,
              "PC2 and glTF are little endian; this writer stores native floats");

}  // namespace

void write_pc2(const std::string& path, const SurfaceAnimation& a, const Pc2Options& o) {
  char header[kPc2HeaderBytes] = {};
  std::memcpy(header, "POINTCACHE2", 12);  // with its terminating NUL
  const std::int32_t version = 1, points = static_cast<std::int32_t>(a.vertex_count()),
                     samples = static_cast<std::int32_t>(a.frame_count());
  std::memcpy(header + 12, &version, 4);
  std::memcpy(header + 16, &points, 4);
  std::memcpy(header + 20, &o.start_frame, 4);
  std::memcpy(header + 24, &o.sample_rate, 4);
  std::memcpy(header + 28, &samples, 4);
  std::string bytes(header, sizeof header);
  bytes.reserve(sizeof header + a.frame_count() * a.rest.size() * sizeof(float));
  for (const auto& frame : a.frames) {
    bytes.append(reinterpret_cast<const char*>(frame.data()), frame.size() * sizeof(float));
  }
  write_text_atomically(path, bytes);
}

ObjAttributes texture_attributes(const SurfaceAnimation& a) {
  ObjAttributes out;
  if (a.has_uvs()) {
    out.uvs = a.uvs;
    out.uv_triangles = a.uv_triangles;
  }
  return out;
}

void write_obj(const std::string& path, const std::vector<float>& positions,
               const std::vector<std::int32_t>& triangles, const std::string& comment,
               const ObjAttributes& attributes) {
  const auto& n = attributes.normals;
  const auto& c = attributes.colors;
  if (!n.empty() && n.size() != positions.size()) {
    throw ConfigError(path, "normals", "expected one normal per vertex");
  }
  if (!c.empty() && c.size() != positions.size()) {
    throw ConfigError(path, "colors", "expected one colour per vertex");
  }
  const auto& uv = attributes.uvs;
  const auto& ut = attributes.uv_triangles;
  if (!ut.empty() && ut.size() != triangles.size()) {
    throw ConfigError(path, "uv_triangles", "expected one texture corner per triangle corner");
  }
  std::string text;
  text.reserve(positions.size() * (14 + (n.empty() ? 0 : 14) + (c.empty() ? 0 : 8)) +
               triangles.size() * (n.empty() ? 8 : 14) + 64);
  if (!comment.empty()) text += "# " + comment + "\n";
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3) {
    text += fmt::format("v {:.9g} {:.9g} {:.9g}", positions[i], positions[i + 1], positions[i + 2]);
    if (!c.empty()) text += fmt::format(" {:.4f} {:.4f} {:.4f}", c[i], c[i + 1], c[i + 2]);
    text += '\n';
  }
  for (std::size_t i = 0; i + 2 < n.size(); i += 3) {
    text += fmt::format("vn {:.6f} {:.6f} {:.6f}\n", n[i], n[i + 1], n[i + 2]);
  }
  if (!ut.empty()) {
    for (std::size_t i = 0; i + 1 < uv.size(); i += 2) {
      text += fmt::format("vt {:.9g} {:.9g}\n", uv[i], uv[i + 1]);
    }
  }
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const auto a = triangles[t] + 1, b = triangles[t + 1] + 1, d = triangles[t + 2] + 1;
    if (!ut.empty()) {
      const auto ta = ut[t] + 1, tb = ut[t + 1] + 1, td = ut[t + 2] + 1;
      text += n.empty()
                  ? fmt::format("f {}/{} {}/{} {}/{}\n", a, ta, b, tb, d, td)
                  : fmt::format("f {0}/{1}/{0} {2}/{3}/{2} {4}/{5}/{4}\n", a, ta, b, tb, d, td);
      continue;
    }
    // Normals share the vertex numbering, so each corner names the same index twice.
    text += n.empty() ? fmt::format("f {} {} {}\n", a, b, d)
                      : fmt::format("f {0}//{0} {1}//{1} {2}//{2}\n", a, b, d);
  }
  write_text_atomically(path, text);
}

std::vector<std::string> write_obj_sequence(const std::string& directory, const SurfaceAnimation& a,
                                            const std::string& prefix, VertexScalar color,
                                            const std::vector<std::vector<float>>& color_values) {
  if (color == VertexScalar::von_mises && color_values.size() != a.frame_count()) {
    throw ConfigError(directory, "--color", "von Mises colours need the stress of every frame");
  }
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw IoError(directory, "", "cannot create the directory: " + ec.message());
  const int digits =
      a.frame_count() > 10000 ? static_cast<int>(std::to_string(a.frame_count() - 1).size()) : 4;
  float max = color == VertexScalar::displacement ? max_displacement(a) : 0.0f;
  if (color == VertexScalar::von_mises) {
    for (const float s : peak_over_frames(color_values)) max = std::max(max, s);
  }
  std::vector<std::string> paths;
  for (std::size_t k = 0; k < a.frame_count(); ++k) {
    const auto path =
        (std::filesystem::path(directory) / fmt::format("{}_{:0{}}.obj", prefix, k, digits))
            .string();
    ObjAttributes attributes = texture_attributes(a);
    attributes.normals = smooth_normals(a.frames[k], a.triangles);
    if (color != VertexScalar::none) {
      // OBJ viewers take vertex colours as sRGB: the colour map's own bytes.
      const auto values =
          color == VertexScalar::von_mises ? color_values[k] : displacement_magnitude(a, k);
      for (float d : values) {
        const Rgb rgb = map_color(ColorMap::viridis, max > 0 ? d / max : 0.0);
        for (auto ch : {rgb.r, rgb.g, rgb.b}) attributes.colors.push_back(ch / 255.0f);
      }
    }
    write_obj(path, a.frames[k], a.triangles,
              fmt::format("sinew surface {} frame {} t = {:.9g} s", a.name, k, a.times[k]),
              attributes);
    paths.push_back(path);
  }
  return paths;
}

}  // namespace sinew::postprocess
