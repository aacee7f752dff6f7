#pragma once
// Helpers for the voxelizer pipeline tests: temporary folders, OBJ writing, spec running.
#include <gtest/gtest.h>

#include <unistd.h>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"

namespace sinew::voxelizer::testing {

// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("sinew-voxpipe-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::ofstream out(path_ / name);
    out << text;
    return path_ / name;
  }

 private:
  std::filesystem::path path_;
};

// Writes mesh (coordinates as they are) as a Wavefront OBJ.
inline void write_obj(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path);
  out.precision(17);
  for (const auto& v : mesh.vertices) out << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& t : mesh.triangles) {
    out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  }
}

// Spec lines (units: mm) for the paper's skin (Warburton & Maddock 2013): its material preset and
// the three layers from the outer surface in, stratum corneum 0.02 mm, dermis 1.8 mm, hypodermis.
inline const std::string kPaperLayers = R"(materials: {preset: warburton2013}
layers:
  - {material: stratum_corneum, thickness: 0.02}
  - {material: dermis, thickness: 1.8}
  - {material: hypodermis}
)";

inline VoxelizeResult run_spec(const std::string& yaml, const std::filesystem::path& file,
                               int threads = 0) {
  VoxelizeOptions options;
  options.threads = threads;
  return voxelize(parse_spec(yaml, file), options);
}

// Runs the library on a spec and returns the message of the error of type E it throws (a test
// failure when it throws another or none).
template <typename E>
std::string expect_error(const std::string& yaml, const std::filesystem::path& file,
                         VoxelizeOptions options = {}) {
  try {
    voxelize(parse_spec(yaml, file), options);
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no error";
  return "";
}

inline double material_volume(const Summary& s, const std::string& name) {
  for (const auto& v : s.material_volumes)
    if (v.name == name) return v.volume;
  return -1;
}

// ../shared/data/meshes next to the source tree, or $SINEW_SHARED_MESH_DIR when set (a worktree
// whose parent has no shared/).
inline std::filesystem::path shared_mesh_dir() {
  if (const char* dir = std::getenv("SINEW_SHARED_MESH_DIR"); dir && *dir) return dir;
  return SINEW_SHARED_MESH_DIR;
}

}  // namespace sinew::voxelizer::testing
