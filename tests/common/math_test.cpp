// The fixed-size math of common/math.hpp against Eigen on random inputs, in float and double.
#include "sinew/common/math.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace {

using sinew::Mat3;
using sinew::SymMat3;
using sinew::Vec3;

template <typename T>
struct Random {
  std::mt19937 rng{12345};
  std::uniform_real_distribution<T> u{T(-1), T(1)};
  T scalar() { return u(rng); }
  Vec3<T> vec() { return {scalar(), scalar(), scalar()}; }
  // Diagonally dominant, so well conditioned for inverse tests.
  Mat3<T> mat(bool well_conditioned = false) {
    Mat3<T> m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m.m[i][j] = scalar() + (well_conditioned && i == j ? T(3) : T(0));
    return m;
  }
  SymMat3<T> sym(bool well_conditioned = false) {
    SymMat3<T> s;
    for (int i = 0; i < 6; ++i) s.s[i] = scalar() + (well_conditioned && i < 3 ? T(3) : T(0));
    return s;
  }
};

template <typename T>
Eigen::Matrix<T, 3, 3> eig(const Mat3<T>& m) {
  Eigen::Matrix<T, 3, 3> e;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e(i, j) = m.m[i][j];
  return e;
}
template <typename T>
Eigen::Matrix<T, 3, 3> eig(const SymMat3<T>& s) {
  Eigen::Matrix<T, 3, 3> e;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e(i, j) = s(i, j);
  return e;
}
template <typename T>
Eigen::Matrix<T, 3, 1> eig(const Vec3<T>& v) {
  return {v.x, v.y, v.z};
}

// Relative tolerance: float carries ~7 digits, double ~16; the formulas lose a few.
template <typename T>
T tol() {
  return std::is_same_v<T, float> ? T(2e-5) : T(1e-13);
}

template <typename T>
void expect_near(const Mat3<T>& a, const Eigen::Matrix<T, 3, 3>& b) {
  const T scale = std::max(T(1), b.cwiseAbs().maxCoeff());
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(a.m[i][j], b(i, j), tol<T>() * scale) << i << "," << j;
}
template <typename T>
void expect_near(const SymMat3<T>& a, const Eigen::Matrix<T, 3, 3>& b) {
  const T scale = std::max(T(1), b.cwiseAbs().maxCoeff());
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(a(i, j), b(i, j), tol<T>() * scale) << i << "," << j;
}
template <typename T>
void expect_near(const Vec3<T>& a, const Eigen::Matrix<T, 3, 1>& b) {
  const T scale = std::max(T(1), b.cwiseAbs().maxCoeff());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b(i), tol<T>() * scale) << i;
}

template <typename T>
class MathTest : public ::testing::Test {
 protected:
  Random<T> rnd;
  static constexpr int kTrials = 200;
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(MathTest, Scalars);

TYPED_TEST(MathTest, DeterminantMatchesEigen) {
  using T = TypeParam;
  for (int t = 0; t < this->kTrials; ++t) {
    const auto m = this->rnd.mat();
    EXPECT_NEAR(sinew::determinant(m), eig(m).determinant(), tol<T>() * 4);
  }
}

TYPED_TEST(MathTest, InverseMatchesEigen) {
  for (int t = 0; t < this->kTrials; ++t) {
    const auto m = this->rnd.mat(true);
    expect_near(sinew::inverse(m), Eigen::Matrix<TypeParam, 3, 3>(eig(m).inverse()));
  }
}

TYPED_TEST(MathTest, ProductsMatchEigen) {
  using E = Eigen::Matrix<TypeParam, 3, 3>;
  for (int t = 0; t < this->kTrials; ++t) {
    const auto a = this->rnd.mat(), b = this->rnd.mat();
    const auto v = this->rnd.vec(), w = this->rnd.vec();
    const auto s = this->rnd.sym();
    expect_near(a * b, E(eig(a) * eig(b)));
    expect_near(a * v, Eigen::Matrix<TypeParam, 3, 1>(eig(a) * eig(v)));
    expect_near(a * s, E(eig(a) * eig(s)));
    expect_near(a + b, E(eig(a) + eig(b)));
    expect_near(a - b, E(eig(a) - eig(b)));
    expect_near(sinew::transpose(a), E(eig(a).transpose()));
    expect_near(sinew::outer(v, w), E(eig(v) * eig(w).transpose()));
    expect_near(sinew::cross(v, w), Eigen::Matrix<TypeParam, 3, 1>(eig(v).cross(eig(w))));
    EXPECT_NEAR(sinew::dot(v, w), eig(v).dot(eig(w)), tol<TypeParam>() * 3);
    EXPECT_NEAR(sinew::norm(v), eig(v).norm(), tol<TypeParam>() * 3);
    EXPECT_NEAR(sinew::trace(a), eig(a).trace(), tol<TypeParam>() * 3);
    EXPECT_NEAR(sinew::double_dot(a, b), (eig(a).array() * eig(b).array()).sum(),
                tol<TypeParam>() * 9);
  }
}

TYPED_TEST(MathTest, TransposeProductIsRightCauchyGreen) {
  using E = Eigen::Matrix<TypeParam, 3, 3>;
  for (int t = 0; t < this->kTrials; ++t) {
    const auto f = this->rnd.mat();
    expect_near(sinew::transpose_product(f), E(eig(f).transpose() * eig(f)));
  }
}

TYPED_TEST(MathTest, SymmetricDeterminantAndInverseMatchEigen) {
  using T = TypeParam;
  using E = Eigen::Matrix<T, 3, 3>;
  for (int t = 0; t < this->kTrials; ++t) {
    const auto s = this->rnd.sym();
    EXPECT_NEAR(sinew::determinant(s), eig(s).determinant(), tol<T>() * 4);
    const auto w = this->rnd.sym(true);
    expect_near(sinew::inverse(w), E(eig(w).inverse()));
    expect_near(sinew::to_mat3(w), eig(w));
  }
}

TYPED_TEST(MathTest, QuadraticFormAndSymmetricHelpersMatchEigen) {
  using T = TypeParam;
  using E = Eigen::Matrix<T, 3, 3>;
  for (int t = 0; t < this->kTrials; ++t) {
    const auto s = this->rnd.sym(), r = this->rnd.sym();
    const auto a = this->rnd.vec();
    EXPECT_NEAR(sinew::quadratic_form(s, a), eig(a).dot(eig(s) * eig(a)), tol<T>() * 9);
    expect_near(sinew::sym_outer(a), E(eig(a) * eig(a).transpose()));
    const auto m = this->rnd.mat();
    expect_near(sinew::sym_part(m), E(T(0.5) * (eig(m) + eig(m).transpose())));
    EXPECT_NEAR(sinew::double_dot(s, r), (eig(s).array() * eig(r).array()).sum(), tol<T>() * 9);
    EXPECT_NEAR(sinew::trace(s), eig(s).trace(), tol<T>() * 3);
    expect_near(s + r, E(eig(s) + eig(r)));
    expect_near(s - r, E(eig(s) - eig(r)));
    expect_near(T(2.5) * s, E(T(2.5) * eig(s)));
  }
}

TEST(MathVoigt, IndexOrderIsXxYyZzYzXzXy) {
  using S = SymMat3<double>;
  EXPECT_EQ(S::voigt_index(0, 0), 0);
  EXPECT_EQ(S::voigt_index(1, 1), 1);
  EXPECT_EQ(S::voigt_index(2, 2), 2);
  EXPECT_EQ(S::voigt_index(1, 2), 3);
  EXPECT_EQ(S::voigt_index(2, 1), 3);
  EXPECT_EQ(S::voigt_index(0, 2), 4);
  EXPECT_EQ(S::voigt_index(2, 0), 4);
  EXPECT_EQ(S::voigt_index(0, 1), 5);
  EXPECT_EQ(S::voigt_index(1, 0), 5);
  const S id = sinew::sym_identity<double>();
  EXPECT_EQ(sinew::determinant(id), 1.0);
  const auto i3 = sinew::identity3<double>();
  EXPECT_EQ(sinew::determinant(i3), 1.0);
}

}  // namespace
