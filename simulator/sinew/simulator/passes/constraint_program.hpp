#pragma once
// The loads and constraints of a step as one program per constrained node, written once for both
// engines: the host builds it (backend_core.cpp, make_constraint_program) in the one order of loads
// and constraints, and the CPU's constraint pass (engine/cpu_engine.cpp) and the CUDA node, tile
// and constraint kernels run it with run_program.
#include <cstdint>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/passes/sliding_lists.hpp"
#include "sinew/simulator/physics/element.hpp"
#include "sinew/simulator/physics/jaw.hpp"
#include "sinew/simulator/physics/lip_contact.hpp"

namespace sinew::simulator {

// The loads and constraints of a step as one program per constrained node: op = kind << 28 | arg,
// a node's ops in the CPU's order (nodal forces by set, capture of u*, sliding, planes in list
// order, lip contact, prescribed sets in order, jaw, rigid). Each op writes only its node (the
// lips' contact reads its partner's u(n) and u(n−1), which no op writes), so one thread per node
// running its ops in that order gives the CPU's result with no race (a node in two sets, or on two
// planes, included).
enum ConstraintOp : std::int32_t {
  kOpForce = 0,      // arg: force set
  kOpCapture = 1,    // arg: prescribed entry q (u* = u)
  kOpSlide = 2,      // arg: sliding entry
  kOpPlane = 3,      // arg: plane entry (its unit normal)
  kOpPrescribe = 4,  // arg: prescribed entry q
  kOpRigid = 5,
  kOpJaw = 6,  // arg: its capture entry q (as a prescribed entry's); the jaw's map in the factors
  kOpContact = 7,  // arg: contact entry (its partner across the lips' cut and its share)
};
constexpr std::int32_t kOpShift = 28, kOpArg = (1 << kOpShift) - 1;
// Whether the op is a prescribed motion whose reaction is (u − u*)/A, u* captured before the
// node's constraints (add_program_work).
SINEW_HD_INLINE bool op_prescribes(std::int32_t code) {
  const std::int32_t kind = code >> kOpShift;
  return kind == kOpPrescribe || kind == kOpJaw;
}

template <typename T>
struct ConstraintData {
  const std::int32_t* node;    // C constrained nodes
  const std::int32_t* offset;  // C + 1
  const std::int32_t* op;
  std::int32_t count;
  const T* inverse_mass;
  physics::CentralDifference<T> cd;
  const Vec3<T>* force_per_node;        // per force set
  const std::int32_t* prescribed_set;   // per prescribed entry (−1: a jaw node's)
  const Vec3<T>* prescribed_value;      // per prescribed set
  const std::int32_t* prescribed_mask;  // per prescribed set: bit c = component c prescribed
  Vec3<T>* prescribed_free;             // per prescribed entry: u* before constraints
  const Vec3<T>* plane_normal;          // per plane entry
  SlideData<T> slide;
  const Vec3<T>* rest;
  const Vec3<T>* gravity;  // per node; null without gravity
  std::int32_t force_sets;
  // Where the jaw's map (physics/jaw.hpp, kJawMapSize numbers) starts in the factors; −1: no jaw.
  std::int32_t jaw_factor = -1;
  // Lip contact (physics/lip_contact.hpp), per contact entry: the partner node and σ s (σ = +1
  // for the upper node, −1 for the lower; s its share); the face's unit up.
  const std::int32_t* contact_partner = nullptr;
  const T* contact_share = nullptr;
  Vec3<T> contact_up{T(0), T(0), T(0)};
  // u(n) and u(n−1) of every node, read by the contact ops (the engines set them at each step: the
  // state's buffers rotate); null in a program without contact.
  const Vec3<T>* u_now = nullptr;
  const Vec3<T>* u_prev = nullptr;
};

// Runs ops [begin, end) of node i on v (its u(n+1) after the update) and returns the result;
// `projected` (zero on entry) gets the sum of the sliding and plane projections' moves, for
// add_program_work. factor: [force factors at t_n | prescribed factors at t_n+1 | the jaw's map at
// t_n+1]. With `loads` off
// (the initial constraints at t = 0) nodal forces and captures are skipped.
// kSlide: 0 the model has no sliding (the op is compiled out); 1 sliding with the list refresh
// (and grid search) inline; 2 sliding with lists refreshed ahead by slide_refresh_kernel.
// `start`: slide_start of sliding entry `started` when loaded ahead (−1: none).
template <typename T, int kSlide>
SINEW_HD_INLINE Vec3<T> run_ops(const ConstraintData<T>& d, std::int32_t i, std::int32_t begin,
                                std::int32_t end, const T* factor, bool loads, Vec3<T> v,
                                Vec3<T>& projected, const SlideStart<T>& start = {},
                                std::int32_t started = -1) {
  for (std::int32_t q = begin; q < end; ++q) {
    const std::int32_t code = d.op[q], arg = code & kOpArg;
    const Vec3<T> before = v;
    switch (code >> kOpShift) {
      case kOpForce:
        // A force at factor 0 is skipped rather than added as ±0: a set that is off leaves the
        // node's bits as if the set were absent (a live run's empty force slot and the reproduced
        // scene's inactive drag sets, docs/live.md).
        if (loads && factor[arg] != T(0))
          physics::add_nodal_force(d.cd, d.inverse_mass[i], factor[arg] * d.force_per_node[arg], v);
        break;
      case kOpCapture:
        if (loads) d.prescribed_free[arg] = v;
        break;
      case kOpSlide:
        if constexpr (kSlide != 0) {
          SlideStart<T> st = start;
          if (arg != started) st = slide_start(d.slide, arg, false);
          v = slide_entry<T, kSlide == 1>(d.slide, arg, st, d.rest[i], v);
          projected = projected + (v - before);
        }
        break;
      case kOpPlane:
        v = physics::project_to_plane(v, d.plane_normal[arg]);
        projected = projected + (v - before);
        break;
      case kOpContact: {
        if (!loads) break;  // the initial constraints: the lips at rest, apart
        const std::int32_t j = d.contact_partner[arg];
        const T share = d.contact_share[arg];
        const Vec3<T> normal = share < T(0) ? -d.contact_up : d.contact_up;
        v = physics::lip_contact(v, d.rest[i] - d.rest[j],
                                 physics::coasting(d.cd, d.u_now[j], d.u_prev[j]), normal,
                                 share < T(0) ? -share : share);
        projected = projected + (v - before);
        break;
      }
      case kOpPrescribe: {
        const std::int32_t set = d.prescribed_set[arg], mask = d.prescribed_mask[set];
        const bool comps[3] = {(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0};
        physics::prescribe(factor[d.force_sets + set], d.prescribed_value[set], comps, v);
        break;
      }
      case kOpJaw:
        v = physics::jaw_displacement(factor + d.jaw_factor, d.rest[i]);
        break;
      default:
        v = Vec3<T>{T(0), T(0), T(0)};
    }
  }
  return v;
}

// Adds to w the work over the step of node i's nodal forces and constraint forces (ops [begin,
// end), begin < end), Σ R · (u(n+1) − u(n−1))/2, term by term: v = u(n+1) after run_ops, vp =
// u(n−1), `projected` and d.prescribed_free as run_ops left them. A constraint moves the node
// from where the forces put it; its force is that move over A = Δt²/m (central differences):
// R = (u − u*)/A for a prescribed set (u* captured before the node's constraints, so this also
// counts the projections of a node that is prescribed too), and for a node with no prescribed set
// R = Σ (v after − v before)/A over its sliding, plane and contact projections (zero work on a
// fixed surface in exact arithmetic; nonzero when the projection stops a node thrown at the
// surface, or works on round-off noise in float: docs/physics.md, "Instability"). Rigid nodes do
// not move: no work. Separate from run_ops so that an engine can add the terms where the node is
// not run (the partitioned engine adds every node's terms on every rank in the one-device chunk
// order).
template <typename T>
SINEW_HD_INLINE void add_program_work(const ConstraintData<T>& d, std::int32_t i,
                                      std::int32_t begin, std::int32_t end, const T* factor,
                                      const Vec3<T>& v, const Vec3<T>& vp, const Vec3<T>& projected,
                                      double& w) {
  const double a = double(d.cd.a_over_inverse_mass) * double(d.inverse_mass[i]);
  bool prescribed = false;
  for (std::int32_t q = begin; q < end; ++q) {
    const std::int32_t code = d.op[q], arg = code & kOpArg, kind = code >> kOpShift;
    if (kind == kOpForce) {
      if (factor[arg] == T(0)) continue;
      const double f = double(factor[arg]);
      for (int k = 0; k < 3; ++k)
        w += f * double(d.force_per_node[arg][k]) * 0.5 * (double(v[k]) - double(vp[k]));
    } else if (op_prescribes(code)) {
      prescribed = true;
      for (int k = 0; k < 3; ++k) {
        const double fc = (double(v[k]) - double(d.prescribed_free[arg][k])) / a;
        w += fc * 0.5 * (double(v[k]) - double(vp[k]));
      }
    }
  }
  if (!prescribed) {
    for (int k = 0; k < 3; ++k)
      w += double(projected[k]) / a * 0.5 * (double(v[k]) - double(vp[k]));
  }
}

// run_ops on node i, then, with `work`, add_program_work into w (u(n−1) from up).
template <typename T, int kSlide>
SINEW_HD_INLINE Vec3<T> run_program(const ConstraintData<T>& d, std::int32_t i, std::int32_t begin,
                                    std::int32_t end, const T* factor, bool loads, Vec3<T> v,
                                    const Vec3<T>* up, bool work, double& w,
                                    const SlideStart<T>& start = {}, std::int32_t started = -1) {
  Vec3<T> projected{T(0), T(0), T(0)};  // the moves of the sliding and plane projections
  v = run_ops<T, kSlide>(d, i, begin, end, factor, loads, v, projected, start, started);
  if (work && begin < end) add_program_work(d, i, begin, end, factor, v, up[i], projected, w);
  return v;
}

}  // namespace sinew::simulator
