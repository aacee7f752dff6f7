// The execution plan: only requested effects allocate and compute, collections by what they
// compute, the time-step rule and its refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/plan.hpp"

namespace sinew::simulator::testing {
namespace {
using SimSetup = sinew::simulator::Setup;

formats::Model layered_muscle_block() {
  formats::BoxSpec spec;
  spec.dims = {4, 4, 4};
  spec.voxel_size = 1e-3;
  spec.materials = {neo_hookean(1000, 0.49, 1000, "soft"), neo_hookean(4000, 0.49, 1100, "firm")};
  spec.layer_boundaries = {1.5e-3};  // cuts the second row of elements: multi-material
  formats::BoxMuscleSpec m;
  m.element_min = {0, 0, 2};
  m.element_max = {4, 4, 4};
  spec.muscles = {m};
  spec.created = "2026-01-01T00:00:00Z";
  return formats::make_box_model(spec);
}

bool has_array(const Plan& p, const std::string& prefix) {
  for (const auto& a : p.arrays)
    if (a.name.rfind(prefix, 0) == 0) return true;
  return false;
}

TEST(Plan, EffectsThatAreOffAllocateNothing) {
  const auto model = layered_muscle_block();
  SimSetup s;
  const Plan off = make_plan(model, s);
  EXPECT_FALSE(has_array(off, "muscle"));
  EXPECT_FALSE(has_array(off, "sliding"));
  EXPECT_FALSE(has_array(off, "gravity"));
  for (const auto& c : off.collections) EXPECT_FALSE(c.muscle);
  EXPECT_NE(off.explain().find("muscles off: no muscle arrays"), std::string::npos);
  s.effects.muscles = true;
  s.effects.gravity = true;
  s.activation = {Curve::constant(1.0)};
  const Plan on = make_plan(model, s);
  EXPECT_TRUE(has_array(on, "muscle"));
  EXPECT_TRUE(has_array(on, "gravity"));
  EXPECT_GT(on.total_bytes(), off.total_bytes());
  EXPECT_EQ(on.muscle_entries, 32u);
}

TEST(Plan, CollectionsGroupElementsByWhatTheyCompute) {
  const auto model = layered_muscle_block();
  SimSetup s;
  s.effects.muscles = true;
  const Plan p = make_plan(model, s);
  std::map<std::string, std::size_t> count;
  std::size_t total = 0;
  for (const auto& c : p.collections) {
    count[c.name] = c.elements.size();
    total += c.elements.size();
  }
  EXPECT_EQ(total, 64u);
  EXPECT_EQ(count["single-material, no muscle"], 16u);    // row k = 0
  EXPECT_EQ(count["multi-material, no muscle"], 16u);     // row k = 1 (cut at 1.5 h)
  EXPECT_EQ(count["single-material, with muscle"], 32u);  // rows 2, 3
  // One shared row per material, one own row per multi-material element.
  EXPECT_EQ(p.parameters.size(), 2u + 16u);
  const auto& r = p.parameters[std::size_t(p.parameter_row[16])];
  EXPECT_NEAR(r.mu, 0.5 * 1000 + 0.5 * 4000, 1e-9);
  EXPECT_NEAR(r.density, 0.5 * 1000 + 0.5 * 1100, 1e-9);
}

TEST(Plan, TimeStepRuleAndRefusal) {
  const auto model = layered_muscle_block();
  SimSetup s;
  const Plan p = make_plan(model, s);
  // The stiffest element: firm, λ + 2μ = κ + 4μ/3, ρ = 1100.
  const double mu = 4000, kappa = 2 * mu * 1.49 / (3 * 0.02);
  const double crit = 1e-3 / std::sqrt((kappa + 4 * mu / 3) / 1100);
  EXPECT_NEAR(p.dt_critical, crit, 1e-12 * crit);
  EXPECT_NEAR(p.dt, 0.5 * crit, 1e-12 * crit);
  EXPECT_NE(p.explain().find("automatic"), std::string::npos);
  // Mass scaling by 4 doubles the step and is reported.
  s.mass_scaling = 4;
  const Plan scaled = make_plan(model, s);
  EXPECT_NEAR(scaled.dt_critical, 2 * crit, 1e-12 * crit);
  EXPECT_FALSE(scaled.warnings.empty());
  s.mass_scaling = 1;
  // A user Δt above the estimate is refused unless forced.
  s.time_step.policy = TimeStepPolicy::user;
  s.time_step.user_dt = 0.6 * crit;
  EXPECT_THROW(make_plan(model, s), ConfigError);
  s.time_step.policy = TimeStepPolicy::forced;
  const Plan forced = make_plan(model, s);
  EXPECT_EQ(forced.dt, 0.6 * crit);
  EXPECT_FALSE(forced.warnings.empty());
  // An automatic step above 0.8 h/c (one-point cubes are stable to ≈ 0.85 at ν = 0.49) is run
  // with a warning; 0.8 itself is quiet.
  s.time_step.policy = TimeStepPolicy::automatic;
  const auto courant_warnings = [&](double safety) {
    s.time_step.safety_factor = safety;
    int n = 0;
    for (const auto& w : make_plan(model, s).warnings)
      n += w.find("can go unstable") != std::string::npos;
    return n;
  };
  EXPECT_EQ(courant_warnings(0.8), 0);
  EXPECT_EQ(courant_warnings(0.9), 1);
  s.time_step.safety_factor = 0.5;
  // Muscles stiffen the estimate by σref (a_max · 3.6 + fp'(x*)).
  s.time_step.policy = TimeStepPolicy::automatic;
  s.effects.muscles = true;
  s.activation = {Curve::constant(1.0)};
  const Plan m = make_plan(model, s);
  EXPECT_LT(m.dt_critical, crit);
}

// A damaged model's muscle reference stress of 1e308 Pa makes h/c underflow to 0; that was
// reported as the scene's duration being "inf steps at Δt = 0 s" (scripts/fuzz_inputs.py).
TEST(Plan, AStepOfZeroNamesTheModelAndTheElement) {
  auto model = layered_muscle_block();
  model.muscles.front().reference_stress = 1e308;
  SimSetup s;
  s.effects.muscles = true;
  s.activation = {Curve::constant(1.0)};
  try {
    make_plan(model, s);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "model");
    EXPECT_NE(std::string(e.what()).find("the stable step h/c is 0 s at element 32 (wave modulus "
                                         "inf Pa"),
              std::string::npos)
        << e.what();
  }
}

// A muscle's passive p1 of 1e30 (a finite slope, a stable step of 2.4e-21 s) was reported as the
// scene's duration being 4e18 steps, "more than a run can count" (issue 33): waves faster than in
// any solid name the model, the element and where its stiffness comes from.
TEST(Plan, WavesFasterThanAnySolidNameTheModelAndTheMuscle) {
  auto model = layered_muscle_block();
  model.muscles.front().passive_p1 = 1e30;
  SimSetup s;
  s.effects.muscles = true;
  s.activation = {Curve::constant(1.0)};
  s.duration = 0.01;
  try {
    make_plan(model, s);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.field(), "model") << what;
    EXPECT_NE(what.find("Pa of its muscle fibres"), std::string::npos) << what;
    EXPECT_NE(what.find("faster than in any solid"), std::string::npos) << what;
    EXPECT_NE(what.find("passive curve (p1, p2)"), std::string::npos) << what;
    EXPECT_EQ(what.find("duration"), std::string::npos) << what;
  }
}

TEST(Plan, BadSetupsNameTheField) {
  const auto model = layered_muscle_block();
  SimSetup s;
  s.rigid_nodes = {0, 100000};
  try {
    make_plan(model, s);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "rigid_nodes");
    EXPECT_EQ(e.index().value_or(-1), 1);
  }
  s.rigid_nodes.clear();
  s.effects.muscles = true;
  s.activation = {Curve::constant(1.0), Curve::constant(1.0)};
  EXPECT_THROW(make_plan(model, s), ConfigError);
}

}  // namespace
}  // namespace sinew::simulator::testing
