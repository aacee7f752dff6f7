#pragma once
// Shared helpers of the sim-io tests (scene, writers, runner): temporary folders, a small box
// model with a muscle and an embedded visual surface, and file reading.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::simulator::testing {

// A fresh folder under the system temp dir, removed at the end of the test.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("sinew_") + tag + "_" + std::to_string(::getpid());
    if (info) name += std::string("_") + info->test_suite_name() + "_" + info->name();
    for (auto& c : name) {
      if (c == '/') c = '_';
    }
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string str() const { return path_.string(); }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// Options of a quiet CPU run of `scene` into `out` that prints nothing.
inline RunOptions options_for(const std::string& scene, const std::string& out) {
  RunOptions o;
  o.scene_path = scene;
  o.output_dir = out;
  o.device = "cpu";
  o.quiet = true;
  o.print = [](const std::string&) {};
  return o;
}

inline formats::Material soft_material(const std::string& name = "soft") {
  return formats::make_neo_hookean_material(name, 3000.0, 0.45, 1000.0);
}

// nx × ny × nz voxels of side h (default 4 × 4 × 4 of 1 cm), optionally with a muscle "flexor"
// along x over the whole block and a visual surface "skin" (two triangles on the top face, its
// four vertices embedded in the top elements).
inline formats::Model small_box(bool muscle = false, bool surface = false, int nx = 4, int ny = 4,
                                int nz = 4, double h = 0.01) {
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  spec.materials = {soft_material()};
  spec.created = "2026-01-01T00:00:00Z";
  if (muscle) {
    formats::BoxMuscleSpec m;
    m.name = "flexor";
    m.element_min = {0, 0, 0};
    m.element_max = {nx, ny, nz};
    m.fibre = {1, 0, 0};
    m.reference_stress = 2000;  // soft enough for a stable few steps
    spec.muscles.push_back(m);
  }
  auto model = formats::make_box_model(spec);
  if (surface) {
    formats::Surface s;
    s.name = "skin";
    s.role = formats::SurfaceRole::visual;
    const double top = nz * h;
    s.vertices = {{0, 0, top}, {nx * h, 0, top}, {nx * h, ny * h, top}, {0, ny * h, top}};
    s.triangles = {{0, 1, 2}, {0, 2, 3}};
    // Corner vertices sit at the outer top corner of the corner elements.
    const auto element_at = [&](int i, int j, int k) {
      return formats::Index(i + nx * (j + ny * k));
    };
    s.embedding_element = {element_at(0, 0, nz - 1), element_at(nx - 1, 0, nz - 1),
                           element_at(nx - 1, ny - 1, nz - 1), element_at(0, ny - 1, nz - 1)};
    s.embedding_local = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
    model.surfaces.push_back(s);
  }
  return model;
}

}  // namespace sinew::simulator::testing
