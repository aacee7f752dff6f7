// Scene files: every key parsed into the Scene, unknown keys and every error named by file and key
// path, and the resolver's mapping onto the engine's Setup.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/run/scene.hpp"
#include "sinew/simulator/run/scene_jaw.hpp"

namespace sinew::simulator {
namespace {

using testing::small_box;

const char* kFullScene = R"(
title: every key
model: models/box.h5
effects: [elasticity, hourglass, damping, gravity, muscles, loads]
duration: 0.25
time_step: {mode: fixed, value: 1.0e-4, force: true}
damping: 12.5
mass_scaling: 4
time_scaling: 2
hourglass: {kappa: 0.1, modulus: p_wave}
precision: float
gravity: [0, -9.81, 0]
muscles:
  flexor: {ramp: 0.05, hold: 0.1, release: 0.05, start: 0.02, peak: 0.8}
node_sets:
  top: {plane: {point: [0, 0, 0.04], normal: [0, 0, 2]}, tolerance: 1.0e-5}
  corner_box: {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}}
  bottom: {model: z_min}
  picked: {nodes: [0, 3, 3, 1]}
boundary_conditions:
  - {type: fixed, set: bottom}
  - {type: fixed, set: x_min, components: [x]}
  - {type: plane, set: y_min, normal: [0, 1, 0]}
  - type: displacement
    set: top
    components: [z]
    value: [0, 0, -0.002]
    curve: [[0, 0], [0.1, 1]]
  - {type: force, set: picked, value: [1, 2, 3], per_node: true, curve: 0.5}
initial_velocity:
  - {set: corner_box, value: [0.1, 0, 0]}
output:
  interval: 0.01
  fields: [stress, J, energy_density]
  probe_interval: 0.005
probes:
  - {name: tip, type: displacement, point: [0.04, 0.04, 0.04]}
  - {name: n5, type: displacement, node: 5}
  - {name: base, type: reaction, set: bottom}
)";

TEST(SceneParse, EveryKey) {
  const auto s = parse_scene_text(kFullScene, "full.yaml", "/data/scenes");
  EXPECT_EQ(s.title, "every key");
  EXPECT_EQ(s.model, "models/box.h5");
  EXPECT_EQ(s.model_path, "/data/scenes/models/box.h5");
  ASSERT_EQ(s.effects.size(), 6u);
  EXPECT_TRUE(s.has(Effect::muscles));
  EXPECT_FALSE(s.has(Effect::sliding));
  EXPECT_DOUBLE_EQ(s.duration, 0.25);
  EXPECT_FALSE(s.time_step.automatic);
  EXPECT_DOUBLE_EQ(s.time_step.value, 1e-4);
  EXPECT_TRUE(s.time_step.force);
  EXPECT_DOUBLE_EQ(s.damping, 12.5);
  EXPECT_DOUBLE_EQ(s.mass_scaling, 4);
  EXPECT_DOUBLE_EQ(s.time_scaling, 2);
  EXPECT_DOUBLE_EQ(s.hourglass.kappa, 0.1);
  EXPECT_EQ(s.hourglass.modulus, HourglassModulus::p_wave);
  EXPECT_EQ(s.precision, Precision::float32);
  EXPECT_DOUBLE_EQ(s.gravity[1], -9.81);

  ASSERT_EQ(s.activations.size(), 1u);
  EXPECT_EQ(s.activations[0].muscle, "flexor");
  // start 0.02, ramp 0.05 to 0.8, hold 0.1, release 0.05: (0,0) (0.02,0) (0.07,0.8) (0.17,0.8)
  // (0.22,0)
  const auto& pts = s.activations[0].curve.curve.points;
  ASSERT_EQ(pts.size(), 5u);
  EXPECT_DOUBLE_EQ(pts[1][0], 0.02);
  EXPECT_DOUBLE_EQ(pts[2][1], 0.8);
  EXPECT_DOUBLE_EQ(pts[3][0], 0.17);
  EXPECT_DOUBLE_EQ(pts[4][0], 0.22);
  EXPECT_DOUBLE_EQ(pts[4][1], 0.0);
  EXPECT_DOUBLE_EQ(s.activations[0].curve.curve.at(0.045), 0.4);

  ASSERT_EQ(s.node_sets.size(), 4u);
  EXPECT_EQ(s.node_sets[0].kind, SceneNodeSet::Kind::plane);
  EXPECT_DOUBLE_EQ(s.node_sets[0].normal[2], 1.0);  // normalised
  EXPECT_DOUBLE_EQ(*s.node_sets[0].tolerance, 1e-5);
  EXPECT_EQ(s.node_sets[1].kind, SceneNodeSet::Kind::box);
  EXPECT_EQ(s.node_sets[2].model_set, "z_min");
  EXPECT_EQ(s.node_sets[3].ids.size(), 4u);

  ASSERT_EQ(s.boundary.size(), 5u);
  EXPECT_EQ(s.boundary[1].components, (std::array<bool, 3>{true, false, false}));
  EXPECT_EQ(s.boundary[2].kind, SceneBoundary::Kind::plane);
  EXPECT_EQ(s.boundary[3].kind, SceneBoundary::Kind::displacement);
  ASSERT_TRUE(s.boundary[3].curve.has_value());
  EXPECT_EQ(s.boundary[3].curve->curve.points.size(), 2u);
  EXPECT_TRUE(s.boundary[4].per_node);
  EXPECT_DOUBLE_EQ(s.boundary[4].curve->curve.at(7.0), 0.5);

  ASSERT_EQ(s.initial_velocity.size(), 1u);
  EXPECT_EQ(s.initial_velocity[0].set, "corner_box");
  EXPECT_DOUBLE_EQ(s.output.interval, 0.01);
  EXPECT_TRUE(s.output.has(OutputField::displacement));
  EXPECT_TRUE(s.output.has(OutputField::stress));
  EXPECT_TRUE(s.output.has(OutputField::jacobian));
  EXPECT_TRUE(s.output.has(OutputField::energy_density));
  EXPECT_FALSE(s.output.has(OutputField::surfaces));
  EXPECT_DOUBLE_EQ(*s.output.probe_interval, 0.005);
  ASSERT_EQ(s.probes.size(), 3u);
  EXPECT_TRUE(s.probes[0].point.has_value());
  EXPECT_EQ(*s.probes[1].node, 5);
  EXPECT_EQ(s.probes[2].kind, SceneProbe::Kind::reaction);
}

// `units: mm`: the full scene written in millimetres reads to the same SI values as in metres —
// every length (boxes, planes, tolerances, displacements, probe points), velocity and
// acceleration converted, forces (N) and times (s) untouched.
TEST(SceneParse, UnitsMillimetresConvertEveryLengthAtTheEdge) {
  std::string mm = std::string("units: mm\n") + kFullScene;
  const std::pair<const char*, const char*> edits[] = {
      {"gravity: [0, -9.81, 0]", "gravity: [0, -9810, 0]"},
      {"point: [0, 0, 0.04]", "point: [0, 0, 40]"},
      {"tolerance: 1.0e-5", "tolerance: 1.0e-2"},
      {"max: [0.01, 0.01, 0.01]", "max: [10, 10, 10]"},
      {"value: [0, 0, -0.002]", "value: [0, 0, -2]"},
      {"value: [0.1, 0, 0]", "value: [100, 0, 0]"},
      {"point: [0.04, 0.04, 0.04]", "point: [40, 40, 40]"}};
  for (const auto& [from, to] : edits) {
    const auto at = mm.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    mm.replace(at, std::string(from).size(), to);
  }
  const auto si = parse_scene_text(kFullScene, "full.yaml", "");
  const auto s = parse_scene_text(mm, "full_mm.yaml", "");
  EXPECT_DOUBLE_EQ(s.length_unit, 1e-3);
  auto same = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[std::size_t(k)], b[std::size_t(k)], 1e-15);
  };
  same(s.gravity, si.gravity);
  same(s.node_sets[0].point, si.node_sets[0].point);
  EXPECT_NEAR(*s.node_sets[0].tolerance, *si.node_sets[0].tolerance, 1e-18);
  same(s.node_sets[1].min, si.node_sets[1].min);
  same(s.node_sets[1].max, si.node_sets[1].max);
  same(s.boundary[3].value, si.boundary[3].value);  // displacement, m
  same(s.boundary[4].value, si.boundary[4].value);  // force, N: [1, 2, 3] in both
  EXPECT_DOUBLE_EQ(s.boundary[4].value[2], 3.0);
  same(s.initial_velocity[0].value, si.initial_velocity[0].value);
  same(*s.probes[0].point, *si.probes[0].point);
  EXPECT_DOUBLE_EQ(s.duration, si.duration);
  EXPECT_DOUBLE_EQ(s.output.interval, si.output.interval);
  try {
    parse_scene_text("units: inch\nmodel: m.h5\neffects: [elasticity]\nduration: 1\n", "u.yaml",
                     "");
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("u.yaml: units"), std::string::npos) << e.what();
  }
}

TEST(SceneParse, MinimalSceneHasDefaults) {
  const auto s =
      parse_scene_text("model: m.h5\neffects: [elasticity]\nduration: 1\n", "min.yaml", "");
  EXPECT_TRUE(s.time_step.automatic);
  EXPECT_FALSE(s.time_step.safety_factor.has_value());
  EXPECT_EQ(s.precision, Precision::float64);
  EXPECT_DOUBLE_EQ(s.mass_scaling, 1);
  EXPECT_DOUBLE_EQ(s.output.interval, 0);
  EXPECT_EQ(s.output.fields.size(), 1u);
  EXPECT_EQ(s.model_path, "m.h5");
}

TEST(SceneParse, ScalarShorthands) {
  const auto s = parse_scene_text(
      "model: m.h5\neffects: [elasticity, loads]\nduration: 1\ntime_step: 2.0e-5\n"
      "initial_velocity: [0, 0, 1]\n"
      "boundary_conditions:\n  - {type: displacement, set: all, value: [0, 0, 1], curve: {points: "
      "[[0, 0], [1, 1]]}}\n",
      "s.yaml", "");
  EXPECT_FALSE(s.time_step.automatic);
  EXPECT_DOUBLE_EQ(s.time_step.value, 2e-5);
  ASSERT_EQ(s.initial_velocity.size(), 1u);
  EXPECT_EQ(s.initial_velocity[0].set, "all");
  EXPECT_DOUBLE_EQ(s.boundary[0].curve->curve.at(0.5), 0.5);
  const auto f = parse_scene_text(
      "model: m.h5\neffects: [elasticity]\nduration: 1\ntime_step: {value: 1.0e-5, safety_factor: "
      "0.9}\n",
      "f.yaml", "");
  EXPECT_FALSE(f.time_step.automatic);
  EXPECT_FALSE(f.time_step.force);
  EXPECT_DOUBLE_EQ(*f.time_step.safety_factor, 0.9);
  const auto a = parse_scene_text(
      "model: m.h5\neffects: [elasticity]\nduration: 1\ntime_step: auto\n", "a.yaml", "");
  EXPECT_TRUE(a.time_step.automatic);
  const auto r = parse_scene_text(
      "model: m.h5\neffects: [elasticity, muscles]\nduration: 1\nmuscles: {m: {ramp: 0.1}}\n",
      "r.yaml", "");
  EXPECT_EQ(r.activations[0].curve.curve.points.size(), 2u);  // no release: held at the peak
  EXPECT_DOUBLE_EQ(r.activations[0].curve.curve.at(5), 1.0);
}

struct ErrorCase {
  const char* name;
  const char* yaml;     // appended to a valid base
  const char* field;    // expected key path
  const char* problem;  // expected substring of the message
};

const char* kBase =
    "model: m.h5\neffects: [elasticity, hourglass, damping, loads]\ndamping: 1\nduration: 1\n";

class SceneErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneErrors, NameFileKeyAndProblem) {
  const auto& c = GetParam();
  std::string text =
      std::string(c.name).rfind("raw_", 0) == 0 ? std::string(c.yaml) : std::string(kBase) + c.yaml;
  try {
    parse_scene_text(text, "scene.yaml", "");
    FAIL() << "expected a ConfigError for " << c.name;
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "scene.yaml");
    EXPECT_EQ(e.field(), c.field) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Scene, SceneErrors,
    ::testing::Values(
        ErrorCase{"unknown_top_key", "outputs: {}\n", "outputs", "unknown key 'outputs'"},
        ErrorCase{"unknown_nested_key", "output: {interval: 0.1, every: 2}\n", "output.every",
                  "unknown key 'every'"},
        ErrorCase{"unknown_bc_key",
                  "boundary_conditions:\n  - {type: fixed, set: all, value: [0, 0, 0]}\n",
                  "boundary_conditions[0].value", "unknown key 'value'"},
        ErrorCase{"unknown_probe_key",
                  "probes:\n  - {name: a, type: reaction, set: all, node: 3}\n", "probes[0].node",
                  "unknown key"},
        ErrorCase{"raw_missing_model", "effects: [elasticity]\nduration: 1\n", "model", "missing"},
        ErrorCase{"raw_missing_effects", "model: m.h5\nduration: 1\n", "effects", "missing"},
        ErrorCase{"raw_missing_duration", "model: m.h5\neffects: [elasticity]\n", "duration",
                  "missing"},
        ErrorCase{"raw_negative_duration", "model: m.h5\neffects: [elasticity]\nduration: -1\n",
                  "duration", "must be > 0"},
        ErrorCase{"raw_not_a_number", "model: m.h5\neffects: [elasticity]\nduration: soon\n",
                  "duration", "expected a number"},
        ErrorCase{"raw_unknown_effect", "model: m.h5\neffects: [elasticity, magic]\nduration: 1\n",
                  "effects[1]", "unknown value 'magic'"},
        ErrorCase{"raw_no_elasticity", "model: m.h5\neffects: [hourglass]\nduration: 1\n",
                  "effects", "'elasticity' is required"},
        ErrorCase{"raw_effect_twice",
                  "model: m.h5\neffects: [elasticity, elasticity]\nduration: 1\n", "effects[1]",
                  "listed twice"},
        ErrorCase{"raw_damping_missing",
                  "model: m.h5\neffects: [elasticity, damping]\nduration: 1\n", "damping",
                  "needs the mass-proportional"},
        ErrorCase{"raw_damping_without_effect",
                  "model: m.h5\neffects: [elasticity]\nduration: 1\ndamping: 3\n", "damping",
                  "not in effects"},
        ErrorCase{"raw_gravity_without_effect",
                  "model: m.h5\neffects: [elasticity]\nduration: 1\ngravity: [0, 0, 1]\n",
                  "gravity", "not in effects"},
        ErrorCase{"raw_muscles_without_effect",
                  "model: m.h5\neffects: [elasticity]\nduration: 1\nmuscles: {a: 1}\n", "muscles",
                  "not in effects"},
        ErrorCase{"raw_hourglass_without_effect",
                  "model: m.h5\neffects: [elasticity]\nduration: 1\nhourglass: {kappa: 0.1}\n",
                  "hourglass", "not in effects"},
        ErrorCase{"raw_loads_without_effect",
                  "model: m.h5\neffects: [elasticity]\nduration: 1\nboundary_conditions:\n"
                  "  - {type: force, set: all, value: [0, 0, 1]}\n",
                  "boundary_conditions[0]", "'loads' effect"},
        ErrorCase{"curve_not_monotone",
                  "boundary_conditions:\n  - {type: displacement, set: all, value: [0, 0, 1], "
                  "curve: [[0, 0], [0.5, 1], [0.5, 2]]}\n",
                  "boundary_conditions[0].curve", "curve not monotone in t"},
        ErrorCase{"curve_bad_point",
                  "boundary_conditions:\n  - {type: force, set: all, value: [0, 0, 1], curve: [[0, "
                  "0, 1]]}\n",
                  "boundary_conditions[0].curve[0]", "expected a point"},
        ErrorCase{"curve_points_and_ramp",
                  "boundary_conditions:\n  - {type: force, set: all, value: [0, 0, 1], curve: "
                  "{points: [[0, 1]], ramp: 1}}\n",
                  "boundary_conditions[0].curve.ramp", "not both"},
        ErrorCase{"curve_zero_ramp",
                  "boundary_conditions:\n  - {type: force, set: all, value: [0, 0, 1], curve: "
                  "{ramp: 0}}\n",
                  "boundary_conditions[0].curve.ramp", "must be > 0"},
        ErrorCase{"curve_hold_without_release",
                  "boundary_conditions:\n  - {type: force, set: all, value: [0, 0, 1], curve: "
                  "{ramp: 1, hold: 1}}\n",
                  "boundary_conditions[0].curve.hold", "needs 'release'"},
        ErrorCase{"raw_activation_above_one",
                  "model: m.h5\neffects: [elasticity, muscles]\nduration: 1\nmuscles: {m: [[0, 0], "
                  "[1, 1.5]]}\n",
                  "muscles.m", "activation must lie in [0, 1]"},
        ErrorCase{"time_step_unknown_mode", "time_step: {mode: sometimes}\n", "time_step.mode",
                  "unknown value"},
        ErrorCase{"time_step_fixed_without_value", "time_step: {mode: fixed}\n", "time_step",
                  "needs 'value'"},
        ErrorCase{"time_step_force_with_auto", "time_step: {mode: auto, force: true}\n",
                  "time_step.force", "only applies to mode: fixed"},
        ErrorCase{"time_step_safety_above_one", "time_step: {safety_factor: 1.5}\n",
                  "time_step.safety_factor", "(0, 1]"},
        ErrorCase{"time_step_negative", "time_step: -1.0e-5\n", "time_step", "must be > 0"},
        ErrorCase{"mass_scaling_below_one", "mass_scaling: 0.5\n", "mass_scaling", "must be >= 1"},
        ErrorCase{"time_scaling_below_one", "time_scaling: 0\n", "time_scaling", "must be >= 1"},
        ErrorCase{"hourglass_modulus", "hourglass: {modulus: bulk}\n", "hourglass.modulus",
                  "unknown value 'bulk'"},
        ErrorCase{"precision", "precision: half\n", "precision", "unknown value 'half'"},
        ErrorCase{"raw_gravity_vector",
                  "model: m.h5\neffects: [elasticity, gravity]\nduration: 1\ngravity: [0, 1]\n",
                  "gravity", "list of 3 numbers"},
        ErrorCase{"node_set_two_kinds",
                  "node_sets:\n  a: {box: {min: [0, 0, 0], max: [1, 1, 1]}, nodes: [1]}\n",
                  "node_sets.a", "exactly one of"},
        ErrorCase{"node_set_box_inverted",
                  "node_sets:\n  a: {box: {min: [0, 2, 0], max: [1, 1, 1]}}\n",
                  "node_sets.a.box.max", "max is below min along y"},
        ErrorCase{"node_set_plane_zero_normal",
                  "node_sets:\n  a: {plane: {point: [0, 0, 0], normal: [0, 0, 0]}}\n",
                  "node_sets.a.plane.normal", "zero vector"},
        ErrorCase{"node_set_tolerance_without_plane",
                  "node_sets:\n  a: {nodes: [1], tolerance: 0.1}\n", "node_sets.a.tolerance",
                  "only applies to a plane"},
        ErrorCase{"node_set_negative_id", "node_sets:\n  a: {nodes: [1, -2]}\n",
                  "node_sets.a.nodes[1]", ">= 0"},
        ErrorCase{"node_set_named_all", "node_sets:\n  all: {nodes: [1]}\n", "node_sets.all",
                  "built-in"},
        ErrorCase{"node_set_bad_name", "node_sets:\n  a b: {nodes: [1]}\n", "node_sets.a b",
                  "may only contain"},
        ErrorCase{"bc_without_type", "boundary_conditions:\n  - {set: all}\n",
                  "boundary_conditions[0]", "needs 'type'"},
        ErrorCase{"bc_unknown_type", "boundary_conditions:\n  - {type: glue, set: all}\n",
                  "boundary_conditions[0].type", "unknown value 'glue'"},
        ErrorCase{"bc_without_set", "boundary_conditions:\n  - {type: fixed}\n",
                  "boundary_conditions[0]", "needs 'set'"},
        ErrorCase{"bc_bad_component",
                  "boundary_conditions:\n  - {type: fixed, set: all, components: [x, w]}\n",
                  "boundary_conditions[0].components[1]", "unknown value 'w'"},
        ErrorCase{"bc_component_twice",
                  "boundary_conditions:\n  - {type: fixed, set: all, components: [x, x]}\n",
                  "boundary_conditions[0].components[1]", "listed twice"},
        ErrorCase{"bc_plane_without_normal", "boundary_conditions:\n  - {type: plane, set: all}\n",
                  "boundary_conditions[0]", "needs 'normal'"},
        ErrorCase{"bc_force_without_value", "boundary_conditions:\n  - {type: force, set: all}\n",
                  "boundary_conditions[0]", "needs 'value'"},
        ErrorCase{"bc_not_a_list", "boundary_conditions: {type: fixed}\n", "boundary_conditions",
                  "expected a list"},
        ErrorCase{"initial_velocity_item", "initial_velocity:\n  - {set: all}\n",
                  "initial_velocity[0]", "needs 'set'"},
        ErrorCase{"output_unknown_field", "output: {fields: [stress, strain]}\n",
                  "output.fields[1]", "unknown value 'strain'"},
        ErrorCase{"output_negative_interval", "output: {interval: -1}\n", "output.interval",
                  "must be >= 0"},
        ErrorCase{"probe_without_name", "probes:\n  - {type: reaction, set: all}\n", "probes[0]",
                  "needs a 'name'"},
        ErrorCase{"probe_name_twice",
                  "probes:\n  - {name: a, type: reaction, set: all}\n  - {name: a, type: reaction, "
                  "set: all}\n",
                  "probes[1].name", "used twice"},
        ErrorCase{"probe_node_and_point",
                  "probes:\n  - {name: a, type: displacement, node: 1, point: [0, 0, 0]}\n",
                  "probes[0]", "exactly one of 'node' or 'point'"},
        ErrorCase{"probe_node_not_integer",
                  "probes:\n  - {name: a, type: displacement, node: 1.5}\n", "probes[0].node",
                  "expected an integer"},
        ErrorCase{"key_twice", "output: {interval: 0.1, interval: 0.2}\n", "output.interval",
                  "given twice"},
        ErrorCase{"jaw_unknown_key", "jaw: {open_deg: 10}\n", "jaw.open_deg",
                  "unknown key 'open_deg'"},
        ErrorCase{"jaw_empty", "jaw: {}\n", "jaw", "at least one of opening_deg"},
        ErrorCase{"jaw_opening_out_of_range", "jaw: {opening_deg: [[0, 0], [0.1, 45]]}\n",
                  "jaw.opening_deg", "must lie in [0, 40] degrees"},
        ErrorCase{"jaw_closing_below_rest", "jaw: {opening_deg: -2}\n", "jaw.opening_deg",
                  "point 0 has -2"},
        ErrorCase{"jaw_protrusion_out_of_range", "jaw: {protrusion_mm: {ramp: 0.1, peak: 15}}\n",
                  "jaw.protrusion_mm", "must lie in [-1, 12] mm"},
        ErrorCase{"jaw_lateral_out_of_range", "jaw: {lateral_mm: -16}\n", "jaw.lateral_mm",
                  "must lie in [-15, 15] mm"},
        ErrorCase{"jaw_time_backwards", "jaw: {opening_deg: [[0.1, 0], [0.05, 5]]}\n",
                  "jaw.opening_deg", "not monotone"},
        ErrorCase{"raw_not_yaml", "model: [unclosed\n", "", "not valid YAML"},
        ErrorCase{"raw_not_a_map", "- a\n- b\n", "", "a scene is a mapping"}),
    [](const ::testing::TestParamInfo<ErrorCase>& info) { return std::string(info.param.name); });

TEST(SceneParse, ErrorsGiveTheLine) {
  try {
    parse_scene_text(
        "model: m.h5\neffects: [elasticity]\nduration: 1\noutput:\n  interval: 0.1\n  bogus: 1\n",
        "lines.yaml", "");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("line 6"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("lines.yaml: output.bogus: unknown key", 0), 0u)
        << e.what();
  }
}

TEST(SceneParse, MissingFileIsAnIoError) {
  EXPECT_THROW(parse_scene("/nonexistent/scene.yaml"), IoError);
}

// ---- resolver ----

Scene scene_for(const std::string& body) {
  return parse_scene_text("model: box.h5\nduration: 0.1\n" + body, "r.yaml", "");
}

// A small box whose x_max face above the bottom row is a jaw hinged about a line along y.
formats::Model box_with_jaw() {
  auto model = small_box();
  formats::Jaw jaw;
  for (std::size_t n = 0; n < model.node_count(); ++n)
    if (model.node_lattice[n][0] == 4 && model.node_lattice[n][2] > 0)
      jaw.nodes.push_back(Index(n));
  jaw.pivot = {0.05, 0, 0.04};
  jaw.axis = {0, 1, 0};
  jaw.forward = {1, 0, 0};
  jaw.incisal = {0.04, 0.02, 0};
  model.jaw = jaw;
  return model;
}

TEST(SceneResolve, TheJawInDegreesAndMillimetresBecomesRadiansAndMetres) {
  const auto model = box_with_jaw();
  const auto r =
      resolve_scene(scene_for("effects: [elasticity]\njaw:\n  opening_deg: {ramp: 0.05, peak: 30}\n"
                              "  protrusion_mm: [[0, 0], [0.05, 4]]\n"),
                    model);
  ASSERT_TRUE(r.setup.jaw);
  const auto& j = *r.setup.jaw;
  EXPECT_EQ(j.nodes, model.jaw->nodes);
  EXPECT_NEAR(j.opening.at(0.05), 30 * std::acos(-1.0) / 180, 1e-15);
  EXPECT_NEAR(j.protrusion.at(0.05), 4e-3, 1e-18);
  EXPECT_TRUE(j.lateral.points.empty());  // left out: 0 throughout
  EXPECT_EQ(j.pose(1.0).lateral, 0.0);
  for (const Index nd : j.nodes)
    EXPECT_FALSE(std::binary_search(r.setup.rigid_nodes.begin(), r.setup.rigid_nodes.end(), nd));
  // The incisal point, r = (−10, ·, −40) mm from the pivot in the plane normal to the axis (y),
  // turned 30° about +y, (x, z) → (x cos θ + z sin θ, −x sin θ + z cos θ), and moved 4 mm along x.
  const double c = std::cos(std::acos(-1.0) / 6), sn = std::sin(std::acos(-1.0) / 6);
  const double ux = (-0.01 * c - 0.04 * sn) + 0.01 + 4e-3, uz = (0.01 * sn - 0.04 * c) + 0.04;
  EXPECT_NEAR(incisal_opening(j, 0.05), std::hypot(ux, uz), 1e-15);
  EXPECT_EQ(incisal_opening(j, 0.0), 0.0);
}

TEST(SceneResolve, AModelJawWithoutASceneJawIsHeldClosed) {
  const auto model = box_with_jaw();
  const auto r = resolve_scene(scene_for("effects: [elasticity]\n"), model);
  EXPECT_FALSE(r.setup.jaw);
  for (const Index nd : model.jaw->nodes)
    EXPECT_TRUE(std::binary_search(r.setup.rigid_nodes.begin(), r.setup.rigid_nodes.end(), nd));
}

TEST(SceneResolve, AJawOnAModelWithoutOneIsRefused) {
  try {
    resolve_scene(scene_for("effects: [elasticity]\njaw: {opening_deg: 5}\n"), small_box());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "jaw");
    EXPECT_NE(std::string(e.what()).find("the model has no jaw"), std::string::npos) << e.what();
  }
}

TEST(SceneResolve, JawNodesFixedByTheSceneAreRefused) {
  try {
    resolve_scene(scene_for("effects: [elasticity]\njaw: {opening_deg: 5}\n"
                            "boundary_conditions:\n  - {type: fixed, set: x_max}\n"),
                  box_with_jaw());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "jaw");
    EXPECT_NE(std::string(e.what()).find("nodes of the jaw are also fixed"), std::string::npos)
        << e.what();
  }
}

TEST(SceneResolve, MapsEveryKeyOntoTheSetup) {
  auto model = small_box(true);
  // A model set whose name the scene refers to directly.
  const auto s = parse_scene_text(kFullScene, "full.yaml", "");
  const auto r = resolve_scene(s, model);
  const auto& setup = r.setup;
  EXPECT_TRUE(setup.effects.elasticity && setup.effects.hourglass && setup.effects.damping &&
              setup.effects.gravity && setup.effects.muscles && setup.effects.loads);
  EXPECT_FALSE(setup.effects.sliding);
  EXPECT_EQ(setup.precision, Precision::float32);
  EXPECT_DOUBLE_EQ(setup.duration, 0.5);  // scene duration × time scaling
  EXPECT_DOUBLE_EQ(setup.time_scaling, 2);
  EXPECT_EQ(setup.time_step.policy, TimeStepPolicy::forced);
  EXPECT_DOUBLE_EQ(setup.time_step.user_dt, 1e-4);
  EXPECT_DOUBLE_EQ(setup.damping_alpha, 12.5);
  EXPECT_DOUBLE_EQ(setup.mass_scaling, 4);
  EXPECT_DOUBLE_EQ(setup.hourglass.kappa, 0.1);
  EXPECT_EQ(setup.hourglass.modulus, HourglassModulus::p_wave);
  EXPECT_DOUBLE_EQ(setup.gravity[1], -9.81);
  ASSERT_EQ(setup.activation.size(), 1u);
  EXPECT_DOUBLE_EQ(setup.activation[0].at(0.1), 0.8);

  // bottom = the model's z_min face (25 nodes), fixed in all components: rigid.
  EXPECT_EQ(setup.rigid_nodes.size(), 25u);
  EXPECT_TRUE(std::is_sorted(setup.rigid_nodes.begin(), setup.rigid_nodes.end()));
  // x fixed on x_min is a plane with normal x; the explicit plane on y_min.
  ASSERT_EQ(setup.sliding_planes.size(), 2u);
  EXPECT_EQ(setup.sliding_planes[0].normal, (Vec3d{1, 0, 0}));
  EXPECT_EQ(setup.sliding_planes[0].nodes.size(), 25u);
  EXPECT_EQ(setup.sliding_planes[1].normal, (Vec3d{0, 1, 0}));
  // The top plane set: the 25 nodes at z = 0.04.
  ASSERT_EQ(setup.prescribed.size(), 1u);
  EXPECT_EQ(setup.prescribed[0].nodes.size(), 25u);
  for (auto n : setup.prescribed[0].nodes) EXPECT_NEAR(model.node_position(n)[2], 0.04, 1e-12);
  EXPECT_EQ(setup.prescribed[0].components, (std::array<bool, 3>{false, false, true}));
  EXPECT_DOUBLE_EQ(setup.prescribed[0].value[2], -0.002);
  // Per-node force × 3 distinct nodes (0, 1, 3) = the set's total.
  ASSERT_EQ(setup.forces.size(), 1u);
  EXPECT_EQ(setup.forces[0].nodes, (std::vector<Index>{0, 1, 3}));
  EXPECT_DOUBLE_EQ(setup.forces[0].total[2], 9.0);
  EXPECT_DOUBLE_EQ(setup.forces[0].curve.at(0), 0.5);
  // Box [0, 0.01]³: the 8 nodes of the first element.
  ASSERT_EQ(setup.initial_velocities.size(), 1u);
  EXPECT_EQ(setup.initial_velocities[0].nodes.size(), 8u);
  EXPECT_DOUBLE_EQ(setup.output_interval, 0.02);  // simulated time

  ASSERT_EQ(r.probes.size(), 3u);
  EXPECT_EQ(r.probes[0].nodes, (std::vector<Index>{124}));  // the far corner
  EXPECT_DOUBLE_EQ(r.probes[0].distance, 0.0);
  EXPECT_EQ(r.probes[1].nodes, (std::vector<Index>{5}));
  EXPECT_EQ(r.probes[2].nodes.size(), 25u);
  EXPECT_DOUBLE_EQ(r.output_interval, 0.01);
  EXPECT_DOUBLE_EQ(r.probe_interval, 0.005);
}

TEST(SceneResolve, CommandLineOverridesPrecisionAndThreads) {
  const auto model = small_box();
  ResolveOptions o;
  o.precision = Precision::float64;
  o.threads = 3;
  const auto r = resolve_scene(scene_for("effects: [elasticity]\nprecision: float\n"), model, o);
  EXPECT_EQ(r.setup.precision, Precision::float64);
  EXPECT_EQ(r.setup.threads, 3);
}

TEST(SceneResolve, KeepsTheModelsRigidNodesAndMergesFixedSets) {
  formats::BoxSpec spec;
  spec.dims = {2, 2, 2};
  spec.voxel_size = 0.01;
  spec.materials = {testing::soft_material()};
  spec.rigid_faces = {"z_min"};
  spec.created = "2026-01-01T00:00:00Z";
  const auto model = formats::make_box_model(spec);
  const auto r = resolve_scene(
      scene_for("effects: [elasticity]\nboundary_conditions:\n  - {type: fixed, set: x_min}\n"),
      model);
  // 9 on z_min + 9 on x_min − 3 shared.
  EXPECT_EQ(r.setup.rigid_nodes.size(), 15u);
}

TEST(SceneResolve, PointProbeTakesTheNearestNode) {
  const auto model = small_box();
  const auto r = resolve_scene(scene_for("effects: [elasticity]\nprobes:\n  - {name: p, type: "
                                         "displacement, point: [0.0101, 0.0002, 0.019]}\n"),
                               model);
  ASSERT_EQ(r.probes.size(), 1u);
  const auto n = r.probes[0].nodes[0];
  EXPECT_EQ(model.node_lattice[std::size_t(n)], (formats::Lattice{1, 0, 2}));
  EXPECT_NEAR(r.probes[0].distance, std::sqrt(0.0001 * 0.0001 + 0.0002 * 0.0002 + 0.001 * 0.001),
              1e-12);
}

struct ResolveError {
  const char* name;
  const char* body;
  const char* field;
  const char* problem;
};

class SceneResolveErrors : public ::testing::TestWithParam<ResolveError> {};

TEST_P(SceneResolveErrors, NameFileKeyAndProblem) {
  const auto& c = GetParam();
  const auto model = small_box(true);
  const auto scene = scene_for(c.body);
  try {
    resolve_scene(scene, model);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "r.yaml");
    EXPECT_EQ(e.field(), c.field) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Scene, SceneResolveErrors,
    ::testing::Values(
        ResolveError{"unknown_node_set",
                     "effects: [elasticity]\nboundary_conditions:\n  - {type: fixed, set: topp}\n",
                     "boundary_conditions[0].set", "unknown node set 'topp' (known: all, x_min"},
        ResolveError{"unknown_model_set",
                     "effects: [elasticity]\nnode_sets:\n  a: {model: ceiling}\n"
                     "boundary_conditions:\n  - {type: fixed, set: a}\n",
                     "node_sets.a.model", "the model has no node set 'ceiling'"},
        ResolveError{
            "empty_box",
            "effects: [elasticity]\nnode_sets:\n  a: {box: {min: [1, 1, 1], max: [2, 2, 2]}}\n"
            "boundary_conditions:\n  - {type: fixed, set: a}\n",
            "node_sets.a", "selects no node"},
        ResolveError{"node_out_of_range",
                     "effects: [elasticity]\nnode_sets:\n  a: {nodes: [3, 125]}\n"
                     "boundary_conditions:\n  - {type: fixed, set: a}\n",
                     "node_sets.a.nodes[1]", "out of range: the model has 125 nodes"},
        ResolveError{"shadows_model_set",
                     "effects: [elasticity]\nnode_sets:\n  x_min: {nodes: [1]}\n",
                     "node_sets.x_min", "already has a node set"},
        ResolveError{"unknown_muscle", "effects: [elasticity, muscles]\nmuscles: {extensor: 1}\n",
                     "muscles.extensor", "unknown muscle 'extensor' (the model has: flexor)"},
        ResolveError{"sliding_without_bindings", "effects: [elasticity, sliding]\n", "effects",
                     "no sliding nodes"},
        ResolveError{
            "probe_node_out_of_range",
            "effects: [elasticity]\nprobes:\n  - {name: a, type: displacement, node: 999}\n",
            "probes[0].node", "out of range"},
        ResolveError{"probe_unknown_set",
                     "effects: [elasticity]\nprobes:\n  - {name: a, type: reaction, set: lid}\n",
                     "probes[0].set", "unknown node set 'lid'"},
        ResolveError{"velocity_unknown_set",
                     "effects: [elasticity]\ninitial_velocity:\n  - {set: lid, value: [0, 0, 1]}\n",
                     "initial_velocity[0].set", "unknown node set 'lid'"},
        ResolveError{"surfaces_without_visual",
                     "effects: [elasticity]\noutput: {fields: [surfaces]}\n", "output.fields",
                     "no visual surface"}),
    [](const ::testing::TestParamInfo<ResolveError>& info) {
      return std::string(info.param.name);
    });

TEST(SceneResolve, MusclesWithoutAModelMuscleAreAnError) {
  const auto model = small_box(false);
  EXPECT_THROW(resolve_scene(scene_for("effects: [elasticity, muscles]\n"), model), ConfigError);
}

// Issue 34: a model's sliding bindings or muscles that the scene's effects leave out are named
// (ResolvedScene::left_out, which the run lists as warnings), not dropped without a word.
TEST(SceneResolve, WhatTheModelDefinesAndTheSceneLeavesOutIsNamed) {
  auto model = small_box(true);
  formats::Surface glide;
  glide.name = "glide";
  glide.role = formats::SurfaceRole::sliding;
  glide.vertices = {{-1, -1, -0.01}, {1, -1, -0.01}, {1, 1, -0.01}};
  glide.triangles = {{0, 1, 2}};
  model.surfaces.push_back(glide);
  const auto surface = static_cast<Index>(model.surfaces.size() - 1);
  for (Index n = 0; n < 3; ++n) model.sliding.push_back({n, surface, 0.01, 0});

  const auto bare = resolve_scene(scene_for("effects: [elasticity]\n"), model);
  ASSERT_EQ(bare.left_out.size(), 2u);
  EXPECT_NE(bare.left_out[0].find("binds 3 nodes to the sliding surface 'glide'"),
            std::string::npos)
      << bare.left_out[0];
  EXPECT_NE(bare.left_out[0].find("leave out 'sliding'"), std::string::npos);
  EXPECT_NE(bare.left_out[1].find("the model has 1 muscle, but"), std::string::npos)
      << bare.left_out[1];

  const auto full = resolve_scene(scene_for("effects: [elasticity, muscles, sliding]\n"), model);
  EXPECT_TRUE(full.left_out.empty());
  // A model with neither says nothing.
  EXPECT_TRUE(
      resolve_scene(scene_for("effects: [elasticity]\n"), small_box(false)).left_out.empty());
}

}  // namespace
}  // namespace sinew::simulator
