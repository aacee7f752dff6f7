#include "sinew/fit/target_shapes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::fit {
namespace {

std::string line_field(int line) {
  return fmt::format("line {}", line);
}

// The whole token as a finite number, else FormatError naming `what` and the token.
double finite_token(const std::string& token, const std::string& file, int line,
                    const std::string& what) {
  char* end = nullptr;
  const double v = token.empty() ? 0.0 : std::strtod(token.c_str(), &end);
  if (token.empty() || end != token.c_str() + token.size())
    throw FormatError(file, line_field(line), fmt::format("{}: not a number: '{}'", what, token));
  if (!std::isfinite(v))
    throw FormatError(file, line_field(line),
                      fmt::format("{}: not a finite number: '{}'", what, token));
  return v;
}

// The lines of `text` without their line ends, with their 1-based numbers; blank lines and
// `#` comments left out.
std::vector<std::pair<int, std::string>> content_lines(const std::string& text) {
  std::vector<std::pair<int, std::string>> out;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const auto a = line.find_first_not_of(" \t\r");
    if (a == std::string::npos || line[a] == '#') continue;
    const auto b = line.find_last_not_of(" \t\r");
    out.emplace_back(n, line.substr(a, b - a + 1));
  }
  return out;
}

}  // namespace

TargetManifest parse_target_manifest(const std::string& text, const std::string& file,
                                     const std::string& directory) {
  TargetManifest m;
  m.file = file;
  bool header = false;
  for (const auto& [line, content] : content_lines(text)) {
    const auto comma = content.find(',');
    const std::string first = content.substr(0, comma);
    const std::string second = comma == std::string::npos ? "" : content.substr(comma + 1);
    auto trimmed = [](std::string s) {
      const auto a = s.find_first_not_of(" \t");
      const auto b = s.find_last_not_of(" \t");
      return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
    };
    const std::string t = trimmed(first), mesh = trimmed(second);
    if (!header) {
      if (t != "time" || mesh != "mesh")
        throw FormatError(file, line_field(line),
                          fmt::format("the header must be 'time,mesh', not '{}'", content));
      header = true;
      continue;
    }
    if (comma == std::string::npos || mesh.empty() || mesh.find(',') != std::string::npos)
      throw FormatError(file, line_field(line),
                        fmt::format("expected 'time,mesh' (two cells), got '{}'", content));
    const double time = finite_token(t, file, line, "time");
    if (!(time > 0))
      throw FormatError(file, line_field(line),
                        fmt::format("time {} s: a target's time must be after the scene's start "
                                    "(0 s, the rest shape)",
                                    t));
    if (!m.times.empty() && time <= m.times.back())
      throw FormatError(file, line_field(line),
                        fmt::format("time {} does not come after the previous target's {} (line "
                                    "{}): times must increase strictly",
                                    t, m.times.back(), m.lines.back()));
    const std::filesystem::path p(mesh);
    m.times.push_back(time);
    m.meshes.push_back(p.is_absolute() ? p.string()
                                       : (std::filesystem::path(directory) / p).string());
    m.lines.push_back(line);
  }
  if (!header) throw FormatError(file, "", "no header line 'time,mesh'");
  if (m.times.empty()) throw FormatError(file, "", "no target after the header");
  return m;
}

TargetManifest read_target_manifest(const std::string& path) {
  return parse_target_manifest(read_text_file(path, "target manifest"), path,
                               std::filesystem::path(path).parent_path().string());
}

ObjMesh parse_obj_mesh(const std::string& text, const std::string& file) {
  ObjMesh mesh;
  mesh.file = file;
  for (const auto& [line, content] : content_lines(text)) {
    std::istringstream in(content);
    std::string tag;
    in >> tag;
    if (tag == "v") {
      std::array<double, 3> p{};
      static constexpr const char* kAxis[] = {"x", "y", "z"};
      for (int d = 0; d < 3; ++d) {
        std::string token;
        if (!(in >> token))
          throw FormatError(file, line_field(line),
                            fmt::format("vertex {} has {} coordinates, not 3: '{}'",
                                        mesh.vertices.size() + 1, d, content));
        p[d] = finite_token(token, file, line,
                            fmt::format("vertex {} {}", mesh.vertices.size() + 1, kAxis[d]));
      }
      mesh.vertices.push_back(p);
      mesh.vertex_lines.push_back(line);
    } else if (tag == "f") {
      std::vector<std::string> corners;
      for (std::string c; in >> c;) corners.push_back(c);
      if (corners.size() != 3)
        throw FormatError(file, line_field(line),
                          fmt::format("face {} has {} vertices: the skin's faces are triangles "
                                      "(keep the rest OBJ's faces; do not quadrangulate)",
                                      mesh.face_lines.size() + 1, corners.size()));
      mesh.face_lines.push_back(line);
      // A negative index counts back from the vertices read so far; a positive one is checked
      // against the vertex count once the whole file is read.
      std::array<std::int32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const std::string id = corners[static_cast<std::size_t>(k)].substr(
            0, corners[static_cast<std::size_t>(k)].find('/'));
        char* end = nullptr;
        const long v = id.empty() ? 0 : std::strtol(id.c_str(), &end, 10);
        const long n = static_cast<long>(mesh.vertices.size());
        const long zero_based = v > 0 ? v - 1 : n + v;
        if (id.empty() || end != id.c_str() + id.size() || v == 0 || zero_based < 0 ||
            (v > 0 && v > std::numeric_limits<std::int32_t>::max()))
          throw FormatError(file, line_field(line),
                            fmt::format("face {}: not a vertex index: '{}'", mesh.face_lines.size(),
                                        corners[static_cast<std::size_t>(k)]));
        tri[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(zero_based);
      }
      mesh.triangles.push_back(tri);
    }
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (const auto id : mesh.triangles[t])
      if (id >= static_cast<std::int32_t>(mesh.vertices.size()))
        throw FormatError(file, line_field(mesh.face_lines[t]),
                          fmt::format("face {}: vertex {} does not exist (the file has {} "
                                      "vertices)",
                                      t + 1, id + 1, mesh.vertices.size()));
  if (mesh.vertices.empty()) throw FormatError(file, "", "no vertex ('v x y z' line)");
  return mesh;
}

ObjMesh read_obj_mesh(const std::string& path) {
  return parse_obj_mesh(read_text_file(path, "target mesh"), path);
}

void check_target_topology(const ObjMesh& mesh, const formats::Surface& surface) {
  const std::string hint = fmt::format(
      "a target must have the topology of the model's surface '{}' (sinew-export's rest OBJ, "
      "sculpted with its vertex order kept)",
      surface.name);
  if (mesh.vertices.size() != surface.vertices.size())
    throw FormatError(mesh.file, "v",
                      fmt::format("{} vertices, the surface has {}: {}", mesh.vertices.size(),
                                  surface.vertices.size(), hint));
  if (mesh.triangles.size() != surface.triangles.size())
    throw FormatError(mesh.file, "f",
                      fmt::format("{} faces, the surface has {}: {}", mesh.triangles.size(),
                                  surface.triangles.size(), hint));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& a = mesh.triangles[t];
    const auto& b = surface.triangles[t];
    if (a[0] != b[0] || a[1] != b[1] || a[2] != b[2])
      throw FormatError(
          mesh.file, line_field(mesh.face_lines[t]),
          fmt::format("face {} is 'f {} {} {}', the surface's is 'f {} {} {}' "
                      "(1-based): {}",
                      t + 1, a[0] + 1, a[1] + 1, a[2] + 1, b[0] + 1, b[1] + 1, b[2] + 1, hint));
  }
}

void check_target_scale(const ObjMesh& mesh, const formats::Surface& surface, double unit) {
  auto diagonal = [](const auto& points, double scale) {
    std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (const auto& p : points)
      for (int d = 0; d < 3; ++d) {
        lo[static_cast<std::size_t>(d)] = std::min(lo[static_cast<std::size_t>(d)], p[d] * scale);
        hi[static_cast<std::size_t>(d)] = std::max(hi[static_cast<std::size_t>(d)], p[d] * scale);
      }
    return std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  };
  const double target = diagonal(mesh.vertices, unit), rest = diagonal(surface.vertices, 1.0);
  if (!(target <= kTargetScaleTolerance * rest && rest <= kTargetScaleTolerance * target))
    throw FormatError(
        mesh.file, "v",
        fmt::format("the target spans {:.4g} m (its bounding box's diagonal at {:.4g} m per unit), "
                    "the surface '{}' {:.4g} m at rest: {:.3g} times its size; a target in other "
                    "units? sinew-export writes m; give --marker-unit (m per unit of the targets, "
                    "e.g. 0.001 for mm)",
                    target, unit, surface.name, rest, target / rest));
}

std::array<double, 8> trilinear_weights(const formats::Point& local) {
  // Node a of the hex8 order has natural-coordinate signs (2·di − 1, 2·dj − 1, 2·dk − 1).
  static constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                        {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  std::array<double, 8> w{};
  for (int a = 0; a < 8; ++a) {
    w[static_cast<std::size_t>(a)] = 1;
    for (int d = 0; d < 3; ++d)
      w[static_cast<std::size_t>(a)] *= (1 + (2 * kCorner[a][d] - 1) * local[d]) / 2;
  }
  return w;
}

std::vector<ProbePath> marker_paths(const TargetMarkers& targets,
                                    const std::vector<ProbePath>& probes) {
  std::vector<ProbePath> out;
  for (const auto& weights : targets.weights) {
    ProbePath p;
    p.times = probes.at(weights.front().first).times;
    p.u.assign(p.times.size(), {0, 0, 0});
    for (const auto& [probe, w] : weights) {
      const auto& q = probes.at(probe);
      if (q.times.size() != p.times.size())
        throw FormatError(targets.probes[probe], "time",
                          "its probe rows differ from the other target probes' rows");
      for (std::size_t r = 0; r < p.u.size(); ++r)
        for (int d = 0; d < 3; ++d) p.u[r][d] += w * q.u[r][d];
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<std::int32_t> spread_vertices(const formats::Surface& surface, std::size_t count,
                                          std::int32_t seed) {
  const std::size_t n = surface.vertices.size();
  std::vector<std::int32_t> chosen;
  if (count == 0 || count >= n) {
    for (std::size_t v = 0; v < n; ++v) chosen.push_back(static_cast<std::int32_t>(v));
    return chosen;
  }
  std::vector<double> d2(n, std::numeric_limits<double>::infinity());
  std::int32_t next = seed;
  while (chosen.size() < count) {
    chosen.push_back(next);
    const auto& p = surface.vertices[static_cast<std::size_t>(next)];
    std::size_t far = 0;
    for (std::size_t v = 0; v < n; ++v) {
      const auto& q = surface.vertices[v];
      const double e = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                       (p[2] - q[2]) * (p[2] - q[2]);
      d2[v] = std::min(d2[v], e);
      if (d2[v] > d2[far]) far = v;
    }
    next = static_cast<std::int32_t>(far);
  }
  return chosen;
}

TargetMarkers target_markers(const TargetManifest& manifest, const std::vector<ObjMesh>& meshes,
                             const formats::Model& model, const formats::Surface& surface,
                             std::size_t count) {
  // Seed: the vertex that moves most in any target, so the largest change is always a marker.
  std::int32_t seed = 0;
  double most = -1;
  for (const auto& mesh : meshes)
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
      double d2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double e = mesh.vertices[v][d] - surface.vertices[v][d];
        d2 += e * e;
      }
      if (d2 > most) {
        most = d2;
        seed = static_cast<std::int32_t>(v);
      }
    }
  TargetMarkers t;
  t.vertices = spread_vertices(surface, count, seed);
  std::sort(t.vertices.begin(), t.vertices.end());
  t.markers.file = manifest.file;
  t.markers.header_line = 1;
  // The nodes of the markers' elements, one probe each.
  std::vector<std::vector<std::pair<formats::Index, double>>> node_weights;
  for (const auto v : t.vertices) {
    const auto i = static_cast<std::size_t>(v);
    const auto& nodes = model.element_nodes[static_cast<std::size_t>(surface.embedding_element[i])];
    const auto w = trilinear_weights(surface.embedding_local[i]);
    node_weights.emplace_back();
    formats::Point rest{0, 0, 0};
    for (std::size_t a = 0; a < 8; ++a) {
      if (!(w[a] > 1e-12)) continue;
      node_weights.back().emplace_back(nodes[a], w[a]);
      t.nodes.push_back(nodes[a]);
      const auto x = model.node_position(nodes[a]);
      for (int d = 0; d < 3; ++d) rest[d] += w[a] * x[d];
    }
    t.rest.push_back(rest);
    t.markers.names.push_back(fmt::format("target_v{}", v));
  }
  std::sort(t.nodes.begin(), t.nodes.end());
  t.nodes.erase(std::unique(t.nodes.begin(), t.nodes.end()), t.nodes.end());
  for (const auto n : t.nodes) t.probes.push_back(fmt::format("target_n{}", n));
  for (const auto& nw : node_weights) {
    t.weights.emplace_back();
    for (const auto& [node, w] : nw)
      t.weights.back().emplace_back(
          static_cast<std::size_t>(std::lower_bound(t.nodes.begin(), t.nodes.end(), node) -
                                   t.nodes.begin()),
          w);
  }
  for (std::size_t f = 0; f < manifest.times.size(); ++f) {
    t.markers.times.push_back(manifest.times[f]);
    t.markers.lines.push_back(manifest.lines[f]);
    std::vector<std::array<double, 3>> row;
    for (std::size_t m = 0; m < t.vertices.size(); ++m) {
      const auto i = static_cast<std::size_t>(t.vertices[m]);
      row.push_back(meshes[f].vertices[i]);
    }
    t.markers.positions.push_back(std::move(row));
    t.markers.seen.push_back(std::vector<bool>(t.vertices.size(), true));
  }
  return t;
}

}  // namespace sinew::fit
