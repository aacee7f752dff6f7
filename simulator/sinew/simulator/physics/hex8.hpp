#pragma once
// The voxel element: an 8-node hexahedron that is an undeformed cube of side h, integrated at its
// centre (one Gauss point). physics-notes §1; paper §6.4 (one set of derivatives for all elements).
//
// Node order (formats/model.hpp, VTK): a = 0..7 at (di, dj, dk) =
//   (0,0,0) (1,0,0) (1,1,0) (0,1,0) (0,0,1) (1,0,1) (1,1,1) (0,1,1),
// natural-coordinate signs s_a = (ξa, ηa, ζa) = 2·(di, dj, dk) − 1.
//   ∂N_a/∂X = s_a / (4h)                     (at the centre of the cube)
//   V0 = h³
//   F = I + Σ_a u_a ⊗ ∇0N_a                    (u_a: nodal displacement, m)
//   f_a = V0 · F · S · ∇0N_a                   (internal nodal force, N; S: 2nd Piola–Kirchhoff,
//   Pa)
// Every function is pure, SINEW_HD and templated on the scalar T (float or double).
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

// Sign s_a[k] ∈ {−1, +1} of node a (0..7) along axis k (0..2).
SINEW_HD_INLINE int hex8_sign(int a, int k) {
  // Branch-free: di = bit 0 of ((a & 3) + 1) >> 1 ... i.e. 0,1,1,0 over a & 3; dj = bit 1 of a;
  // dk = bit 2 of a. Constant-folds when the caller's loops are unrolled.
  const int d = (k == 0) ? ((((a & 3) + 1) >> 1) & 1) : ((k == 1) ? ((a >> 1) & 1) : (a >> 2));
  return 2 * d - 1;
}

// ∇0N_a of the cube of side h: s_a / (4h), 1/m.
template <typename T>
SINEW_HD_INLINE Vec3<T> hex8_gradient(int a, T h) {
  const T c = T(1) / (T(4) * h);
  return {c * T(hex8_sign(a, 0)), c * T(hex8_sign(a, 1)), c * T(hex8_sign(a, 2))};
}

// F = I + Σ_a u_a ⊗ ∇0N_a for the cube of side h. u: the 8 nodal displacements, m.
template <typename T>
SINEW_HD_INLINE Mat3<T> hex8_deformation_gradient(const Vec3<T> (&u)[8], T h) {
  // Σ_a u_a ⊗ s_a, then one scaling by 1/(4h).
  Mat3<T> g = zero3<T>();
  for (int a = 0; a < 8; ++a) {
    for (int k = 0; k < 3; ++k) {
      const T s = T(hex8_sign(a, k));
      g.m[0][k] += s * u[a].x;
      g.m[1][k] += s * u[a].y;
      g.m[2][k] += s * u[a].z;
    }
  }
  const T c = T(1) / (T(4) * h);
  Mat3<T> f;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) f.m[i][k] = (i == k ? T(1) : T(0)) + c * g.m[i][k];
  return f;
}

// f_a = V0 F S ∇0N_a = h³ (F S) s_a / (4h) = (h²/4) (F S) s_a, N. Writes the 8 forces to `out`.
template <typename T>
SINEW_HD_INLINE void hex8_nodal_forces(const Mat3<T>& f, const SymMat3<T>& s, T h,
                                       Vec3<T> (&out)[8]) {
  const Mat3<T> p = f * s;  // first Piola–Kirchhoff stress P = F S, Pa
  const T c = h * h / T(4);
  // P s_a for the 8 sign patterns: combine the columns of P.
  for (int a = 0; a < 8; ++a) {
    const T sx = T(hex8_sign(a, 0)), sy = T(hex8_sign(a, 1)), sz = T(hex8_sign(a, 2));
    out[a].x = c * (p.m[0][0] * sx + p.m[0][1] * sy + p.m[0][2] * sz);
    out[a].y = c * (p.m[1][0] * sx + p.m[1][1] * sy + p.m[1][2] * sz);
    out[a].z = c * (p.m[2][0] * sx + p.m[2][1] * sy + p.m[2][2] * sz);
  }
}

// Cauchy stress σ = J⁻¹ F S Fᵀ, Pa.
template <typename T>
SINEW_HD_INLINE SymMat3<T> cauchy_stress(const Mat3<T>& f, const SymMat3<T>& s, T j) {
  const Mat3<T> sigma = (T(1) / j) * (f * s * transpose(f));
  return sym_part(sigma);
}

// von Mises equivalent stress of a symmetric stress tensor, Pa.
template <typename T>
SINEW_HD_INLINE T von_mises(const SymMat3<T>& s) {
  const T a = s.s[0] - s.s[1], b = s.s[1] - s.s[2], c = s.s[2] - s.s[0];
  const T shear = s.s[3] * s.s[3] + s.s[4] * s.s[4] + s.s[5] * s.s[5];
  return std::sqrt(T(0.5) * (a * a + b * b + c * c) + T(3) * shear);
}

}  // namespace sinew::simulator::physics
