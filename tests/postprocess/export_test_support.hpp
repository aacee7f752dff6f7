#pragma once
// Helpers shared by the post-processing tests (export_test.cpp, artist_tools_test.cpp): test meshes,
// a stretching-sphere surface animation and a results file holding it, temporary folders, bytes.
#include <hdf5.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sinew/formats/hdf5_file.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "test_meshes.hpp"

namespace sinew::postprocess::testing {

namespace fs = std::filesystem;
namespace h5 = sinew::formats::hdf5;

struct Mesh {
  std::vector<float> positions;
  std::vector<std::int32_t> triangles;
};

// Icosphere (test_meshes.hpp) as a float mesh.
inline Mesh icosphere(int levels, double radius, std::array<double, 3> c = {0, 0, 0}) {
  const auto soup = sinew::simulator::testing::make_icosphere(levels, radius, c);
  Mesh m;
  for (const auto& p : soup.vertices)
    for (int k = 0; k < 3; ++k) m.positions.push_back(static_cast<float>(p[std::size_t(k)]));
  for (const auto& tri : soup.triangles)
    m.triangles.insert(m.triangles.end(), tri.begin(), tri.end());
  return m;
}

inline fs::path temp_dir(const std::string& name) {
  const auto d =
      fs::temp_directory_path() / ("sinew_export_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A surface animation: an icosphere stretched along y by (1 + 0.1 k / (F − 1)) at frame k.
inline SurfaceAnimation stretching_sphere(std::size_t frames) {
  const auto m = icosphere(2, 0.05);
  SurfaceAnimation a;
  a.name = "skin";
  a.triangles = m.triangles;
  for (std::size_t k = 0; k < frames; ++k) {
    auto x = m.positions;
    for (std::size_t i = 1; i < x.size(); i += 3) {
      x[i] *= static_cast<float>(1.0 + 0.1 * static_cast<double>(k) / (frames - 1));
    }
    a.frames.push_back(x);
    a.times.push_back(0.01 * static_cast<double>(k));
  }
  a.rest = a.frames.front();
  return a;
}

// A results file as docs/results-format.md describes it, with the animation's surface under
// /surfaces/<name> and a matching (one-element) volume mesh. `frames_extra` adds positions rows
// beyond the complete frames (a frame being written).
inline void write_results(const std::string& path, const SurfaceAnimation& a,
                          bool frames_extra = false,
                          const std::string& format = sinew::simulator::kResultsFormatName) {
  auto f = h5::create_file(path);
  h5::set_attribute(f, "format", format, path);
  h5::set_attribute(f, "format_version", std::int64_t{sinew::simulator::kResultsFormatVersion},
                    path);
  h5::create_group(f, "/mesh", path);
  h5::create_group(f, "/frames", path);
  h5::create_group(f, "/surfaces", path);
  h5::create_group(f, "/surfaces/" + a.name, path);
  std::vector<double> rest(24, 0.0);
  for (int i = 0; i < 8; ++i) {
    rest[3 * i] = i & 1 ? 0.1 : -0.1;
    rest[3 * i + 1] = i & 2 ? 0.1 : -0.1;
    rest[3 * i + 2] = i & 4 ? 0.1 : -0.1;
  }
  h5::write(f, "/mesh/rest_positions", {8, 3}, rest.data(), path);
  const std::vector<std::int32_t> conn = {0, 1, 3, 2, 4, 5, 7, 6}, mat = {0};
  h5::write(f, "/mesh/connectivity", {1, 8}, conn.data(), path);
  h5::write(f, "/mesh/material", {1}, mat.data(), path);
  const hsize_t nf = a.frame_count(), nv = a.vertex_count();
  std::vector<std::int64_t> steps(nf);
  for (hsize_t k = 0; k < nf; ++k) steps[k] = static_cast<std::int64_t>(100 * k);
  h5::write(f, "/frames/time", {nf}, a.times.data(), path);
  h5::write(f, "/frames/step", {nf}, steps.data(), path);
  std::vector<double> disp(nf * 24, 0.0);
  h5::write(f, "/frames/displacement", {nf, 8, 3}, disp.data(), path);
  std::vector<double> pos;
  for (const auto& fr : a.frames) pos.insert(pos.end(), fr.begin(), fr.end());
  if (frames_extra) pos.insert(pos.end(), a.frames.back().begin(), a.frames.back().end());
  h5::write(f, "/surfaces/" + a.name + "/positions", {nf + (frames_extra ? 1 : 0), nv, 3},
            pos.data(), path);
  h5::write(f, "/surfaces/" + a.name + "/triangles", {a.triangle_count(), 3}, a.triangles.data(),
            path);
}

template <typename T>
inline T get(const std::vector<char>& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

inline std::vector<char> slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A .glb split into its JSON document and the byte offset of each accessor's data in `bytes`.
struct Glb {
  std::vector<char> bytes;
  std::uint32_t json_len = 0;
  nlohmann::json doc;

  std::size_t data(std::size_t accessor) const {
    const auto& acc = doc["accessors"][accessor];
    const auto& v = doc["bufferViews"][acc["bufferView"].get<std::size_t>()];
    return 20 + json_len + 8 + v.value("byteOffset", std::size_t{0});
  }
};

inline Glb read_glb(const fs::path& p) {
  Glb g;
  g.bytes = slurp(p);
  g.json_len = get<std::uint32_t>(g.bytes, 12);
  g.doc = nlohmann::json::parse(g.bytes.begin() + 20, g.bytes.begin() + 20 + g.json_len);
  return g;
}

}  // namespace sinew::postprocess::testing
