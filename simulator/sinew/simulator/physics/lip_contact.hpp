#pragma once
// Contact between the lips (docs/physics.md "Lip contact"; the pairs are the model's
// /jaw/lip_pairs, docs/model-format.md). The jaw's cut leaves the upper and the lower lip one voxel
// apart at rest; across each pair (upper node i_u, lower node i_l, straight across the cut) the
// contact keeps
//     g = (x_u − x_l) · n ≥ 0,    x = X + u (rest position plus displacement, m),
// n the unit up of the face (forward × axis of the jaw), so the cut may close but the lips cannot
// pass through each other. Each node reads and writes only its own u(n+1), as every op of the
// constraint program does, so the partner's u(n+1) is predicted: ũ_j = B u_j(n) + Cc u_j(n−1),
// where it coasts with no force (central_difference.hpp coasting). A node closing the gap moves
// back along n by its share s of the overlap:
//     g' = (X_i − X_j + u_i(n+1) − ũ_j) · σ n,    u_i(n+1) ← u_i(n+1) − s g' σ n  if g' < 0,
// σ = +1 for the upper node, −1 for the lower. s = ½ when both nodes are free: two nodes of equal
// mass closing at any speed stop where they meet, momentum kept (a perfectly inelastic impact, to
// the partner's acceleration in one step). s = 1 when the partner is held. Pressed together, the
// pair yields by what the contact force moves a node in one step, Δt² F / m (the force is never
// formed: kinematic contact as in explicit codes, Taylor & Flanagan 1989, PRONTO-3D; LS-DYNA's
// constraint method), with no penalty parameter and no change of the stable Δt.
// The overlap's products and sums are rounded one by one (physics/jaw.hpp): the contact's own
// arithmetic is the same on the CPU and the GPU; the prediction's multiply-adds are the update's.
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/jaw.hpp"

namespace sinew::simulator::physics {

// Node i's u(n+1) v after the contact with its partner j: rest_offset = X_i − X_j (m), uj = ũ_j,
// the partner's predicted u(n+1) (m), normal = σ n (unit, pointing from the partner to node i),
// share = s.
template <typename T>
SINEW_HD_INLINE Vec3<T> lip_contact(const Vec3<T>& v, const Vec3<T>& rest_offset, const Vec3<T>& uj,
                                    const Vec3<T>& normal, T share) {
  T gap = T(0);
  for (int k = 0; k < 3; ++k)
    gap = rounded_sum(gap, rounded_product(rounded_sum(rest_offset[k], v[k] - uj[k]), normal[k]));
  if (!(gap < T(0))) return v;
  const T push = rounded_product(share, gap);
  Vec3<T> out;
  for (int k = 0; k < 3; ++k) out[k] = v[k] - rounded_product(push, normal[k]);
  return out;
}

}  // namespace sinew::simulator::physics
