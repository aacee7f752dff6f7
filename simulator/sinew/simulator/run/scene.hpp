#pragma once
// The simulator's scene file (YAML): what to simulate on which model, as the user wrote it.
// docs/scene-format.md documents every key with an example; this header mirrors it one to one.
//
// Two steps turn a file into the engine's input:
//  1. parse_scene / parse_scene_text read and check the YAML on its own (types, ranges, unknown
//     keys, curves monotone in t, effects consistent with the keys given) into a Scene.
//  2. resolve_scene checks the Scene against a Model (node sets and muscles exist, probes lie on
//     the model) and produces the engine's Setup with node ids (setup.hpp).
// Every error is a ConfigError naming the scene file and the key path, e.g.
//   "box.yaml: boundary_conditions[2].set: unknown node set 'topp' (scene sets: top, bottom; ...)",
// and, for what parse_scene finds, the line (the YAML is read by common's yaml_reader.hpp).
// SI units throughout: metres, seconds, newtons, pascals.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/simulator/engine/curve.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/output/probes.hpp"
#include "sinew/simulator/run/scene_curve.hpp"
#include "sinew/simulator/run/scene_jaw.hpp"

namespace sinew::simulator {

// The physical effects a scene can ask for. Only the listed ones are simulated; the engine
// allocates nothing for the others.
enum class Effect { elasticity, hourglass, damping, gravity, muscles, sliding, loads, contact };
inline constexpr std::array<Effect, 8> kAllEffects = {
    Effect::elasticity, Effect::hourglass, Effect::damping, Effect::gravity,
    Effect::muscles,    Effect::sliding,   Effect::loads,   Effect::contact};
const char* to_string(Effect effect);

struct SceneTimeStep {
  bool automatic = true;
  // Δt = safety_factor × the critical estimate (automatic), and the bound a fixed value must
  // respect unless forced. Default: the engine's (setup.hpp TimeStep).
  std::optional<double> safety_factor;
  double value = 0;    // s, fixed Δt when !automatic
  bool force = false;  // accept a fixed Δt above the bound
};

const char* hourglass_modulus_name(HourglassModulus modulus);  // "shear", "p_wave"
const char* precision_name(Precision precision);               // "float", "double"

struct SceneActivation {
  std::string muscle;  // the model's muscle name
  SceneCurve curve;    // activation a(t) ∈ [0, 1]
  std::string key;
};

// A named node set defined in the scene.
struct SceneNodeSet {
  enum class Kind { model, box, plane, nodes } kind = Kind::model;
  std::string name;
  std::string model_set;                    // Kind::model: the model's set of that name
  std::array<double, 3> min{}, max{};       // Kind::box: nodes whose rest position lies inside, m
  std::array<double, 3> point{}, normal{};  // Kind::plane: nodes within tolerance of the plane
  std::optional<double> tolerance;          // Kind::plane, m; default 1e-3 × voxel size
  std::vector<std::int64_t> ids;            // Kind::nodes: explicit node ids
  std::string key;
};

enum class Component : int { x = 0, y = 1, z = 2 };

struct SceneBoundary {
  // fixed: the listed components of every node of the set stay zero.
  // plane: the nodes slide on the plane through their rest position with the given normal.
  // displacement: the listed components follow value × curve(t).
  // force: value × curve(t) is applied, either in total spread evenly over the set's nodes or on
  //        every node.
  enum class Kind { fixed, plane, displacement, force } kind = Kind::fixed;
  std::string set;
  std::array<bool, 3> components{true, true, true};
  std::array<double, 3> normal{};   // plane
  std::array<double, 3> value{};    // displacement (m) or force (N)
  bool per_node = false;            // force: value is per node rather than the set's total
  std::optional<SceneCurve> curve;  // none: constant 1
  std::string key;
};

struct SceneInitialVelocity {
  std::string set;                // "all" or a node set
  std::array<double, 3> value{};  // m/s
  std::string key;
};

enum class OutputField { displacement, stress, jacobian, energy_density, surfaces };
const char* to_string(OutputField field);

struct SceneOutput {
  double interval = 0;  // s of simulated time between frames; 0: first and last only
  std::vector<OutputField> fields{OutputField::displacement};
  std::optional<double> probe_interval;  // s; default: every step
  bool has(OutputField f) const;
};

struct SceneProbe {
  using Kind = ProbeKind;  // output/probes.hpp
  Kind kind = Kind::displacement;
  std::string name;
  // displacement: either a node id or a point (nearest node of the model)
  std::optional<std::int64_t> node;
  std::optional<std::array<double, 3>> point;
  std::string set;  // reaction: the node set whose reaction force (sum) is recorded
  std::string key;
};

struct Scene {
  std::string file;        // the scene file as given (for messages); "" for text
  std::string directory;   // its folder, to resolve relative paths
  std::string model;       // path as written
  std::string model_path;  // resolved against the scene's folder
  std::string title;
  // `units:` m (default), cm or mm: metres per scene length unit. Every length read from the scene
  // (node-set boxes, planes and tolerances, prescribed displacements, probe points) and every
  // velocity and acceleration (initial velocities, gravity) is converted to SI on reading with it;
  // forces stay in N, times in s. The fields below are SI.
  double length_unit = 1;

  std::vector<Effect> effects;
  double duration = 0;  // s
  SceneTimeStep time_step;
  double damping = 0;       // α, 1/s (mass-proportional), with Effect::damping
  double mass_scaling = 1;  // ρ multiplier ≥ 1
  double time_scaling = 1;  // the simulated motion is slowed down by this factor ≥ 1
  Hourglass hourglass;      // κHG and M*, with Effect::hourglass
  Precision precision = Precision::float64;
  std::array<double, 3> gravity{0, 0, -9.81};  // m/s², with Effect::gravity
  std::vector<SceneActivation> activations;
  std::vector<SceneNodeSet> node_sets;
  std::vector<SceneBoundary> boundary;
  std::vector<SceneInitialVelocity> initial_velocity;
  SceneOutput output;
  std::vector<SceneProbe> probes;
  std::optional<SceneJaw> jaw;

  bool has(Effect e) const;
};

// What the run needs beyond the engine's Setup.
struct ResolvedScene {
  Setup setup;
  std::vector<ResolvedProbe> probes;
  // Output, in scene time (simulated time / time_scaling).
  double output_interval = 0;  // s; 0: first and last frame only
  double probe_interval = 0;   // s; 0: every step
  std::vector<OutputField> fields;
  std::vector<std::string> effects;  // effect names, in the scene's order
  // What the model defines and the scene's effects leave out, one sentence each (sliding bindings
  // without `sliding`, muscles without `muscles`): simulating only what the scene names is right,
  // doing it without a word is not. The run lists them as warnings (log, --explain,
  // run_summary.json).
  std::vector<std::string> left_out;
};

// Options given on the command line that override the scene.
struct ResolveOptions {
  std::optional<Precision> precision;
  int threads = 0;
};

// Checks the scene against the model and builds the engine's input. Node sets resolve by name:
// the built-in "all", then the scene's node_sets, then the model's node sets. Throws ConfigError
// naming the scene file and key (unknown node set or muscle, a set that selects no node, a node id
// out of range, ...).
ResolvedScene resolve_scene(const Scene& scene, const formats::Model& model,
                            const ResolveOptions& options = {});
// The node ids of a named set as resolve_scene sees it (sorted, unique). `key` names the place in
// the scene for the error message.
std::vector<Index> resolve_node_set(const Scene& scene, const formats::Model& model,
                                    const std::string& name, const std::string& key);

// Reads and checks a scene file. Throws ConfigError (file, key path, problem) or IoError.
Scene parse_scene(const std::string& path);
// The same from text; `file` names it in messages and `directory` resolves the model path.
Scene parse_scene_text(const std::string& text, const std::string& file,
                       const std::string& directory);

}  // namespace sinew::simulator
