// sinew-forehead -o DIR [--set NAME=VALUE ...] [--list]
// Writes the procedural forehead's closed OBJ meshes (skull.obj, skull_glide.obj,
// skull_glide_coarse.obj, skin.obj, frontalis_left.obj, frontalis_right.obj, galea.obj) and the
// open skin_surface.obj into DIR, in millimetres, and prints the model's landmarks and mesh sizes
// (docs/forehead.md). --set changes one parameter of sinew::voxelizer::ForeheadParams (mm,
// degrees); --list prints every parameter and its value.
// Any error: a message on stderr, exit code 1 (2 for command-line errors).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/voxelizer/forehead.hpp"

namespace {

using sinew::voxelizer::ForeheadParams;

std::vector<std::pair<std::string, double*>> parameter_table(ForeheadParams& p) {
  return {{"skull_half_width", &p.skull_half_width},
          {"skull_vertical_radius", &p.skull_vertical_radius},
          {"skull_depth", &p.skull_depth},
          {"ridge_height", &p.ridge_height},
          {"ridge_deg", &p.ridge_deg},
          {"ridge_width_deg", &p.ridge_width_deg},
          {"ridge_yaw_deg", &p.ridge_yaw_deg},
          {"ridge_spread_deg", &p.ridge_spread_deg},
          {"patch_half_angle_deg", &p.patch_half_angle_deg},
          {"patch_bottom_deg", &p.patch_bottom_deg},
          {"patch_top_deg", &p.patch_top_deg},
          {"thickness_mid", &p.thickness_mid},
          {"thickness_brow", &p.thickness_brow},
          {"brow_deg", &p.brow_deg},
          {"brow_width_deg", &p.brow_width_deg},
          {"temple_thinning", &p.temple_thinning},
          {"muscle_height", &p.muscle_height},
          {"muscle_thickness", &p.muscle_thickness},
          {"muscle_bottom_deg", &p.muscle_bottom_deg},
          {"muscle_top_deg", &p.muscle_top_deg},
          {"medial_gap_bottom", &p.medial_gap_bottom},
          {"medial_gap_top", &p.medial_gap_top},
          {"muscle_lateral_deg", &p.muscle_lateral_deg},
          {"galea_height", &p.galea_height},
          {"galea_thickness", &p.galea_thickness},
          {"galea_half_angle_deg", &p.galea_half_angle_deg},
          {"galea_bottom_deg", &p.galea_bottom_deg},
          {"galea_top_deg", &p.galea_top_deg},
          {"skin_base_depth", &p.skin_base_depth},
          {"skull_cap_depth", &p.skull_cap_depth},
          {"skull_margin", &p.skull_margin},
          {"spacing", &p.spacing},
          {"surface_spacing", &p.surface_spacing},
          {"glide_depth", &p.glide_depth},
          {"glide_thickness", &p.glide_thickness},
          {"glide_margin", &p.glide_margin},
          {"glide_depth_coarse", &p.glide_depth_coarse},
          {"glide_spacing", &p.glide_spacing}};
}

void apply_setting(ForeheadParams& p, const std::string& setting) {
  const auto eq = setting.find('=');
  if (eq == std::string::npos) {
    throw sinew::ConfigError("", "--set", "expected NAME=VALUE, got '" + setting + "'");
  }
  const std::string name = setting.substr(0, eq), value = setting.substr(eq + 1);
  std::string known;
  for (auto& [n, ptr] : parameter_table(p)) {
    if (n == name) {
      try {
        std::size_t used = 0;
        *ptr = std::stod(value, &used);
        if (used != value.size()) throw std::invalid_argument(value);
      } catch (const std::exception&) {
        throw sinew::ConfigError("", "--set " + name, "not a number: '" + value + "'");
      }
      return;
    }
    known += (known.empty() ? "" : ", ") + n;
  }
  throw sinew::ConfigError("", "--set", "unknown parameter '" + name + "' (known: " + known + ")");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sinew-forehead: the procedural forehead's meshes (OBJ, mm) for sinew-voxelize"};
  std::string dir;
  std::vector<std::string> settings;
  bool list = false;
  app.add_option("-o,--output", dir, "folder to write the meshes into (created if needed)");
  app.add_option("--set", settings, "change a parameter: NAME=VALUE (mm, degrees); repeatable");
  app.add_flag("--list", list, "print every parameter with its value and exit");
  CLI11_PARSE(app, argc, argv);

  return sinew::tool::run("sinew-forehead", [&] {
    ForeheadParams p;
    for (const auto& s : settings) apply_setting(p, s);
    if (list) {
      for (auto& [n, ptr] : parameter_table(p)) std::printf("%-22s %g\n", n.c_str(), *ptr);
      return sinew::tool::kExitOk;
    }
    if (dir.empty()) throw sinew::ConfigError("", "-o", "give the output folder: -o DIR");
    const auto written = sinew::voxelizer::write_forehead(p, dir);
    const auto meshes = sinew::voxelizer::make_forehead(p);
    const auto l = sinew::voxelizer::forehead_landmarks(p);
    std::printf("forehead: %.1f mm wide at the brow, %.1f mm from the patch's bottom to its top\n",
                l.width, l.height);
    std::printf("  brow centre (skin)     [%.2f, %.2f, %.2f] mm\n", l.brow_centre.x,
                l.brow_centre.y, l.brow_centre.z);
    std::printf("  galea's lower edge     [%.2f, %.2f, %.2f] mm (skin above it)\n",
                l.hairline_centre.x, l.hairline_centre.y, l.hairline_centre.z);
    std::printf("  skin bounding box      [%.2f, %.2f, %.2f] .. [%.2f, %.2f, %.2f] mm\n", l.lo.x,
                l.lo.y, l.lo.z, l.hi.x, l.hi.y, l.hi.z);
    const std::vector<const sinew::voxelizer::TriangleMesh*> all{
        &meshes.skull,        &meshes.skull_glide,    &meshes.skull_glide_coarse, &meshes.skin,
        &meshes.skin_surface, &meshes.frontalis_left, &meshes.frontalis_right,    &meshes.galea};
    for (std::size_t k = 0; k < written.size(); ++k) {
      std::printf("  %-40s %7zu vertices %7zu triangles\n", written[k].string().c_str(),
                  all[k]->vertices.size(), all[k]->triangles.size());
    }
    return sinew::tool::kExitOk;
  });
}
