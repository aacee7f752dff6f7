// The error measures of the accuracy study (bench/accuracy_study_measures.hpp) on sequences and
// fields whose answers are known in closed form.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "../../bench/accuracy_study_measures.hpp"

namespace sinew::accuracy {
namespace {

TEST(AccuracyMeasures, RichardsonRecoversLimitAndOrderForConstantRatio) {
  // f(h) = 3 + 2 h²: exact for any three meshes.
  auto f = [](double h) { return 3 + 2 * h * h; };
  const auto e = richardson(0.4, f(0.4), 0.2, f(0.2), 0.1, f(0.1));
  ASSERT_TRUE(e.ok);
  EXPECT_NEAR(e.order, 2.0, 1e-9);
  EXPECT_NEAR(e.value, 3.0, 1e-12);
}

TEST(AccuracyMeasures, RichardsonHandlesNonConstantRatiosAndFractionalOrders) {
  // f(h) = −1 + 0.7 h^1.5 on h = 2/3, 1/2, 1/3 (the study's n = 3, 4, 6 meshes), decreasing f.
  auto f = [](double h) { return -1 + 0.7 * std::pow(h, 1.5); };
  const double h1 = 2.0 / 3, h2 = 0.5, h3 = 1.0 / 3;
  const auto e = richardson(h1, f(h1), h2, f(h2), h3, f(h3));
  ASSERT_TRUE(e.ok);
  EXPECT_NEAR(e.order, 1.5, 1e-9);
  EXPECT_NEAR(e.value, -1.0, 1e-12);
}

TEST(AccuracyMeasures, RichardsonRefusesAnOscillatingSequence) {
  const auto e = richardson(0.4, 1.1, 0.2, 0.95, 0.1, 1.02);
  EXPECT_FALSE(e.ok);
  EXPECT_EQ(e.value, 1.02);  // the finest value
  EXPECT_TRUE(std::isnan(e.order));
}

TEST(AccuracyMeasures, ObservedOrderIsTheLogLogSlope) {
  std::vector<double> h = {1, 0.5, 0.25, 0.125}, e;
  for (double x : h) e.push_back(0.3 * x * x);
  EXPECT_NEAR(observed_order(h, e), 2.0, 1e-12);
  e = {0.1, 0.05, 0.0, 0.0125};  // a zero error is left out
  EXPECT_NEAR(observed_order(h, e), 1.0, 1e-12);
  EXPECT_TRUE(std::isnan(observed_order({1}, {1})));
}

TEST(AccuracyMeasures, BilinearSampleIsExactForBilinearFieldsAndNodal) {
  FaceField f;
  f.nx = 4;
  f.ny = 3;
  f.x0 = 0.1;
  f.y0 = -0.2;
  f.h = 0.5;
  auto field = [](double x, double y) {
    return std::array<double, 3>{1 + 2 * x - y + 0.5 * x * y, x, -3 * y};
  };
  for (int j = 0; j <= f.ny; ++j)
    for (int i = 0; i <= f.nx; ++i) f.values.push_back(field(f.x0 + i * f.h, f.y0 + j * f.h));
  for (double x : {0.1, 0.37, 1.2, 2.1})
    for (double y : {-0.2, 0.05, 0.9, 1.3}) {
      const auto s = sample(f, x, y), r = field(x, y);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(s[std::size_t(k)], r[std::size_t(k)], 1e-12);
    }
  // Outside the face: clamped to the edge.
  const auto c = sample(f, 5.0, -1.0), r = field(2.1, -0.2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[std::size_t(k)], r[std::size_t(k)], 1e-12);
}

TEST(AccuracyMeasures, FieldErrorIsNormalisedByTheLargestReferenceMagnitude) {
  const std::vector<std::array<double, 3>> ref = {{3, 4, 0}, {0, 0, 1}};
  const std::vector<std::array<double, 3>> u = {{3, 4, 0.5}, {0, 0, 1}};
  const auto e = field_error(u, ref);
  EXPECT_DOUBLE_EQ(e.ref_max, 5.0);
  EXPECT_DOUBLE_EQ(e.max_rel, 0.1);
  EXPECT_NEAR(e.rms_rel, std::sqrt(0.25 / 2) / 5, 1e-15);
  EXPECT_TRUE(std::isnan(field_error(u, {{0, 0, 0}, {0, 0, 0}}).max_rel));
  EXPECT_TRUE(std::isnan(field_error(u, {{1, 0, 0}}).max_rel));
}

}  // namespace
}  // namespace sinew::accuracy
