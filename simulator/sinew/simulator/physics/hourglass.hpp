#pragma once
// Stiffness-based hourglass control in the total Lagrangian frame (Joldes, Wittek, Miller 2008;
// Flanagan & Belytschko 1981; physics-notes §3).
//
// Hourglass base vectors over the 8 nodes (s_a = natural-coordinate signs, hex8.hpp):
//   Γ1(a) = ξa ηa,  Γ2(a) = ηa ζa,  Γ3(a) = ζa ξa,  Γ4(a) = ξa ηa ζa
// Shape vectors, orthogonal to every linear displacement field:
//   γα = Γα − Σ_k (Γα · X_k) ∇0N_k            (X_k: the 8 reference coordinates along k)
// For a cube (indeed any parallelepiped) Γα · X_k = 0, so γα = Γα and the 8×8 matrix
//   H = Σα γα γαᵀ
// is one constant integer matrix for every voxel element (paper §6.4).
// Hourglass force and energy, per displacement component i (u(b,i), m):
//   f_HG(a,i) = k Σα γα(a) q(α,i),  q(α,i) = Σ_b γα(b) u(b,i)        N
//   E_HG = ½ k Σ_{α,i} q(α,i)²                                        J
//   k = κHG · V0 · M* · Σ_a |∇0N_a|² / 8 = κHG · M* · 3h/16  for the cube (|∇0N_a|² = 3/(16h²))
// M* = 2μ (shear, default: no bending lock as ν -> 0.5) or λ + 2μ (p-wave, NiftySim).
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/hex8.hpp"

namespace sinew::simulator::physics {

// Γα(a) for α = 0..3, a = 0..7.
SINEW_HD_INLINE int hourglass_base(int alpha, int a) {
  const int x = hex8_sign(a, 0), y = hex8_sign(a, 1), z = hex8_sign(a, 2);
  switch (alpha) {
    case 0:
      return x * y;
    case 1:
      return y * z;
    case 2:
      return z * x;
    default:
      return x * y * z;
  }
}

// H(a, b) = Σα Γα(a) Γα(b): the constant 8×8 hourglass matrix of the cube (integer entries).
// f_HG(a, i) = k Σ_b H(a, b) u(b, i); add_hourglass_forces computes the same through the four
// projections q(α, i), which is cheaper than the matrix product.
SINEW_HD_INLINE int hourglass_matrix(int a, int b) {
  int h = 0;
  for (int alpha = 0; alpha < 4; ++alpha) h += hourglass_base(alpha, a) * hourglass_base(alpha, b);
  return h;
}

// γα for a general hexahedron from its reference node coordinates X (m) and gradients ∇0N (1/m):
// γα(a) = Γα(a) − Σ_k (Σ_b Γα(b) X_b,k) ∇0N_a,k. For the cube this returns Γα to round-off; the
// engine uses it once at setup to build H and tests check the cube identity.
template <typename T>
SINEW_HD_INLINE void hourglass_shape_vectors(const Vec3<T> (&x)[8], const Vec3<T> (&grad)[8],
                                             T (&gamma)[4][8]) {
  for (int alpha = 0; alpha < 4; ++alpha) {
    Vec3<T> gx{T(0), T(0), T(0)};
    for (int b = 0; b < 8; ++b) gx += T(hourglass_base(alpha, b)) * x[b];
    for (int a = 0; a < 8; ++a) gamma[alpha][a] = T(hourglass_base(alpha, a)) - dot(gx, grad[a]);
  }
}

// k = κHG · M* · 3h/16 for the cube of side h, N/m.
template <typename T>
SINEW_HD_INLINE T hourglass_stiffness(T kappa_hg, T modulus, T h) {
  return kappa_hg * modulus * T(3) * h / T(16);
}

// The four projections q(α, i) = Σ_b Γα(b) u(b, i) of the nodal displacements u (m), γα = Γα
// (exact for the cube).
template <typename T>
SINEW_HD_INLINE void hourglass_projections(const Vec3<T> (&u)[8], Vec3<T> (&q)[4]) {
  for (int alpha = 0; alpha < 4; ++alpha) {
    q[alpha] = Vec3<T>{T(0), T(0), T(0)};
    for (int b = 0; b < 8; ++b) {
      const T g = T(hourglass_base(alpha, b));
      q[alpha].x += g * u[b].x;
      q[alpha].y += g * u[b].y;
      q[alpha].z += g * u[b].z;
    }
  }
}

// Adds the hourglass forces k Σα Γα(a) q(α) of the projections q to f (N) and returns the
// hourglass energy ½ k Σ q² (J) when `energy` is true (0 otherwise); k from hourglass_stiffness.
template <typename T>
SINEW_HD_INLINE T add_hourglass_projection_forces(const Vec3<T> (&q)[4], T k, Vec3<T> (&f)[8],
                                                  bool energy) {
  T e = T(0);
  for (int alpha = 0; alpha < 4; ++alpha) {
    if (energy) e += T(0.5) * k * dot(q[alpha], q[alpha]);
    const Vec3<T> kq = k * q[alpha];
    for (int a = 0; a < 8; ++a) {
      const T g = T(hourglass_base(alpha, a));
      f[a].x += g * kq.x;
      f[a].y += g * kq.y;
      f[a].z += g * kq.z;
    }
  }
  return e;
}

// Both: adds the hourglass forces of the cube with displacements u to f and returns the energy
// (when `energy`). element_forces takes the two steps apart so that u is dead before the stress.
template <typename T>
SINEW_HD_INLINE T add_hourglass_forces(const Vec3<T> (&u)[8], T k, Vec3<T> (&f)[8], bool energy) {
  Vec3<T> q[4];
  hourglass_projections(u, q);
  return add_hourglass_projection_forces(q, k, f, energy);
}

}  // namespace sinew::simulator::physics
