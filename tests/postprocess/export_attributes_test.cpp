// The exports' timing (frame_timing), per-vertex attributes (vertex_attributes: normals, colours;
// element_fields: the von Mises stress carried from elements to vertices)
// as written into glTF and OBJ files, and the temporary-name-then-rename writes (common/atomic_file.hpp).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "export_test_support.hpp"
#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/postprocess/element_fields.hpp"
#include "sinew/postprocess/frame_timing.hpp"
#include "sinew/postprocess/gltf_writer.hpp"
#include "sinew/postprocess/pc2_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/vertex_attributes.hpp"

namespace {

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;

std::vector<double> uniform_times(std::size_t n, double dt) {
  std::vector<double> t;
  for (std::size_t k = 0; k < n; ++k) t.push_back(dt * static_cast<double>(k));
  return t;
}

TEST(ExportTiming, DefaultRateIs24Or30FromTheOutputRate) {
  EXPECT_EQ(default_fps(uniform_times(33, 0.005)), 24.0);  // 200 Hz: the brow raise demo
  EXPECT_EQ(default_fps(uniform_times(10, 1.0 / 60)), 30.0);
  EXPECT_EQ(default_fps(uniform_times(10, 1.0 / 30)), 30.0);
  EXPECT_EQ(default_fps(uniform_times(10, 0.01)), 24.0);       // 100 Hz
  EXPECT_EQ(default_fps(uniform_times(10, 0.001)), 24.0);      // 1 kHz
  EXPECT_EQ(default_fps(uniform_times(10, 1.0 / 120)), 24.0);  // 5× and 4×: a tie
  EXPECT_EQ(default_fps({0.0}), 24.0);
  // Time scale: 10 ms × 10 = 0.1 s is 3 frames at 30 fps, 2.4 at 24.
  EXPECT_EQ(default_fps(uniform_times(10, 0.01), 10.0), 30.0);
  EXPECT_EQ(default_fps(uniform_times(10, 0.01), 25.0), 24.0);  // 6 frames at 24
  // A short last interval (duration not a whole number of intervals) does not change the rate.
  auto t = uniform_times(10, 1.0 / 60);
  t.back() = t[8] + 0.001;
  EXPECT_EQ(default_fps(t), 30.0);
}

TEST(ExportTiming, KeyTimesNeverFallAfterTheirFrame) {
  for (double fps : {24.0, 25.0, 30.0, 30000.0 / 1001.0, 60.0}) {
    for (std::int64_t n = 0; n < 20000; ++n) {
      const float t = key_time(n, fps);
      ASSERT_LE(static_cast<double>(t) * fps, static_cast<double>(n)) << fps << " " << n;
      // ... and is the last float that does not (so at most one float step early).
      const float next = std::nextafter(t, 1e30f);
      ASSERT_GT(static_cast<double>(next) * fps, static_cast<double>(n)) << fps << " " << n;
    }
  }
}

TEST(ExportTiming, OneResultsFramePerFrameByDefault) {
  const auto timing = frame_timing(uniform_times(33, 0.005));
  EXPECT_EQ(timing.fps, 24.0);
  ASSERT_EQ(timing.frame.size(), 33u);
  for (std::size_t k = 0; k < 33; ++k) {
    EXPECT_EQ(timing.frame[k], static_cast<std::int64_t>(k));
    EXPECT_EQ(timing.time[k], key_time(static_cast<std::int64_t>(k), 24.0));
  }
  EXPECT_EQ(frame_timing(uniform_times(3, 0.005), {.fps = 60}).fps, 60.0);
}

TEST(ExportTiming, TimeScaleSnapsToFramesAndRefusesTwoOnOne) {
  // Times a rounding error after multiples of 5 ms (what the issue saw), 40× slower at 30 fps:
  // 6 frames per results frame, on the frames exactly.
  std::vector<double> t;
  for (int k = 0; k < 8; ++k) t.push_back(0.005 * k * (1 + 1e-12));
  const auto timing = frame_timing(t, {.fps = 30, .time_scale = 40});
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_EQ(timing.frame[k], 6 * static_cast<std::int64_t>(k));
  }
  try {
    frame_timing(t, {.fps = 24, .time_scale = 2});  // 0.24 frames per results frame
    FAIL() << "expected a ConfigError";
  } catch (const sinew::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--time-scale"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("same frame"), std::string::npos) << e.what();
  }
  // The default rate for 40 ms × 1 would be 24 fps, 0.96 frames apart (frames 12 and 13 both on
  // 12): 30 keeps them apart.
  const auto apart = frame_timing(uniform_times(20, 0.04), {.time_scale = 1});
  EXPECT_EQ(apart.fps, 30.0);
  EXPECT_EQ(apart.frame.back(), 23);                                       // 0.76 s × 30 = 22.8
  EXPECT_THROW(frame_timing(t, {.time_scale = 0.1}), sinew::ConfigError);  // both collide
  EXPECT_THROW(frame_timing(t, {.fps = -1}), sinew::ConfigError);
  EXPECT_THROW(frame_timing(t, {.fps = 24, .time_scale = -1}), sinew::ConfigError);
  EXPECT_THROW(frame_timing(t, {.fps = 24, .time_scale = 1e300}), sinew::ConfigError);
}

TEST(ExportAttributes, SmoothNormalsOfASpherePointOutward) {
  const auto m = icosphere(2, 0.05);
  const auto n = smooth_normals(m.positions, m.triangles);
  ASSERT_EQ(n.size(), m.positions.size());
  for (std::size_t i = 0; i < n.size(); i += 3) {
    const double len = std::hypot(n[i], n[i + 1], n[i + 2]);
    EXPECT_NEAR(len, 1.0, 1e-6);
    const double r = std::hypot(m.positions[i], m.positions[i + 1], m.positions[i + 2]);
    const double cos =
        (n[i] * m.positions[i] + n[i + 1] * m.positions[i + 1] + n[i + 2] * m.positions[i + 2]) / r;
    EXPECT_GT(cos, 0.99) << "vertex " << i / 3;
  }
  // A vertex of no triangle gets the fallback, still unit length.
  auto p = m.positions;
  p.insert(p.end(), {1.0f, 1.0f, 1.0f});
  const auto n2 = smooth_normals(p, m.triangles, {0.0f, 1.0f, 0.0f});
  EXPECT_EQ(n2[n2.size() - 2], 1.0f);
}

// The glTF's NORMAL and morph-target normals give each frame's smooth normals; COLOR_0 and
// _DISPLACEMENT give the peak displacement.
TEST(ExportAttributes, GltfCarriesNormalsPerFrameAndThePeakDisplacement) {
  const auto dir = temp_dir("attributes");
  const auto a = stretching_sphere(4);
  GltfOptions o;
  o.color = VertexScalar::displacement;
  write_glb((dir / "a.glb").string(), a, o);
  const auto glb = read_glb(dir / "a.glb");
  const auto& bytes = glb.bytes;
  const auto& doc = glb.doc;
  const auto& prim = doc["meshes"][0]["primitives"][0];
  auto data = [&](std::size_t accessor) { return glb.data(accessor); };
  const auto nv = a.vertex_count();
  const auto base = data(prim["attributes"]["NORMAL"]);
  for (std::size_t k = 0; k < a.frame_count(); ++k) {
    const auto want = smooth_normals(a.frames[k], a.triangles);
    const auto delta = data(prim["targets"][k]["NORMAL"]);
    for (std::size_t i = 0; i < 3 * nv; ++i) {
      const float got = get<float>(bytes, base + 4 * i) + get<float>(bytes, delta + 4 * i);
      ASSERT_NEAR(got, want[i], 1e-6) << "frame " << k << " component " << i;
    }
  }
  const auto peak = peak_displacement(a);
  const auto d_at = data(prim["attributes"]["_DISPLACEMENT"]);
  const auto c_at = data(prim["attributes"]["COLOR_0"]);
  float max = 0;
  for (std::size_t i = 0; i < nv; ++i) {
    EXPECT_EQ(get<float>(bytes, d_at + 4 * i), peak[i]);
    max = std::max(max, peak[i]);
    for (std::size_t c = 0; c < 3; ++c) {
      const float x = get<float>(bytes, c_at + 12 * i + 4 * c);
      EXPECT_TRUE(x >= 0.0f && x <= 1.0f);
    }
  }
  EXPECT_NEAR(max, 0.1f * 0.05f, 1e-6);  // the poles move by 10 % of the radius
  EXPECT_FLOAT_EQ(doc["materials"][0]["extras"]["max_m"].get<float>(), max);
  EXPECT_EQ(doc["animations"][0]["extras"]["fps"], 24.0);
}

TEST(ExportAttributes, ObjCarriesNormalsAndColours) {
  const auto dir = temp_dir("obj_attributes");
  const auto a = stretching_sphere(3);
  const auto paths =
      write_obj_sequence((dir / "seq").string(), a, "frame", VertexScalar::displacement);
  ASSERT_EQ(paths.size(), 3u);
  std::ifstream in(paths[2]);
  std::size_t v = 0, vn = 0, f = 0;
  std::string line;
  const auto n = smooth_normals(a.frames[2], a.triangles);
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      double x[6];
      ASSERT_TRUE(s >> x[0] >> x[1] >> x[2] >> x[3] >> x[4] >> x[5]) << line;
      for (int c = 3; c < 6; ++c) EXPECT_TRUE(x[c] >= 0 && x[c] <= 1) << line;
      ++v;
    } else if (tag == "vn") {
      double x[3];
      ASSERT_TRUE(s >> x[0] >> x[1] >> x[2]) << line;
      for (std::size_t c = 0; c < 3; ++c) EXPECT_NEAR(x[c], n[3 * vn + c], 1e-6);
      ++vn;
    } else if (tag == "f") {
      std::string corner;
      while (s >> corner) {
        const auto slash = corner.find("//");
        ASSERT_NE(slash, std::string::npos) << line;
        EXPECT_EQ(corner.substr(0, slash), corner.substr(slash + 2)) << line;
      }
      ++f;
    }
  }
  EXPECT_EQ(v, a.vertex_count());
  EXPECT_EQ(vn, a.vertex_count());
  EXPECT_EQ(f, a.triangle_count());
  EXPECT_THROW(write_obj((dir / "bad.obj").string(), a.rest, a.triangles, "",
                         {.normals = {1, 0, 0}, .colors = {}}),
               sinew::ConfigError);
}

// No temporary file is left behind, and a failed write leaves the final name untouched.
TEST(ExportOutputFile, WritesByRenameAndCleansUpAfterAnError) {
  const auto dir = temp_dir("output_file");
  const auto path = (dir / "a.glb").string();
  sinew::write_text_atomically(path, "first");
  sinew::write_text_atomically(path, "second");
  const auto content = slurp(path);
  EXPECT_EQ(std::string(content.begin(), content.end()), "second");
  // Renaming onto a non-empty directory fails: the temporary file must go.
  fs::create_directories(dir / "taken.glb" / "inside");
  EXPECT_THROW(sinew::write_text_atomically((dir / "taken.glb").string(), "x"), sinew::IoError);
  EXPECT_THROW(sinew::write_text_atomically((dir / "missing" / "a.glb").string(), "x"),
               sinew::IoError);
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++entries;
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }
  EXPECT_EQ(entries, 2u);  // a.glb and taken.glb/
}

// A results file of two unit elements along x (nodes (i, j, k), i = 0..2, id i + 3 (j + 2 k)),
// two frames, von Mises 0 everywhere in frame 0 and (1, 3) Pa in elements (0, 1) in frame 1, and a
// visual surface "skin" of three vertices embedded at known natural coordinates. With
// `stress` false the file has no /frames/von_mises.
void write_two_element_results(const std::string& path, bool stress = true) {
  auto f = h5::create_file(path);
  h5::set_attribute(f, "format", std::string(sinew::simulator::kResultsFormatName), path);
  h5::set_attribute(f, "format_version", std::int64_t{sinew::simulator::kResultsFormatVersion},
                    path);
  for (const char* g : {"/mesh", "/frames", "/surfaces", "/surfaces/skin"})
    h5::create_group(f, g, path);
  std::vector<double> rest;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) rest.insert(rest.end(), {double(i), double(j), double(k)});
  h5::write(f, "/mesh/rest_positions", {12, 3}, rest.data(), path);
  std::vector<std::int32_t> conn;
  for (int e = 0; e < 2; ++e)
    for (const auto& c : {std::array<int, 3>{0, 0, 0},
                          {1, 0, 0},
                          {1, 1, 0},
                          {0, 1, 0},
                          {0, 0, 1},
                          {1, 0, 1},
                          {1, 1, 1},
                          {0, 1, 1}})
      conn.push_back(e + c[0] + 3 * (c[1] + 2 * c[2]));
  h5::write(f, "/mesh/connectivity", {2, 8}, conn.data(), path);
  const std::vector<double> times = {0.0, 0.01}, u(2 * 12 * 3, 0.0);
  const std::vector<std::int64_t> steps = {0, 10};
  h5::write(f, "/frames/time", {2}, times.data(), path);
  h5::write(f, "/frames/step", {2}, steps.data(), path);
  h5::write(f, "/frames/displacement", {2, 12, 3}, u.data(), path);
  const std::vector<double> von_mises = {0.0, 0.0, 1.0, 3.0};
  if (stress) h5::write(f, "/frames/von_mises", {2, 2}, von_mises.data(), path);
  // Vertices: element 0's centre (x = 0.5), on the shared face (x = 1), at x = 1.75 in element 1.
  const std::vector<double> x = {0.5, 0.5, 0.5, 1.0, 0.65, 0.4, 1.75, 1.0, 1.0};
  std::vector<double> positions(x);
  positions.insert(positions.end(), x.begin(), x.end());
  h5::write(f, "/surfaces/skin/positions", {2, 3, 3}, positions.data(), path);
  const std::vector<std::int32_t> tri = {0, 1, 2}, element = {0, 1, 1};
  h5::write(f, "/surfaces/skin/triangles", {1, 3}, tri.data(), path);
  h5::write(f, "/surfaces/skin/embedding_element", {3}, element.data(), path);
  const std::vector<double> local = {0, 0, 0, -1, 0.3, -0.2, 0.5, 1, 1};
  h5::write(f, "/surfaces/skin/embedding_local", {3, 3}, local.data(), path);
}

// Nodal averages (1 at x = 0, (1 + 3) / 2 = 2 at x = 1, 3 at x = 2) interpolated by the hex8
// functions, linear in x here: 1.5, 2 and 2.75 Pa; frame 0 is zero.
TEST(ExportElementFields, VonMisesIsNodeAveragedAndInterpolated) {
  const auto dir = temp_dir("element_fields");
  const auto path = (dir / "results.h5").string();
  write_two_element_results(path);
  const auto a = read_surface(path, "skin");
  const auto s = element_field_at_vertices(path, a, "/frames/von_mises");
  ASSERT_EQ(s.size(), 2u);
  for (float v : s[0]) EXPECT_EQ(v, 0.0f);
  ASSERT_EQ(s[1].size(), 3u);
  EXPECT_NEAR(s[1][0], 1.5f, 1e-6);
  EXPECT_NEAR(s[1][1], 2.0f, 1e-6);
  EXPECT_NEAR(s[1][2], 2.75f, 1e-6);
  // The volume's boundary: every node, its nodal average.
  const auto v = read_surface(path, "volume");
  const auto sv = element_field_at_vertices(path, v, "/frames/von_mises");
  ASSERT_EQ(v.vertex_count(), 12u);
  for (std::size_t i = 0; i < v.vertex_count(); ++i)
    EXPECT_NEAR(sv[1][i], 1.0 + v.rest[3 * i], 1e-6) << "node at x = " << v.rest[3 * i];

  // glTF: _VON_MISES holds the peak (frame 1), COLOR_0 viridis over [0, 2.75 Pa].
  GltfOptions o;
  o.color = VertexScalar::von_mises;
  o.color_values = s;
  const auto glb = dir / "stress.glb";
  write_glb(glb.string(), a, o);
  const auto bytes = slurp(glb);
  const auto json_len = get<std::uint32_t>(bytes, 12);
  const auto doc = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_len);
  const auto& attributes = doc["meshes"][0]["primitives"][0]["attributes"];
  ASSERT_TRUE(attributes.contains("_VON_MISES"));
  ASSERT_TRUE(attributes.contains("COLOR_0"));
  const auto& acc = doc["accessors"][attributes["_VON_MISES"].get<int>()];
  const auto& view = doc["bufferViews"][acc["bufferView"].get<int>()];
  const std::size_t at = 20 + json_len + 8 + view["byteOffset"].get<std::size_t>();
  EXPECT_NEAR(get<float>(bytes, at), 1.5f, 1e-6);
  EXPECT_NEAR(get<float>(bytes, at + 8), 2.75f, 1e-6);
  EXPECT_EQ(doc["materials"][0]["extras"]["unit"], "Pa");
  EXPECT_NEAR(doc["materials"][0]["extras"]["max_pa"].get<double>(), 2.75, 1e-6);
  // OBJ sequence: frame 1's vertex colours are viridis over [0, 2.75]: the last vertex at the top.
  const auto paths =
      write_obj_sequence((dir / "seq").string(), a, "frame", VertexScalar::von_mises, s);
  ASSERT_EQ(paths.size(), 2u);
  std::ifstream obj(paths[1]);
  std::string line, last_v;
  while (std::getline(obj, line))
    if (line.rfind("v ", 0) == 0) last_v = line;
  const Rgb top = map_color(ColorMap::viridis, 1.0);
  EXPECT_NE(last_v.find(fmt::format("{:.4f} {:.4f} {:.4f}", top.r / 255.0f, top.g / 255.0f,
                                    top.b / 255.0f)),
            std::string::npos)
      << last_v;
}

TEST(ExportElementFields, MissingStressOrEmbeddingIsAClearError) {
  const auto dir = temp_dir("element_fields_missing");
  const auto path = (dir / "results.h5").string();
  write_two_element_results(path, false);
  const auto a = read_surface(path, "skin");
  try {
    element_field_at_vertices(path, a, "/frames/von_mises");
    ADD_FAILURE() << "no error without /frames/von_mises";
  } catch (const sinew::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("/frames/von_mises"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("output.fields including stress"), std::string::npos)
        << e.what();
  }
  // A results file written before surfaces carried their embedding.
  const auto old = (dir / "old.h5").string();
  write_results(old, stretching_sphere(2));
  {
    auto f = h5::open_file(old, true);
    const std::vector<double> zero(2, 0.0);
    h5::write(f, "/frames/von_mises", {2, 1}, zero.data(), old);
  }
  const auto b = read_surface(old);
  try {
    element_field_at_vertices(old, b, "/frames/von_mises");
    ADD_FAILURE() << "no error without the embedding";
  } catch (const sinew::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("/surfaces/skin/embedding_element"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("run the scene again"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_vertex_scalar("stress"), sinew::ConfigError);
  EXPECT_EQ(parse_vertex_scalar("von_mises"), VertexScalar::von_mises);
}

}  // namespace
