#pragma once
// The steering of a live session since its last reset, step by step, and the scene that
// reproduces it (docs/live.md, "Record and reproduce"): slider moves become piecewise-linear
// activation curves, drags become force conditions on node sets, and sinew-simulate on
// that scene (same backend and precision) computes the same bits.
//
// Exactness. An override applied before step n is the activation of steps ≥ n, as a knot at
// t_n = n · Δt / time_scaling (the step's curve time, written with 17 significant digits so it
// reads back as the same double); a curve evaluated exactly at a knot returns the knot's value,
// and between two knots of one value the value itself. Where the scene's own curve resumes (or
// ends) inside one of its sloped segments, the steps of that segment's cut part get a knot each
// (their exact values), so no step sees a segment the original run did not. Drags are force sets
// at factor 1 during the drag and 0 otherwise; a set at factor 0 adds nothing
// (passes/constraint_program.hpp), like the live run's empty force slot.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/curve.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::live {

struct ActivationChange {
  std::int64_t step = 0;  // applied before this step
  std::size_t muscle = 0;
  std::optional<double> value;  // none: back to the curve
};

struct DragSpan {
  std::int64_t start = 0, end = -1;  // steps [start, end); end −1: still held
  std::vector<formats::Index> nodes;
  std::array<double, 3> total{};  // N, spread evenly: each node gets total · (1 / nodes), as a
                                  // scene's force condition without per_node spreads its value
};

struct SteeringLog {
  std::vector<ActivationChange> activations;
  std::vector<DragSpan> drags;
  std::vector<std::pair<std::int64_t, std::string>> events;  // (step, what) for the log file
  void clear() { *this = SteeringLog{}; }
};

// The knots (scene time, value) of muscle m's activation over steps 0 .. end_step when `changes`
// (this muscle's, in step order) override its scene curve `original`. dt: the run's Δt; s: its
// time scaling.
std::vector<std::array<double, 2>> reproduce_activation(
    const simulator::Curve& original, const std::vector<ActivationChange>& changes, double dt,
    double s, std::int64_t end_step);

// The scene (JSON, which the YAML scene reader reads) that reproduces the session up to end_step:
// the original scene's keys with `model` made absolute, `duration` = end_step · Δt / s, the live
// run's Δt as a fixed time step, the steered muscles' curves and the drags' node sets and force
// conditions added.
std::string reproduce_scene(const simulator::Scene& scene, const std::string& scene_text,
                            const std::vector<simulator::Curve>& activation_curves,
                            const std::vector<std::string>& muscle_names, double dt, double s,
                            std::int64_t end_step, const SteeringLog& log);

// The steering log as JSON (steps, scene times, what changed).
std::string steering_log_json(const SteeringLog& log, double dt, double s, std::int64_t end_step);

}  // namespace sinew::live
