#pragma once
// The jaw: the mandible as a rigid body apart from the skull (docs/physics.md "Jaw"; its geometry
// is the model's /jaw, docs/model-format.md). A pose of the mandible is
//   opening θ (rad): rotation about the temporomandibular axis a (unit, the subject's left)
//                    through the pivot p (midway between the condyles); θ > 0 opens the mouth
//                    (the chin moves down and back, with up = forward × a);
//   protrusion (m) along forward f (unit, normal to a), lateral shift (m) along a,
// and carries a point at rest x to x' = R(θ)(x − p) + p + protrusion · f + lateral · a.
// Its nodes' displacement is u = x' − x = M (x − p) + d with M = R − I and d the translation:
// Rodrigues, R = I + sin θ K + (1 − cos θ) K², K = [a]× (so M = sin θ K + (1 − cos θ) K²).
// The host evaluates the pose's 15 numbers (jaw_displacement_map, double); both engines apply them
// with jaw_displacement, whose products and sums are rounded one by one (no fused multiply-add on
// the GPU), so a jaw node's position is the same bits on the CPU and the GPU.
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

struct JawPose {
  double opening = 0;     // rad, about +axis
  double protrusion = 0;  // m, along forward
  double lateral = 0;     // m, along axis (the subject's left)
};

// The map's layout: M row-major (0–8), the pivot p (9–11), the translation d (12–14).
inline constexpr int kJawMapSize = 15;

// The 15 numbers of `pose` for a jaw of this pivot (m), unit axis and unit forward.
inline void jaw_displacement_map(const double (&pivot)[3], const double (&axis)[3],
                                 const double (&forward)[3], const JawPose& pose,
                                 double (&map)[kJawMapSize]) {
  const double s = std::sin(pose.opening), c1 = 1.0 - std::cos(pose.opening);
  const double k[3][3] = {{0, -axis[2], axis[1]}, {axis[2], 0, -axis[0]}, {-axis[1], axis[0], 0}};
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) {
      double k2 = 0;  // (K²)_{r,col} = a_r a_col − δ_{r,col}
      for (int q = 0; q < 3; ++q) k2 += k[r][q] * k[q][col];
      map[3 * r + col] = s * k[r][col] + c1 * k2;
    }
    map[9 + r] = pivot[r];
    map[12 + r] = pose.protrusion * forward[r] + pose.lateral * axis[r];
  }
}

// a · b and a + b each rounded on its own: the GPU contracts a · b + c into one fused
// multiply-add unless told not to, the CPU build does not.
template <typename T>
SINEW_HD_INLINE T rounded_product(T a, T b) {
#if defined(__CUDA_ARCH__)
  if constexpr (std::is_same_v<T, float>)
    return __fmul_rn(a, b);
  else
    return __dmul_rn(a, b);
#else
  return a * b;
#endif
}
template <typename T>
SINEW_HD_INLINE T rounded_sum(T a, T b) {
#if defined(__CUDA_ARCH__)
  if constexpr (std::is_same_v<T, float>)
    return __fadd_rn(a, b);
  else
    return __dadd_rn(a, b);
#else
  return a + b;
#endif
}

// u = M (x − p) + d of a jaw node resting at x (m), from a map in the run's scalar.
template <typename T>
SINEW_HD_INLINE Vec3<T> jaw_displacement(const T* map, const Vec3<T>& x) {
  const T r[3] = {x[0] - map[9], x[1] - map[10], x[2] - map[11]};
  Vec3<T> u;
  for (int row = 0; row < 3; ++row) {
    T sum = rounded_product(map[3 * row], r[0]);
    sum = rounded_sum(sum, rounded_product(map[3 * row + 1], r[1]));
    sum = rounded_sum(sum, rounded_product(map[3 * row + 2], r[2]));
    u[row] = rounded_sum(sum, map[12 + row]);
  }
  return u;
}

}  // namespace sinew::simulator::physics
