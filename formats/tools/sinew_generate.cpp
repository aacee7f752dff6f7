// sinew-generate: writes generated models. One generator so far:
//   sinew-generate box --dims 8 8 8 --voxel-size 0.001 --material soft:3000:0.49:1000 -o box.h5
// Layers along z: repeat --material (bottom first) and give --layer-boundary heights in metres.
// A muscle: --muscle NAME:MATERIAL --muscle-box I0 J0 K0 I1 J1 K1 --fibre FX FY FZ.
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model_file.hpp"

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  std::string part;
  while (std::getline(in, part, sep)) parts.push_back(part);
  return parts;
}

double number(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) {
    throw sinew::ConfigError("", option, "'" + text + "' is not a number");
  }
  return v;
}

// NAME:E:nu:rho (Pa, 1, kg/m³).
sinew::formats::Material parse_material(const std::string& text) {
  const auto parts = split(text, ':');
  if (parts.size() != 4 || parts[0].empty()) {
    throw sinew::ConfigError("", "--material", "'" + text + "' is not NAME:E:nu:rho");
  }
  return sinew::formats::make_neo_hookean_material(parts[0], number(parts[1], "--material"),
                                                   number(parts[2], "--material"),
                                                   number(parts[3], "--material"));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Generate sinew model files.", "sinew-generate"};
  app.set_version_flag("--version", std::string("sinew-generate ") + sinew::kVersion);
  app.require_subcommand(1);

  auto* box =
      app.add_subcommand("box", "a block of nx x ny x nz voxels, optional layers and muscle");
  sinew::formats::BoxSpec spec;
  spec.dims = {8, 8, 8};
  std::vector<std::int32_t> dims{8, 8, 8};
  std::vector<double> origin{0, 0, 0};
  std::vector<std::string> materials;
  std::string muscle, output;
  std::vector<std::int32_t> muscle_box;
  std::vector<double> fibre{1, 0, 0};
  sinew::formats::BoxMuscleSpec muscle_spec;
  bool quiet = false;
  box->add_option("--dims", dims, "voxels along x, y, z")->expected(3);
  box->add_option("--voxel-size", spec.voxel_size, "voxel side h, m")->default_val(spec.voxel_size);
  box->add_option("--origin", origin, "position of the corner (x, y, z) min, m")->expected(3);
  box->add_option("--material", materials,
                  "NAME:E:nu:rho (Pa, -, kg/m^3); repeat for layers along z, bottom first")
      ->required();
  box->add_option("--layer-boundary", spec.layer_boundaries,
                  "layer boundary heights above the bottom face, m (one fewer than materials)");
  box->add_option("--muscle", muscle,
                  "NAME:MATERIAL, a muscle whose passive tissue is that material");
  box->add_option(
         "--muscle-box", muscle_box,
         "I0 J0 K0 I1 J1 K1: the muscle's elements, base corners in [I0, I1) x [J0, J1) x [K0, K1) "
         "(default: every element)")
      ->expected(6);
  box->add_option("--fibre", fibre, "muscle fibre direction (normalised)")->expected(3);
  box->add_option("--muscle-fraction", muscle_spec.fraction, "muscle volume fraction per element")
      ->default_val(1.0);
  box->add_option("--reference-stress", muscle_spec.reference_stress, "muscle sigma_ref, Pa")
      ->default_val(5e6);
  box->add_option("--optimal-stretch", muscle_spec.optimal_stretch, "muscle lambda_opt")
      ->default_val(1.0);
  box->add_option(
      "--rigid-face", spec.rigid_faces,
      "make a face's nodes rigid: x_min, x_max, y_min, y_max, z_min, z_max (repeatable)");
  box->add_option("--created", spec.created,
                  "creation time recorded in the provenance (default: now, ISO 8601 UTC); fix it "
                  "for reproducible, byte-identical files");
  box->add_option("-o,--output", output, "model file to write (.h5)")->required();
  box->add_flag("-q,--quiet", quiet, "log only errors");
  CLI11_PARSE(app, argc, argv);

  return sinew::tool::run("sinew-generate", [&] {
    if (quiet) sinew::log::set_level(sinew::log::Level::error);
    spec.dims = {dims[0], dims[1], dims[2]};
    spec.origin = {origin[0], origin[1], origin[2]};
    for (const auto& m : materials) spec.materials.push_back(parse_material(m));
    if (!muscle.empty()) {
      const auto parts = split(muscle, ':');
      if (parts.size() != 2 || parts[0].empty()) {
        throw sinew::ConfigError("", "--muscle", "'" + muscle + "' is not NAME:MATERIAL");
      }
      muscle_spec.name = parts[0];
      muscle_spec.material = -1;
      for (std::size_t i = 0; i < spec.materials.size(); ++i) {
        if (spec.materials[i].name == parts[1]) muscle_spec.material = static_cast<std::int32_t>(i);
      }
      if (muscle_spec.material < 0) {
        throw sinew::ConfigError("", "--muscle", "no material named '" + parts[1] + "'");
      }
      if (muscle_box.empty()) muscle_box = {0, 0, 0, dims[0], dims[1], dims[2]};
      muscle_spec.element_min = {muscle_box[0], muscle_box[1], muscle_box[2]};
      muscle_spec.element_max = {muscle_box[3], muscle_box[4], muscle_box[5]};
      muscle_spec.fibre = {fibre[0], fibre[1], fibre[2]};
      spec.muscles.push_back(muscle_spec);
    } else if (!muscle_box.empty()) {
      throw sinew::ConfigError("", "--muscle-box", "given without --muscle");
    }
    auto model = sinew::formats::make_box_model(spec);
    model.provenance.tool = "sinew-generate box";
    sinew::formats::write_model(model, output);
    sinew::log::info("wrote {}: {} nodes, {} elements, {} materials, {} muscles", output,
                     model.node_count(), model.element_count(), model.materials.size(),
                     model.muscles.size());
    return sinew::tool::kExitOk;
  });
}
