// Broken mesh files end in errors naming the file (issue 33): assimp's validation, the checks
// before assimp reads a file, and the helper process that turns a crash or a hang into an error.
// Every file is small and written here; each one crashed, hung or misread assimp 5.2.5 before.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/mesh_import.hpp"
#include "sinew/voxelizer/mesh_isolation.hpp"
#include "test_shapes.hpp"

namespace sinew::voxelizer {
namespace {

using testing::TempDir;

// A tetrahedron's four vertices as ASCII PLY, followed by `faces` (one per line, after a header
// declaring `face_count` of them).
std::string tetra_ply(const std::string& faces, int face_count = 4,
                      const std::string& third_vertex = "0 1 0") {
  return "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement face " +
         std::to_string(face_count) +
         "\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n" + third_vertex +
         "\n0 0 1\n" + faces;
}
const std::string kTetraFaces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

std::filesystem::path write(const TempDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir.path / name, std::ios::binary) << text;
  return dir.path / name;
}

// The error load_mesh throws for `file`, of type E, checked to name the file.
template <typename E>
std::string load_error(const std::filesystem::path& file) {
  try {
    load_mesh(file);
  } catch (const E& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    return what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << file << ": no error";
  return "";
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// A face naming vertex 1,000,000 of 4 segfaulted assimp's post-processing: with
// aiProcess_ValidateDataStructure it is refused with assimp's message. In this process, on
// purpose: without the validation the test dies.
TEST(MeshImport, ValidationRefusesAFaceNamingAVertexTheFileDoesNotHave) {
  TempDir dir("sinew_mesh_import_validate");
  const auto file = write(dir, "oor.ply", tetra_ply("3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 1000000\n"));
  const ImportOutcome o = import_with_assimp(file);
  EXPECT_EQ(o.kind, ImportOutcome::Kind::format_error);
  EXPECT_NE(o.problem.find("out of range"), std::string::npos) << o.problem;
  EXPECT_NE(load_error<FormatError>(file).find("out of range"), std::string::npos);
}

// A face with no corners fails an assertion in assimp's TriangulateProcess.cpp (SIGABRT) even
// with the validation: the helper process dies, the tool reports it.
TEST(MeshImport, AFileThatCrashesAssimpIsAnErrorNamingIt) {
  TempDir dir("sinew_mesh_import_crash");
  const auto file = write(dir, "empty_face.ply", tetra_ply("3 0 2 1\n3 0 1 3\n3 0 3 2\n0\n"));
  const std::string what = load_error<FormatError>(file);
  EXPECT_NE(what.find("assimp crashed reading it (signal 6"), std::string::npos) << what;
  // The tool goes on: the next file loads.
  const auto good = write(dir, "good.ply", tetra_ply(kTetraFaces));
  EXPECT_EQ(load_mesh(good).triangles.size(), 4u);
}

// assimp 5.2 reads a PLY header without end_header for ever, and the body of an ASCII PLY with
// fewer lines than its header declares too: both are refused before assimp starts.
TEST(MeshImport, APlyHeaderThatDoesNotEndOrFitIsRefusedAtOnce) {
  TempDir dir("sinew_mesh_import_header");
  const auto start = std::chrono::steady_clock::now();
  std::string no_end = tetra_ply(kTetraFaces);
  no_end.erase(no_end.find("end_header\n"), 11);
  EXPECT_NE(load_error<FormatError>(write(dir, "no_end.ply", no_end)).find("no end_header"),
            std::string::npos);
  const auto truncated = write(dir, "short.ply", tetra_ply("3 0 2 1\n3 0 1 3\n"));
  EXPECT_NE(load_error<FormatError>(truncated).find("declares 8 entries but 6 lines"),
            std::string::npos);
  // A count no file of this size can hold (assimp reserves memory for it).
  const auto huge = write(dir, "huge.ply", tetra_ply(kTetraFaces, 2000000000));
  EXPECT_NE(load_error<FormatError>(huge).find("declares 2000000000 entries"), std::string::npos);
  const auto not_ply = write(dir, "text.ply", "solid x\nendsolid x\n");
  EXPECT_NE(load_error<FormatError>(not_ply).find("does not begin with 'ply'"), std::string::npos);
  EXPECT_LT(seconds_since(start), 10.0);
}

// A 2 GB file of zeros named .ply (sparse here: it costs no disk) crashed assimp with SIGBUS; it
// is refused from its first bytes.
TEST(MeshImport, ATwoGigabyteFileOfZerosNamedPlyIsRefusedFromItsFirstBytes) {
  TempDir dir("sinew_mesh_import_zeros");
  const auto file = dir.path / "zeros.ply";
  std::ofstream(file).close();
  std::filesystem::resize_file(file, 2ull << 30);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(load_error<FormatError>(file).find("does not begin with 'ply'"), std::string::npos);
  EXPECT_LT(seconds_since(start), 10.0);
}

// assimp's JoinIdenticalVertices merges a vertex with a NaN coordinate into another one (every
// comparison with NaN is false): the NaN check after the import never saw it, in PLY (ASCII and
// binary), OFF and STL (the faces then name the wrong corners). The coordinates are checked
// before that step.
std::int64_t nan_index(const std::filesystem::path& file) {
  try {
    load_mesh(file);
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ": vertices["), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("NaN or infinite"), std::string::npos) << e.what();
    return e.index().value_or(-1);
  }
  ADD_FAILURE() << file << ": no GeometryError";
  return -1;
}

TEST(MeshImport, NanOrInfinityIsRefusedInEveryFormat) {
  TempDir dir("sinew_mesh_import_nan");
  EXPECT_EQ(nan_index(write(dir, "nan.ply", tetra_ply(kTetraFaces, 4, "0 nan 0"))), 2);
  EXPECT_EQ(nan_index(write(dir, "inf.ply", tetra_ply(kTetraFaces, 4, "-inf 1 0"))), 2);
  EXPECT_EQ(
      nan_index(write(dir, "nan.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 NaN 0\n0 0 1\n" + kTetraFaces)),
      2);
  EXPECT_EQ(nan_index(write(dir, "nan.stl",
                            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                            "vertex 1 nan 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n")),
            1);
  // Binary little-endian PLY, vertex 2's y a NaN.
  std::string bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 4\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float v[12] = {0, 0, 0, 1, 0, 0, 0, nan, 0, 0, 0, 1};
  bin.append(reinterpret_cast<const char*>(v), sizeof v);
  for (const auto& f : {std::array<int, 3>{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}) {
    bin.push_back(3);
    bin.append(reinterpret_cast<const char*>(f.data()), 12);
  }
  EXPECT_EQ(nan_index(write(dir, "nan_binary.ply", bin)), 2);
}

TEST(MeshImport, OffAndStlCountsTheFileCannotHoldAreRefused) {
  TempDir dir("sinew_mesh_import_counts");
  const auto off =
      write(dir, "big.off", "OFF\n4000000000 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n" + kTetraFaces);
  EXPECT_NE(load_error<FormatError>(off).find("4000000000 vertices"), std::string::npos);
  std::string stl(80, ' ');
  const std::uint32_t count = 1000;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  stl.append(50, '\0');
  const auto binary = write(dir, "short.stl", stl);
  EXPECT_NE(load_error<FormatError>(binary).find("1000 triangles"), std::string::npos);
}

// The FormatError of an isolated import through `helper`, with its deadline.
std::string isolated_error(const std::filesystem::path& file, const std::filesystem::path& helper,
                           double seconds) {
  try {
    import_mesh_isolated(file, {helper, seconds});
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << helper << ": no FormatError";
  return "";
}

// The helper's deadline: a stand-in helper that never answers is stopped and reported.
TEST(MeshImport, AnImportPastItsDeadlineIsStopped) {
  TempDir dir("sinew_mesh_import_hang");
  const auto helper = write(dir, "slow-import", "#!/bin/sh\nexec sleep 60\n");
  ::chmod(helper.c_str(), 0755);
  const auto file = write(dir, "any.obj", "v 0 0 0\n");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(isolated_error(file, helper, 0.3).find("did not finish reading it in 1 s"),
            std::string::npos);
  EXPECT_LT(seconds_since(start), 10.0);
  // A helper that dies by a signal, one that sends nothing, one that is not there.
  const auto segv = write(dir, "segv-import", "#!/bin/sh\nkill -SEGV $$\n");
  ::chmod(segv.c_str(), 0755);
  EXPECT_NE(isolated_error(file, segv, 10).find("crashed reading it (signal 11"),
            std::string::npos);
  EXPECT_NE(isolated_error(file, "/bin/true", 10).find("damaged result"), std::string::npos);
  EXPECT_THROW(import_mesh_isolated(file, {dir.path / "no-such-helper", 10}), IoError);
}

TEST(MeshImport, TheHelperIsNamedByTheEnvironmentOrFound) {
  EXPECT_EQ(find_mesh_import_helper().filename(), "sinew-mesh-import");
  TempDir dir("sinew_mesh_import_env");
  const auto file = write(dir, "tetra.ply", tetra_ply(kTetraFaces));
  ::setenv("SINEW_MESH_IMPORT", "/nonexistent/sinew-mesh-import", 1);
  EXPECT_THROW(find_mesh_import_helper(), IoError);
  // The error names the mesh too.
  EXPECT_NE(load_error<IoError>(file).find("/nonexistent/sinew-mesh-import"), std::string::npos);
  ::unsetenv("SINEW_MESH_IMPORT");
  EXPECT_EQ(load_mesh(file).triangles.size(), 4u);
}

TEST(MeshImport, TheStreamRoundTripsAndRefusesDamage) {
  ImportOutcome o;
  o.mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  o.mesh.triangles = {{0, 1, 2}};
  o.mesh.corner_uvs = {{{{0, 0}, {1, 0}, {0, 1}}}};
  o.mesh.parts = 1;
  const std::string bytes = encode_outcome(o);
  const ImportOutcome back = decode_outcome(bytes, "m.obj");
  EXPECT_EQ(back.kind, ImportOutcome::Kind::mesh);
  EXPECT_EQ(back.mesh.vertices[1].x, 1);
  EXPECT_EQ(back.mesh.triangles, o.mesh.triangles);
  EXPECT_EQ(back.mesh.corner_uvs, o.mesh.corner_uvs);
  for (std::size_t n : {std::size_t{0}, std::size_t{5}, bytes.size() - 1})
    EXPECT_THROW(decode_outcome(std::string_view(bytes).substr(0, n), "m.obj"), FormatError) << n;
  ImportOutcome e;
  e.kind = ImportOutcome::Kind::geometry_error;
  e.field = "vertices";
  e.problem = "line 3: 'nan' is not a finite number";
  const ImportOutcome eb = decode_outcome(encode_outcome(e), "m.ply");
  EXPECT_EQ(eb.kind, e.kind);
  EXPECT_EQ(eb.problem, e.problem);
}

}  // namespace
}  // namespace sinew::voxelizer
