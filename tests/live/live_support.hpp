#pragma once
// The small model and scene of the sinew-live tests: a 12 × 4 × 3 block of 2 mm voxels of soft
// tissue (E = 3 kPa, ν = 0.45, ρ = 1000 kg/m³), clamped at x = 0, with a muscle "flexor" along x
// over the whole block and the visual surface "skin" (the boundary without the clamped face). Its
// Δt is about 0.3 ms, so a test steps through tenths of a second in a few thousand steps.
#include <fstream>
#include <string>

#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"

namespace sinew::live::testing {

inline void write_live_model(const std::string& path) {
  formats::BoxSpec spec;
  spec.dims = {12, 4, 3};
  spec.voxel_size = 0.002;
  spec.materials = {formats::make_neo_hookean_material("soft", 3000.0, 0.45, 1000.0)};
  spec.created = "2026-01-01T00:00:00Z";
  formats::BoxMuscleSpec m;
  m.name = "flexor";
  m.element_min = {0, 0, 0};
  m.element_max = {12, 4, 3};
  m.fibre = {1, 0, 0};
  m.reference_stress = 1500;
  spec.muscles.push_back(m);
  auto model = formats::make_box_model(spec);
  simulator::add_boundary_visual_surface(model, "skin", "x_min");
  formats::write_model(model, path);
}

// The scene next to the model (model file name `model`): the muscle ramps to 0.3 over 0.05 s and
// holds; loads on (drags), damping 20/s; frames every 0.01 s with stress and J.
inline std::string live_scene_text(const std::string& model) {
  return "title: live test block\n"
         "model: " +
         model +
         "\n"
         "effects: [elasticity, hourglass, damping, muscles, loads]\n"
         "duration: 2.0\n"
         "damping: 20\n"
         "muscles:\n"
         "  flexor: {ramp: 0.05, peak: 0.3}\n"
         "boundary_conditions:\n"
         "  - {type: fixed, set: x_min}\n"
         "output:\n"
         "  interval: 0.01\n"
         "  fields: [stress, J]\n";
}

inline void write_live_case(const std::string& dir) {
  write_live_model(dir + "/live_box.h5");
  std::ofstream(dir + "/live_box.yaml") << live_scene_text("live_box.h5");
}

}  // namespace sinew::live::testing
