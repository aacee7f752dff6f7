#pragma once
// Sliding constraints (paper §4, §6.2.2; physics-notes §5): node q keeps its rest distance d_q from
// a static surface while free to move tangentially. After the explicit update:
//   p = closest point of the surface to the node's position x
//   n = (x − p)/|x − p|, turned to the side of the triangle's outward normal when it points
//       inward (node pushed back out); the triangle's unit normal when |x − p| is ~0
//   x' = p + d_q n
// Sliding plane (symmetry condition): the displacement loses its component along the plane's unit
// normal, u' = u − (u · n) n (the node stays on the plane through its rest position).
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection §5.1.5).
template <typename T>
SINEW_HD_INLINE Vec3<T> closest_point_on_triangle(const Vec3<T>& p, const Vec3<T>& a,
                                                  const Vec3<T>& b, const Vec3<T>& c) {
  const Vec3<T> ab = b - a, ac = c - a, ap = p - a;
  const T d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= T(0) && d2 <= T(0)) return a;
  const Vec3<T> bp = p - b;
  const T d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= T(0) && d4 <= d3) return b;
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= T(0) && d1 >= T(0) && d3 <= T(0)) {
    const T v = d1 / (d1 - d3);
    return a + v * ab;
  }
  const Vec3<T> cp = p - c;
  const T d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= T(0) && d5 <= d6) return c;
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= T(0) && d2 >= T(0) && d6 <= T(0)) {
    const T w = d2 / (d2 - d6);
    return a + w * ac;
  }
  const T va = d3 * d6 - d5 * d4;
  if (va <= T(0) && (d4 - d3) >= T(0) && (d5 - d6) >= T(0)) {
    const T w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return b + w * (c - b);
  }
  const T denom = T(1) / (va + vb + vc);
  const T v = vb * denom, w = vc * denom;
  return a + v * ab + w * ac;
}

// Unit outward normal of a counter-clockwise triangle (a, b, c).
template <typename T>
SINEW_HD_INLINE Vec3<T> triangle_normal(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  const Vec3<T> n = cross(b - a, c - a);
  const T len = norm(n);
  return len > T(0) ? (T(1) / len) * n : Vec3<T>{T(0), T(0), T(1)};
}

// x' = p + d n (see top). p: closest point, normal: unit outward normal of p's triangle.
template <typename T>
SINEW_HD_INLINE Vec3<T> project_to_rest_distance(const Vec3<T>& x, const Vec3<T>& p,
                                                 const Vec3<T>& normal, T rest_distance) {
  Vec3<T> d = x - p;
  const T len = norm(d);
  const T tiny = T(1e-6) * (rest_distance > T(0) ? rest_distance : T(1));
  Vec3<T> n;
  if (len <= tiny) {
    n = normal;
  } else {
    n = (T(1) / len) * d;
    if (dot(n, normal) < T(0)) n = -n;  // behind the surface: back out to the outer side
  }
  return p + rest_distance * n;
}

// u' = u − (u · n) n for a unit n.
template <typename T>
SINEW_HD_INLINE Vec3<T> project_to_plane(const Vec3<T>& u, const Vec3<T>& unit_normal) {
  const T d =
      multiply_add(u.z, unit_normal.z, multiply_add(u.y, unit_normal.y, u.x * unit_normal.x));
  Vec3<T> v;
  for (int k = 0; k < 3; ++k) v[k] = multiply_add(-d, unit_normal[k], u[k]);
  return v;
}

}  // namespace sinew::simulator::physics
