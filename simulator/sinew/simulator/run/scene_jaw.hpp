#pragma once
// The scene's `jaw:` (docs/scene-format.md "jaw"): the mandible's motion as curves, read and
// checked against the ranges of healthy adults, then resolved against the model's /jaw into the
// engine's JawMotion (setup.hpp; physics/jaw.hpp gives the motion).
//
//   jaw:
//     opening_deg: {ramp: 0.08, peak: 12}    # degrees about the temporomandibular axis
//     protrusion_mm: [[0, 0], [0.2, 2]]      # mm along the face's forward direction
//     lateral_mm: 0                          # mm towards the subject's left (negative: right)
//
// Lengths are mm and angles degrees whatever the scene's `units:` (the clinical units of these
// ranges). A model without a /jaw and a scene with `jaw:` is an error; a model with a jaw and a
// scene without `jaw:` holds the jaw closed (its nodes join the rigid nodes).
#include <optional>
#include <string>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/run/scene_curve.hpp"

namespace sinew {
class YamlNode;
}

namespace sinew::simulator {

// The jaw's motion (scene key `jaw:`, docs/scene-format.md; the model's /jaw): curves of the
// opening (degrees about the temporomandibular axis), the protrusion and the lateral shift (mm,
// whatever `units:` says), each checked against the range of healthy adults (scene_jaw.hpp).
// A key left out is 0 throughout.
struct SceneJaw {
  std::optional<SceneCurve> opening_deg, protrusion_mm, lateral_mm;
  std::string key;
};

// The ranges a scene may ask for (every point of each curve), from measurements of adults:
//  - opening 0 to 40°: maximal opening rotates the mandible 32–39° (Muto & Kanazawa 1996, issue
//    28's PMC3428458); at 0 the teeth meet, so no closing below it;
//  - protrusion −1 to 12 mm: maximal protrusion 8.8 ± 2.3 mm (500 adults, Swiss Dent J, "Maximum
//    mandibular mobility in patients with temporomandibular disorders", Basel), retrusion about
//    1 mm behind the teeth's meeting (Posselt's envelope of motion, 1952);
//  - lateral shift −15 to 15 mm: 9.4 ± 2.5 mm to the right, 11.8 ± 3.1 mm to the left (the same
//    500 adults).
inline constexpr double kJawOpeningMinDegrees = 0, kJawOpeningMaxDegrees = 40;
inline constexpr double kJawProtrusionMinMm = -1, kJawProtrusionMaxMm = 12;
inline constexpr double kJawLateralMaxMm = 15;

// Reads `jaw:`; throws ConfigError naming the key and line for unknown keys, bad curves and a
// point out of range (its index and value).
SceneJaw parse_scene_jaw(const YamlNode& n);

// Sets setup.jaw from the scene's `jaw:` (none: the scene has no `jaw:`) and the model's /jaw (degrees to radians, mm to m), or,
// without `jaw:`, adds the model's jaw nodes to setup.rigid_nodes (the jaw closed). Throws
// ConfigError naming the scene file and `jaw` when the scene moves a jaw the model lacks, or
// when the scene's own conditions fix, prescribe or slide nodes of the jaw. Call it after the
// boundary conditions are resolved.
// scene_file names the scene in messages.
void resolve_scene_jaw(const std::optional<SceneJaw>& jaw, const std::string& scene_file,
                       const formats::Model& model, Setup& setup);

// The distance (m) between the incisal point carried by the jaw at curve time t and where it
// rests: the incisal opening then (0 with the jaw closed).
double incisal_opening(const JawMotion& jaw, double t);
// The largest incisal opening of setup.jaw over steps 0 … steps of dt (simulated s; at most 4096
// evenly spaced samples and every curve point), m; 0 without a jaw.
double max_incisal_opening(const Setup& setup, double dt, std::int64_t steps);

// The model's lips' pairs (its /jaw/lip_pairs) with the face's up (the jaw's forward × axis); none
// when the model has no jaw or its jaw no pairs.
std::optional<LipContact> lip_contact_of(const formats::Model& model);

// The smallest gap across the lips' pairs, (x_upper − x_lower) · up with x = rest + u (m; u: N × 3
// displacements, m): negative where a lip has passed through the other (with `contact` no more
// than the partner's lag of one step, physics/lip_contact.hpp).
double smallest_lip_gap(const LipContact& contact, const formats::Model& model,
                        const std::vector<double>& u);

}  // namespace sinew::simulator
