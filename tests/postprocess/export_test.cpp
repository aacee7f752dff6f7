// Visual output: results reader, software rasteriser, PNG, contact sheet, glTF/PC2/OBJ writers
// and the sinew-render / sinew-export tools end to end.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "export_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/postprocess/contact_sheet.hpp"
#include "sinew/postprocess/gltf_writer.hpp"
#include "sinew/postprocess/pc2_writer.hpp"
#include "sinew/postprocess/png_writer.hpp"
#include "sinew/postprocess/rasterizer.hpp"
#include "sinew/postprocess/render_session.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "test_meshes.hpp"

namespace {

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;
namespace fs = std::filesystem;
namespace h5 = sinew::formats::hdf5;

// A cube of edge `a` centred at c (12 triangles, outward).
Mesh cube(double a, std::array<double, 3> c) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    m.positions.push_back(static_cast<float>(c[0] + (i & 1 ? a : -a) / 2));
    m.positions.push_back(static_cast<float>(c[1] + (i & 2 ? a : -a) / 2));
    m.positions.push_back(static_cast<float>(c[2] + (i & 4 ? a : -a) / 2));
  }
  m.triangles = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                 2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  return m;
}

Mesh merge(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const auto offset = static_cast<std::int32_t>(a.positions.size() / 3);
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (auto t : b.triangles) m.triangles.push_back(t + offset);
  return m;
}

// Pixels differing from `background` by more than `threshold` in any channel.
std::size_t covered(const Image& img, Rgb background, int threshold = 8) {
  std::size_t n = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const auto c = img.at(x, y);
      if (std::abs(c.r - background.r) > threshold || std::abs(c.g - background.g) > threshold ||
          std::abs(c.b - background.b) > threshold) {
        ++n;
      }
    }
  }
  return n;
}

// ---------------------------------------------------------------------------------------------

TEST(ExportImage, PngRoundTripsExactly) {
  const auto dir = temp_dir("png");
  Image img(37, 23);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      img.set(x, y,
              {static_cast<std::uint8_t>(7 * x), static_cast<std::uint8_t>(11 * y),
               static_cast<std::uint8_t>(x * y)});
    }
  }
  write_png((dir / "a.png").string(), img);
  const auto back = read_png((dir / "a.png").string());
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 23);
  EXPECT_EQ(back.pixels, img.pixels);
  std::ofstream(dir / "not.png") << "hello";
  EXPECT_THROW(read_png((dir / "not.png").string()), sinew::FormatError);
  EXPECT_THROW(write_png((dir / "missing" / "b.png").string(), img), sinew::IoError);
}

TEST(ExportRasterizer, SphereCoversTheExpectedPixelFraction) {
  // A sphere of radius r at distance d seen with vertical field of view fov: its silhouette is
  // a disc of radius (H/2) tan(asin(r/d)) / tan(fov/2) pixels.
  const double r = 0.05, d = 0.3, fov = 30.0;
  const auto m = icosphere(4, r);
  RenderOptions o;
  o.width = 240;
  o.height = 200;
  o.camera.position = {0, 0, d};
  o.camera.fov_y_deg = fov;
  const Image img = render(m.positions, m.triangles, o);
  ASSERT_EQ(img.width, 240);
  ASSERT_EQ(img.height, 200);
  const double radius_px =
      0.5 * o.height * std::tan(std::asin(r / d)) / std::tan(fov * std::numbers::pi / 360.0);
  const double expected = std::numbers::pi * radius_px * radius_px / (o.width * o.height);
  const double measured =
      static_cast<double>(covered(img, o.shading.background)) / (o.width * o.height);
  EXPECT_NEAR(measured / expected, 1.0, 0.03) << "expected " << expected << ", got " << measured;
  // Centred: the centre pixel is lit, the corners are background.
  EXPECT_NE(img.at(120, 100), o.shading.background);
  EXPECT_EQ(img.at(0, 0), o.shading.background);
  EXPECT_EQ(img.at(239, 199), o.shading.background);
}

TEST(ExportRasterizer, NearerSurfaceHidesFartherOne) {
  // Two squares facing the camera, the red-coloured one nearer: z-buffering shows it whatever
  // the drawing order.
  Mesh m;
  m.positions = {-0.1f,  -0.1f, 0.0f,  0.1f,  -0.1f,  0.0f,   0.1f,  0.1f,
                 0.0f,   -0.1f, 0.1f,  0.0f,  -0.05f, -0.05f, 0.05f, 0.05f,
                 -0.05f, 0.05f, 0.05f, 0.05f, 0.05f,  -0.05f, 0.05f, 0.05f};
  for (bool near_first : {false, true}) {
    std::vector<std::int32_t> far = {0, 1, 2, 0, 2, 3}, near = {4, 5, 6, 4, 6, 7};
    m.triangles = near_first ? near : far;
    m.triangles.insert(m.triangles.end(), (near_first ? far : near).begin(),
                       (near_first ? far : near).end());
    ScalarColoring c;
    c.values = {0, 0, 0, 0, 1, 1, 1, 1};
    c.map = ColorMap::blue_red;
    c.bar = false;
    RenderOptions o;
    o.width = o.height = 64;
    o.camera.position = {0, 0, 0.5};
    o.coloring = &c;
    const auto img = render(m.positions, m.triangles, o);
    const auto centre = img.at(32, 32);
    EXPECT_GT(centre.r, 2 * centre.b) << "near square (red) must be in front";
    const auto edge = img.at(32, 12);  // only the far (blue) square there
    EXPECT_GT(edge.b, edge.r);
  }
}

TEST(ExportRasterizer, MatchesTheStoredReferenceImage) {
  // A fixed scene: an icosphere and an intersecting cube, coloured by height (viridis), fixed
  // camera, colour bar and caption.
  const auto scene = merge(icosphere(3, 0.05), cube(0.05, {0.045, -0.02, 0.02}));
  ScalarColoring c;
  for (std::size_t i = 1; i < scene.positions.size(); i += 3)
    c.values.push_back(scene.positions[i]);
  c.min = -0.05f;
  c.max = 0.05f;
  c.label = "y (mm)";
  c.label_scale = 1000;
  RenderOptions o;
  o.width = 240;
  o.height = 180;
  o.camera.position = {0.12, 0.09, 0.25};
  o.camera.target = {0.01, 0, 0};
  o.camera.fov_y_deg = 35;
  o.coloring = &c;
  o.caption = "frame 0  t=0 s";
  const Image img = render(scene.positions, scene.triangles, o);
  const auto out_dir = temp_dir("reference");
  write_png((out_dir / "actual.png").string(), img);
  const auto ref_path = fs::path(SINEW_SOURCE_DIR) / "tests/postprocess/data/export_reference.png";
  ASSERT_TRUE(fs::exists(ref_path))
      << "missing " << ref_path << "; this run's image is in " << out_dir.string();
  const Image ref = read_png(ref_path.string());
  ASSERT_EQ(ref.width, img.width);
  ASSERT_EQ(ref.height, img.height);
  double sum = 0;
  std::size_t off = 0;
  for (std::size_t i = 0; i < img.pixels.size(); i += 3) {
    int worst = 0;
    for (int k = 0; k < 3; ++k) {
      const int dlt = std::abs(int(img.pixels[i + k]) - int(ref.pixels[i + k]));
      sum += dlt;
      worst = std::max(worst, dlt);
    }
    if (worst > 32) ++off;
  }
  const double mean = sum / static_cast<double>(img.pixels.size());
  const double off_fraction = static_cast<double>(off) / (img.width * img.height);
  EXPECT_LT(mean, 2.0) << "mean absolute difference (of 255)";
  EXPECT_LT(off_fraction, 0.01) << "fraction of pixels off by more than 32/255";
}

TEST(ExportRasterizer, AutomaticFramingKeepsTheMeshInsideFromEveryView) {
  const auto m = cube(0.1, {1.0, 2.0, -3.0});
  for (auto view : {View::front, View::side, View::top, View::three_quarter}) {
    for (auto up : {UpAxis::y, UpAxis::z}) {
      RenderOptions o;
      o.width = 160;
      o.height = 100;
      o.camera = frame_view(m.positions, view, 1.6, up);
      const auto img = render(m.positions, m.triangles, o);
      // Nothing touches the border; something is drawn.
      for (int x = 0; x < img.width; ++x) {
        ASSERT_EQ(img.at(x, 0), o.shading.background);
        ASSERT_EQ(img.at(x, img.height - 1), o.shading.background);
      }
      for (int y = 0; y < img.height; ++y) {
        ASSERT_EQ(img.at(0, y), o.shading.background);
        ASSERT_EQ(img.at(img.width - 1, y), o.shading.background);
      }
      EXPECT_GT(covered(img, o.shading.background), 1000u);
    }
  }
  EXPECT_THROW(parse_view("diagonal"), sinew::ConfigError);
}

TEST(ExportContactSheet, TilesFramesWithLabels) {
  std::vector<Image> frames(5, Image(30, 20, {0, 0, 200}));
  ContactSheetOptions o;
  o.columns = 3;
  const auto sheet = contact_sheet(frames, {"frame 0", "frame 1", "2", "3", "4"}, o);
  const int label_h = contact_sheet_label_height(o);
  EXPECT_EQ(sheet.width, 3 * (30 + o.padding) + o.padding);
  EXPECT_EQ(sheet.height, 2 * (20 + label_h + o.padding) + o.padding);
  EXPECT_EQ(sheet.at(o.padding, o.padding), (Rgb{0, 0, 200}));
  // The label band under the first tile holds ink.
  std::size_t ink = 0;
  for (int y = o.padding + 20; y < o.padding + 20 + label_h; ++y) {
    for (int x = o.padding; x < o.padding + 30; ++x) ink += sheet.at(x, y) == o.ink;
  }
  EXPECT_GT(ink, 20u);
  EXPECT_THROW(contact_sheet({}, {}, o), sinew::ConfigError);
  EXPECT_THROW(contact_sheet({Image(3, 3), Image(4, 3)}, {}, o), sinew::ConfigError);
  EXPECT_EQ(spread_frames(11, 4), (std::vector<std::size_t>{0, 3, 7, 10}));
  EXPECT_EQ(spread_frames(3, 8), (std::vector<std::size_t>{0, 1, 2}));
}

TEST(ExportResultsReader, ReadsTheSurfaceOfAResultsFile) {
  const auto dir = temp_dir("reader");
  const auto a = stretching_sphere(5);
  const auto path = (dir / "results.h5").string();
  write_results(path, a, /*frames_extra=*/true);
  EXPECT_EQ(list_surfaces(path), std::vector<std::string>{"skin"});
  const auto b = read_surface(path);
  EXPECT_EQ(b.name, "skin");
  EXPECT_EQ(b.frame_count(), 5u);  // the incomplete sixth row is ignored
  EXPECT_EQ(b.vertex_count(), a.vertex_count());
  EXPECT_EQ(b.triangles, a.triangles);
  EXPECT_EQ(b.times, a.times);
  EXPECT_EQ(b.frames[3], a.frames[3]);
  EXPECT_EQ(b.rest, a.frames[0]);
  // |u| of vertex i at the last frame = 0.1 |y_i|.
  const auto u = displacement_magnitude(b, 4);
  for (std::size_t i = 0; i < u.size(); ++i) {
    EXPECT_NEAR(u[i], 0.1 * std::abs(a.rest[3 * i + 1]), 1e-7);
  }
  EXPECT_NEAR(max_displacement(b), 0.1 * 0.05, 1e-7);
}

TEST(ExportResultsReader, RejectsBadFilesWithClearErrors) {
  const auto dir = temp_dir("bad");
  const auto good = stretching_sphere(3);
  auto expect_format_error = [](const std::string& path, const std::string& fragment) {
    try {
      read_surface(path);
      FAIL() << "no error for " << path;
    } catch (const sinew::FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  };
  const auto text = (dir / "text.h5").string();
  std::ofstream(text) << "not hdf5";
  expect_format_error(text, "not an HDF5 file");
  const auto other = (dir / "other.h5").string();
  write_results(other, good, false, "something-else");
  expect_format_error(other, "not a sinew results file");
  auto bad = good;
  bad.triangles[7] = static_cast<std::int32_t>(bad.vertex_count());
  const auto range = (dir / "range.h5").string();
  write_results(range, bad);
  expect_format_error(range, "/surfaces/skin/triangles[2]");
  EXPECT_THROW(read_surface(other.substr(0, other.size() - 3) + "_missing.h5"), sinew::IoError);
  const auto ok = (dir / "ok.h5").string();
  write_results(ok, good);
  try {
    read_surface(ok, "face");
    FAIL() << "no error for a missing surface";
  } catch (const sinew::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("no such surface (stored: skin)"), std::string::npos)
        << e.what();
  }
}

// The glTF 2.0 rules a .glb must follow (specification §4.4 and the accessor/bufferView rules).
void validate_glb(const fs::path& path, std::size_t vertices, std::size_t frames) {
  const auto bytes = slurp(path);
  ASSERT_GE(bytes.size(), 20u);
  EXPECT_EQ(get<std::uint32_t>(bytes, 0), 0x46546C67u) << "magic glTF";
  EXPECT_EQ(get<std::uint32_t>(bytes, 4), 2u) << "version";
  ASSERT_EQ(get<std::uint32_t>(bytes, 8), bytes.size()) << "header length = file length";
  const auto json_len = get<std::uint32_t>(bytes, 12);
  EXPECT_EQ(get<std::uint32_t>(bytes, 16), 0x4E4F534Au) << "first chunk JSON";
  EXPECT_EQ(json_len % 4, 0u);
  const std::size_t bin_at = 20 + json_len;
  ASSERT_LE(bin_at + 8, bytes.size());
  const auto bin_len = get<std::uint32_t>(bytes, bin_at);
  EXPECT_EQ(get<std::uint32_t>(bytes, bin_at + 4), 0x004E4942u) << "second chunk BIN";
  EXPECT_EQ(bin_len % 4, 0u);
  EXPECT_EQ(bin_at + 8 + bin_len, bytes.size());
  const auto doc = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_len);
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  ASSERT_EQ(doc["buffers"].size(), 1u);
  const std::size_t buffer_len = doc["buffers"][0]["byteLength"];
  EXPECT_LE(buffer_len, bin_len);
  EXPECT_GE(buffer_len + 3, bin_len) << "BIN chunk at most 3 padding bytes longer";
  const auto& views = doc["bufferViews"];
  for (const auto& v : views) {
    const std::size_t off = v.value("byteOffset", 0), len = v["byteLength"];
    EXPECT_LE(off + len, buffer_len);
    EXPECT_EQ(off % 4, 0u);
  }
  auto component_size = [](int type) {
    return type == 5126 || type == 5125 ? 4 : type == 5123 ? 2 : 1;
  };
  auto components = [](const std::string& t) {
    return t == "SCALAR" ? 1 : t == "VEC3" ? 3 : t == "VEC4" ? 4 : 2;
  };
  const auto& accessors = doc["accessors"];
  for (const auto& a : accessors) {
    const auto& v = views.at(a["bufferView"].get<std::size_t>());
    const std::size_t off = a.value("byteOffset", 0), count = a["count"];
    const int cs = component_size(a["componentType"]);
    const std::size_t elem = static_cast<std::size_t>(cs * components(a["type"]));
    const std::size_t stride = v.value("byteStride", elem);
    EXPECT_EQ(off % static_cast<std::size_t>(cs), 0u);
    EXPECT_GE(count, 1u);
    EXPECT_LE(off + stride * (count - 1) + elem, v["byteLength"].get<std::size_t>());
  }
  const auto& prim = doc["meshes"][0]["primitives"][0];
  auto check_position = [&](std::size_t index, bool exact_bounds) {
    const auto& a = accessors.at(index);
    ASSERT_TRUE(a.contains("min") && a.contains("max")) << "POSITION needs min/max";
    EXPECT_EQ(a["count"], vertices);
    EXPECT_EQ(a["componentType"], 5126);
    EXPECT_EQ(a["type"], "VEC3");
    if (!exact_bounds) return;
    const auto& v = views[a["bufferView"].get<std::size_t>()];
    const std::size_t base = bin_at + 8 + v.value("byteOffset", 0) + a.value("byteOffset", 0);
    for (int k = 0; k < 3; ++k) {
      float lo = 1e30f, hi = -1e30f;
      for (std::size_t i = 0; i < vertices; ++i) {
        const float x = get<float>(bytes, base + 12 * i + 4 * static_cast<std::size_t>(k));
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
      EXPECT_EQ(a["min"][k].get<float>(), lo);
      EXPECT_EQ(a["max"][k].get<float>(), hi);
    }
  };
  check_position(prim["attributes"]["POSITION"], true);
  ASSERT_EQ(prim["targets"].size(), frames);
  for (const auto& t : prim["targets"]) check_position(t["POSITION"], true);
  const auto& idx = accessors.at(prim["indices"].get<std::size_t>());
  EXPECT_EQ(idx["componentType"], 5125);
  EXPECT_EQ(idx["count"].get<std::size_t>() % 3, 0u);
  EXPECT_EQ(doc["meshes"][0]["weights"].size(), frames);
  const auto& anim = doc["animations"][0];
  const auto& s = anim["samplers"][0];
  const auto& in = accessors.at(s["input"].get<std::size_t>());
  EXPECT_TRUE(in.contains("min") && in.contains("max"));
  EXPECT_EQ(in["count"], frames);
  EXPECT_EQ(accessors.at(s["output"].get<std::size_t>())["count"], frames * frames);
  EXPECT_EQ(anim["channels"][0]["target"]["path"], "weights");
  EXPECT_EQ(anim["channels"][0]["target"]["node"], 0);
}

TEST(ExportGltf, GlbFollowsTheSpecificationRules) {
  const auto dir = temp_dir("gltf");
  const auto a = stretching_sphere(4);
  write_glb((dir / "a.glb").string(), a);
  validate_glb(dir / "a.glb", a.vertex_count(), 4);
  GltfOptions o;
  o.up = UpAxis::z;
  o.linear = true;
  o.time_scale = 10;
  write_glb((dir / "b.glb").string(), a, o);
  validate_glb(dir / "b.glb", a.vertex_count(), 4);
  // Morph target 3 + rest = frame 3 (turned to +Y up for up = z: (x, y, z) -> (x, z, -y)).
  const auto glb = read_glb(dir / "b.glb");
  const auto& bytes = glb.bytes;
  const auto& doc = glb.doc;
  const auto& prim = doc["meshes"][0]["primitives"][0];
  auto data = [&](std::size_t accessor) { return glb.data(accessor); };
  const auto rest_at = data(prim["attributes"]["POSITION"]);
  const auto t3_at = data(prim["targets"][3]["POSITION"]);
  for (std::size_t i = 0; i < a.vertex_count(); i += 7) {
    const float* x = &a.frames[3][3 * i];
    const float expect[3] = {x[0], x[2], -x[1]};
    for (std::size_t k = 0; k < 3; ++k) {
      const float got =
          get<float>(bytes, rest_at + 12 * i + 4 * k) + get<float>(bytes, t3_at + 12 * i + 4 * k);
      EXPECT_NEAR(got, expect[k], 1e-7);
    }
  }
  EXPECT_EQ(doc["animations"][0]["samplers"][0]["interpolation"], "LINEAR");
  EXPECT_FLOAT_EQ(
      doc["accessors"][doc["animations"][0]["samplers"][0]["input"].get<int>()]["max"][0]
          .get<float>(),
      0.3f);
}

TEST(ExportPc2, HeaderFrameCountAndSize) {
  const auto dir = temp_dir("pc2");
  const auto a = stretching_sphere(6);
  write_pc2((dir / "a.pc2").string(), a);
  const auto bytes = slurp(dir / "a.pc2");
  const std::size_t v = a.vertex_count();
  ASSERT_EQ(bytes.size(), kPc2HeaderBytes + 6 * v * 12);
  EXPECT_EQ(std::memcmp(bytes.data(), "POINTCACHE2\0", 12), 0);
  EXPECT_EQ(get<std::int32_t>(bytes, 12), 1);
  EXPECT_EQ(get<std::int32_t>(bytes, 16), static_cast<std::int32_t>(v));
  EXPECT_EQ(get<float>(bytes, 20), 0.0f);  // results frame 0 at frame 0, as in the glTF
  EXPECT_EQ(get<float>(bytes, 24), 1.0f);
  EXPECT_EQ(get<std::int32_t>(bytes, 28), 6);
  // Sample 5, vertex 10, y.
  EXPECT_EQ(get<float>(bytes, kPc2HeaderBytes + (5 * v + 10) * 12 + 4), a.frames[5][31]);

  write_obj((dir / "rest.obj").string(), a.rest, a.triangles, "rest");
  std::ifstream in(dir / "rest.obj");
  std::size_t nv = 0, nt = 0;
  std::string line;
  int max_index = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++nv;
    if (line.rfind("f ", 0) == 0) {
      ++nt;
      std::istringstream s(line.substr(2));
      int i;
      while (s >> i) max_index = std::max(max_index, i);
    }
  }
  EXPECT_EQ(nv, v);
  EXPECT_EQ(nt, a.triangle_count());
  EXPECT_EQ(max_index, static_cast<int>(v));  // 1-based

  const auto paths = write_obj_sequence((dir / "seq").string(), a);
  ASSERT_EQ(paths.size(), 6u);
  EXPECT_TRUE(fs::exists(dir / "seq" / "frame_0000.obj"));
  EXPECT_TRUE(fs::exists(dir / "seq" / "frame_0005.obj"));
}

TEST(ExportResultsReader, VolumeBoundaryIsClosedAndOutward) {
  // write_results stores one hex8 element of edge 0.2 m with u = 0 at every frame: its boundary
  // is 8 vertices and 12 triangles enclosing, by the divergence theorem
  // V = Σ x0 · (x1 × x2) / 6 over outward triangles, 0.008 m³.
  const auto dir = temp_dir("volume");
  const auto path = (dir / "results.h5").string();
  write_results(path, stretching_sphere(3));
  const auto b = read_volume_boundary(path);
  EXPECT_EQ(b.name, "volume");
  EXPECT_EQ(b.vertex_count(), 8u);
  EXPECT_EQ(b.triangle_count(), 12u);
  EXPECT_EQ(b.frame_count(), 3u);
  double volume = 0;
  for (std::size_t t = 0; t < b.triangles.size(); t += 3) {
    const float* p0 = &b.rest[3 * static_cast<std::size_t>(b.triangles[t])];
    const float* p1 = &b.rest[3 * static_cast<std::size_t>(b.triangles[t + 1])];
    const float* p2 = &b.rest[3 * static_cast<std::size_t>(b.triangles[t + 2])];
    volume += (p0[0] * (p1[1] * p2[2] - p1[2] * p2[1]) - p0[1] * (p1[0] * p2[2] - p1[2] * p2[0]) +
               p0[2] * (p1[0] * p2[1] - p1[1] * p2[0])) /
              6.0;
  }
  EXPECT_NEAR(volume, 0.008, 1e-9);
  // Asked for by name when no surface is called "volume".
  EXPECT_EQ(read_surface(path, "volume").triangles, b.triangles);
}

TEST(ExportResultsReader, ReadsWhatTheSimulatorsResultsWriterWrites) {
  // One hex8 element (edge 0.1 m) holding an icosphere as its visual surface, displaced by the
  // linear field u = (0, s y, 0), which the hex8 embedding reproduces exactly: the surface read
  // back must be X + (0, s Y, 0).
  namespace formats = sinew::formats;
  formats::Model model;
  const double h = 0.1;
  model.grid.voxel_size = h;
  model.grid.dims = {1, 1, 1};
  model.node_lattice = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                        {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  model.element_lattice = {{0, 0, 0}};
  model.element_nodes = {{0, 1, 2, 3, 4, 5, 6, 7}};
  model.materials.resize(1);
  model.material_offsets = {0, 1};
  model.material_ids = {0};
  model.material_fractions = {1.0};
  const auto sphere = icosphere(2, 0.04, {0.05, 0.05, 0.05});
  formats::Surface skin;
  skin.name = "skin";
  skin.role = formats::SurfaceRole::visual;
  for (std::size_t i = 0; i < sphere.positions.size(); i += 3) {
    const formats::Point x = {sphere.positions[i], sphere.positions[i + 1],
                              sphere.positions[i + 2]};
    skin.vertices.push_back(x);
    skin.embedding_element.push_back(0);
    skin.embedding_local.push_back({2 * x[0] / h - 1, 2 * x[1] / h - 1, 2 * x[2] / h - 1});
  }
  for (std::size_t t = 0; t < sphere.triangles.size(); t += 3) {
    skin.triangles.push_back(
        {sphere.triangles[t], sphere.triangles[t + 1], sphere.triangles[t + 2]});
  }
  model.surfaces.push_back(skin);
  const auto dir = temp_dir("writer");
  sinew::simulator::ResultsOptions options;
  options.surfaces = true;
  const std::vector<double> strain = {0.0, 0.05, 0.1};
  {
    sinew::simulator::ResultsWriter writer(dir.string(), model, options);
    for (std::size_t k = 0; k < strain.size(); ++k) {
      std::vector<double> u(24, 0.0);
      for (std::size_t n = 0; n < 8; ++n) u[3 * n + 1] = strain[k] * h * model.node_lattice[n][1];
      writer.append_frame(0.1 * static_cast<double>(k), static_cast<std::int64_t>(10 * k), u, {});
    }
  }
  const auto a = read_surface((dir / "results.h5").string());
  ASSERT_EQ(a.frame_count(), 3u);
  ASSERT_EQ(a.vertex_count(), skin.vertices.size());
  EXPECT_EQ(a.triangles, sphere.triangles);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(a.times[k], 0.1 * static_cast<double>(k));
    for (std::size_t i = 0; i < a.vertex_count(); ++i) {
      const auto& x = skin.vertices[i];
      EXPECT_NEAR(a.frames[k][3 * i], x[0], 1e-7);
      EXPECT_NEAR(a.frames[k][3 * i + 1], x[1] * (1 + strain[k]), 1e-7);
      EXPECT_NEAR(a.frames[k][3 * i + 2], x[2], 1e-7);
    }
  }
  const auto u = displacement_magnitude(a, 2);
  EXPECT_NEAR(u[0], 0.1 * skin.vertices[0][1], 1e-7);
}

#if defined(SINEW_RENDER_EXE) && defined(SINEW_EXPORT_EXE)
TEST(ExportTools, RenderAndExportAResultsFile) {
  const auto dir = temp_dir("tools");
  const auto results = (dir / "results.h5").string();
  write_results(results, stretching_sphere(5));
  auto run = [&](const std::string& args) {
    const std::string cmd =
        std::string(SINEW_RENDER_EXE) + " " + args + " > " + (dir / "log.txt").string() + " 2>&1";
    return std::system(cmd.c_str());
  };
  auto run_export = [&](const std::string& args) {
    const std::string cmd =
        std::string(SINEW_EXPORT_EXE) + " " + args + " > " + (dir / "log.txt").string() + " 2>&1";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(run(results + " --color displacement --size 200x150 -o " + (dir / "last.png").string() +
                " --sequence " + (dir / "seq").string() + " --contact-sheet " +
                (dir / "sheet.png").string() + " --columns 3"),
            0);
  const auto last = read_png((dir / "last.png").string());
  EXPECT_EQ(last.width, 200);
  EXPECT_EQ(last.height, 150);
  EXPECT_GT(covered(last, {255, 255, 255}), 3000u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(fs::exists(dir / "seq" / ("frame_000" + std::to_string(k) + ".png")));
  }
  const auto sheet = read_png((dir / "sheet.png").string());
  EXPECT_GT(sheet.width, 3 * 200);
  EXPECT_GT(sheet.height, 2 * 150);
  EXPECT_NE(run(results + " --frame 9 -o " + (dir / "x.png").string()), 0);
  ASSERT_EQ(run_export(results + " --glb " + (dir / "a.glb").string() + " --pc2 " +
                       (dir / "a.pc2").string() + " --rest-obj " + (dir / "rest.obj").string() +
                       " --obj-sequence " + (dir / "objs").string()),
            0);
  validate_glb(dir / "a.glb", stretching_sphere(5).vertex_count(), 5);
  EXPECT_TRUE(fs::exists(dir / "a.pc2"));
  EXPECT_TRUE(fs::exists(dir / "rest.obj"));
  EXPECT_TRUE(fs::exists(dir / "objs" / "frame_0004.obj"));
  EXPECT_NE(run_export(results + " --pc2 " + (dir / "b.pc2").string()), 0);
}

// --gif without ffmpeg: a `convert` on PATH that is not ImageMagick's is named as such, not called
// missing (a stand-in `convert` made the old message "neither ... is on PATH" untrue).
TEST(ExportTools, GifWithoutAnEncoderSaysWhichToolIsWrong) {
  const auto dir = temp_dir("gif_encoder");
  const auto results = (dir / "results.h5").string();
  write_results(results, stretching_sphere(2));
  fs::create_directories(dir / "bin");
  const auto fake = dir / "bin" / "convert";
  std::ofstream(fake) << "#!/bin/sh\necho 'Version: not an image tool'\n";
  fs::permissions(fake, fs::perms::owner_all);
  const auto log = (dir / "log.txt").string();
  auto gif = [&](const std::string& path) {
    const std::string cmd = "PATH='" + path + "' " + SINEW_RENDER_EXE + " " + results + " --gif " +
                            (dir / "a.gif").string() + " > " + log + " 2>&1";
    return std::system(cmd.c_str());
  };
  auto text = [&] {
    std::ifstream in(log);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_NE(gif((dir / "bin").string()), 0);
  EXPECT_NE(text().find("is not ImageMagick's"), std::string::npos) << text();
  EXPECT_FALSE(fs::exists(dir / "a.gif"));
  EXPECT_NE(gif((dir / "empty").string()), 0);
  EXPECT_NE(text().find("neither is ImageMagick's convert"), std::string::npos) << text();
}
#endif

}  // namespace
