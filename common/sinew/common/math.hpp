#pragma once
// Small fixed-size linear algebra usable in CUDA kernels and on the host.
//
// Vec3<T>: a 3-vector. Mat3<T>: a general 3x3 matrix, row-major, m[row][col]. SymMat3<T>: a
// symmetric 3x3 matrix stored as its 6 independent entries in Voigt order (xx, yy, zz, yz, xz, xy).
// T is float or double. Everything is header-only, constexpr-free plain arithmetic, and marked
// SINEW_HD so the CPU loop and the CUDA kernels share the same code.
#include <cmath>

#include "sinew/common/host_device.hpp"

namespace sinew {

template <typename T>
struct Vec3 {
  T x, y, z;
  SINEW_HD_INLINE T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  SINEW_HD_INLINE const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

template <typename T>
struct Mat3 {
  T m[3][3];
  SINEW_HD_INLINE T& operator()(int r, int c) { return m[r][c]; }
  SINEW_HD_INLINE const T& operator()(int r, int c) const { return m[r][c]; }
};

// Voigt order: s[0]=xx, s[1]=yy, s[2]=zz, s[3]=yz, s[4]=xz, s[5]=xy.
template <typename T>
struct SymMat3 {
  T s[6];
  SINEW_HD_INLINE T operator()(int r, int c) const { return s[voigt_index(r, c)]; }
  SINEW_HD_INLINE static int voigt_index(int r, int c) {
    if (r == c) return r;
    const int sum = r + c;  // (1,2)->3, (0,2)->2 -> 4, (0,1)->1 -> 5
    return sum == 3 ? 3 : (sum == 2 ? 4 : 5);
  }
};

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
using Mat3f = Mat3<float>;
using Mat3d = Mat3<double>;
using SymMat3f = SymMat3<float>;
using SymMat3d = SymMat3<double>;

// ---- Vec3 ----
template <typename T>
SINEW_HD_INLINE Vec3<T> operator+(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <typename T>
SINEW_HD_INLINE Vec3<T> operator-(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <typename T>
SINEW_HD_INLINE Vec3<T> operator-(const Vec3<T>& a) {
  return {-a.x, -a.y, -a.z};
}
template <typename T>
SINEW_HD_INLINE Vec3<T> operator*(T s, const Vec3<T>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <typename T>
SINEW_HD_INLINE Vec3<T> operator*(const Vec3<T>& a, T s) {
  return {s * a.x, s * a.y, s * a.z};
}
template <typename T>
SINEW_HD_INLINE Vec3<T>& operator+=(Vec3<T>& a, const Vec3<T>& b) {
  a.x += b.x;
  a.y += b.y;
  a.z += b.z;
  return a;
}
template <typename T>
SINEW_HD_INLINE Vec3<T>& operator-=(Vec3<T>& a, const Vec3<T>& b) {
  a.x -= b.x;
  a.y -= b.y;
  a.z -= b.z;
  return a;
}
// a · b + c. On the GPU one explicit FMA (one rounding) that the compiler cannot contract another
// way in another kernel, so the kernels sharing a law give the same bits (the tile and the node
// kernel: docs/cuda-backend.md, tiled = gather); on the host as written.
template <typename T>
SINEW_HD_INLINE T multiply_add(T a, T b, T c) {
#if defined(__CUDA_ARCH__)
  return fma(a, b, c);
#else
  return a * b + c;
#endif
}

template <typename T>
SINEW_HD_INLINE T dot(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
SINEW_HD_INLINE Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
SINEW_HD_INLINE T squared_norm(const Vec3<T>& a) {
  return dot(a, a);
}
template <typename T>
SINEW_HD_INLINE T norm(const Vec3<T>& a) {
  return std::sqrt(dot(a, a));
}

// ---- Mat3 ----
template <typename T>
SINEW_HD_INLINE Mat3<T> identity3() {
  return {{{T(1), T(0), T(0)}, {T(0), T(1), T(0)}, {T(0), T(0), T(1)}}};
}
template <typename T>
SINEW_HD_INLINE Mat3<T> zero3() {
  return {{{T(0), T(0), T(0)}, {T(0), T(0), T(0)}, {T(0), T(0), T(0)}}};
}
template <typename T>
SINEW_HD_INLINE Mat3<T> operator+(const Mat3<T>& a, const Mat3<T>& b) {
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] + b.m[i][j];
  return r;
}
template <typename T>
SINEW_HD_INLINE Mat3<T> operator-(const Mat3<T>& a, const Mat3<T>& b) {
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][j] - b.m[i][j];
  return r;
}
template <typename T>
SINEW_HD_INLINE Mat3<T> operator*(T s, const Mat3<T>& a) {
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = s * a.m[i][j];
  return r;
}
template <typename T>
SINEW_HD_INLINE Mat3<T> operator*(const Mat3<T>& a, const Mat3<T>& b) {
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  return r;
}
template <typename T>
SINEW_HD_INLINE Vec3<T> operator*(const Mat3<T>& a, const Vec3<T>& v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
          a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
template <typename T>
SINEW_HD_INLINE Mat3<T> transpose(const Mat3<T>& a) {
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}
template <typename T>
SINEW_HD_INLINE T trace(const Mat3<T>& a) {
  return a.m[0][0] + a.m[1][1] + a.m[2][2];
}
template <typename T>
SINEW_HD_INLINE T determinant(const Mat3<T>& a) {
  return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
         a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
         a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}
// Inverse through the adjugate; the caller guarantees det != 0.
template <typename T>
SINEW_HD_INLINE Mat3<T> inverse(const Mat3<T>& a) {
  const T inv_det = T(1) / determinant(a);
  Mat3<T> r;
  r.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) * inv_det;
  r.m[0][1] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) * inv_det;
  r.m[0][2] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) * inv_det;
  r.m[1][0] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) * inv_det;
  r.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) * inv_det;
  r.m[1][2] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) * inv_det;
  r.m[2][0] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) * inv_det;
  r.m[2][1] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) * inv_det;
  r.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) * inv_det;
  return r;
}
template <typename T>
SINEW_HD_INLINE Mat3<T> outer(const Vec3<T>& a, const Vec3<T>& b) {
  return {{{a.x * b.x, a.x * b.y, a.x * b.z},
           {a.y * b.x, a.y * b.y, a.y * b.z},
           {a.z * b.x, a.z * b.y, a.z * b.z}}};
}
// Frobenius inner product A : B.
template <typename T>
SINEW_HD_INLINE T double_dot(const Mat3<T>& a, const Mat3<T>& b) {
  T s = T(0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s += a.m[i][j] * b.m[i][j];
  return s;
}

// ---- SymMat3 ----
template <typename T>
SINEW_HD_INLINE SymMat3<T> sym_identity() {
  return {{T(1), T(1), T(1), T(0), T(0), T(0)}};
}
template <typename T>
SINEW_HD_INLINE SymMat3<T> sym_zero() {
  return {{T(0), T(0), T(0), T(0), T(0), T(0)}};
}
template <typename T>
SINEW_HD_INLINE SymMat3<T> operator+(const SymMat3<T>& a, const SymMat3<T>& b) {
  SymMat3<T> r;
  for (int i = 0; i < 6; ++i) r.s[i] = a.s[i] + b.s[i];
  return r;
}
template <typename T>
SINEW_HD_INLINE SymMat3<T> operator-(const SymMat3<T>& a, const SymMat3<T>& b) {
  SymMat3<T> r;
  for (int i = 0; i < 6; ++i) r.s[i] = a.s[i] - b.s[i];
  return r;
}
template <typename T>
SINEW_HD_INLINE SymMat3<T> operator*(T k, const SymMat3<T>& a) {
  SymMat3<T> r;
  for (int i = 0; i < 6; ++i) r.s[i] = k * a.s[i];
  return r;
}
template <typename T>
SINEW_HD_INLINE SymMat3<T>& operator+=(SymMat3<T>& a, const SymMat3<T>& b) {
  for (int i = 0; i < 6; ++i) a.s[i] += b.s[i];
  return a;
}
template <typename T>
SINEW_HD_INLINE T trace(const SymMat3<T>& a) {
  return a.s[0] + a.s[1] + a.s[2];
}
template <typename T>
SINEW_HD_INLINE T determinant(const SymMat3<T>& a) {
  const T xx = a.s[0], yy = a.s[1], zz = a.s[2], yz = a.s[3], xz = a.s[4], xy = a.s[5];
  return xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
}
// Inverse through the adjugate; the caller guarantees det != 0.
template <typename T>
SINEW_HD_INLINE SymMat3<T> inverse(const SymMat3<T>& a) {
  const T xx = a.s[0], yy = a.s[1], zz = a.s[2], yz = a.s[3], xz = a.s[4], xy = a.s[5];
  const T c_xx = yy * zz - yz * yz;
  const T c_xy = xz * yz - xy * zz;
  const T c_xz = xy * yz - yy * xz;
  const T inv_det = T(1) / (xx * c_xx + xy * c_xy + xz * c_xz);
  return {{c_xx * inv_det, (xx * zz - xz * xz) * inv_det, (xx * yy - xy * xy) * inv_det,
           (xy * xz - xx * yz) * inv_det, c_xz * inv_det, c_xy * inv_det}};
}
template <typename T>
SINEW_HD_INLINE Mat3<T> to_mat3(const SymMat3<T>& a) {
  return {{{a.s[0], a.s[5], a.s[4]}, {a.s[5], a.s[1], a.s[3]}, {a.s[4], a.s[3], a.s[2]}}};
}
// Symmetric part of a general matrix, (A + Aᵀ)/2.
template <typename T>
SINEW_HD_INLINE SymMat3<T> sym_part(const Mat3<T>& a) {
  return {{a.m[0][0], a.m[1][1], a.m[2][2], T(0.5) * (a.m[1][2] + a.m[2][1]),
           T(0.5) * (a.m[0][2] + a.m[2][0]), T(0.5) * (a.m[0][1] + a.m[1][0])}};
}
// C = Fᵀ F (right Cauchy–Green tensor).
template <typename T>
SINEW_HD_INLINE SymMat3<T> transpose_product(const Mat3<T>& f) {
  SymMat3<T> c;
  const int rows[6] = {0, 1, 2, 1, 0, 0};
  const int cols[6] = {0, 1, 2, 2, 2, 1};
  for (int k = 0; k < 6; ++k) {
    const int i = rows[k], j = cols[k];
    c.s[k] = f.m[0][i] * f.m[0][j] + f.m[1][i] * f.m[1][j] + f.m[2][i] * f.m[2][j];
  }
  return c;
}
// a · S a for a symmetric S.
template <typename T>
SINEW_HD_INLINE T quadratic_form(const SymMat3<T>& s, const Vec3<T>& a) {
  return s.s[0] * a.x * a.x + s.s[1] * a.y * a.y + s.s[2] * a.z * a.z +
         T(2) * (s.s[3] * a.y * a.z + s.s[4] * a.x * a.z + s.s[5] * a.x * a.y);
}
// a ⊗ a as a symmetric matrix.
template <typename T>
SINEW_HD_INLINE SymMat3<T> sym_outer(const Vec3<T>& a) {
  return {{a.x * a.x, a.y * a.y, a.z * a.z, a.y * a.z, a.x * a.z, a.x * a.y}};
}
// Product of a general matrix with a symmetric one, A S.
template <typename T>
SINEW_HD_INLINE Mat3<T> operator*(const Mat3<T>& a, const SymMat3<T>& s) {
  return a * to_mat3(s);
}
// Frobenius inner product of two symmetric matrices.
template <typename T>
SINEW_HD_INLINE T double_dot(const SymMat3<T>& a, const SymMat3<T>& b) {
  return a.s[0] * b.s[0] + a.s[1] * b.s[1] + a.s[2] * b.s[2] +
         T(2) * (a.s[3] * b.s[3] + a.s[4] * b.s[4] + a.s[5] * b.s[5]);
}

}  // namespace sinew
