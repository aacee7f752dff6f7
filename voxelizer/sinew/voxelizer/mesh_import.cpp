#include "sinew/voxelizer/mesh_import.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

using Kind = ImportOutcome::Kind;

ImportOutcome failure(Kind kind, std::string field, std::string problem) {
  ImportOutcome o;
  o.kind = kind;
  o.field = std::move(field);
  o.problem = std::move(problem);
  return o;
}

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string read_head(const std::filesystem::path& file, std::size_t limit) {
  std::ifstream in(file, std::ios::binary);
  std::string s(limit, '\0');
  in.read(s.data(), static_cast<std::streamsize>(limit));
  s.resize(static_cast<std::size_t>(in.gcount()));
  return s;
}

// Lines of `file` from byte `offset` on that hold something other than whitespace. Streams the
// file in blocks: ASCII meshes can be large.
std::int64_t lines_with_tokens(const std::filesystem::path& file, std::uint64_t offset) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  std::string block(1 << 20, '\0');
  std::int64_t lines = 0;
  bool seen = false;
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const std::size_t n = static_cast<std::size_t>(in.gcount());
    for (std::size_t i = 0; i < n; ++i) {
      const char c = block[i];
      if (c == '\n' || c == '\r') {
        lines += seen ? 1 : 0;
        seen = false;
      } else if (!std::isspace(static_cast<unsigned char>(c))) {
        seen = true;
      }
    }
  }
  return lines + (seen ? 1 : 0);
}

std::optional<std::uint64_t> parse_count(const std::string& s) {
  if (s.empty() || s.size() > 19 ||
      !std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    return std::nullopt;
  return std::stoull(s);
}

// PLY: the header must start with "ply", end with end_header within 1 MiB (assimp 5.2 reads a
// header without one for ever), and its element counts must fit in the bytes after it (the reader
// trusts a damaged count). An ASCII body must have a line per declared entry.
std::optional<ImportOutcome> check_ply(const std::filesystem::path& file, std::uint64_t size) {
  constexpr std::size_t kHeaderLimit = 1 << 20;
  const std::string head = read_head(file, kHeaderLimit);
  if (head.size() < 4 || head.compare(0, 3, "ply") != 0 ||
      !std::isspace(static_cast<unsigned char>(head[3]))) {
    return failure(Kind::format_error, "", "not a PLY file: it does not begin with 'ply'");
  }
  std::size_t end = std::string::npos;
  for (std::size_t at = head.find("end_header"); at != std::string::npos;
       at = head.find("end_header", at + 1)) {
    if (head[at - 1] == '\n' || head[at - 1] == '\r') {
      end = at;
      break;
    }
  }
  if (end == std::string::npos) {
    return failure(Kind::format_error, "header",
                   size > kHeaderLimit ? "the PLY header has no end_header line in its first MiB"
                                       : "the PLY header has no end_header line");
  }
  std::size_t body = head.find('\n', end);
  body = body == std::string::npos ? head.size() : body + 1;
  const std::uint64_t body_bytes = size - body;

  static const std::map<std::string, int> kSize = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  struct Element {
    std::string name;
    std::uint64_t count = 0, min_bytes = 0, properties = 0;
  };
  std::vector<Element> elements;
  bool ascii = false;
  std::istringstream lines(head.substr(0, end));
  std::string text;
  std::int64_t line_no = 0;
  while (std::getline(lines, text)) {
    ++line_no;
    std::istringstream words(text);
    std::string word, a, b, c;
    words >> word;
    if (word == "format") {
      words >> a;
      ascii = a == "ascii";
    } else if (word == "element") {
      words >> a >> b;
      const auto count = parse_count(b);
      if (!count) {
        return failure(Kind::format_error, "header",
                       "line " + std::to_string(line_no) + ": element '" + a + "' has count '" +
                           b.substr(0, 40) + "', not a number");
      }
      elements.push_back({a, *count, 0, 0});
    } else if (word == "property" && !elements.empty()) {
      words >> a >> b >> c;
      const auto it = kSize.find(a == "list" ? b : a);
      elements.back().min_bytes += it == kSize.end() ? 1 : static_cast<std::uint64_t>(it->second);
      elements.back().properties += 1;
    }
  }
  // Each entry takes at least one byte per property in ASCII, its scalar sizes (a list: its count)
  // in binary, and one byte without properties (assimp would loop over a count of 2^63 of them).
  // Compared in long double: counts of 2^64 - 1 must not wrap.
  long double needed = 0;
  for (const Element& e : elements) {
    const std::uint64_t per_entry = std::max<std::uint64_t>(ascii ? e.properties : e.min_bytes, 1);
    needed += static_cast<long double>(e.count) * static_cast<long double>(per_entry);
    if (needed > static_cast<long double>(body_bytes)) {
      return failure(Kind::format_error, "header",
                     "element '" + e.name + "' declares " + std::to_string(e.count) +
                         " entries: more than the " + std::to_string(body_bytes) +
                         " bytes after the header can hold (a truncated or damaged file)");
    }
  }
  if (!ascii) return std::nullopt;
  // One entry per line: assimp's ASCII reader loops for ever at the end of a file with fewer.
  std::uint64_t entries = 0;
  for (const Element& e : elements) entries += e.count;
  const std::int64_t body_lines = lines_with_tokens(file, body);
  if (static_cast<std::uint64_t>(body_lines) < entries) {
    return failure(Kind::format_error, "",
                   "the PLY header declares " + std::to_string(entries) + " entries but " +
                       std::to_string(body_lines) +
                       " lines follow it (a truncated or damaged file)");
  }
  return std::nullopt;
}

// OFF: the counts (vertices, faces) must fit in the file.
std::optional<ImportOutcome> check_off(const std::filesystem::path& file, std::uint64_t size) {
  const std::string head = read_head(file, 4096);
  std::istringstream in(head);
  std::string word;
  std::vector<std::string> counts;
  while (in >> word && counts.size() < 2) {
    if (word[0] == '#') {
      std::getline(in, word);
    } else if (word.find("OFF") == std::string::npos) {
      counts.push_back(word);
    }
  }
  if (counts.size() == 2) {
    const auto v = parse_count(counts[0]), f = parse_count(counts[1]);
    if (!v || !f) {
      return failure(Kind::format_error, "header",
                     "the OFF header's counts '" + counts[0].substr(0, 40) + " " +
                         counts[1].substr(0, 40) + "' are not numbers");
    }
    // A vertex takes at least 3 numbers, a face at least 4 ("3 a b c"), each a byte and a space.
    const long double needed = 6.0L * static_cast<long double>(*v) + 8.0L * (*f);
    if (needed > static_cast<long double>(size)) {
      return failure(Kind::format_error, "header",
                     "the OFF header declares " + std::to_string(*v) + " vertices and " +
                         std::to_string(*f) + " faces: more than the file's " +
                         std::to_string(size) + " bytes can hold");
    }
  }
  return std::nullopt;
}

// STL: a binary file's triangle count must fit in its size (an ASCII file starts with "solid"
// and has no count).
std::optional<ImportOutcome> check_stl(const std::filesystem::path& file, std::uint64_t size) {
  const std::string head = read_head(file, 84);
  if (head.size() < 84 || head.compare(0, 5, "solid") == 0) return std::nullopt;
  std::uint32_t count = 0;
  std::memcpy(&count, head.data() + 80, 4);
  if (size < 84 + 50ull * count) {
    return failure(Kind::format_error, "header",
                   "the binary STL header declares " + std::to_string(count) +
                       " triangles: more than the file's " + std::to_string(size) +
                       " bytes can hold");
  }
  return std::nullopt;
}

// The first vertex that is not finite, in the scene as read (before any post-processing).
// aiProcess_JoinIdenticalVertices merges a NaN vertex into another (every comparison with NaN is
// false), so after it the NaN is gone and the faces name the wrong corners: 161 of 162 vertices
// of an ASCII PLY with one "nan" came back, in every format but OBJ.
std::optional<ImportOutcome> check_finite(const aiScene* scene) {
  for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
    const aiMesh* mesh = scene->mMeshes[k];
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& p = mesh->mVertices[i];
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) continue;
      ImportOutcome o = failure(
          Kind::geometry_error, "vertices",
          "coordinate is NaN or infinite" +
              (scene->mNumMeshes > 1 ? " (part " + std::to_string(k) + " of the file)" : ""));
      o.index = i;
      return o;
    }
  }
  return std::nullopt;
}

// Appends the triangles of `node` and its children to `out`; node transforms in double precision
// (assimp's matrices are float). Returns a problem for a face that names a vertex its mesh does
// not have (aiProcess_ValidateDataStructure refuses those; checked again here as it is cheap).
std::optional<std::string> collect(const aiScene* scene, const aiNode* node,
                                   const aiMatrix4x4& parent, ImportedMesh& out,
                                   std::vector<std::array<std::array<double, 2>, 3>>& uvs) {
  const aiMatrix4x4 world = parent * node->mTransformation;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    if (node->mMeshes[k] >= scene->mNumMeshes) return "a node names a mesh the file does not have";
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    if (out.vertices.size() + mesh->mNumVertices > std::numeric_limits<std::int32_t>::max())
      return "more than 2^31 vertices";
    // assimp joins vertices equal in position and texture coordinates; a seam keeps one vertex per
    // (u, v). Join equal positions here (the texture coordinates go with the triangle corners).
    // Keyed by the bits, so a NaN coordinate (refused by load_mesh) is never joined to another.
    std::map<std::array<std::uint32_t, 3>, std::int32_t> first;
    std::vector<std::int32_t> index(mesh->mNumVertices);
    const aiMatrix4x4& w = world;
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& p = mesh->mVertices[i];
      const std::array<std::uint32_t, 3> bits{std::bit_cast<std::uint32_t>(p.x),
                                              std::bit_cast<std::uint32_t>(p.y),
                                              std::bit_cast<std::uint32_t>(p.z)};
      const auto [at, added] = first.emplace(bits, static_cast<std::int32_t>(out.vertices.size()));
      index[i] = at->second;
      if (!added) continue;
      const double x = p.x, y = p.y, z = p.z;
      out.vertices.push_back(
          {double(w.a1) * x + double(w.a2) * y + double(w.a3) * z + double(w.a4),
           double(w.b1) * x + double(w.b2) * y + double(w.b3) * z + double(w.b4),
           double(w.c1) * x + double(w.c2) * y + double(w.c3) * z + double(w.c4)});
    }
    const aiVector3D* uv = mesh->HasTextureCoords(0) ? mesh->mTextureCoords[0] : nullptr;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      std::array<std::int32_t, 3> t{};
      std::array<std::array<double, 2>, 3> c{};
      for (int j = 0; j < 3; ++j) {
        const unsigned v = face.mIndices[j];
        if (v >= mesh->mNumVertices) {
          return "face " + std::to_string(f) + " names vertex " + std::to_string(v) + " of " +
                 std::to_string(mesh->mNumVertices);
        }
        t[j] = index[v];
        c[j] = uv ? std::array<double, 2>{uv[v].x, uv[v].y} : std::array<double, 2>{nan, nan};
      }
      out.triangles.push_back(t);
      uvs.push_back(c);
      if (!uv) ++out.missing_uvs;
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c)
    if (auto bad = collect(scene, node->mChildren[c], world, out, uvs)) return bad;
  return std::nullopt;
}

// Appending and reading the stream's fields (native byte order: both ends run on one machine).
template <typename T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
void put_text(std::string& s, const std::string& text) {
  put(s, static_cast<std::uint32_t>(text.size()));
  s += text;
}
constexpr std::string_view kMagic{"sinew-mesh-import 1\n"};

}  // namespace

std::optional<ImportOutcome> import_precheck(const std::filesystem::path& file) {
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(file, ec);
  if (ec) return failure(Kind::io_error, "", "cannot read the file's size: " + ec.message());
  const std::string ext = lower_extension(file);
  if (ext == ".ply") return check_ply(file, size);
  if (ext == ".off") return check_off(file, size);
  if (ext == ".stl") return check_stl(file, size);
  return std::nullopt;
}

ImportOutcome import_with_assimp(const std::filesystem::path& file) {
  if (auto refused = import_precheck(file)) return std::move(*refused);
  Assimp::Importer importer;
  // Positions and texture coordinates only: JoinIdenticalVertices then joins corners that differ
  // in normals only; collect() joins equal positions whatever their texture coordinates.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_BONEWEIGHTS |
                                  aiComponent_ANIMATIONS | aiComponent_TEXTURES |
                                  aiComponent_LIGHTS | aiComponent_CAMERAS | aiComponent_MATERIALS);
  // Read and validated first: ValidateDataStructure refuses a face naming a vertex past its mesh
  // or a broken node tree with a message instead of letting the triangulation read out of bounds
  // (37 of the 51 crashes of issue 33). The other steps run once the coordinates are checked.
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_ValidateDataStructure);
  if (scene != nullptr && scene->mMeshes != nullptr) {
    if (auto bad = check_finite(scene)) return std::move(*bad);
  }
  if (scene != nullptr) {
    scene = importer.ApplyPostProcessing(aiProcess_RemoveComponent | aiProcess_Triangulate |
                                         aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  }
  if (scene == nullptr) {
    const std::string message = importer.GetErrorString();
    // The validation's words for a file of points or lines only: no faces is no triangles, as
    // load_mesh says when the triangles are missing after post-processing.
    if (message.find("Validation failed") != std::string::npos &&
        message.find("contains no faces") != std::string::npos)
      return failure(Kind::geometry_error, "", "the file contains no triangles");
    return failure(Kind::format_error, "", "cannot read the mesh: " + message);
  }
  ImportOutcome o;
  o.mesh.parts = scene->mNumMeshes;
  std::vector<std::array<std::array<double, 2>, 3>> uvs;
  if (scene->mRootNode != nullptr) {
    if (auto bad = collect(scene, scene->mRootNode, aiMatrix4x4(), o.mesh, uvs))
      return failure(Kind::format_error, "", "cannot read the mesh: " + *bad);
  }
  if (o.mesh.missing_uvs == 0) o.mesh.corner_uvs = std::move(uvs);
  return o;
}

std::string encode_outcome(const ImportOutcome& o) {
  std::string s(kMagic);
  put(s, static_cast<std::uint8_t>(o.kind));
  if (o.kind != Kind::mesh) {
    put(s, o.index);
    put_text(s, o.field);
    put_text(s, o.problem);
    return s;
  }
  const ImportedMesh& m = o.mesh;
  put(s, static_cast<std::uint64_t>(m.vertices.size()));
  put(s, static_cast<std::uint64_t>(m.triangles.size()));
  put(s, static_cast<std::uint8_t>(!m.corner_uvs.empty()));
  put(s, m.missing_uvs);
  put(s, m.parts);
  s.reserve(s.size() + m.vertices.size() * 24 + m.triangles.size() * (12 + 48));
  s.append(reinterpret_cast<const char*>(m.vertices.data()), m.vertices.size() * sizeof(Vec3d));
  s.append(reinterpret_cast<const char*>(m.triangles.data()), m.triangles.size() * 12);
  s.append(reinterpret_cast<const char*>(m.corner_uvs.data()), m.corner_uvs.size() * 48);
  return s;
}

ImportOutcome decode_outcome(std::string_view bytes, const std::string& file) {
  static_assert(sizeof(Vec3d) == 24 && sizeof(std::array<std::array<double, 2>, 3>) == 48);
  std::size_t at = 0;
  auto damaged = [&](const std::string& what) {
    return FormatError(file, "",
                       "the mesh importer (sinew-mesh-import) sent a damaged result: " + what);
  };
  auto take = [&](void* dst, std::uint64_t n) {
    if (n > bytes.size() - at) throw damaged("cut short");
    std::memcpy(dst, bytes.data() + at, n);
    at += n;
  };
  auto get = [&]<typename T>(T& v) { take(&v, sizeof(T)); };
  auto get_text = [&](std::string& text) {
    std::uint32_t n = 0;
    get(n);
    if (n > bytes.size() - at) throw damaged("cut short");
    text.assign(bytes.data() + at, n);
    at += n;
  };
  if (bytes.substr(0, kMagic.size()) != kMagic) throw damaged("no header");
  at = kMagic.size();
  ImportOutcome o;
  std::uint8_t kind = 0;
  get(kind);
  if (kind > static_cast<std::uint8_t>(Kind::io_error)) throw damaged("unknown outcome");
  o.kind = static_cast<Kind>(kind);
  if (o.kind != Kind::mesh) {
    get(o.index);
    get_text(o.field);
    get_text(o.problem);
    return o;
  }
  std::uint64_t nv = 0, nt = 0;
  std::uint8_t has_uvs = 0;
  get(nv);
  get(nt);
  get(has_uvs);
  get(o.mesh.missing_uvs);
  get(o.mesh.parts);
  const std::uint64_t left = bytes.size() - at;
  // Checked before allocating: the counts come from another process.
  if (nv > left / 24 || nt > left / 12 || nv * 24 + nt * (has_uvs ? 60 : 12) != left)
    throw damaged("the counts do not match the bytes");
  o.mesh.vertices.resize(nv);
  o.mesh.triangles.resize(nt);
  take(o.mesh.vertices.data(), nv * 24);
  take(o.mesh.triangles.data(), nt * 12);
  if (has_uvs) {
    o.mesh.corner_uvs.resize(nt);
    take(o.mesh.corner_uvs.data(), nt * 48);
  }
  return o;
}

}  // namespace sinew::voxelizer
