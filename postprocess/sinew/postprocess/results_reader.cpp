#include "sinew/postprocess/results_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>

#include "sinew/common/error.hpp"
#include "sinew/common/input_file.hpp"
#include "sinew/common/log.hpp"
#include "sinew/formats/file_kind.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/results_format.hpp"
#include "sinew/postprocess/results_file.hpp"

namespace sinew::postprocess {

namespace h5 = formats::hdf5;

namespace {

using formats::kResultsFormatName;
using formats::kResultsFormatVersion;

std::vector<std::string> surface_names(hid_t file, const std::string& path) {
  if (!h5::exists(file, "surfaces")) return {};
  auto names = h5::members(file, "/surfaces", path);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

h5::Handle open_results(const std::string& path) {
  require_regular_file(path, "results file");
  if (!h5::is_hdf5(path)) {
    throw FormatError(path, "", "not an HDF5 file (expected sinew results, results.h5)");
  }
  auto file = h5::open_file(path, false);
  if (!formats::has_format(file, path, kResultsFormatName)) {
    throw formats::wrong_kind(file, path, "a sinew results file",
                              "give the results.h5 that sinew-simulate wrote");
  }
  if (!h5::has_attribute(file, "format_version") ||
      h5::int_attribute(file, "format_version", path) != kResultsFormatVersion) {
    throw FormatError(path, "format_version",
                      fmt::format("unsupported results format version (this reader knows {})",
                                  kResultsFormatVersion));
  }
  return file;
}

std::vector<std::string> list_surfaces(const std::string& path) {
  auto file = open_results(path);
  return surface_names(file, path);
}

SurfaceAnimation read_surface(const std::string& path, const std::string& name) {
  auto file = open_results(path);
  const auto names = surface_names(file, path);
  std::string chosen = name;
  const bool known = std::find(names.begin(), names.end(), chosen) != names.end();
  if ((chosen.empty() && names.empty()) || (chosen == kVolumeBoundaryName && !known)) {
    return read_volume_boundary(path);
  }
  if (chosen.empty()) {
    if (names.size() > 1) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw FormatError(path, "/surfaces",
                        fmt::format("several surfaces ({}): name one with --surface", list));
    }
    chosen = names.front();
  } else if (!known) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    throw FormatError(path, "/surfaces/" + chosen,
                      fmt::format("no such surface (stored: {})", list.empty() ? "none" : list));
  }
  const std::string group = "/surfaces/" + chosen;
  const std::string tri_name = group + "/triangles", pos_name = group + "/positions";
  for (const auto& ds : {std::string("/frames/time"), tri_name, pos_name}) {
    if (!h5::exists(file, ds)) throw FormatError(path, ds, "missing dataset");
  }

  SurfaceAnimation a;
  a.file = path;
  a.name = chosen;
  a.times = h5::read<double>(file, "/frames/time", path);
  const auto tri_shape = h5::shape(file, tri_name, path);
  if (tri_shape.size() != 2 || tri_shape[1] != 3) {
    throw FormatError(path, tri_name, "expected shape T × 3");
  }
  a.triangles = h5::read<std::int32_t>(file, tri_name, path);
  const auto pos_shape = h5::shape(file, pos_name, path);
  if (pos_shape.size() != 3 || pos_shape[2] != 3) {
    throw FormatError(path, pos_name, "expected shape F × V × 3");
  }
  const std::size_t frames = a.times.size();
  if (pos_shape[0] < frames) {
    throw FormatError(
        path, pos_name,
        fmt::format("{} frames of positions for {} frame times", pos_shape[0], frames));
  }
  if (frames == 0) throw FormatError(path, "/frames/time", "no complete frame");
  const std::size_t per_frame = static_cast<std::size_t>(pos_shape[1]) * 3;
  const auto all = h5::read<float>(file, pos_name, path);
  a.frames.resize(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    a.frames[f].assign(all.begin() + static_cast<std::ptrdiff_t>(f * per_frame),
                       all.begin() + static_cast<std::ptrdiff_t>((f + 1) * per_frame));
  }
  a.rest = a.frames.front();
  const std::string uv_name = group + "/uvs", uvt_name = group + "/uv_triangles";
  if (h5::exists(file, uv_name) || h5::exists(file, uvt_name)) {
    for (const auto& ds : {uv_name, uvt_name}) {
      if (!h5::exists(file, ds))
        throw FormatError(path, ds, "missing dataset (uvs and uv_triangles go together)");
    }
    const auto uv_shape = h5::shape(file, uv_name, path);
    if (uv_shape.size() != 2 || uv_shape[1] != 2) {
      throw FormatError(path, uv_name, "expected shape Q × 2");
    }
    const auto uvt_shape = h5::shape(file, uvt_name, path);
    if (uvt_shape.size() != 2 || uvt_shape[1] != 3 || uvt_shape[0] != tri_shape[0]) {
      throw FormatError(path, uvt_name,
                        fmt::format("expected shape {} × 3 (one row per triangle)", tri_shape[0]));
    }
    a.uvs = h5::read<float>(file, uv_name, path);
    a.uv_triangles = h5::read<std::int32_t>(file, uvt_name, path);
  }
  if (h5::exists(file, "/frames/step")) {
    const auto steps = h5::read<std::int64_t>(file, "/frames/step", path);
    if (!steps.empty() && steps.front() != 0) {
      log::warn("{}: the first frame is step {}, not 0: displacements are measured from it", path,
                steps.front());
    }
  }
  validate(a);
  return a;
}

SurfaceAnimation read_volume_boundary(const std::string& path) {
  auto file = open_results(path);
  for (const auto* ds :
       {"/mesh/rest_positions", "/mesh/connectivity", "/frames/time", "/frames/displacement"}) {
    if (!h5::exists(file, ds)) throw FormatError(path, ds, "missing dataset");
  }
  const auto rest_shape = h5::shape(file, "/mesh/rest_positions", path);
  if (rest_shape.size() != 2 || rest_shape[1] != 3) {
    throw FormatError(path, "/mesh/rest_positions", "expected shape N × 3");
  }
  const auto conn_shape = h5::shape(file, "/mesh/connectivity", path);
  if (conn_shape.size() != 2 || conn_shape[1] != 8) {
    throw FormatError(path, "/mesh/connectivity", "expected shape E × 8");
  }
  const auto n = static_cast<std::size_t>(rest_shape[0]);
  const auto rest = h5::read<double>(file, "/mesh/rest_positions", path);
  const auto conn = h5::read<std::int32_t>(file, "/mesh/connectivity", path);
  for (std::size_t i = 0; i < conn.size(); ++i) {
    if (conn[i] < 0 || static_cast<std::size_t>(conn[i]) >= n) {
      throw FormatError(path, "/mesh/connectivity",
                        fmt::format("node id {} out of range [0, {})", conn[i], n))
          .at(static_cast<std::int64_t>(i / 8));
    }
  }
  // Faces shared by two elements are interior; the key is the sorted node ids.
  static constexpr int kFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                       {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::map<std::array<std::int32_t, 4>, std::pair<int, std::array<std::int32_t, 4>>> faces;
  for (std::size_t e = 0; e < conn.size() / 8; ++e) {
    for (const auto& f : kFaces) {
      std::array<std::int32_t, 4> quad{}, key{};
      for (int k = 0; k < 4; ++k) quad[k] = key[k] = conn[8 * e + static_cast<std::size_t>(f[k])];
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, 0, quad);
      ++it->second.first;
    }
  }
  std::vector<std::int32_t> index(n, -1), nodes;
  SurfaceAnimation a;
  a.file = path;
  a.name = kVolumeBoundaryName;
  for (const auto& [key, value] : faces) {
    if (value.first != 1) continue;
    for (auto node : key) index[static_cast<std::size_t>(node)] = 0;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (index[i] == 0) {
      index[i] = static_cast<std::int32_t>(nodes.size());
      nodes.push_back(static_cast<std::int32_t>(i));
    }
  }
  for (const auto& [key, value] : faces) {
    if (value.first != 1) continue;
    const auto& q = value.second;
    for (int k : {0, 1, 2, 0, 2, 3}) a.triangles.push_back(index[static_cast<std::size_t>(q[k])]);
  }
  if (a.triangles.empty()) throw FormatError(path, "/mesh/connectivity", "no elements");
  a.times = h5::read<double>(file, "/frames/time", path);
  const auto u_shape = h5::shape(file, "/frames/displacement", path);
  if (u_shape.size() != 3 || u_shape[1] != n || u_shape[2] != 3 || u_shape[0] < a.times.size()) {
    throw FormatError(path, "/frames/displacement",
                      fmt::format("expected shape F × {} × 3 with F ≥ {}", n, a.times.size()));
  }
  if (a.times.empty()) throw FormatError(path, "/frames/time", "no complete frame");
  const auto u = h5::read<float>(file, "/frames/displacement", path);
  a.frames.resize(a.times.size());
  for (std::size_t f = 0; f < a.times.size(); ++f) {
    auto& x = a.frames[f];
    x.resize(nodes.size() * 3);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const auto node = static_cast<std::size_t>(nodes[i]);
      for (std::size_t k = 0; k < 3; ++k) {
        // Name the stored dataset that holds a NaN, not the derived /surfaces/volume/positions.
        if (!std::isfinite(rest[3 * node + k])) {
          throw FormatError(path, "/mesh/rest_positions", "non-finite coordinate")
              .at(static_cast<std::int64_t>(node));
        }
        if (!std::isfinite(u[(f * n + node) * 3 + k])) {
          throw FormatError(path, "/frames/displacement",
                            fmt::format("non-finite value at node {} in frame {}", node, f))
              .at(static_cast<std::int64_t>(f));
        }
        x[3 * i + k] = static_cast<float>(rest[3 * node + k]) + u[(f * n + node) * 3 + k];
      }
    }
  }
  a.rest = a.frames.front();
  a.volume_nodes = std::move(nodes);
  validate(a);
  return a;
}

void validate(const SurfaceAnimation& a) {
  const std::string group = "/surfaces/" + a.name;
  if (a.triangles.size() % 3 != 0 || a.triangles.empty()) {
    throw FormatError(a.file, group + "/triangles", "expected T × 3 vertex ids, T > 0");
  }
  if (a.rest.size() % 3 != 0 || a.rest.empty()) {
    throw FormatError(a.file, group + "/positions", "expected V × 3 coordinates, V > 0");
  }
  const auto v = static_cast<std::int64_t>(a.vertex_count());
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    if (a.triangles[i] < 0 || a.triangles[i] >= v) {
      throw FormatError(a.file, group + "/triangles",
                        fmt::format("vertex id {} out of range [0, {})", a.triangles[i], v))
          .at(static_cast<std::int64_t>(i / 3));
    }
  }
  if (!a.uv_triangles.empty() || !a.uvs.empty()) {
    if (a.uv_triangles.size() != a.triangles.size() || a.uvs.size() % 2 != 0) {
      throw FormatError(a.file, group + "/uv_triangles",
                        fmt::format("{} texture corner ids for {} triangle corners",
                                    a.uv_triangles.size(), a.triangles.size()));
    }
    const auto q = static_cast<std::int64_t>(a.uvs.size() / 2);
    for (std::size_t i = 0; i < a.uv_triangles.size(); ++i) {
      if (a.uv_triangles[i] < 0 || a.uv_triangles[i] >= q) {
        throw FormatError(
            a.file, group + "/uv_triangles",
            fmt::format("texture coordinate id {} out of range [0, {})", a.uv_triangles[i], q))
            .at(static_cast<std::int64_t>(i / 3));
      }
    }
    for (std::size_t i = 0; i < a.uvs.size(); ++i) {
      if (!std::isfinite(a.uvs[i])) {
        throw FormatError(a.file, group + "/uvs", "non-finite texture coordinate")
            .at(static_cast<std::int64_t>(i / 2));
      }
    }
  }
  if (a.frames.size() != a.times.size() || a.frames.empty()) {
    throw FormatError(a.file, "/frames/time",
                      fmt::format("{} frame times for {} frames", a.times.size(), a.frames.size()));
  }
  for (std::size_t f = 0; f < a.times.size(); ++f) {
    if (!std::isfinite(a.times[f]) || (f > 0 && !(a.times[f] > a.times[f - 1]))) {
      throw FormatError(a.file, "/frames/time", "frame times must be finite and increasing")
          .at(static_cast<std::int64_t>(f));
    }
    if (a.frames[f].size() != a.rest.size()) {
      throw FormatError(a.file, group + "/positions", "frame has a different vertex count")
          .at(static_cast<std::int64_t>(f));
    }
    for (std::size_t i = 0; i < a.frames[f].size(); ++i) {
      if (!std::isfinite(a.frames[f][i])) {
        throw FormatError(a.file, group + "/positions",
                          fmt::format("non-finite coordinate at vertex {}", i / 3))
            .at(static_cast<std::int64_t>(f));
      }
    }
  }
}

std::vector<float> displacement_magnitude(const SurfaceAnimation& a, std::size_t frame) {
  const auto& x = a.frames.at(frame);
  std::vector<float> out(a.vertex_count());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const float dx = x[3 * i] - a.rest[3 * i], dy = x[3 * i + 1] - a.rest[3 * i + 1],
                dz = x[3 * i + 2] - a.rest[3 * i + 2];
    out[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  return out;
}

float max_displacement(const SurfaceAnimation& a) {
  float m = 0.0f;
  for (std::size_t f = 0; f < a.frame_count(); ++f) {
    for (float d : displacement_magnitude(a, f)) m = std::max(m, d);
  }
  return m;
}

}  // namespace sinew::postprocess
