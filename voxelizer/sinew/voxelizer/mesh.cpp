#include "sinew/voxelizer/mesh.hpp"

#include <assimp/scene.h>
#include <assimp/Exporter.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "sinew/common/error.hpp"
#include "sinew/common/input_file.hpp"
#include "sinew/common/log.hpp"
#include "sinew/voxelizer/mesh_isolation.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Union-find with path halving; used for components.
struct DisjointSets {
  std::vector<std::int64_t> parent;
  explicit DisjointSets(std::int64_t n) : parent(static_cast<std::size_t>(n)) {
    std::iota(parent.begin(), parent.end(), std::int64_t{0});
  }
  std::int64_t find(std::int64_t i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  }
  void unite(std::int64_t a, std::int64_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

struct KeyHash {
  std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::int64_t v : k) {
      h ^= static_cast<std::uint64_t>(v) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

std::array<std::int64_t, 3> cell_of(const Vec3d& p, double cell) {
  return {static_cast<std::int64_t>(std::floor(p.x / cell)),
          static_cast<std::int64_t>(std::floor(p.y / cell)),
          static_cast<std::int64_t>(std::floor(p.z / cell))};
}

// remap[i] = index of the first vertex (in index order) within tolerance of vertex i. Greedy:
// each vertex joins the first earlier representative it is close to, so the result is
// deterministic.
std::vector<std::int64_t> weld_map(const std::vector<Vec3d>& v, double tol) {
  const std::int64_t n = static_cast<std::int64_t>(v.size());
  std::vector<std::int64_t> remap(v.size());
  if (tol == 0) {
    struct PosHash {
      std::size_t operator()(const std::array<double, 3>& k) const {
        std::size_t h = std::hash<double>()(k[0]);
        h ^= std::hash<double>()(k[1]) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        h ^= std::hash<double>()(k[2]) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        return h;
      }
    };
    std::unordered_map<std::array<double, 3>, std::int64_t, PosHash> first;
    first.reserve(v.size());
    for (std::int64_t i = 0; i < n; ++i) {
      // +0.0 folds -0.0 into 0.0 so that both weld.
      const std::array<double, 3> key{v[i].x + 0.0, v[i].y + 0.0, v[i].z + 0.0};
      remap[i] = first.emplace(key, i).first->second;
    }
    return remap;
  }
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<std::int64_t>, KeyHash> grid;
  grid.reserve(v.size());
  const double tol2 = tol * tol;
  for (std::int64_t i = 0; i < n; ++i) {
    const auto c = cell_of(v[i], tol);
    std::int64_t best = i;
    for (int dx = -1; dx <= 1 && best == i; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (std::int64_t r : it->second) {
            if (r < best && squared_norm(v[r] - v[i]) <= tol2) best = r;
          }
        }
      }
    }
    remap[i] = best;
    if (best == i) grid[c].push_back(i);
  }
  return remap;
}

bool degenerate(const TriangleMesh& m, const std::array<std::int32_t, 3>& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
  const double longest2 = std::max({squared_norm(b - a), squared_norm(c - b), squared_norm(a - c)});
  return norm(cross(b - a, c - a)) <= 1e-14 * longest2;
}

// Edge statistics, components, area and volume of a mesh whose triangles are all valid.
void measure(const TriangleMesh& m, MeshDiagnostics& d) {
  d.vertices = static_cast<std::int64_t>(m.vertices.size());
  d.triangles = static_cast<std::int64_t>(m.triangles.size());
  // Each directed edge as (min, max, +1 if min->max else -1); sorting groups the uses of an edge.
  struct Use {
    std::int32_t a, b;
    int dir;
    bool operator<(const Use& o) const {
      return a != o.a ? a < o.a : (b != o.b ? b < o.b : dir < o.dir);
    }
  };
  std::vector<Use> uses;
  uses.reserve(m.triangles.size() * 3);
  DisjointSets sets(d.vertices);
  double area = 0, volume = 0;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t i = t[k], j = t[(k + 1) % 3];
      uses.push_back(i < j ? Use{i, j, +1} : Use{j, i, -1});
    }
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
    const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    area += 0.5 * norm(cross(b - a, c - a));
    volume += dot(a, cross(b, c)) / 6.0;
  }
  std::sort(uses.begin(), uses.end());
  d.boundary_edges = d.non_manifold_edges = d.inconsistently_oriented_edges = 0;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].a == uses[i].a && uses[j].b == uses[i].b) ++j;
    const std::size_t count = j - i;
    if (count == 1) ++d.boundary_edges;
    if (count > 2) ++d.non_manifold_edges;
    if (count == 2 && uses[i].dir == uses[i + 1].dir) ++d.inconsistently_oriented_edges;
    i = j;
  }
  std::vector<char> used(m.vertices.size(), 0);
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) used[t[k]] = 1;
  d.components = 0;
  for (std::int64_t i = 0; i < d.vertices; ++i)
    if (used[i] && sets.find(i) == i) ++d.components;
  d.closed = d.boundary_edges == 0 && d.non_manifold_edges == 0 && d.triangles > 0;
  d.area = area;
  d.enclosed_volume = volume;
}

}  // namespace

double metres_per_unit(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::m:
      return 1.0;
    case LengthUnit::cm:
      return 0.01;
    case LengthUnit::mm:
      return 0.001;
  }
  return 1.0;
}

LengthUnit parse_length_unit(const std::string& name, const std::string& field) {
  if (name == "m") return LengthUnit::m;
  if (name == "cm") return LengthUnit::cm;
  if (name == "mm") return LengthUnit::mm;
  throw ConfigError("", field, "unknown length unit '" + name + "' (expected m, cm or mm)");
}

const char* to_string(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::m:
      return "m";
    case LengthUnit::cm:
      return "cm";
    case LengthUnit::mm:
      return "mm";
  }
  return "?";
}

Mat3d rotation_matrix(const Vec3d& rotate_deg) {
  const double ax = rotate_deg.x * kPi / 180, ay = rotate_deg.y * kPi / 180,
               az = rotate_deg.z * kPi / 180;
  const double cx = std::cos(ax), sx = std::sin(ax), cy = std::cos(ay), sy = std::sin(ay),
               cz = std::cos(az), sz = std::sin(az);
  const Mat3d rx{{{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}}};
  const Mat3d ry{{{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}}};
  const Mat3d rz{{{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
  return rz * (ry * rx);
}

Vec3d apply_transform(const MeshTransform& t, const Vec3d& x) {
  const double s = metres_per_unit(t.unit) * t.scale;
  return rotation_matrix(t.rotate_deg) * (s * x) + t.translate;
}

void apply_transform(const MeshTransform& t, TriangleMesh& mesh) {
  const double s = metres_per_unit(t.unit) * t.scale;
  const Mat3d r = rotation_matrix(t.rotate_deg);
  for (Vec3d& v : mesh.vertices) v = r * (s * v) + t.translate;
  // A mirroring transform (negative scale) would turn the mesh inside out; keep it outward.
  if (s < 0) flip_orientation(mesh);
}

void flip_orientation(TriangleMesh& mesh) {
  for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
  for (auto& c : mesh.corner_uvs) std::swap(c[1], c[2]);
}

IndexedUvs indexed_uvs(const TriangleMesh& mesh) {
  IndexedUvs out;
  std::map<std::array<double, 2>, std::int32_t> id;
  for (const CornerUvs& c : mesh.corner_uvs) {
    std::array<std::int32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const auto [at, added] = id.emplace(c[k], static_cast<std::int32_t>(out.uvs.size()));
      if (added) out.uvs.push_back(c[k]);
      t[k] = at->second;
    }
    out.triangles.push_back(t);
  }
  return out;
}

TriangleMesh load_mesh(const std::filesystem::path& path, const MeshTransform& t) {
  const std::string file = path.string();
  require_regular_file(path, "mesh");  // a folder, a FIFO or a device is no mesh
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError(file, "", "cannot open the file for reading");
  }
  if (!std::isfinite(t.scale) || t.scale == 0)
    throw GeometryError(file, "scale", "scale must be finite and non-zero");
  // In the helper process (mesh_isolation.hpp): a file that crashes or hangs assimp is an error.
  ImportedMesh imported = import_mesh_isolated(path);
  TriangleMesh mesh;
  mesh.source = file;
  mesh.vertices = std::move(imported.vertices);
  mesh.triangles = std::move(imported.triangles);
  mesh.corner_uvs = std::move(imported.corner_uvs);
  const std::int64_t missing_uvs = imported.missing_uvs;
  if (mesh.triangles.empty()) throw GeometryError(file, "", "the file contains no triangles");
  // Texture coordinates are kept only when every triangle has finite ones: a mesh needs none to
  // be voxelized, so damaged ones are dropped with a warning rather than refused.
  std::int64_t bad_uvs = 0;
  for (const auto& c : mesh.corner_uvs)
    for (const auto& uv : c)
      if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) ++bad_uvs;
  if (missing_uvs > 0 && missing_uvs < static_cast<std::int64_t>(mesh.triangles.size())) {
    log::warn("{}: {} of {} triangles have no texture coordinates; none are kept", file,
              missing_uvs, mesh.triangles.size());
  } else if (missing_uvs == 0 && bad_uvs > 0) {
    log::warn("{}: {} texture coordinates are not finite; none are kept", file, bad_uvs);
  }
  if (missing_uvs > 0 || bad_uvs > 0) mesh.corner_uvs.clear();
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3d& v = mesh.vertices[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
      throw GeometryError(file, "vertices", "coordinate is NaN or infinite")
          .at(static_cast<std::int64_t>(i));
  }
  apply_transform(t, mesh);
  log::debug("{}: {} vertices, {} triangles loaded ({} meshes)", file, mesh.vertices.size(),
             mesh.triangles.size(), imported.parts);
  return mesh;
}

void save_mesh(const TriangleMesh& mesh, const std::filesystem::path& path) {
  const std::string file = path.string();
  std::string ext = path.extension().string();
  if (!ext.empty()) ext = ext.substr(1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == "dae") ext = "collada";
  if (ext == "gltf") ext = "gltf2";
  if (ext == "glb") ext = "glb2";
  if (ext == "ply") ext = "plyb";
  if (ext == "stl") ext = "stlb";
  // assimp 5.2 cannot re-read its own binary FBX (block offsets); its ASCII FBX reads back.
  if (ext == "fbx") ext = "fbxa";

  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMaterials = 1;
  auto* m = new aiMesh();
  scene.mMeshes = new aiMesh* [1] { m };
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  m->mMaterialIndex = 0;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mNumVertices = static_cast<unsigned>(mesh.vertices.size());
  m->mVertices = new aiVector3D[m->mNumVertices];
  for (unsigned i = 0; i < m->mNumVertices; ++i) {
    const Vec3d& v = mesh.vertices[i];
    m->mVertices[i] = aiVector3D(float(v.x), float(v.y), float(v.z));
  }
  m->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  m->mFaces = new aiFace[m->mNumFaces];
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    m->mFaces[f].mNumIndices = 3;
    m->mFaces[f].mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k)
      m->mFaces[f].mIndices[k] = static_cast<unsigned>(mesh.triangles[f][k]);
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, ext, file) != AI_SUCCESS) {
    throw IoError(file, "", std::string("cannot write the mesh: ") + exporter.GetErrorString());
  }
}

BoundingBox bounding_box(const TriangleMesh& mesh) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  BoundingBox b{{inf, inf, inf}, {-inf, -inf, -inf}};
  for (const Vec3d& v : mesh.vertices) {
    b.lo = {std::min(b.lo.x, v.x), std::min(b.lo.y, v.y), std::min(b.lo.z, v.z)};
    b.hi = {std::max(b.hi.x, v.x), std::max(b.hi.y, v.y), std::max(b.hi.z, v.z)};
  }
  return b;
}

MeshDiagnostics describe_mesh(const TriangleMesh& mesh) {
  MeshDiagnostics d;
  measure(mesh, d);
  return d;
}

void check_triangle_indices(const TriangleMesh& mesh) {
  const std::int64_t n = static_cast<std::int64_t>(mesh.vertices.size());
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= n)
        throw GeometryError(mesh.source, "triangles", "vertex index out of range")
            .at(&t - mesh.triangles.data());
}

MeshDiagnostics clean_mesh(TriangleMesh& mesh, double weld_tolerance) {
  if (!(weld_tolerance >= 0))
    throw GeometryError(mesh.source, "weld_tolerance", "must be a non-negative number");
  MeshDiagnostics d;
  check_triangle_indices(mesh);
  const std::int64_t n = static_cast<std::int64_t>(mesh.vertices.size());

  const std::vector<std::int64_t> remap = weld_map(mesh.vertices, weld_tolerance);
  for (std::int64_t i = 0; i < n; ++i)
    if (remap[i] != i) ++d.duplicate_vertices_merged;

  // Welded, non-degenerate, non-repeated triangles, in their original order.
  struct TriHash {
    std::size_t operator()(const std::array<std::int32_t, 3>& t) const {
      return KeyHash()({t[0], t[1], t[2]});
    }
  };
  std::unordered_map<std::array<std::int32_t, 3>, char, TriHash> seen;
  seen.reserve(mesh.triangles.size());
  std::vector<std::array<std::int32_t, 3>> kept;
  kept.reserve(mesh.triangles.size());
  const bool has_uvs = mesh.corner_uvs.size() == mesh.triangles.size();
  std::vector<CornerUvs> kept_uvs;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t0 = mesh.triangles[i];
    std::array<std::int32_t, 3> t{static_cast<std::int32_t>(remap[t0[0]]),
                                  static_cast<std::int32_t>(remap[t0[1]]),
                                  static_cast<std::int32_t>(remap[t0[2]])};
    if (degenerate(mesh, t)) {
      ++d.degenerate_triangles_removed;
      continue;
    }
    // Canonical rotation (smallest index first) keeps the cyclic order.
    const int r = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    const std::array<std::int32_t, 3> key{t[r], t[(r + 1) % 3], t[(r + 2) % 3]};
    if (!seen.emplace(key, 1).second) {
      ++d.duplicate_triangles_removed;
      continue;
    }
    kept.push_back(t);
    if (has_uvs) kept_uvs.push_back(mesh.corner_uvs[i]);
  }
  // Compact the vertices: keep referenced ones in their original order.
  std::vector<std::int32_t> new_index(static_cast<std::size_t>(n), -1);
  for (const auto& t : kept)
    for (int k = 0; k < 3; ++k) new_index[t[k]] = 0;
  std::vector<Vec3d> vertices;
  for (std::int64_t i = 0; i < n; ++i) {
    if (new_index[i] == 0) {
      new_index[i] = static_cast<std::int32_t>(vertices.size());
      vertices.push_back(mesh.vertices[i]);
    } else if (remap[i] == i) {
      ++d.unreferenced_vertices_removed;
    }
  }
  for (auto& t : kept)
    for (int k = 0; k < 3; ++k) t[k] = new_index[t[k]];
  mesh.vertices = std::move(vertices);
  mesh.triangles = std::move(kept);
  mesh.corner_uvs = std::move(kept_uvs);
  measure(mesh, d);
  return d;
}

}  // namespace sinew::voxelizer
