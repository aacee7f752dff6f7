// The artist's texture coordinates from a skin mesh to the exported files: an OBJ box whose six
// faces each have their own square of a texture atlas (a seam along every edge: a corner vertex
// carries three (u, v)) goes through sinew-voxelize (model file), sinew-simulate (results file)
// and sinew-export (glTF TEXCOORD_0, rest OBJ and OBJ sequence `vt`). Every triangle must come out
// with the same corners: the same positions with the same (u, v) at each, compared as sets of
// triangles whatever the vertex numbering. Then the Khronos glTF validator and Blender 3.4
// (blender_uv_check.py: the UV layer of the imported glTF and OBJ) when installed (each skips,
// saying so, without its tool).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "export_test_support.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace {

using namespace sinew::postprocess;
using namespace sinew::postprocess::testing;

// One triangle corner: position in µm and (u, v) in 1e-6, rounded (the files hold float32).
using Corner = std::array<long long, 5>;
// A triangle as its corners from the smallest one on (the cyclic order, i.e. the orientation,
// is kept).
using Triangle = std::array<Corner, 3>;

Corner corner(double x, double y, double z, double u, double v) {
  return {std::llround(x * 1e6), std::llround(y * 1e6), std::llround(z * 1e6),
          std::llround(u * 1e6), std::llround(v * 1e6)};
}

Triangle canonical(Triangle t) {
  const auto first = std::min_element(t.begin(), t.end()) - t.begin();
  std::rotate(t.begin(), t.begin() + first, t.end());
  return t;
}

int run(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " > '" + log.string() + "' 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The box [0, 12] × [0, 4] × [0, 4] mm, each face an n × n grid of quads (two triangles each),
// outward, positions shared between faces; face f's texture square is cell (f mod 3, f / 3) of a
// 3 × 2 atlas. Writes the OBJ (mm) and returns its triangles in metres.
std::set<Triangle> write_atlas_box(const fs::path& path, int n) {
  const double size[3] = {12, 4, 4};
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<double, 2>> uvs;
  std::string faces;
  std::set<Triangle> triangles;
  auto vertex = [&](std::array<double, 3> p) {
    const auto at = std::find(vertices.begin(), vertices.end(), p);
    if (at != vertices.end()) return static_cast<int>(at - vertices.begin()) + 1;
    vertices.push_back(p);
    return static_cast<int>(vertices.size());
  };
  int f = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side, ++f) {
      // (a, b): the face's in-plane axes, ordered so that a × b points outward.
      const int a = side == 1 ? (axis + 1) % 3 : (axis + 2) % 3;
      const int b = side == 1 ? (axis + 2) % 3 : (axis + 1) % 3;
      auto point = [&](int i, int j) {
        std::array<double, 3> p{};
        p[axis] = side * size[axis];
        p[a] = size[a] * i / n;
        p[b] = size[b] * j / n;
        return p;
      };
      auto uv = [&](int i, int j) {
        uvs.push_back({(f % 3 + double(i) / n) / 3.0, (f / 3 + double(j) / n) / 2.0});
        return static_cast<int>(uvs.size());
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const std::array<std::array<int, 2>, 4> q = {
              {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}}};
          std::array<int, 4> v{}, t{};
          for (int k = 0; k < 4; ++k) {
            v[k] = vertex(point(q[k][0], q[k][1]));
            t[k] = uv(q[k][0], q[k][1]);
          }
          for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
            faces += "f";
            Triangle key;
            for (int k = 0; k < 3; ++k) {
              faces += " " + std::to_string(v[tri[k]]) + "/" + std::to_string(t[tri[k]]);
              const auto& p = vertices[v[tri[k]] - 1];
              const auto& w = uvs[t[tri[k]] - 1];
              key[k] = corner(p[0] * 1e-3, p[1] * 1e-3, p[2] * 1e-3, w[0], w[1]);
            }
            faces += "\n";
            triangles.insert(canonical(key));
          }
        }
      }
    }
  }
  std::ofstream out(path);
  out << "# a box with a texture atlas, mm\n";
  for (const auto& p : vertices) out << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
  out.precision(17);
  for (const auto& w : uvs) out << "vt " << w[0] << " " << w[1] << "\n";
  out << faces;
  return triangles;
}

// The triangles of an OBJ with `v`, `vt` and `f v/vt[/vn]` lines.
std::set<Triangle> obj_triangles(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::array<double, 3>> v;
  std::vector<std::array<double, 2>> vt;
  std::set<Triangle> out;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream is(line);
    std::string tag;
    is >> tag;
    if (tag == "v") {
      std::array<double, 3> p{};
      is >> p[0] >> p[1] >> p[2];
      v.push_back(p);
    } else if (tag == "vt") {
      std::array<double, 2> w{};
      is >> w[0] >> w[1];
      vt.push_back(w);
    } else if (tag == "f") {
      Triangle t;
      for (int k = 0; k < 3; ++k) {
        std::string c;
        is >> c;
        const auto slash = c.find('/');
        EXPECT_NE(slash, std::string::npos) << path << ": a face without texture ids: " << line;
        if (slash == std::string::npos) return out;
        const int a = std::stoi(c.substr(0, slash)) - 1, b = std::stoi(c.substr(slash + 1)) - 1;
        t[k] = corner(v.at(a)[0], v.at(a)[1], v.at(a)[2], vt.at(b)[0], vt.at(b)[1]);
      }
      out.insert(canonical(t));
    }
  }
  return out;
}

// The triangles of a .glb's first primitive: POSITION, TEXCOORD_0 turned back to OBJ's v up.
std::set<Triangle> glb_triangles(const fs::path& path) {
  const auto bytes = slurp(path);
  const auto json_len = get<std::uint32_t>(bytes, 12);
  const auto doc = nlohmann::json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_len);
  const std::size_t bin = 20 + json_len + 8;
  auto data = [&](int accessor) {
    const auto& acc = doc["accessors"][accessor];
    const auto& view = doc["bufferViews"][acc["bufferView"].get<int>()];
    return bin + view["byteOffset"].get<std::size_t>() + acc["byteOffset"].get<std::size_t>();
  };
  const auto& prim = doc["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_0")) << path;
  if (!prim["attributes"].contains("TEXCOORD_0")) return {};
  const auto pos = data(prim["attributes"]["POSITION"].get<int>());
  const auto uv = data(prim["attributes"]["TEXCOORD_0"].get<int>());
  const auto idx = data(prim["indices"].get<int>());
  const auto count = doc["accessors"][prim["indices"].get<int>()]["count"].get<std::size_t>();
  std::set<Triangle> out;
  for (std::size_t t = 0; t < count / 3; ++t) {
    Triangle tri;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto i = get<std::uint32_t>(bytes, idx + 4 * (3 * t + k));
      tri[k] = corner(get<float>(bytes, pos + 12 * i), get<float>(bytes, pos + 12 * i + 4),
                      get<float>(bytes, pos + 12 * i + 8), get<float>(bytes, uv + 8 * i),
                      1.0 - get<float>(bytes, uv + 8 * i + 4));
    }
    out.insert(canonical(tri));
  }
  return out;
}

TEST(TextureCoordinates, FromTheSkinMeshToGltfAndObj) {
  const auto dir = temp_dir("uv");
  const auto expected = write_atlas_box(dir / "skin.obj", 4);
  ASSERT_EQ(expected.size(), 6u * 4 * 4 * 2);
  std::ofstream(dir / "spec.yaml") << R"(units: mm
output: model.h5
resolution: {voxel_size: 1}
outer: {path: skin.obj, unit: mm}
materials:
  table:
    soft: {youngs_modulus: 3000, poisson_ratio: 0.45, density: 1000}
layers: [{material: soft}]
boundary:
  - {type: rigid, box: {min: [-1, -1, -1], max: [13, 5, 0.01]}}
)";
  std::ofstream(dir / "scene.yaml") << R"(title: sagging textured box
model: model.h5
effects: [elasticity, hourglass, damping, gravity]
duration: 0.04
damping: 50
gravity: [0, -9.81, 0]
output: {interval: 0.01, fields: [surfaces, stress]}
)";
  ASSERT_EQ(
      run("cd '" + dir.string() + "' && " + SINEW_VOXELIZE_EXE + " spec.yaml", dir / "vox.log"), 0)
      << text_of(dir / "vox.log");
  ASSERT_EQ(run(std::string(SINEW_SIMULATE_EXE) + " " + (dir / "scene.yaml").string() + " -o " +
                    (dir / "sim").string(),
                dir / "sim.log"),
            0)
      << text_of(dir / "sim.log");
  const auto results = (dir / "sim" / "results.h5").string();

  // The results file: the model's surface with its texture coordinates, every corner as it was.
  const auto a = read_surface(results);
  ASSERT_TRUE(a.has_uvs());
  std::set<Triangle> stored;
  for (std::size_t t = 0; t < a.triangle_count(); ++t) {
    Triangle tri;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(a.triangles[3 * t + k]);
      const auto q = static_cast<std::size_t>(a.uv_triangles[3 * t + k]);
      tri[k] = corner(a.rest[3 * v], a.rest[3 * v + 1], a.rest[3 * v + 2], a.uvs[2 * q],
                      a.uvs[2 * q + 1]);
    }
    stored.insert(canonical(tri));
  }
  EXPECT_EQ(stored, expected);
  // One vertex per position (the seams are in the texture ids): the 5 × 5 grids of six faces
  // sharing their edges, 2 + 4 n² + 2 ... = 6 n² + 2 for a box with n × n quads per face.
  EXPECT_EQ(a.vertex_count(), 6u * 4 * 4 + 2);
  EXPECT_GT(max_displacement(a), 1e-6f) << "the box did not sag";

  const auto glb = dir / "skin.glb", pc2 = dir / "skin.pc2", rest = dir / "rest.obj";
  ASSERT_EQ(run(std::string(SINEW_EXPORT_EXE) + " " + results + " --glb " + glb.string() +
                    " --pc2 " + pc2.string() + " --rest-obj " + rest.string() + " --obj-sequence " +
                    (dir / "seq").string() + " --color displacement",
                dir / "export.log"),
            0)
      << text_of(dir / "export.log");
  EXPECT_EQ(glb_triangles(glb), expected);
  EXPECT_EQ(obj_triangles(rest), expected);
  EXPECT_EQ(obj_triangles(dir / "seq" / "frame_0000.obj"), expected);
  // The PC2's vertex order is the rest OBJ's: as many `v` lines as the cache has points.
  EXPECT_EQ(get<std::int32_t>(slurp(pc2), 16), static_cast<std::int32_t>(a.vertex_count()));

  // The same skin coloured by its peak von Mises stress (element stress averaged to the nodes and
  // interpolated at each vertex, element_fields.hpp): split at the seams like the positions.
  const auto stress_glb = dir / "stress.glb";
  ASSERT_EQ(run(std::string(SINEW_EXPORT_EXE) + " " + results + " --color von_mises --glb " +
                    stress_glb.string(),
                dir / "export_stress.log"),
            0)
      << text_of(dir / "export_stress.log");
  EXPECT_NE(text_of(dir / "export_stress.log").find("von Mises stress at the surface: 0 .. "),
            std::string::npos)
      << text_of(dir / "export_stress.log");
  EXPECT_EQ(glb_triangles(stress_glb), expected);

  const fs::path validator = fs::path(SINEW_SOURCE_DIR) / ".cache" / "gltf-validator";
  if (std::system("command -v node > /dev/null 2>&1") != 0 ||
      !fs::exists(validator / "node_modules" / "gltf-validator")) {
    std::printf("[  SKIPPED ] glTF validator: node or the npm gltf-validator not installed\n");
  } else {
    EXPECT_EQ(
        run("node '" + std::string(SINEW_SOURCE_DIR) + "/tests/postprocess/gltf_validate.mjs' " +
                glb.string() + " " + stress_glb.string(),
            dir / "validator.log"),
        0)
        << text_of(dir / "validator.log");
  }
  if (std::system("command -v blender > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "blender not installed (apt-get install blender): UVs in Blender not checked";
  }
  // Blender world coordinates: +Y up turned to +Z up, (x, y, z) → (x, −z, y); UVs v up.
  nlohmann::json corners = nlohmann::json::array();
  for (const auto& t : expected)
    for (const auto& c : t) corners.push_back({c[0], -c[2], c[1], c[3], c[4]});
  std::ofstream(dir / "uv_expect.json") << corners.dump();
  EXPECT_EQ(run("blender -b --factory-startup --python-exit-code 1 -P '" +
                    std::string(SINEW_SOURCE_DIR) + "/tests/postprocess/blender_uv_check.py' -- " +
                    glb.string() + " " + rest.string() + " " + (dir / "uv_expect.json").string(),
                dir / "blender.log"),
            0)
      << text_of(dir / "blender.log");
}

}  // namespace
