// CUDA backend: kernels are thin entry points (index -> physics/element.hpp call); the host class
// mirrors CpuEngine's step, checks and state. Design and measurements: docs/cuda-backend.md.
#include <cuda_pipeline.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include <cstdio>

#include "sinew/common/error.hpp"
#include "sinew/simulator/cuda_backend.hpp"
#include "sinew/simulator/lattice_tiles.hpp"
#include "sinew/simulator/physics/element.hpp"
#include "sinew/simulator/prepared_model.hpp"

#define SINEW_CUDA_CHECK(call)                                                                    \
  do {                                                                                            \
    const cudaError_t sinew_cuda_status_ = (call);                                                \
    if (sinew_cuda_status_ != cudaSuccess)                                                        \
      throw ::sinew::Error(std::string(__FILE__) + ":" + std::to_string(__LINE__), #call,         \
                           std::string("CUDA error: ") + cudaGetErrorString(sinew_cuda_status_)); \
  } while (0)
#define SINEW_CUDA_LAUNCHED() SINEW_CUDA_CHECK(cudaGetLastError())

namespace sinew::simulator {
namespace {

constexpr int kBlock = 256;

// Sum of `value` over the kBlock threads of a block: a tree reduction in the shared array `s`
// (kBlock doubles) in a fixed order, so the sum is the same bits every run. Valid in every thread
// after the call; `tid` is the caller's threadIdx.x (only kernel entry points read it).
__device__ __forceinline__ double block_sum(double value, double* s, int tid) {
  s[tid] = value;
  __syncthreads();
  for (int stride = kBlock / 2; stride > 0; stride /= 2) {
    if (tid < stride) s[tid] += s[tid + stride];
    __syncthreads();
  }
  const double sum = s[0];
  __syncthreads();  // `s` may be reused at once
  return sum;
}

// Whether this block is the last of its grid to get here (CUDA's threadFenceReduction pattern):
// every block's thread 0 wrote its partial before the call; the last block may then read all
// partials (with __ldcg: past the L1) and sum them in index order (deterministic). The counter is
// back at 0 afterwards.
__device__ __forceinline__ bool last_block(unsigned* counter, int tid, unsigned blocks) {
  __shared__ bool last;
  __threadfence();
  if (tid == 0) {
    const unsigned done = atomicAdd(counter, 1u);
    last = done == blocks - 1;
    if (last) *counter = 0;
  }
  __syncthreads();
  return last;
}

// Σ partial[0 .. count) in the fixed order of blowup/work totals (strided per thread, then
// block_sum); for the last block only.
__device__ __forceinline__ double sum_partials(const double* partial, int count, double* s,
                                               int tid) {
  double w = 0;
  for (int k = tid; k < count; k += kBlock) w += __ldcg(partial + k);
  return block_sum(w, s, tid);
}

// printf-style formatting for messages (fmt's compile-time format strings do not pass nvcc).
template <typename... A>
std::string format(const char* f, A... a) {
  const int n = std::snprintf(nullptr, 0, f, a...);
  std::string s(std::size_t(n > 0 ? n : 0), '\0');
  std::snprintf(s.data(), s.size() + 1, f, a...);
  return s;
}
// kernel<<<grid, block, shared, s>>>(args...), as a programmatic dependent launch when
// `programmatic` (the kernel waits with wait_for_previous_kernel(): see there).
template <typename... P, typename... A>
void launch_kernel(void (*kernel)(P...), unsigned grid, unsigned block, std::size_t shared,
                   cudaStream_t s, bool programmatic, A... args) {
  cudaLaunchAttribute attribute[1] = {};
  attribute[0].id = cudaLaunchAttributeProgrammaticStreamSerialization;
  attribute[0].val.programmaticStreamSerializationAllowed = 1;
  cudaLaunchConfig_t config = {};
  config.gridDim = dim3(grid);
  config.blockDim = dim3(block);
  config.dynamicSmemBytes = shared;
  config.stream = s;
  config.attrs = attribute;
  config.numAttrs = programmatic ? 1 : 0;
  SINEW_CUDA_CHECK(cudaLaunchKernelEx(&config, kernel, P(args)...));
}
inline unsigned blocks_for(std::size_t n) {
  return unsigned((n + kBlock - 1) / kBlock);
}

// Programmatic dependent launch (Hopper, sm_90; docs/cuda-backend.md, "Launches"). The step's
// kernels in a graph are launched with programmatic stream serialisation: a kernel's blocks may
// start while the kernel before it in the stream still runs. Each such kernel first loads only
// what no kernel of the step writes (tables, static data, and what the kernel two launches back
// wrote: see below), then calls wait_for_previous_kernel(), which returns once the kernel before
// it has completed with its writes visible, and only then reads its inputs and writes anything.
// It calls let_next_kernel_start() right after the wait, so the next kernel's blocks can take the
// SM room this grid leaves (and run their own loads) as soon as all of this grid's blocks are
// past their wait: a kernel two launches back has therefore always completed when a kernel's
// first loads run. Both are no-ops for a kernel launched plainly (or below sm_90).
__device__ __forceinline__ void wait_for_previous_kernel() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}
__device__ __forceinline__ void let_next_kernel_start() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
#endif
}

// ---------------------------------------------------------------------------------------------
// Device memory

template <typename V>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& o) noexcept : p_(o.p_), n_(o.n_) {
    o.p_ = nullptr;
    o.n_ = 0;
  }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  ~DeviceArray() {
    if (p_) cudaFree(p_);
  }
  void allocate(std::size_t n) {
    if (p_) SINEW_CUDA_CHECK(cudaFree(p_));
    p_ = nullptr;
    n_ = n;
    if (n) SINEW_CUDA_CHECK(cudaMalloc(&p_, n * sizeof(V)));
  }
  // Setup-time transfers on the legacy stream, completed before returning (the engine's work runs
  // on a non-blocking stream that does not order itself after the legacy stream).
  void upload(const std::vector<V>& v) {
    allocate(v.size());
    if (n_) SINEW_CUDA_CHECK(cudaMemcpy(p_, v.data(), n_ * sizeof(V), cudaMemcpyHostToDevice));
    SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  }
  void zero() {
    if (n_) SINEW_CUDA_CHECK(cudaMemset(p_, 0, n_ * sizeof(V)));
    SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  }
  std::vector<V> download() const {
    SINEW_CUDA_CHECK(cudaDeviceSynchronize());
    std::vector<V> v(n_);
    if (n_) SINEW_CUDA_CHECK(cudaMemcpy(v.data(), p_, n_ * sizeof(V), cudaMemcpyDeviceToHost));
    return v;
  }
  V* get() const { return p_; }
  std::size_t size() const { return n_; }
  std::size_t bytes() const { return n_ * sizeof(V); }

 private:
  V* p_ = nullptr;
  std::size_t n_ = 0;
};

template <typename V>
class PinnedArray {
 public:
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() {
    if (p_) cudaFreeHost(p_);
  }
  void allocate(std::size_t n) {
    if (p_) SINEW_CUDA_CHECK(cudaFreeHost(p_));
    p_ = nullptr;
    n_ = n;
    if (n) SINEW_CUDA_CHECK(cudaMallocHost(&p_, n * sizeof(V)));
  }
  V* get() const { return p_; }
  std::size_t size() const { return n_; }

 private:
  V* p_ = nullptr;
  std::size_t n_ = 0;
};

struct Status {
  int bad_jacobian;      // some element had J ≤ 0 or NaN
  int bad_displacement;  // some node got a NaN/Inf displacement
  int blowup;            // kinetic energy above the blow-up bound at a checked step
  int slide_miss;        // a sliding node left its (ahead-refreshed) list: replay the batch
};

// The blow-up bound without the external work (which the device accumulates): factor × (base +
// |W|).
struct BlowupBound {
  double base;  // J, max(0, initial energy) + active-muscle bound + round-off floor
  double factor;
};

// ---------------------------------------------------------------------------------------------
// Kernels. One thread per element / node / constraint entry.

template <typename T>
struct ElementData {
  const std::array<Index, 8>* nodes;  // E × 8
  const std::int32_t* row;            // E
  const physics::ElementRow<T>* rows;
  const std::int32_t* muscle_offset;  // E + 1
  const std::int32_t* muscle_id;
  const T* muscle_fraction;
  const Vec3<T>* muscle_fibre;
  const physics::MuscleParams<T>* muscle_params;
  T h;
  std::int32_t elements;  // E
};

// kMode: 0 gather (E × 8 buffer), 1 atomic (into nodal forces), 2 gather + per-element energies.
template <typename T, bool kElastic, bool kMuscle, bool kHourglass, int kMode>
__global__ void __launch_bounds__(kBlock)
    element_kernel(ElementData<T> d, const std::int32_t* __restrict__ list, std::int32_t count,
                   const Vec3<T>* __restrict__ u, const T* __restrict__ activation,
                   Vec3<T>* __restrict__ out, double* __restrict__ energy, Status* status) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  const std::int32_t e = list[i];
  const int4* np = reinterpret_cast<const int4*>(d.nodes + e);
  const int4 n0 = __ldg(np), n1 = __ldg(np + 1);
  const int ids[8] = {n0.x, n0.y, n0.z, n0.w, n1.x, n1.y, n1.z, n1.w};
  const physics::ElementRow<T> row = d.rows[d.row[e]];
  physics::MuscleEntries<T> m{
      d.muscle_id, d.muscle_fraction, d.muscle_fibre, d.muscle_params, activation, 0, 0};
  if constexpr (kMuscle) {
    m.begin = d.muscle_offset[e];
    m.end = d.muscle_offset[e + 1];
  }
  wait_for_previous_kernel();
  let_next_kernel_start();
  Vec3<T> ue[8];
#pragma unroll
  for (int a = 0; a < 8; ++a) ue[a] = u[ids[a]];
  Vec3<T> fe[8];
  const auto r =
      physics::element_forces<T, kElastic, kMuscle, kHourglass, kMode == 2>(ue, d.h, row, m, fe);
  if (!(r.j > T(0))) status->bad_jacobian = 1;
  if constexpr (kMode == 1) {
#pragma unroll
    for (int a = 0; a < 8; ++a) {
      atomicAdd(&out[ids[a]].x, fe[a].x);
      atomicAdd(&out[ids[a]].y, fe[a].y);
      atomicAdd(&out[ids[a]].z, fe[a].z);
    }
  } else {
    // Corner-major (a · E + e): consecutive elements write consecutive entries, and the nodes of a
    // lattice row read consecutive entries back in the gather.
#pragma unroll
    for (int a = 0; a < 8; ++a)
      out[std::size_t(a) * std::size_t(d.elements) + std::size_t(e)] = fe[a];
  }
  if constexpr (kMode == 2) {
    energy[2 * std::size_t(e)] = r.strain;
    energy[2 * std::size_t(e) + 1] = r.hourglass;
  }
}

// Internal forces only (no update): gather into f.
template <typename T>
__global__ void gather_kernel(std::int32_t n, const Vec3<T>* __restrict__ element_force,
                              const std::int32_t* __restrict__ offset,
                              const std::int32_t* __restrict__ inc, Vec3<T>* __restrict__ f) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= n) return;
  f[i] = physics::gather_node_force(element_force, inc, offset[i], offset[i + 1]);
}

template <typename T>
struct NodeData {
  const T* inverse_mass;
  const Vec3<T>* gravity;
  const std::int32_t* offset;  // N + 1 incidence offsets (gather)
  const std::int32_t* inc;
  physics::CentralDifference<T> cd;
  std::int32_t n;
};

// External work and the blow-up test. The work is accumulated per node in double (each node adds
// its own terms, in step order: no reduction per step); it is summed, in a fixed order, only where
// it is read: at blow-up test steps (node kernel, below) and at sync points (host).
struct StepSums {
  double* work_acc;         // N per-node accumulated work (J), or null: no work in this model
  const double* work_base;  // work carried in by restore() (J)
  double* work_partial;     // per node-kernel block: Σ work_acc (test steps)
  double* kinetic_partial;  // per node-kernel block: ½ M |v|² (test steps)
  unsigned* counter;        // last-block detection of the node kernel
  const BlowupBound* bound;
  double inv_dt;
};

// Sliding: per surface its query view, per-triangle corners and skin (sliding_grid.hpp).
template <typename T>
struct SlideSurface {
  SurfaceView<T> view;
  const Vec3<T>* corners;  // triangle_corner_list: 3 per triangle
  T skin;                  // s of the candidate lists (m)
};

// List capacity per sliding node (overflow: full search each step). The face-scale skull lists
// 3.6 triangles per node on average (at most 10) with the default skin, 12.5 (at most 22) with 0.25.
constexpr int kCandidates = 32;

// Per sliding node k: node id, surface, rest distance, closest triangle of the last step (the warm
// start of the tie rule, as the CPU's), the warm start of the grid searches (written by list
// refreshes only, so a refresh running beside a step never touches what the step reads), and its
// candidate list: count (−1: none, search fully), anchor x_s, ids at list[j · count + k] and their
// distances from x_s at list_distance[j · count + k] (sorted: list_surface_candidates).
template <typename T>
struct SlideData {
  const std::int32_t* node;
  const std::int32_t* surface;
  const T* distance;
  std::int32_t* triangle;
  std::int32_t* search_triangle;
  std::int32_t* list_count;
  Vec3<T>* anchor;
  std::int32_t* list;
  T* list_distance;
  const SlideSurface<T>* surfaces;
  std::int32_t count;
  Status* status;
};

// Sliding node k at position x: while x is within s (1 − 1e-3) of the anchor of its list, the
// list holds its closest triangle (sliding_grid.hpp) and nothing is done; otherwise one grid walk
// (list_surface_candidates, warm-started from search_triangle[k], where it leaves the closest
// triangle) re-lists the triangles within d1 + 2 s and moves the anchor to x (list count −1 when
// more than kCandidates: the node then searches fully). `reach` (≤ 1): the fraction of s within
// which the anchor is kept (½ when refreshing ahead of the step, from u(n), so that u(n+1) still
// lies within s of the anchor).
template <typename T>
__device__ __forceinline__ void refresh_slide_list(const SlideData<T>& d, std::int32_t k,
                                                   const Vec3<T>& x, T reach) {
  const SlideSurface<T>& sf = d.surfaces[d.surface[k]];
  const T move = sf.skin * T(0.999) * reach;
  if (d.list_count[k] > 0 && squared_norm(x - d.anchor[k]) <= move * move) return;
  std::int32_t t = d.search_triangle[k];
  d.list_count[k] = list_surface_candidates<kCandidates>(sf.view, x, sf.skin, t, d.list + k,
                                                         d.list_distance + k, d.count);
  d.search_triangle[k] = t;
  d.anchor[k] = x;
}

// Sliding node k at displacement u: the closest triangle among its listed ones and its warm start
// (closest_listed_point; the one the search found, when its list overflowed), then x' = p + d n
// (physics::project_to_rest_distance), as physics::slide_node does. Returns the new
// displacement. kRefresh: refresh_slide_list at x first (the grid search inline when needed).
// Otherwise slide_refresh_kernel refreshed the list from u(n), ahead of the step: if x is not
// within s of its anchor (or the list overflowed) the list may not hold the closest triangle, so
// the node raises status->slide_miss and the host replays the batch with kRefresh (the result
// computed here is then discarded).
//
// SlideStart: what slide_entry reads of entry k that the step's kernels before it do not write
// (the closest triangle of the last step was written by the previous step's constraints), so a
// programmatic launch loads it before its wait: the surface, rest distance and warm start (its id,
// corners and normal); with `lists` (no list refresh in this step: lists_ready) also the list's
// count, anchor and first entries.
template <typename T>
struct SlideStart {
  const SlideSurface<T>* surface;
  T distance;
  std::int32_t triangle;
  Vec3<T> warm[3];
  Vec3<T> normal;
  bool lists;
  std::int32_t listed;
  Vec3<T> anchor;
  ListedGroup<T> first;
};

template <typename T>
__device__ __forceinline__ SlideStart<T> slide_start(const SlideData<T>& d, std::int32_t k,
                                                     bool lists_ready) {
  SlideStart<T> s;
  s.surface = d.surfaces + d.surface[k];
  s.distance = d.distance[k];
  const std::int32_t t = d.triangle[k];
  s.triangle = t;
  for (int c = 0; c < 3; ++c) s.warm[c] = s.surface->corners[3 * t + c];
  s.normal = s.surface->view.normals[t];
  s.lists = lists_ready;
  if (lists_ready) {
    s.listed = d.list_count[k];
    s.anchor = d.anchor[k];
    s.first = load_listed_group(d.list + k, d.list_distance + k, d.count, s.listed, 0);
  }
  return s;
}

template <typename T, bool kRefresh>
__device__ __forceinline__ Vec3<T> slide_entry(const SlideData<T>& d, std::int32_t k,
                                               const SlideStart<T>& start, const Vec3<T>& rest,
                                               const Vec3<T>& u) {
  const Vec3<T> x = rest + u;
  const SlideSurface<T>& sf = *start.surface;
  if constexpr (kRefresh) refresh_slide_list(d, k, x, T(1));  // start.lists is false here
  const std::int32_t listed = start.lists ? start.listed : d.list_count[k];
  const Vec3<T> anchor = start.lists ? start.anchor : d.anchor[k];
  if constexpr (!kRefresh) {
    const T move = sf.skin * T(0.999);
    if (!(listed > 0 && squared_norm(x - anchor) <= move * move)) d.status->slide_miss = 1;
  }
  std::int32_t t = start.triangle;
  Vec3<T> p;
  if (listed > 0) {
    const T moved = std::sqrt(squared_norm(x - anchor));
    const ListedGroup<T> first =
        start.lists ? start.first
                    : load_listed_group(d.list + k, d.list_distance + k, d.count, listed, 0);
    p = closest_listed_point(sf.corners, start.warm, d.list + k, d.list_distance + k, d.count,
                             listed, first, x, moved, sf.skin * T(0.0625), t);
  } else if constexpr (kRefresh) {  // overflow: the grid search, warm-started as the CPU's
    p = closest_surface_search<T, true>(sf.view, x, t);
  } else {  // overflow without a search: a miss (raised above), replayed; any finite point
    p = physics::closest_point_on_triangle(x, start.warm[0], start.warm[1], start.warm[2]);
  }
  d.triangle[k] = t;
  const Vec3<T> normal = t == start.triangle ? start.normal : sf.view.normals[t];
  return physics::project_to_rest_distance(x, p, normal, start.distance) - rest;
}

// The loads and constraints of a step as one program per constrained node: op = kind << 28 | arg,
// a node's ops in the CPU's order (nodal forces by set, capture of u*, sliding, planes in list
// order, prescribed sets in order, rigid). Each op reads and writes only its node, so one thread
// per node running its ops in that order gives the CPU's result with no race (a node in two sets,
// or on two planes, included).
enum ConstraintOp : std::int32_t {
  kOpForce = 0,      // arg: force set
  kOpCapture = 1,    // arg: prescribed entry q (u* = u)
  kOpSlide = 2,      // arg: sliding entry
  kOpPlane = 3,      // arg: plane entry (its unit normal)
  kOpPrescribe = 4,  // arg: prescribed entry q
  kOpRigid = 5,
};
constexpr std::int32_t kOpShift = 28, kOpArg = (1 << kOpShift) - 1;

template <typename T>
struct ConstraintData {
  const std::int32_t* node;    // C constrained nodes
  const std::int32_t* offset;  // C + 1
  const std::int32_t* op;
  std::int32_t count;
  const T* inverse_mass;
  physics::CentralDifference<T> cd;
  const Vec3<T>* force_per_node;        // per force set
  const std::int32_t* prescribed_set;   // per prescribed entry
  const Vec3<T>* prescribed_value;      // per prescribed set
  const std::int32_t* prescribed_mask;  // per prescribed set: bit c = component c prescribed
  Vec3<T>* prescribed_free;             // per prescribed entry: u* before constraints
  const Vec3<T>* plane_normal;          // per plane entry
  SlideData<T> slide;
  const Vec3<T>* rest;
  const Vec3<T>* gravity;  // per node; null without gravity
  std::int32_t force_sets;
};

// Runs ops [begin, end) of node i on v (its u(n+1) after the update) and, with `work`, adds the
// work of its nodal forces and prescribed constraint forces, Σ R · (u(n+1) − u(n−1))/2 with the
// constraint force (u − u*)/A, to w. factor: [force factors at t_n | prescribed factors at t_n+1].
// With `loads` off (the initial constraints at t = 0) nodal forces and captures are skipped.
// kSlide: 0 the model has no sliding (the op is compiled out); 1 sliding with the list refresh
// (and grid search) inline; 2 sliding with lists refreshed ahead by slide_refresh_kernel.
// `start`: slide_start of sliding entry `started` when loaded ahead (−1: none).
template <typename T, int kSlide>
__device__ __forceinline__ Vec3<T> run_program(const ConstraintData<T>& d, std::int32_t i,
                                               std::int32_t begin, std::int32_t end,
                                               const T* factor, bool loads, Vec3<T> v,
                                               const Vec3<T>* up, bool work, double& w,
                                               const SlideStart<T>& start = {},
                                               std::int32_t started = -1) {
  for (std::int32_t q = begin; q < end; ++q) {
    const std::int32_t code = d.op[q], arg = code & kOpArg;
    switch (code >> kOpShift) {
      case kOpForce:
        if (loads)
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
        }
        break;
      case kOpPlane:
        v = physics::project_to_plane(v, d.plane_normal[arg]);
        break;
      case kOpPrescribe: {
        const std::int32_t set = d.prescribed_set[arg], mask = d.prescribed_mask[set];
        const bool comps[3] = {(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0};
        physics::prescribe(factor[d.force_sets + set], d.prescribed_value[set], comps, v);
        break;
      }
      default:
        v = Vec3<T>{T(0), T(0), T(0)};
    }
  }
  if (work && begin < end) {
    const Vec3<T> vp = up[i];
    for (std::int32_t q = begin; q < end; ++q) {
      const std::int32_t code = d.op[q], arg = code & kOpArg, kind = code >> kOpShift;
      if (kind == kOpForce) {
        const double f = double(factor[arg]);
        for (int k = 0; k < 3; ++k)
          w += f * double(d.force_per_node[arg][k]) * 0.5 * (double(v[k]) - double(vp[k]));
      } else if (kind == kOpPrescribe) {
        const double a = double(d.cd.a_over_inverse_mass) * double(d.inverse_mass[i]);
        for (int k = 0; k < 3; ++k) {
          const double fc = (double(v[k]) - double(d.prescribed_free[arg][k])) / a;
          w += fc * 0.5 * (double(v[k]) - double(vp[k]));
        }
      }
    }
  }
  return v;
}

// Models with sliding: after the node kernel, one thread per constrained node runs its program
// and adds to the node's accumulated work the program's work and the change its constraints make
// to the gravity term (the node kernel added g · (u(n+1) − u(n−1))/2 before constraints).
// lists_ready: no list refresh was forked for this step (the lists may be read before the wait).
template <typename T, int kSlide>
__global__ void __launch_bounds__(kBlock, kSlide == 2 ? 4 : 1)
    constraint_kernel(ConstraintData<T> d, const T* factor, bool loads, Vec3<T>* un,
                      const Vec3<T>* up, StepSums sums, bool lists_ready) {
  const std::int32_t c = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (c >= d.count) return;
  const std::int32_t i = d.node[c], begin = d.offset[c], end = d.offset[c + 1];
  // A sliding node's warm start is loaded before the wait (its first op is the slide when it has
  // no nodal force or captured prescription).
  SlideStart<T> start{};
  std::int32_t started = -1;
  if constexpr (kSlide != 0) {
    const std::int32_t code = d.op[begin];
    if ((code >> kOpShift) == kOpSlide) {
      started = code & kOpArg;
      start = slide_start(d.slide, started, kSlide == 2 && lists_ready);
    }
  }
  wait_for_previous_kernel();
  let_next_kernel_start();
  const Vec3<T> before = un[i];
  double w = 0;
  const bool work = loads && sums.work_acc;
  const Vec3<T> v =
      run_program<T, kSlide>(d, i, begin, end, factor, loads, before, up, work, w, start, started);
  un[i] = v;
  if (work) {
    if (d.gravity)
      for (int k = 0; k < 3; ++k)
        w += double(d.gravity[i][k]) * 0.5 * (double(v[k]) - double(before[k]));
    sums.work_acc[i] += w;
  }
}

// Ahead of a step, concurrently with its element and node kernels (a parallel branch of the
// graph): one thread per sliding entry k refreshes its list at its position of u(n), keeping the
// anchor while within s/2 of it, so the grid walks leave the step's critical path and
// constraint_kernel<T, 2> carries no search code. A node that then moves more than s/2 in the step
// raises slide_miss there (exactness is kept by a replay).
template <typename T>
__global__ void __launch_bounds__(kBlock)
    slide_refresh_kernel(SlideData<T> d, const Vec3<T>* __restrict__ rest, const Vec3<T>* u) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= d.count) return;
  const std::int32_t i = d.node[k];
  refresh_slide_list(d, k, rest[i] + u[i], T(0.5));
}

// A node's step in two parts. move_node: the central-difference update of node i from its internal
// force f (ui, upi: its u(n), u(n−1); im: its inverse mass, loaded by the caller) and the finite
// check; with energy_test it adds its kinetic energy at u(n) to ke. Returns u(n+1) before its loads
// and constraints.
template <typename T, bool kGravity>
__device__ __forceinline__ Vec3<T> move_node(const NodeData<T>& d, std::int32_t i, const Vec3<T>& f,
                                             const Vec3<T>& ui, const Vec3<T>& upi, T im,
                                             Status* status, const StepSums& sums, bool energy_test,
                                             double& ke) {
  Vec3<T> g{T(0), T(0), T(0)};
  if constexpr (kGravity) g = d.gravity[i];
  const Vec3<T> v = physics::node_update<T, kGravity>(d.cd, im, f, g, ui, upi);
  if (!(isfinite(v.x) && isfinite(v.y) && isfinite(v.z))) status->bad_displacement = 1;
  if (energy_test) {
    const double vx = (double(ui.x) - double(upi.x)) * sums.inv_dt;
    const double vy = (double(ui.y) - double(upi.y)) * sums.inv_dt;
    const double vz = (double(ui.z) - double(upi.z)) * sums.inv_dt;
    ke += 0.5 / double(im) * (vx * vx + vy * vy + vz * vz);
  }
  return v;
}

// finish_node: (kProgram) node i's loads and constraints, its ops [begin, end) of program.op, on
// its u(n+1) v; writes u(n+1) to un, and adds the node's work of this step to its accumulator
// (gravity; kProgram: its loads and constraint forces; without kProgram gravity before constraints,
// the constraint kernel adds the rest). With energy_test it adds to w_old the node's work up to
// step n − 1 (the accumulator before this step). kSlide: as run_program.
template <typename T, bool kGravity, bool kProgram, int kSlide>
__device__ __forceinline__ void finish_node(const NodeData<T>& d, std::int32_t i, Vec3<T> v,
                                            const Vec3<T>& upi, const Vec3<T>* __restrict__ up,
                                            Vec3<T>* __restrict__ un, const StepSums& sums,
                                            const ConstraintData<T>& program, std::int32_t begin,
                                            std::int32_t end, const T* factor, bool energy_test,
                                            double& w_old) {
  double w = 0;
  bool has_work = kGravity;
  if constexpr (kProgram) {
    v = run_program<T, kSlide>(program, i, begin, end, factor, true, v, up, sums.work_acc, w);
    has_work = has_work || begin < end;
  }
  un[i] = v;
  if constexpr (kGravity) {
    const Vec3<T> g = d.gravity[i];
    for (int c = 0; c < 3; ++c) w += double(g[c]) * 0.5 * (double(v[c]) - double(upi[c]));
  }
  if (sums.work_acc && (has_work || energy_test)) {
    const double w0 = sums.work_acc[i];
    if (has_work) sums.work_acc[i] = w0 + w;
    w_old += w0;
  }
}

// The blow-up test at the end of a node pass, for every thread of the block: the block's sums of
// ke and w_old, then, by the last block of the grid in block order, the kinetic energy of u(n)
// against the bound with the work up to step n − 1.
__device__ __forceinline__ void blowup_test(double ke, double w_old, const StepSums& sums,
                                            Status* status, int tid, unsigned block,
                                            unsigned blocks) {
  __shared__ double sh[kBlock];
  const double k_sum = block_sum(ke, sh, tid);
  const double w_sum = sums.work_acc ? block_sum(w_old, sh, tid) : 0.0;  // uniform
  if (tid == 0) {
    sums.kinetic_partial[block] = k_sum;
    sums.work_partial[block] = w_sum;
  }
  if (last_block(sums.counter, tid, blocks)) {
    const double kinetic = sum_partials(sums.kinetic_partial, int(blocks), sh, tid);
    const double work = *sums.work_base + sum_partials(sums.work_partial, int(blocks), sh, tid);
    if (tid == 0 &&
        (!isfinite(kinetic) || kinetic > sums.bound->factor * (sums.bound->base + fabs(work))))
      status->blowup = 1;
  }
}

// Gather (or read and clear the atomic sums), then move_node and finish_node. kEnergyTest: blow-up
// test steps.
template <typename T, bool kGather, bool kGravity, bool kEnergyTest, bool kProgram>
__global__ void __launch_bounds__(kBlock)
    node_kernel(NodeData<T> d, const Vec3<T>* __restrict__ element_force,
                Vec3<T>* __restrict__ f_sum, const Vec3<T>* __restrict__ u,
                const Vec3<T>* __restrict__ up, Vec3<T>* __restrict__ un, Status* status,
                StepSums sums, ConstraintData<T> program, const std::int32_t* node_offset,
                const T* factor) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  double ke = 0, w_old = 0;
  // Before the wait: offsets, inverse mass, u(n) and u(n−1) (written two launches back, by the
  // previous steps' node or constraint kernels). Bringing the program's data into L1 here as well
  // cost the skin block 0.0149 → 0.0161 ms per step (docs/performance.md).
  std::int32_t first = 0, last = 0, begin = 0, end = 0;  // its incidence entries, its ops
  T im = T(0);
  Vec3<T> ui{T(0), T(0), T(0)}, upi = ui;
  if (i < d.n) {
    if constexpr (kGather) {
      first = d.offset[i];
      last = d.offset[i + 1];
    }
    if constexpr (kProgram) {
      begin = node_offset[i];
      end = node_offset[i + 1];
    }
    im = d.inverse_mass[i];
    ui = u[i];
    upi = up[i];
  }
  wait_for_previous_kernel();
  let_next_kernel_start();
  if (i < d.n) {
    Vec3<T> f;
    if constexpr (kGather) {
      f = physics::gather_node_force(element_force, d.inc, first, last);
    } else {
      f = f_sum[i];
      f_sum[i] = Vec3<T>{T(0), T(0), T(0)};
    }
    const Vec3<T> v = move_node<T, kGravity>(d, i, f, ui, upi, im, status, sums, kEnergyTest, ke);
    finish_node<T, kGravity, kProgram, 0>(d, i, v, upi, up, un, sums, program, begin, end, factor,
                                          kEnergyTest, w_old);
  }
  if constexpr (kEnergyTest)
    blowup_test(ke, w_old, sums, status, int(threadIdx.x), blockIdx.x, gridDim.x);
}

// Tiled assembly (lattice_tiles.hpp): one block per tile walks its node layers upwards; per layer
// it computes the element slots of the layer (one thread per slot, physics::element_forces) from
// the u windows of the node layers below and above them, keeps their corner forces in shared
// memory and lets each of its nodes sum its entries in the gather order (lattice_tiles.hpp), then
// move_node and finish_node; nodes with loads or constraints (kProgram) finish after the last
// layer. Same sums in the same order as gather, with no element force buffer in DRAM.
// Software-pipelined: the table entries, u window and node data a layer needs are loaded one
// layer ahead, so their latency overlaps the element work (three window buffers in rotation; the
// u windows copied to shared memory asynchronously, without registers).
struct TileData {
  const std::int32_t* layers;  // per tile
  const std::int32_t* window;  // tiles × window_stride node ids
  const std::int32_t* slot;    // tiles × slot_stride element ids
  std::int64_t window_stride, slot_stride;
};
constexpr int kTileWindowPoints = kTileWindow * kTileWindow;
constexpr int kTileSlotCount = kTileSlots * kTileSlots;
static_assert(kTileSlotCount == kBlock, "one thread per element slot");
static_assert(kTileWindowPoints <= 2 * kBlock, "two window points per thread at most");
// Shared memory of tile_kernel: three u windows, the top corners of two element layers (the one
// below the node layer and the one being computed), the bottom corners of one.
template <typename T>
constexpr std::size_t tile_shared_bytes() {
  return sizeof(Vec3<T>) * std::size_t(3 * kTileWindowPoints + 12 * kTileSlotCount);
}
// Blocks of tile_kernel resident per SM the compiler must allow (registers ≤ 80 in float): three
// hide the element work's latency better than two with more registers (docs/performance.md:
// 0.0639 → 0.0574 ms/step on the face-scale model, no spills). Double keeps the compiler's choice.
template <typename T>
constexpr int kTileMinBlocks = sizeof(T) == 4 ? 3 : 1;

// dst (shared) = u[id] (global) without passing through registers (Hopper/Ampere cp.async; waited
// for with __pipeline_wait_prior), or zero where id < 0.
template <typename T>
__device__ __forceinline__ void copy_point_async(Vec3<T>* dst, const Vec3<T>* u, std::int32_t id) {
  if (id < 0) {
    *dst = Vec3<T>{T(0), T(0), T(0)};
    return;
  }
  const T* src = &u[id].x;
  T* d = &dst->x;
  for (int c = 0; c < 3; ++c) __pipeline_memcpy_async(d + c, src + c, sizeof(T));
}

template <typename T, bool kElastic, bool kMuscle, bool kHourglass, bool kGravity, bool kProgram>
__global__ void __launch_bounds__(kBlock, kTileMinBlocks<T>)
    tile_kernel(TileData tiles, ElementData<T> ed, NodeData<T> nd, const Vec3<T>* __restrict__ u,
                const T* __restrict__ activation, const Vec3<T>* __restrict__ up,
                Vec3<T>* __restrict__ un, Status* status, StepSums sums, ConstraintData<T> program,
                const std::int32_t* node_offset, const T* factor, bool energy_test) {
  extern __shared__ __align__(16) unsigned char tile_shared[];
  Vec3<T>* const window = reinterpret_cast<Vec3<T>*>(tile_shared);  // [3][window points]
  Vec3<T>* const top = window + 3 * kTileWindowPoints;              // [2][4 corners][slots]
  Vec3<T>* const bottom = top + 8 * kTileSlotCount;                 // [4 corners][slots]
  const int tid = int(threadIdx.x);
  const std::int32_t* wtab = tiles.window + std::int64_t(blockIdx.x) * tiles.window_stride;
  const std::int32_t* stab = tiles.slot + std::int64_t(blockIdx.x) * tiles.slot_stride;
  const int layers = tiles.layers[blockIdx.x];  // window layers 0 .. layers + 1
  const Vec3<T> zero{T(0), T(0), T(0)};
  // This thread's window points (tid, and tid + kBlock when that is < kTileWindowPoints), its
  // element slot (sx, sy) and, for tid < 225, its node at window point (wx, wy).
  const bool second = tid + kBlock < kTileWindowPoints;
  const int sx = tid % kTileSlots, sy = tid / kTileSlots;
  const bool owner = tid < kTileNodes * kTileNodes;
  const int wx = 1 + tid % kTileNodes, wy = 1 + tid / kTileNodes;
  const int node_point = wy * kTileWindow + wx;
  auto window_ids = [&](int l, std::int32_t& a, std::int32_t& b) {
    a = l <= layers + 1 ? wtab[l * kTileWindowPoints + tid] : -1;
    b = second && l <= layers + 1 ? wtab[l * kTileWindowPoints + tid + kBlock] : -1;
  };
  auto fetch = [&](std::int32_t id) { return id >= 0 ? u[id] : zero; };
  // Prologue: windows 0 and 1 in buffers 0 and 1; the ids of window 2; element layer 0; the node
  // of window layer 1. The tables are read before the wait for the previous kernel.
  std::int32_t ia, ib, window_id[2][2];
  for (int l = 0; l < 2; ++l) window_ids(l, window_id[l][0], window_id[l][1]);
  window_ids(2, ia, ib);
  std::int32_t e = stab[tid];
  std::int32_t row_index = e >= 0 ? ed.row[e] : 0;
  wait_for_previous_kernel();
  let_next_kernel_start();
  for (int l = 0; l < 2; ++l) {
    window[l * kTileWindowPoints + tid] = fetch(window_id[l][0]);
    if (second) window[l * kTileWindowPoints + tid + kBlock] = fetch(window_id[l][1]);
  }
  std::int32_t node = -1;  // window layer 0 has no node of the tile
  Vec3<T> node_up = zero;
  T node_im = T(0);
  std::int32_t node_begin = 0, node_end = 0;  // its ops (kProgram)
  __syncthreads();
  double ke = 0, w_old = 0;
  for (int l = 0; l <= layers; ++l) {
    // A: loads for later layers, issued before the element work: window l + 2 (ids known), the
    // ids of window l + 3, the element of layer l + 1 and the node of window layer l + 1.
    {  // window l + 2 into the buffer window l − 1 had (last read before the previous barrier)
      Vec3<T>* w2 = window + ((l + 2) % 3) * kTileWindowPoints;
      copy_point_async(w2 + tid, u, ia);
      if (second) copy_point_async(w2 + tid + kBlock, u, ib);
      __pipeline_commit();
    }
    window_ids(l + 3, ia, ib);
    const std::int32_t e_next = l + 1 <= layers ? stab[(l + 1) * kTileSlotCount + tid] : -1;
    const std::int32_t node_next =
        owner && l + 1 <= layers ? wtab[(l + 1) * kTileWindowPoints + node_point] : -1;
    // B: element layer l (between window layers l and l + 1).
    const Vec3<T>* wl = window + (l % 3) * kTileWindowPoints;
    const Vec3<T>* wu = window + ((l + 1) % 3) * kTileWindowPoints;
    Vec3<T>* top_l = top + (l & 1) * 4 * kTileSlotCount;
    if (e >= 0) {
      const int p = sy * kTileWindow + sx;
      const Vec3<T> ue[8] = {wl[p], wl[p + 1], wl[p + kTileWindow + 1], wl[p + kTileWindow],
                             wu[p], wu[p + 1], wu[p + kTileWindow + 1], wu[p + kTileWindow]};
      const physics::ElementRow<T> row = ed.rows[row_index];
      physics::MuscleEntries<T> m{
          ed.muscle_id, ed.muscle_fraction, ed.muscle_fibre, ed.muscle_params, activation, 0, 0};
      if constexpr (kMuscle) {
        m.begin = ed.muscle_offset[e];
        m.end = ed.muscle_offset[e + 1];
      }
      Vec3<T> fe[8];
      const auto r =
          physics::element_forces<T, kElastic, kMuscle, kHourglass, false>(ue, ed.h, row, m, fe);
      if (!(r.j > T(0))) status->bad_jacobian = 1;
#pragma unroll
      for (int c = 0; c < 4; ++c) {
        bottom[c * kTileSlotCount + tid] = fe[c];
        top_l[c * kTileSlotCount + tid] = fe[4 + c];
      }
    } else {
#pragma unroll
      for (int c = 0; c < 4; ++c) {
        bottom[c * kTileSlotCount + tid] = zero;
        top_l[c * kTileSlotCount + tid] = zero;
      }
    }
    __syncthreads();
    // D: the node of window layer l (node layer l − 1 of the tile).
    if (l >= 1 && node >= 0) {
      const Vec3<T>* below = top + ((l - 1) & 1) * 4 * kTileSlotCount;
      Vec3<T> f = zero;
#pragma unroll
      for (int q = 0; q < 4; ++q)
        f += below[tile_gather_corner(q) * kTileSlotCount + tile_gather_slot(wx, wy, q)];
#pragma unroll
      for (int q = 0; q < 4; ++q)
        f += bottom[tile_gather_corner(q) * kTileSlotCount + tile_gather_slot(wx, wy, q)];
      // Nodes with loads or constraints finish after the layers (their program's dependent loads
      // then overlap instead of holding the block at each layer's barrier).
      const Vec3<T> v = move_node<T, kGravity>(nd, node, f, wl[node_point], node_up, node_im,
                                               status, sums, energy_test, ke);
      if (node_begin == node_end)
        finish_node<T, kGravity, false, 0>(nd, node, v, node_up, up, un, sums, program, 0, 0,
                                           factor, energy_test, w_old);
      else
        un[node] = v;
    }
    // Next layer's element row and node data (their ids had the element work to arrive; the node
    // data has the next element work to arrive).
    e = e_next;
    row_index = e >= 0 ? ed.row[e] : 0;
    node = node_next;
    if (node >= 0) {
      node_up = up[node];
      node_im = nd.inverse_mass[node];
      if constexpr (kProgram) {
        node_begin = node_offset[node];
        node_end = node_offset[node + 1];
      }
    }
    __pipeline_wait_prior(0);  // window l + 2 has landed (the next layer reads it)
    __syncthreads();  // the next layer overwrites `bottom`, the top corners read here, window l
  }
  if constexpr (kProgram) {  // the deferred nodes: their u(n+1) before the program is in un
    if (owner)
      for (int l = 1; l <= layers; ++l) {
        const std::int32_t i = wtab[l * kTileWindowPoints + node_point];
        if (i < 0) continue;
        const std::int32_t begin = node_offset[i], end = node_offset[i + 1];
        if (begin == end) continue;
        finish_node<T, kGravity, true, 0>(nd, i, un[i], up[i], up, un, sums, program, begin, end,
                                          factor, energy_test, w_old);
      }
  }
  if (energy_test) blowup_test(ke, w_old, sums, status, tid, blockIdx.x, gridDim.x);
}

// ---------------------------------------------------------------------------------------------

template <typename T>
Vec3<T> to_vec(const std::array<double, 3>& a) {
  return {T(a[0]), T(a[1]), T(a[2])};
}

std::vector<std::int32_t> to_i32(const std::vector<Index>& v) {
  return {v.begin(), v.end()};
}

struct DeviceCollection {
  bool muscle = false;
  DeviceArray<std::int32_t> elements;
};

template <typename T>
struct DeviceSurface {
  DeviceArray<Vec3<T>> vertices, normals;
  DeviceArray<std::array<std::int32_t, 3>> triangles;
  DeviceArray<std::int32_t> cell_offsets, cell_triangles;
  DeviceArray<Vec3<T>> entry_corners, cell_boxes, triangle_corners;
};

template <typename T>
class CudaEngine final : public Backend, public CudaTiming {
 public:
  CudaEngine(const formats::Model& model, const Setup& setup, Plan plan,
             const CudaOptions& options);
  ~CudaEngine() override;

  std::string name() const override { return "cuda"; }
  const Plan& plan() const override { return plan_; }
  void step(std::int64_t n) override;
  std::int64_t step_index() const override { return step_; }
  double time() const override { return double(step_) * dt_; }
  double dt() const override { return dt_; }
  State state() const override;
  void restore(const State& s) override;
  std::vector<double> displacements() const override;
  std::vector<double> velocities() const override;
  std::vector<double> internal_forces() override;
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override;
  Energies energies() override;
  ElementFields element_fields() override;

  std::vector<float> timed_graph_launches(int launches) override;
  int graph_steps() const override { return batch_; }
  double bytes_per_step() const override;
  ForceAssembly assembly() const override { return options_.assembly; }

 private:
  Vec3<T>* buffer(std::int64_t step, int role) const {  // role 0: u(n), 1: u(n+1), 2: u(n−1)
    return buf_[std::size_t((step + role) % 3)].get();
  }
  double curve_time(double t) const { return t / setup_.time_scaling; }
  void fill_scalars(std::int64_t first_step, int count, int slot0);
  void launch_elements(const Vec3<T>* u, const T* activation, int mode, cudaStream_t s,
                       bool programmatic = false);
  void launch_nodes(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc, bool blowup_test,
                    cudaStream_t s, bool programmatic = false);
  void launch_tiles(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc, bool blowup_test,
                    cudaStream_t s, bool programmatic = false);
  // ahead: the lists were refreshed from u(n) by slide_refresh_kernel (launch_step).
  // programmatic: a programmatic dependent launch (launch_kernel), as for the launches below.
  // lists_ready: no list refresh was forked for this step (constraint_kernel).
  void launch_constraints(const T* factor, bool loads, Vec3<T>* un, const Vec3<T>* up,
                          cudaStream_t s, bool ahead, bool programmatic = false,
                          bool lists_ready = false) {
    const unsigned g = blocks_for(con_node_.size());
    const ConstraintData<T> d = constraint_data();
    auto go = [&](auto kernel) {
      launch_kernel(kernel, g, kBlock, 0, s, programmatic, d, factor, loads, un, up, step_sums(),
                    lists_ready);
    };
    if (slide_node_.size() && ahead)
      go(constraint_kernel<T, 2>);
    else if (slide_node_.size())
      go(constraint_kernel<T, 1>);
    else
      go(constraint_kernel<T, 0>);
    SINEW_CUDA_LAUNCHED();
  }
  // The sliding lists from u(n) for step n (anchors kept within s/2: slide_refresh_kernel).
  void launch_refresh(const Vec3<T>* u, cudaStream_t s) {
    slide_refresh_kernel<T>
        <<<blocks_for(slide_node_.size()), kBlock, 0, s>>>(slide_data(), rest_.get(), u);
    SINEW_CUDA_LAUNCHED();
  }
  // ahead: sliding lists refreshed ahead on slide_stream_ (graph steps, stage timing); direct
  // steps refresh inline and never miss. programmatic: the kernels that follow a kernel in s are
  // programmatic dependent launches (graph steps with programmatic_).
  void launch_step(std::int64_t step, int slot, cudaStream_t s, bool ahead_slide,
                   bool blowup_test = false,
                   std::vector<std::pair<std::string, cudaEvent_t>>* marks = nullptr,
                   bool programmatic = false);
  std::vector<std::pair<std::string, float>> stage_times(int repeats) override;
  void build_graph();
  void run_direct_step();  // one step with its scalars, synchronised and checked
  void check_status_or_replay(std::int64_t first_step, std::int64_t count);
  void snapshot();
  void roll_back();
  [[noreturn]] void fail_jacobian();
  [[noreturn]] void fail_displacement(const std::vector<Vec3<T>>& un);
  std::vector<Vec3<T>> download_vec(const Vec3<T>* p) const;
  void upload_vec(Vec3<T>* p, const std::vector<double>& flat);
  void compute_energy_terms(double& strain, double& hourglass);
  double kinetic_energy(const std::vector<Vec3<T>>& u, const std::vector<Vec3<T>>& up) const;
  double blowup_reference(double work) const {
    return std::max(0.0, initial_energy_) + std::abs(work) + prep_.active_energy_bound +
           energy_floor_;
  }
  double external_work() const;
  void check_blowup(double work);
  void update_bound() {
    const BlowupBound b{std::max(0.0, initial_energy_) + prep_.active_energy_bound + energy_floor_,
                        setup_.blowup_factor};
    SINEW_CUDA_CHECK(cudaMemcpy(bound_.get(), &b, sizeof b, cudaMemcpyHostToDevice));
    SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  }
  std::vector<T> activation_at(double t) const;

  Setup setup_;
  Plan plan_;
  CudaOptions options_;
  PreparedModel prep_;
  double dt_;
  T h_;
  std::size_t n_, e_;
  int batch_;
  physics::CentralDifference<T> cd_;
  double energy_floor_ = 0, initial_energy_ = 0;
  std::int64_t step_ = 0;

  cudaStream_t stream_ = nullptr, copy_stream_ = nullptr;
  cudaEvent_t copy_ready_ = nullptr;
  // Element collections after the first run on side streams, forked from and joined to the step
  // stream (parallel branches of the captured graph): small collections fill the GPU together.
  std::vector<cudaStream_t> side_streams_;
  std::vector<cudaEvent_t> side_done_;
  cudaEvent_t fork_ = nullptr;
  int sm_count_ = 132;
  // Graph steps as programmatic dependent launches (options.programmatic_launch on sm_90+).
  bool programmatic_ = false;
  cudaGraphExec_t graph_ = nullptr;

  // elements
  DeviceArray<std::array<Index, 8>> elem_nodes_;
  DeviceArray<std::int32_t> row_;
  DeviceArray<physics::ElementRow<T>> rows_;
  std::vector<DeviceCollection> collections_;
  DeviceArray<std::int32_t> muscle_offset_, muscle_id_;
  DeviceArray<T> muscle_fraction_;
  DeviceArray<Vec3<T>> muscle_fibre_;
  DeviceArray<physics::MuscleParams<T>> muscle_params_;
  std::size_t muscles_ = 0;
  // forces and nodes
  DeviceArray<Vec3<T>> elem_force_, f_sum_, f_;
  DeviceArray<std::int32_t> inc_offset_, inc_;
  // tiled assembly (lattice_tiles.hpp)
  DeviceArray<std::int32_t> tile_layers_, tile_window_, tile_slot_;
  TileData tile_data_{};
  DeviceArray<T> inverse_mass_;
  DeviceArray<Vec3<T>> gravity_, rest_;
  DeviceArray<Vec3<T>> buf_[3];
  DeviceArray<Vec3<T>> snap_u_, snap_up_;
  DeviceArray<double> element_energy_;
  // per-step scalars: per slot [activation (M) | force factors (F) | prescribed factors (P)]
  std::size_t scalars_per_slot_ = 0;
  DeviceArray<T> scalars_;
  PinnedArray<T> scalars_host_;
  // loads and constraints
  // loads and constraints: one program per constrained node (constraint_kernel)
  DeviceArray<std::int32_t> con_node_, con_offset_, con_op_;
  bool program_in_node_ = false;  // no sliding: the node kernel runs the programs
  // Sliding lists refreshed ahead of each graph step (slide_refresh_kernel on slide_stream_);
  // false after repeated misses, and in direct steps (inline refresh): docs/cuda-backend.md.
  bool slide_ahead_ = true;
  int slide_miss_batches_ = 0;  // graph batches with a miss at the current refresh interval
  int refresh_interval_ = 1;    // steps between list refreshes (options, halved on misses)
  cudaStream_t slide_stream_ = nullptr;
  cudaEvent_t slide_fork_ = nullptr, slide_done_ = nullptr;
  DeviceArray<std::int32_t> node_op_offset_;  // N + 1 into con_op_ (program_in_node_)
  DeviceArray<std::int32_t> prescribed_set_, prescribed_mask_;
  DeviceArray<Vec3<T>> force_per_node_, prescribed_value_, prescribed_free_, plane_normals_;
  ConstraintData<T> constraint_data() const {
    return {con_node_.get(),
            con_offset_.get(),
            con_op_.get(),
            std::int32_t(con_node_.size()),
            inverse_mass_.get(),
            cd_,
            force_per_node_.get(),
            prescribed_set_.get(),
            prescribed_value_.get(),
            prescribed_mask_.get(),
            prescribed_free_.get(),
            plane_normals_.get(),
            slide_data(),
            rest_.get(),
            setup_.effects.gravity ? gravity_.get() : nullptr,
            std::int32_t(prep_.forces.size())};
  }
  StepSums step_sums() const {
    return {work_ ? work_acc_.get() : nullptr,
            work_base_.get(),
            work_partial_.get(),
            ke_partial_.get(),
            counters_.get(),
            bound_.get(),
            1.0 / dt_};
  }
  // kinetic-energy blow-up test inside graphs (at steps ≡ 0 mod energy_interval)
  int interval_ = 10;
  std::int64_t align_ = 3;  // graphs start at steps ≡ 0 mod align_ (3, or lcm(3, interval))
  bool graph_blowup_ = false;
  DeviceArray<double> ke_partial_, work_partial_;
  DeviceArray<unsigned> counters_;
  DeviceArray<BlowupBound> bound_;
  std::vector<std::unique_ptr<DeviceSurface<T>>> surfaces_;
  DeviceArray<SlideSurface<T>> slide_surfaces_;
  DeviceArray<std::int32_t> slide_node_, slide_surface_, slide_triangle_, snap_triangle_;
  DeviceArray<std::int32_t> slide_search_triangle_;
  DeviceArray<std::int32_t> slide_list_count_, slide_list_;
  DeviceArray<T> slide_list_distance_;
  DeviceArray<Vec3<T>> slide_anchor_;
  SlideData<T> slide_data() const {
    return {slide_node_.get(),
            slide_surface_.get(),
            slide_distance_.get(),
            slide_triangle_.get(),
            slide_search_triangle_.get(),
            slide_list_count_.get(),
            slide_anchor_.get(),
            slide_list_.get(),
            slide_list_distance_.get(),
            slide_surfaces_.get(),
            std::int32_t(slide_node_.size()),
            status_.get()};
  }
  void forget_slide_lists(cudaStream_t s) {  // every node searches fully at its next step
    if (slide_list_count_.size())
      SINEW_CUDA_CHECK(
          cudaMemsetAsync(slide_list_count_.get(), 0xff, slide_list_count_.bytes(), s));
  }
  DeviceArray<T> slide_distance_;
  bool work_ = false;
  // external work: per-node accumulators (StepSums) + the base carried in by restore()
  DeviceArray<double> work_acc_, snap_work_acc_, work_base_;
  double work_sum(const double* acc) const;  // base + Σ acc (host, node order); syncs
  // status and output
  DeviceArray<Status> status_;
  PinnedArray<Status> status_host_;
  mutable PinnedArray<Vec3<T>> output_;
};

template <typename T>
CudaEngine<T>::CudaEngine(const formats::Model& model, const Setup& setup, Plan plan,
                          const CudaOptions& options)
    : setup_(setup), plan_(std::move(plan)), options_(options) {
  if (options.sliding_refresh_interval < 1)
    throw ConfigError("", "sliding_refresh_interval",
                      format("must be at least 1 step, got %d", options.sliding_refresh_interval));
  refresh_interval_ = options.sliding_refresh_interval;
  if (options.tiles_per_sm < 1)
    throw ConfigError("", "tiles_per_sm",
                      format("must be at least 1, got %d", options.tiles_per_sm));
  if (!(options.sliding_skin > 0) || !std::isfinite(options.sliding_skin))
    throw ConfigError(
        "", "sliding_skin",
        format("must be a positive number of grid cells, got %g", options.sliding_skin));
  SINEW_CUDA_CHECK(cudaSetDevice(options.device));
  prep_ = prepare_model(model, setup, plan_);
  dt_ = plan_.dt;
  h_ = T(prep_.h);
  n_ = prep_.nodes;
  e_ = prep_.elements;
  if (e_ * 8 >= std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw ConfigError("", "model", "too many elements for the CUDA backend's 32-bit incidence");
  interval_ = std::max(1, setup.energy_interval);
  {
    // Graph batches start at steps ≡ 0 mod lcm(3, interval) so the blow-up tests sit at fixed
    // slots of the captured graph; a very long interval falls back to a test at each sync point.
    const std::int64_t lcm = std::lcm<std::int64_t>(3, interval_);
    graph_blowup_ = lcm <= 1024;
    align_ = graph_blowup_ ? lcm : 3;
    const std::int64_t want = std::max<std::int64_t>(options.graph_steps, align_);
    batch_ = int((want + align_ - 1) / align_ * align_);
  }
  const Effects& fx = setup.effects;
  cd_ = physics::central_difference<T>(dt_, fx.damping ? setup.damping_alpha : 0.0);
  energy_floor_ = double(std::numeric_limits<T>::epsilon()) * prep_.volume * prep_.min_modulus;

  SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
  SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&copy_stream_, cudaStreamNonBlocking));
  SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&copy_ready_, cudaEventDisableTiming));

  elem_nodes_.upload(prep_.element_nodes);
  row_.upload(prep_.row);
  {
    std::vector<physics::ElementRow<T>> rows;
    for (const auto& r : prep_.rows) rows.push_back({T(r[0]), T(r[1]), T(r[2])});
    rows_.upload(rows);
  }
  for (const auto& c : plan_.collections) {
    DeviceCollection dc;
    dc.muscle = c.muscle;
    dc.elements.upload(to_i32(c.elements));
    collections_.push_back(std::move(dc));
  }
  SINEW_CUDA_CHECK(
      cudaDeviceGetAttribute(&sm_count_, cudaDevAttrMultiProcessorCount, options.device));
  {
    int major = 0;
    SINEW_CUDA_CHECK(
        cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, options.device));
    programmatic_ = options.programmatic_launch && major >= 9;
  }
  SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&fork_, cudaEventDisableTiming));
  SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&slide_stream_, cudaStreamNonBlocking));
  SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&slide_fork_, cudaEventDisableTiming));
  SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&slide_done_, cudaEventDisableTiming));
  for (std::size_t c = 1; c < collections_.size(); ++c) {
    side_streams_.emplace_back();
    SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&side_streams_.back(), cudaStreamNonBlocking));
    side_done_.emplace_back();
    SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&side_done_.back(), cudaEventDisableTiming));
  }
  if (fx.muscles) {
    muscle_offset_.upload(
        std::vector<std::int32_t>(prep_.muscle_offset.begin(), prep_.muscle_offset.end()));
    muscle_id_.upload(prep_.muscle_id);
    std::vector<T> fr(prep_.muscle_fraction.begin(), prep_.muscle_fraction.end());
    muscle_fraction_.upload(fr);
    std::vector<Vec3<T>> fib;
    for (const auto& f : prep_.muscle_fibre) fib.push_back(to_vec<T>(f));
    muscle_fibre_.upload(fib);
    std::vector<physics::MuscleParams<T>> mp;
    for (const auto& p : prep_.muscle_params)
      mp.push_back({T(p[0]), T(p[1]), T(p[2]), T(p[3]), T(p[4])});
    muscle_params_.upload(mp);
    muscles_ = mp.size();
  }
  if (options.assembly == ForceAssembly::tiled || options.assembly == ForceAssembly::automatic) {
    // automatic: tiles too many to pay off are not built (max_paying_slots).
    const LatticeTiles tiles = make_lattice_tiles(
        model.node_lattice, model.element_lattice,
        std::size_t(options.tiles_per_sm) * std::size_t(sm_count_),
        options.assembly == ForceAssembly::automatic ? max_paying_slots(e_) : SIZE_MAX);
    if (options.assembly == ForceAssembly::automatic)
      options_.assembly = tiles_pay_off(tiles, e_) ? ForceAssembly::tiled : ForceAssembly::gather;
    if (options_.assembly == ForceAssembly::tiled) {
      tile_layers_.upload(tiles.tile_layers);
      tile_window_.upload(tiles.window_node);
      tile_slot_.upload(tiles.slot_element);
      tile_data_ = {tile_layers_.get(), tile_window_.get(), tile_slot_.get(),
                    std::int64_t(tiles.window_stride()), std::int64_t(tiles.slot_stride())};
    }
  }
  if (options_.assembly == ForceAssembly::gather) {
    elem_force_.allocate(e_ * 8);
  } else if (options_.assembly == ForceAssembly::atomic) {
    f_sum_.allocate(n_);
    f_sum_.zero();
  }
  inc_offset_.upload(
      std::vector<std::int32_t>(prep_.incidence_offset.begin(), prep_.incidence_offset.end()));
  {
    // The gather reads the corner-major buffer: entry e · 8 + a of the incidence becomes a · E + e
    // (same entries, same order: the summation order is the CPU's).
    std::vector<std::int32_t> inc(prep_.incidence.size());
    for (std::size_t k = 0; k < inc.size(); ++k) {
      const auto v = std::size_t(prep_.incidence[k]);
      inc[k] = std::int32_t((v % 8) * e_ + v / 8);
    }
    inc_.upload(inc);
  }
  f_.allocate(n_);
  {
    std::vector<T> im(n_);
    for (std::size_t i = 0; i < n_; ++i) im[i] = T(1.0 / prep_.mass[i]);
    inverse_mass_.upload(im);
    std::vector<Vec3<T>> rest;
    for (const auto& r : prep_.rest) rest.push_back(to_vec<T>(r));
    rest_.upload(rest);
    if (fx.gravity) {
      std::vector<Vec3<T>> g;
      for (const auto& v : prep_.gravity) g.push_back(to_vec<T>(v));
      gravity_.upload(g);
    }
  }
  for (auto& b : buf_) b.allocate(n_);
  snap_u_.allocate(n_);
  snap_up_.allocate(n_);

  // Loads and constraints: per node its ops in the CPU's order (constraint_kernel).
  std::size_t prescribed_entries = 0;
  {
    struct Entry {
      std::int32_t node, code;
    };
    std::vector<Entry> ops;
    auto add = [&](Index node, ConstraintOp kind, std::size_t arg) {
      if (arg > std::size_t(kOpArg))
        throw ConfigError("", "model", "too many constraint entries for the CUDA backend");
      ops.push_back({std::int32_t(node), std::int32_t(kind) << kOpShift | std::int32_t(arg)});
    };
    std::vector<Vec3<T>> fpn, pv;
    std::vector<std::int32_t> pset, pmask;
    for (std::size_t s = 0; s < prep_.forces.size(); ++s) {
      for (auto nd : prep_.forces[s].nodes) add(nd, kOpForce, s);
      fpn.push_back(to_vec<T>(prep_.forces[s].per_node));
    }
    for (std::size_t s = 0; s < prep_.prescribed.size(); ++s) {
      const auto& p = prep_.prescribed[s];
      for (auto nd : p.nodes) {
        add(nd, kOpCapture, pset.size());
        pset.push_back(std::int32_t(s));
      }
      pv.push_back(to_vec<T>(p.per_node));
      pmask.push_back((p.components[0] ? 1 : 0) | (p.components[1] ? 2 : 0) |
                      (p.components[2] ? 4 : 0));
    }
    prescribed_entries = pset.size();
    for (std::size_t k = 0; k < prep_.slide_node.size(); ++k) add(prep_.slide_node[k], kOpSlide, k);
    std::vector<Vec3<T>> pn;
    for (std::size_t k = 0; k < prep_.plane_nodes.size(); ++k) {
      add(prep_.plane_nodes[k], kOpPlane, k);
      pn.push_back(to_vec<T>(prep_.plane_normals[k]));
    }
    {
      std::size_t q = 0;
      for (const auto& p : prep_.prescribed)
        for (auto nd : p.nodes) add(nd, kOpPrescribe, q++);
    }
    for (auto nd : prep_.rigid) add(nd, kOpRigid, 0);
    // Grouped by node (ascending ids: neighbouring sliding nodes share warps), each node's ops
    // in the order added above, which is the CPU's order.
    std::stable_sort(ops.begin(), ops.end(),
                     [](const Entry& x, const Entry& y) { return x.node < y.node; });
    std::vector<std::int32_t> node, offset{0}, code;
    for (std::size_t k = 0; k < ops.size(); ++k) {
      if (k == 0 || ops[k].node != ops[k - 1].node) {
        if (k) offset.push_back(std::int32_t(k));
        node.push_back(ops[k].node);
      }
      code.push_back(ops[k].code);
    }
    if (!ops.empty()) offset.push_back(std::int32_t(ops.size()));
    {  // per node: its ops (node kernel, tile kernel)
      std::vector<std::int32_t> per_node(n_ + 1, 0);
      for (std::size_t c = 0; c < node.size(); ++c)
        per_node[std::size_t(node[c]) + 1] = offset[c + 1] - offset[c];
      for (std::size_t k = 0; k < n_; ++k) per_node[k + 1] += per_node[k];
      node_op_offset_.upload(per_node);
    }
    con_node_.upload(node);
    con_offset_.upload(offset);
    con_op_.upload(code);
    force_per_node_.upload(fpn);
    prescribed_value_.upload(pv);
    prescribed_mask_.upload(pmask);
    prescribed_set_.upload(pset);
    prescribed_free_.allocate(pset.size());
    plane_normals_.upload(pn);
  }
  if (!prep_.surfaces.empty()) {
    std::vector<SlideSurface<T>> views;
    for (const auto& s : prep_.surfaces) {
      auto ds = std::make_unique<DeviceSurface<T>>();
      std::vector<Vec3<T>> v, nrm;
      for (const auto& p : s.vertices) v.push_back(to_vec<T>(p));
      for (const auto& t : s.triangles)
        nrm.push_back(physics::triangle_normal(v[std::size_t(t[0])], v[std::size_t(t[1])],
                                               v[std::size_t(t[2])]));
      ds->vertices.upload(v);
      ds->normals.upload(nrm);
      ds->triangles.upload(s.triangles);
      ds->cell_offsets.upload(s.grid.cell_offsets);
      ds->cell_triangles.upload(s.grid.cell_triangles);
      const SurfaceLists<T> lists = make_surface_lists(s.grid, v, s.triangles);
      ds->entry_corners.upload(lists.corners);
      ds->cell_boxes.upload(lists.cell);
      ds->triangle_corners.upload(triangle_corner_list(v, s.triangles));
      SurfaceView<T> view;
      view.vertices = ds->vertices.get();
      view.triangles = ds->triangles.get();
      view.normals = ds->normals.get();
      view.triangle_count = std::int32_t(s.triangles.size());
      view.cell_offsets = ds->cell_offsets.get();
      view.cell_triangles = ds->cell_triangles.get();
      view.entry_corners = ds->entry_corners.get();
      view.cell_boxes = ds->cell_boxes.get();
      for (int k = 0; k < 3; ++k) {
        view.origin[k] = T(s.grid.origin[std::size_t(k)]);
        view.dims[k] = s.grid.dims[std::size_t(k)];
      }
      view.cell = T(s.grid.cell);
      views.push_back({view, ds->triangle_corners.get(), T(options.sliding_skin * s.grid.cell)});
      surfaces_.push_back(std::move(ds));
    }
    slide_surfaces_.upload(views);
    slide_node_.upload(to_i32(prep_.slide_node));
    slide_surface_.upload(prep_.slide_surface);
    slide_triangle_.upload(prep_.slide_triangle);
    snap_triangle_.allocate(prep_.slide_triangle.size());
    slide_search_triangle_.upload(prep_.slide_triangle);
    slide_list_count_.allocate(prep_.slide_node.size());
    slide_list_.allocate(prep_.slide_node.size() * kCandidates);
    slide_list_distance_.allocate(prep_.slide_node.size() * kCandidates);
    slide_anchor_.allocate(prep_.slide_node.size());
    forget_slide_lists(stream_);
    std::vector<T> d(prep_.slide_distance.begin(), prep_.slide_distance.end());
    slide_distance_.upload(d);
  }
  work_ = fx.gravity || !prep_.forces.empty() || prescribed_entries > 0;
  program_in_node_ = prep_.slide_node.empty() && (con_node_.size() || work_);
  work_base_.allocate(1);
  work_base_.zero();
  if (work_) {
    work_acc_.allocate(n_);
    work_acc_.zero();
    snap_work_acc_.allocate(n_);
  }
  work_partial_.allocate(std::max<std::size_t>(blocks_for(n_), tile_layers_.size()));
  ke_partial_.allocate(std::max<std::size_t>(blocks_for(n_), tile_layers_.size()));
  counters_.allocate(1);
  counters_.zero();
  bound_.upload({BlowupBound{0, 0}});

  scalars_per_slot_ =
      std::max<std::size_t>(1, muscles_ + prep_.forces.size() + prep_.prescribed.size());
  scalars_.allocate(scalars_per_slot_ * std::size_t(batch_ + 1));
  scalars_host_.allocate(scalars_per_slot_ * std::size_t(batch_ + 1));
  status_.allocate(1);
  status_.zero();
  status_host_.allocate(1);
  output_.allocate(n_);

  // Initial state: u(0) = 0 with the constraints at t = 0; u(−1) = u(0) − v0 Δt (as the CPU).
  SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  {
    buf_[0].zero();
    // Constraints at t = 0 on the host path of the device kernels: run them on buffer 0.
    fill_scalars(-1, 1, int(batch_));  // slot `batch_`: prescribed factors at t = 0
    Vec3<T>* u0 = buf_[0].get();
    const T* sc = scalars_.get() + scalars_per_slot_ * std::size_t(batch_);
    if (con_node_.size()) {
      launch_constraints(sc + muscles_, false, u0, u0, stream_, false);
    }
    SINEW_CUDA_LAUNCHED();
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    std::vector<Vec3<T>> u = download_vec(u0), up = u;
    for (const auto& v : setup.initial_velocities)
      for (auto nd : v.nodes)
        for (int k = 0; k < 3; ++k)
          up[std::size_t(nd)][k] = u[std::size_t(nd)][k] - T(v.velocity[std::size_t(k)] * dt_);
    for (auto nd : prep_.rigid) up[std::size_t(nd)] = u[std::size_t(nd)];
    SINEW_CUDA_CHECK(
        cudaMemcpy(buf_[2].get(), up.data(), n_ * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
    SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  }
  const Energies e0 = energies();
  initial_energy_ = std::max(0.0, e0.kinetic + e0.strain + e0.hourglass);
  update_bound();
  build_graph();
}

template <typename T>
CudaEngine<T>::~CudaEngine() {
  if (graph_) cudaGraphExecDestroy(graph_);
  if (copy_ready_) cudaEventDestroy(copy_ready_);
  if (stream_) cudaStreamDestroy(stream_);
  if (copy_stream_) cudaStreamDestroy(copy_stream_);
  for (auto st : side_streams_) cudaStreamDestroy(st);
  for (auto ev : side_done_) cudaEventDestroy(ev);
  if (fork_) cudaEventDestroy(fork_);
  if (slide_fork_) cudaEventDestroy(slide_fork_);
  if (slide_done_) cudaEventDestroy(slide_done_);
  if (slide_stream_) cudaStreamDestroy(slide_stream_);
}

template <typename T>
std::vector<T> CudaEngine<T>::activation_at(double t) const {
  std::vector<T> a(muscles_);
  for (std::size_t m = 0; m < muscles_; ++m)
    a[m] = m < setup_.activation.size() && !setup_.activation[m].points.empty()
               ? T(std::clamp(setup_.activation[m].at(curve_time(t)), 0.0, 1.0))
               : T(0);
  return a;
}

// Scalars of steps first_step .. first_step + count − 1 into slots slot0 ...; a step of −1 fills
// the prescribed factors at t = 0 (the initial constraints).
template <typename T>
void CudaEngine<T>::fill_scalars(std::int64_t first_step, int count, int slot0) {
  T* h = scalars_host_.get() + scalars_per_slot_ * std::size_t(slot0);
  for (int k = 0; k < count; ++k) {
    T* row = h + scalars_per_slot_ * std::size_t(k);
    const double t = double(first_step + k) * dt_;
    const auto a = activation_at(std::max(0.0, t));
    for (std::size_t m = 0; m < muscles_; ++m) row[m] = a[m];
    for (std::size_t s = 0; s < prep_.forces.size(); ++s)
      row[muscles_ + s] = T(prep_.forces[s].curve.at(curve_time(t)));
    for (std::size_t s = 0; s < prep_.prescribed.size(); ++s)
      row[muscles_ + prep_.forces.size() + s] =
          T(prep_.prescribed[s].curve.at(curve_time(t + dt_)));
  }
  SINEW_CUDA_CHECK(cudaMemcpyAsync(scalars_.get() + scalars_per_slot_ * std::size_t(slot0), h,
                                   scalars_per_slot_ * std::size_t(count) * sizeof(T),
                                   cudaMemcpyHostToDevice, stream_));
}

template <typename T>
void CudaEngine<T>::launch_elements(const Vec3<T>* u, const T* activation, int mode, cudaStream_t s,
                                    bool programmatic) {
  ElementData<T> d{elem_nodes_.get(),    row_.get(),           rows_.get(),
                   muscle_offset_.get(), muscle_id_.get(),     muscle_fraction_.get(),
                   muscle_fibre_.get(),  muscle_params_.get(), h_,
                   std::int32_t(e_)};
  const bool el = setup_.effects.elasticity, hg = setup_.effects.hourglass;
  Vec3<T>* out = mode == 1 ? f_sum_.get() : elem_force_.get();
  if (collections_.size() > 1) SINEW_CUDA_CHECK(cudaEventRecord(fork_, s));
  for (std::size_t ci = 0; ci < collections_.size(); ++ci) {
    const auto& c = collections_[ci];
    const cudaStream_t cs = ci == 0 ? s : side_streams_[ci - 1];
    if (ci > 0) SINEW_CUDA_CHECK(cudaStreamWaitEvent(cs, fork_, 0));
    const auto count = std::int32_t(c.elements.size());
    // Fewer than one block of 256 per SM: blocks of 64, spread over more SMs (shorter per-SM
    // queues; the element kernel is latency-bound there).
    const unsigned threads = blocks_for(c.elements.size()) < unsigned(sm_count_) ? 64 : kBlock;
    const unsigned g = unsigned((c.elements.size() + threads - 1) / threads);
    // Side streams start after a fork (an event): plain launches there.
    auto go = [&](auto kernel) {
      launch_kernel(kernel, g, threads, 0, cs, programmatic && collections_.size() == 1, d,
                    c.elements.get(), count, u, activation, out, element_energy_.get(),
                    status_.get());
    };
    // Every effect combination is its own specialised kernel.
#define SINEW_EK(E, M, H)                    \
  if (el == E && c.muscle == M && hg == H) { \
    if (mode == 0)                           \
      go(element_kernel<T, E, M, H, 0>);     \
    else if (mode == 1)                      \
      go(element_kernel<T, E, M, H, 1>);     \
    else                                     \
      go(element_kernel<T, E, M, H, 2>);     \
  }
    SINEW_EK(true, true, true)
    SINEW_EK(true, true, false)
    SINEW_EK(true, false, true)
    SINEW_EK(true, false, false)
    SINEW_EK(false, true, true)
    SINEW_EK(false, true, false)
    SINEW_EK(false, false, true)
    SINEW_EK(false, false, false)
#undef SINEW_EK
    SINEW_CUDA_LAUNCHED();
    if (ci > 0) {
      SINEW_CUDA_CHECK(cudaEventRecord(side_done_[ci - 1], cs));
      SINEW_CUDA_CHECK(cudaStreamWaitEvent(s, side_done_[ci - 1], 0));
    }
  }
}

template <typename T>
void CudaEngine<T>::launch_step(std::int64_t step, int slot, cudaStream_t s, bool ahead_slide,
                                bool blowup_test,
                                std::vector<std::pair<std::string, cudaEvent_t>>* marks,
                                bool programmatic) {
  const Vec3<T>* u = buffer(step, 0);
  const Vec3<T>* up = buffer(step, 2);
  Vec3<T>* un = buffer(step, 1);
  // Stage boundaries for stage_times(): an event recorded after each stage.
  auto mark = [&](const char* stage) {
    if (!marks) return;
    cudaEvent_t ev;
    SINEW_CUDA_CHECK(cudaEventCreate(&ev));
    SINEW_CUDA_CHECK(cudaEventRecord(ev, s));
    marks->emplace_back(stage, ev);
  };
  mark("start");
  const bool ahead = ahead_slide && slide_node_.size();
  // Lists refreshed every refresh_interval_ steps (a batch starts with one); in between a node
  // keeps its list while within s of its anchor (else a miss and a replay).
  const bool refresh = ahead && step % refresh_interval_ == 0;
  const T* sc = scalars_.get() + scalars_per_slot_ * std::size_t(slot);
  if (refresh) {  // fork: the lists for this step, from u(n), beside the element and node kernels
    SINEW_CUDA_CHECK(cudaEventRecord(slide_fork_, s));
    SINEW_CUDA_CHECK(cudaStreamWaitEvent(slide_stream_, slide_fork_, 0));
    launch_refresh(u, slide_stream_);
    SINEW_CUDA_CHECK(cudaEventRecord(slide_done_, slide_stream_));
  }
  // The step's first kernel is launched plainly when a list refresh was forked beside it: launched
  // early, its blocks would take the SMs before the refresh's, and the constraints wait for the
  // refresh (measured, face-scale model: 0.0519 → 0.0564 ms per step with the refresh every 4 steps,
  // 0.0553 → 0.0732 with every step).
  const bool first_programmatic = programmatic && !refresh;
  if (options_.assembly == ForceAssembly::tiled) {
    launch_tiles(u, up, un, sc, blowup_test, s, first_programmatic);
    mark(program_in_node_ ? "elements + nodes in tiles (+ loads, constraints, work, KE test)"
                          : "elements + nodes in tiles (+ KE test)");
  } else {
    launch_elements(u, sc, options_.assembly == ForceAssembly::gather ? 0 : 1, s,
                    first_programmatic);
    mark("elements: F, S (+ muscles), forces, hourglass");
    // After element collections joined from side streams (events): a plain launch.
    launch_nodes(u, up, un, sc, blowup_test, s, programmatic && collections_.size() == 1);
    mark(program_in_node_ ? "nodes: force gather + update + loads, constraints, work (+ KE test)"
                          : "nodes: force gather + central-difference update (+ KE test)");
  }
  if (!program_in_node_ && con_node_.size()) {
    if (refresh) SINEW_CUDA_CHECK(cudaStreamWaitEvent(s, slide_done_, 0));  // join
    launch_constraints(sc + muscles_, true, un, up, s, ahead, programmatic, !refresh);
    mark("loads, sliding, planes, prescribed, rigid + external work");
  }
}

// The node kernel after the element kernels (gather or atomic assembly).
template <typename T>
void CudaEngine<T>::launch_nodes(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                                 bool blowup_test, cudaStream_t s, bool programmatic) {
  const bool gather = options_.assembly == ForceAssembly::gather;
  NodeData<T> nd{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                 std::int32_t(n_)};
  const StepSums sums = step_sums();
  const ConstraintData<T> program = constraint_data();
  auto node = [&](auto kernel) {
    launch_kernel(kernel, blocks_for(n_), kBlock, 0, s, programmatic, nd, elem_force_.get(),
                  f_sum_.get(), u, up, un, status_.get(), sums, program, node_op_offset_.get(),
                  sc + muscles_);
  };
  const bool grav = setup_.effects.gravity, prog = program_in_node_;
  // Every combination is its own specialised kernel.
#define SINEW_NK(G, W, E, P) \
  if (gather == G && grav == W && blowup_test == E && prog == P) node(node_kernel<T, G, W, E, P>);
#define SINEW_NK2(G, W, E) SINEW_NK(G, W, E, true) SINEW_NK(G, W, E, false)
  SINEW_NK2(true, true, true)
  SINEW_NK2(true, true, false)
  SINEW_NK2(true, false, true)
  SINEW_NK2(true, false, false)
  SINEW_NK2(false, true, true)
  SINEW_NK2(false, true, false)
  SINEW_NK2(false, false, true)
  SINEW_NK2(false, false, false)
#undef SINEW_NK2
#undef SINEW_NK
  SINEW_CUDA_LAUNCHED();
}

template <typename T>
void CudaEngine<T>::launch_tiles(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                                 bool blowup_test, cudaStream_t s, bool programmatic) {
  ElementData<T> ed{elem_nodes_.get(),    row_.get(),           rows_.get(),
                    muscle_offset_.get(), muscle_id_.get(),     muscle_fraction_.get(),
                    muscle_fibre_.get(),  muscle_params_.get(), h_,
                    std::int32_t(e_)};
  NodeData<T> nd{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                 std::int32_t(n_)};
  const StepSums sums = step_sums();
  const ConstraintData<T> program = constraint_data();
  const unsigned g = unsigned(tile_layers_.size());
  constexpr std::size_t bytes = tile_shared_bytes<T>();
  auto go = [&](auto kernel) {
    SINEW_CUDA_CHECK(
        cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes)));
    launch_kernel(kernel, g, kBlock, bytes, s, programmatic, tile_data_, ed, nd, u, sc, up, un,
                  status_.get(), sums, program, node_op_offset_.get(), sc + muscles_, blowup_test);
  };
  const Effects& fx = setup_.effects;
  const bool el = fx.elasticity, mu = fx.muscles, hg = fx.hourglass, gr = fx.gravity;
  const bool pr = program_in_node_;  // else the constraint kernel follows
  // Every effect combination is its own specialised kernel.
#define SINEW_TK(E, M, H, G, P) \
  if (el == E && mu == M && hg == H && gr == G && pr == P) go(tile_kernel<T, E, M, H, G, P>);
#define SINEW_TK2(E, M, H, G) SINEW_TK(E, M, H, G, true) SINEW_TK(E, M, H, G, false)
#define SINEW_TK4(E, M, H) SINEW_TK2(E, M, H, true) SINEW_TK2(E, M, H, false)
  SINEW_TK4(true, true, true)
  SINEW_TK4(true, true, false)
  SINEW_TK4(true, false, true)
  SINEW_TK4(true, false, false)
  SINEW_TK4(false, true, true)
  SINEW_TK4(false, true, false)
  SINEW_TK4(false, false, true)
  SINEW_TK4(false, false, false)
#undef SINEW_TK4
#undef SINEW_TK2
#undef SINEW_TK
  SINEW_CUDA_LAUNCHED();
}

// Per-stage device time of direct (non-graph) steps: events between the stages of launch_step,
// medians over `repeats` steps (state advances; flags checked at the end).
template <typename T>
std::vector<std::pair<std::string, float>> CudaEngine<T>::stage_times(int repeats) {
  std::vector<std::string> names;
  std::vector<std::vector<float>> times;
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
  for (int r = 0; r < repeats; ++r) {
    fill_scalars(step_, 1, int(batch_));
    std::vector<std::pair<std::string, cudaEvent_t>> marks;
    launch_step(step_, int(batch_), stream_, slide_ahead_, true, &marks);
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    if (names.empty()) {
      for (std::size_t k = 1; k < marks.size(); ++k) names.push_back(marks[k].first);
      times.resize(names.size());
    }
    for (std::size_t k = 1; k < marks.size() && k - 1 < times.size(); ++k) {
      float ms = 0;
      SINEW_CUDA_CHECK(cudaEventElapsedTime(&ms, marks[k - 1].second, marks[k].second));
      times[k - 1].push_back(ms);
    }
    for (auto& m : marks) cudaEventDestroy(m.second);
    ++step_;
  }
  std::vector<std::pair<std::string, float>> out;
  for (std::size_t k = 0; k < names.size(); ++k) {
    auto v = times[k];
    std::sort(v.begin(), v.end());
    out.emplace_back(names[k], v[v.size() / 2]);
  }
  return out;
}

template <typename T>
void CudaEngine<T>::build_graph() {
  cudaGraph_t g = nullptr;
  SINEW_CUDA_CHECK(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal));
  try {
    // Phase 0: the batch starts at a step ≡ 0 (mod align_), a multiple of 3 and of the interval.
    for (int k = 0; k < batch_; ++k)
      launch_step(k, k, stream_, slide_ahead_, graph_blowup_ && k % interval_ == 0, nullptr,
                  programmatic_);
  } catch (...) {
    cudaStreamEndCapture(stream_, &g);
    if (g) cudaGraphDestroy(g);
    throw;
  }
  SINEW_CUDA_CHECK(cudaStreamEndCapture(stream_, &g));
  const cudaError_t r = cudaGraphInstantiate(&graph_, g, 0);
  cudaGraphDestroy(g);
  SINEW_CUDA_CHECK(r);
}

template <typename T>
void CudaEngine<T>::snapshot() {
  SINEW_CUDA_CHECK(cudaMemcpyAsync(snap_u_.get(), buffer(step_, 0), n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToDevice, stream_));
  SINEW_CUDA_CHECK(cudaMemcpyAsync(snap_up_.get(), buffer(step_, 2), n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToDevice, stream_));
  if (slide_triangle_.size())
    SINEW_CUDA_CHECK(cudaMemcpyAsync(snap_triangle_.get(), slide_triangle_.get(),
                                     slide_triangle_.bytes(), cudaMemcpyDeviceToDevice, stream_));
  if (work_acc_.size())
    SINEW_CUDA_CHECK(cudaMemcpyAsync(snap_work_acc_.get(), work_acc_.get(), work_acc_.bytes(),
                                     cudaMemcpyDeviceToDevice, stream_));
}

template <typename T>
void CudaEngine<T>::roll_back() {
  SINEW_CUDA_CHECK(cudaMemcpyAsync(buffer(step_, 0), snap_u_.get(), n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToDevice, stream_));
  SINEW_CUDA_CHECK(cudaMemcpyAsync(buffer(step_, 2), snap_up_.get(), n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToDevice, stream_));
  if (slide_triangle_.size())
    SINEW_CUDA_CHECK(cudaMemcpyAsync(slide_triangle_.get(), snap_triangle_.get(),
                                     slide_triangle_.bytes(), cudaMemcpyDeviceToDevice, stream_));
  if (work_acc_.size())
    SINEW_CUDA_CHECK(cudaMemcpyAsync(work_acc_.get(), snap_work_acc_.get(), work_acc_.bytes(),
                                     cudaMemcpyDeviceToDevice, stream_));
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
  if (f_sum_.size()) SINEW_CUDA_CHECK(cudaMemsetAsync(f_sum_.get(), 0, f_sum_.bytes(), stream_));
  forget_slide_lists(stream_);  // lists are a cache: the full search gives the same triangles
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

template <typename T>
std::vector<Vec3<T>> CudaEngine<T>::download_vec(const Vec3<T>* p) const {
  std::vector<Vec3<T>> v(n_);
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  SINEW_CUDA_CHECK(cudaMemcpy(v.data(), p, n_ * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
  return v;
}

template <typename T>
void CudaEngine<T>::upload_vec(Vec3<T>* p, const std::vector<double>& flat) {
  std::vector<Vec3<T>> v(n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d) v[i][d] = T(flat[3 * i + std::size_t(d)]);
  SINEW_CUDA_CHECK(cudaMemcpy(p, v.data(), n_ * sizeof(Vec3<T>), cudaMemcpyHostToDevice));
}

template <typename T>
double CudaEngine<T>::work_sum(const double* acc) const {
  double base = 0;
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  SINEW_CUDA_CHECK(cudaMemcpy(&base, work_base_.get(), sizeof(double), cudaMemcpyDeviceToHost));
  if (!work_) return base;
  std::vector<double> a(n_);
  SINEW_CUDA_CHECK(cudaMemcpy(a.data(), acc, n_ * sizeof(double), cudaMemcpyDeviceToHost));
  double w = 0;
  for (double x : a) w += x;
  return base + w;
}

template <typename T>
double CudaEngine<T>::external_work() const {
  return work_sum(work_acc_.get());
}

template <typename T>
void CudaEngine<T>::fail_jacobian() {
  // Worst element at u(n), chosen as the CPU does: the first NaN, else the smallest J (lowest id).
  const auto u = download_vec(buffer(step_, 0));
  double min_j = std::numeric_limits<double>::infinity();
  std::int64_t worst = -1;
  for (std::size_t e = 0; e < e_; ++e) {
    Vec3<T> ue[8];
    for (int a = 0; a < 8; ++a) ue[a] = u[std::size_t(prep_.element_nodes[e][std::size_t(a)])];
    const double j = double(determinant(physics::hex8_deformation_gradient(ue, h_)));
    if (worst < 0 || (!std::isnan(min_j) && (std::isnan(j) || j < min_j))) {
      min_j = j;
      worst = std::int64_t(e);
    }
  }
  const auto& p = prep_.rest[std::size_t(prep_.element_nodes[std::size_t(worst)][0])];
  const double hh = prep_.h / 2;
  throw InstabilityError(
      "", "simulation",
      format("%s at step %lld, t = %.6g s: element %lld (rest centre (%.6g, %.6g, %.6g) m) "
             "has J = %.6g; Δt = %.6g s. Lower the time step (or its safety factor), "
             "or check the loads",
             std::isnan(min_j) ? "NaN deformation" : "inverted element (J ≤ 0)", (long long)step_,
             time(), (long long)worst, p[0] + hh, p[1] + hh, p[2] + hh, min_j, dt_))
      .at(worst);
}

template <typename T>
void CudaEngine<T>::fail_displacement(const std::vector<Vec3<T>>& un) {
  for (std::size_t i = 0; i < n_; ++i) {
    const auto& v = un[i];
    if (std::isfinite(double(v.x)) && std::isfinite(double(v.y)) && std::isfinite(double(v.z)))
      continue;
    const auto& p = prep_.rest[i];
    throw InstabilityError("", "simulation",
                           format("non-finite displacement (NaN/Inf) at step %lld, t = %.6g s: "
                                  "node %zu (rest position (%.6g, %.6g, %.6g) m); "
                                  "Δt = %.6g s. Lower the time step (or its safety factor), "
                                  "or check the loads",
                                  (long long)(step_ + 1), time() + dt_, i, p[0], p[1], p[2], dt_))
        .at(std::int64_t(i));
  }
  throw InstabilityError("", "simulation",
                         format("non-finite displacement at step %lld", (long long)(step_ + 1)));
}

// One step launched directly, then synchronised and checked: the state stays at the last good
// step when it fails.
template <typename T>
void CudaEngine<T>::run_direct_step() {
  fill_scalars(step_, 1, int(batch_));
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
  launch_step(step_, int(batch_), stream_, false);
  SINEW_CUDA_CHECK(cudaMemcpyAsync(status_host_.get(), status_.get(), sizeof(Status),
                                   cudaMemcpyDeviceToHost, stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const Status st = *status_host_.get();
  if (st.bad_jacobian) {
    // u(n+1) was written to the spare buffer only; u(n), u(n−1) are intact. Undo the work term,
    // the warm starts and the atomic sums of this step (the snapshot holds them).
    roll_back();
    fail_jacobian();
  }
  if (step_ % interval_ == 0) {  // the CPU's order: J, then the energy test, then NaN/Inf
    try {
      check_blowup(work_sum(snap_work_acc_.get()));
    } catch (...) {
      roll_back();
      throw;
    }
  }
  if (st.bad_displacement) {
    const auto un = download_vec(buffer(step_, 1));
    roll_back();
    fail_displacement(un);
  }
  ++step_;
}

template <typename T>
void CudaEngine<T>::step(std::int64_t n) {
  const std::int64_t end = step_ + n;
  while (step_ < end) {
    if (step_ % align_ != 0 || end - step_ < batch_) {
      snapshot();
      run_direct_step();
      continue;
    }
    snapshot();
    fill_scalars(step_, batch_, 0);
    SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
    SINEW_CUDA_CHECK(cudaGraphLaunch(graph_, stream_));
    SINEW_CUDA_CHECK(cudaMemcpyAsync(status_host_.get(), status_.get(), sizeof(Status),
                                     cudaMemcpyDeviceToHost, stream_));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    const Status st = *status_host_.get();
    if (st.slide_miss && !(st.bad_jacobian || st.bad_displacement || st.blowup) &&
        ++slide_miss_batches_ >= 2) {
      // Nodes outrun the lists refreshed ahead: from now on the graph refreshes them twice as
      // often, and once every step did not suffice (nodes moving more than s/2 per step), inline
      // (grid searches on the step's path again). Same results either way.
      if (refresh_interval_ > 1)
        refresh_interval_ /= 2;
      else
        slide_ahead_ = false;
      slide_miss_batches_ = 0;
      cudaGraphExecDestroy(graph_);
      graph_ = nullptr;
      build_graph();
    }
    if (st.bad_jacobian || st.bad_displacement || st.blowup || st.slide_miss) {
      // Replay the batch step by step from the snapshot with the CPU's checks at each step: the
      // failing step throws with the state at the last good step. (Direct steps refresh the
      // sliding lists inline: a slide miss replays to the same results as a run without it.) (A device energy sum that
      // crossed the bound only by its different summation order replays without failing.)
      roll_back();
      for (int k = 0; k < batch_; ++k) {
        snapshot();
        run_direct_step();
      }
      continue;
    }
    step_ += batch_;
    if (!graph_blowup_ && (step_ - batch_) / interval_ != (step_ - 1) / interval_)
      check_blowup(external_work());
  }
}

template <typename T>
double CudaEngine<T>::kinetic_energy(const std::vector<Vec3<T>>& u,
                                     const std::vector<Vec3<T>>& up) const {
  constexpr std::size_t kChunk = 1024;  // the CPU backend's chunked order
  double total = 0;
  const double inv_dt = 1.0 / dt_;
  for (std::size_t c = 0; c * kChunk < n_; ++c) {
    double s = 0;
    for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
      const double vx = (double(u[i].x) - double(up[i].x)) * inv_dt;
      const double vy = (double(u[i].y) - double(up[i].y)) * inv_dt;
      const double vz = (double(u[i].z) - double(up[i].z)) * inv_dt;
      s += 0.5 / double(T(1.0 / prep_.mass[i])) * (vx * vx + vy * vy + vz * vz);
    }
    total += s;
  }
  return total;
}

template <typename T>
void CudaEngine<T>::compute_energy_terms(double& strain, double& hourglass) {
  if (element_energy_.size() != 2 * e_) element_energy_.allocate(2 * e_);
  if (!elem_force_.size()) elem_force_.allocate(e_ * 8);
  std::vector<T> act = activation_at(time());
  DeviceArray<T> a;
  a.upload(act);
  launch_elements(buffer(step_, 0), a.get(), 2, stream_);
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const auto en = element_energy_.download();
  // Summed per collection in element-list order, chunk by chunk (the CPU's order).
  strain = hourglass = 0;
  constexpr std::size_t kChunk = 1024;
  for (const auto& c : plan_.collections) {
    for (std::size_t b = 0; b < c.elements.size(); b += kChunk) {
      double s = 0, hg = 0;
      for (std::size_t i = b; i < std::min(c.elements.size(), b + kChunk); ++i) {
        s += en[2 * std::size_t(c.elements[i])];
        hg += en[2 * std::size_t(c.elements[i]) + 1];
      }
      strain += s;
      hourglass += hg;
    }
  }
}

template <typename T>
Energies CudaEngine<T>::energies() {
  Energies e;
  e.step = step_;
  e.time = time();
  compute_energy_terms(e.strain, e.hourglass);
  e.kinetic = kinetic_energy(download_vec(buffer(step_, 0)), download_vec(buffer(step_, 2)));
  e.external_work = external_work();
  return e;
}

template <typename T>
void CudaEngine<T>::check_blowup(double work) {
  const auto u = download_vec(buffer(step_, 0)), up = download_vec(buffer(step_, 2));
  const double ke = kinetic_energy(u, up);
  double strain = 0, hg = 0;
  compute_energy_terms(strain, hg);
  const double total = ke + strain + hg;
  if (std::isfinite(total) && !(ke > setup_.blowup_factor * blowup_reference(work))) return;
  std::size_t worst = 0;
  double vmax = -1;
  for (std::size_t i = 0; i < n_; ++i) {
    const double v = double(squared_norm(u[i] - up[i]));
    if (v > vmax || std::isnan(v)) {
      vmax = v;
      worst = i;
      if (std::isnan(v)) break;
    }
  }
  const auto& p = prep_.rest[worst];
  throw InstabilityError(
      "", "simulation",
      format("kinetic energy blow-up at step %lld, t = %.6g s: %.6g J > %g × %.6g J "
             "(initial energy + |external work| + active-muscle bound); fastest node %zu "
             "(rest position (%.6g, %.6g, %.6g) m, speed %.6g m/s); Δt = %.6g s. "
             "Lower the time step (or its safety factor)",
             (long long)step_, time(), ke, setup_.blowup_factor, blowup_reference(work), worst,
             p[0], p[1], p[2], std::sqrt(vmax) / dt_, dt_))
      .at(std::int64_t(worst));
}

template <typename T>
std::vector<double> CudaEngine<T>::displacements() const {
  // Frames leave on the copy stream into pinned memory, after the step work queued so far.
  SINEW_CUDA_CHECK(cudaEventRecord(copy_ready_, stream_));
  SINEW_CUDA_CHECK(cudaStreamWaitEvent(copy_stream_, copy_ready_, 0));
  SINEW_CUDA_CHECK(cudaMemcpyAsync(output_.get(), buffer(step_, 0), n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToHost, copy_stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(copy_stream_));
  std::vector<double> out(3 * n_);
  const Vec3<T>* u = output_.get();
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d) out[3 * i + std::size_t(d)] = double(u[i][d]);
  return out;
}

template <typename T>
std::vector<double> CudaEngine<T>::velocities() const {
  const auto u = download_vec(buffer(step_, 0)), up = download_vec(buffer(step_, 2));
  std::vector<double> v(3 * n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d)
      v[3 * i + std::size_t(d)] = (double(u[i][d]) - double(up[i][d])) / dt_;
  return v;
}

template <typename T>
std::vector<double> CudaEngine<T>::internal_forces() {
  if (!elem_force_.size()) elem_force_.allocate(e_ * 8);
  std::vector<T> act = activation_at(time());
  DeviceArray<T> a;
  a.upload(act);
  launch_elements(buffer(step_, 0), a.get(), 0, stream_);
  gather_kernel<T><<<blocks_for(n_), kBlock, 0, stream_>>>(std::int32_t(n_), elem_force_.get(),
                                                           inc_offset_.get(), inc_.get(), f_.get());
  SINEW_CUDA_LAUNCHED();
  const auto f = download_vec(f_.get());
  std::vector<double> out(3 * n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d) out[3 * i + std::size_t(d)] = double(f[i][d]);
  return out;
}

template <typename T>
std::array<double, 3> CudaEngine<T>::reaction(const std::vector<Index>& nodes) {
  std::vector<char> in(n_, 0);
  for (auto nd : nodes) {
    if (nd < 0 || std::size_t(nd) >= n_)
      throw ConfigError("", "reaction", format("node id %d out of range [0, %zu)", int(nd), n_));
    in[std::size_t(nd)] = 1;
  }
  const auto f = internal_forces();
  std::array<double, 3> r{0, 0, 0};
  for (auto nd : nodes) {
    const auto i = std::size_t(nd);
    for (std::size_t d = 0; d < 3; ++d) {
      r[d] += f[3 * i + d];
      if (setup_.effects.gravity) r[d] -= double(T(prep_.gravity[i][d]));
    }
  }
  for (const auto& s : prep_.forces) {
    const double k = s.curve.at(curve_time(time()));
    for (auto nd : s.nodes)
      if (in[std::size_t(nd)])
        for (std::size_t d = 0; d < 3; ++d) r[d] -= k * double(T(s.per_node[d]));
  }
  return r;
}

template <typename T>
ElementFields CudaEngine<T>::element_fields() {
  // Output-interval work: computed on the host from u(n) with the same element_field function.
  const auto u = download_vec(buffer(step_, 0));
  const std::vector<T> act = activation_at(time());
  std::vector<physics::MuscleParams<T>> mp;
  for (const auto& p : prep_.muscle_params)
    mp.push_back({T(p[0]), T(p[1]), T(p[2]), T(p[3]), T(p[4])});
  std::vector<T> mf(prep_.muscle_fraction.begin(), prep_.muscle_fraction.end());
  std::vector<Vec3<T>> fib;
  for (const auto& f : prep_.muscle_fibre) fib.push_back(to_vec<T>(f));
  ElementFields out;
  out.jacobian.resize(e_);
  out.von_mises.resize(e_);
  out.energy_density.resize(e_);
  out.cauchy.resize(e_);
  out.material = prep_.dominant_material;
  const bool el = setup_.effects.elasticity, mus = setup_.effects.muscles;
  const std::int64_t count = std::int64_t(e_);
  for (std::int64_t ei = 0; ei < count; ++ei) {
    const auto e = std::size_t(ei);
    Vec3<T> ue[8];
    for (int a = 0; a < 8; ++a) ue[a] = u[std::size_t(prep_.element_nodes[e][std::size_t(a)])];
    const auto& rr = prep_.rows[std::size_t(prep_.row[e])];
    const physics::ElementRow<T> row{T(rr[0]), T(rr[1]), T(rr[2])};
    physics::MuscleEntries<T> m{
        prep_.muscle_id.data(), mf.data(), fib.data(), mp.data(), act.data(), 0, 0};
    if (mus) {
      m.begin = prep_.muscle_offset[e];
      m.end = prep_.muscle_offset[e + 1];
    }
    T j;
    SymMat3<T> sigma;
    double w = 0;
    if (el && mus)
      physics::element_field<T, true, true>(ue, h_, row, m, j, sigma, w);
    else if (el)
      physics::element_field<T, true, false>(ue, h_, row, m, j, sigma, w);
    else if (mus)
      physics::element_field<T, false, true>(ue, h_, row, m, j, sigma, w);
    else
      physics::element_field<T, false, false>(ue, h_, row, m, j, sigma, w);
    out.jacobian[e] = double(j);
    out.von_mises[e] = double(physics::von_mises(sigma));
    for (int k = 0; k < 6; ++k) out.cauchy[e][std::size_t(k)] = double(sigma.s[k]);
    out.energy_density[e] = w;
  }
  return out;
}

template <typename T>
State CudaEngine<T>::state() const {
  State s;
  s.step = step_;
  s.time = time();
  s.dt = dt_;
  auto flat = [&](const std::vector<Vec3<T>>& v) {
    std::vector<double> o(3 * n_);
    for (std::size_t i = 0; i < n_; ++i)
      for (int d = 0; d < 3; ++d) o[3 * i + std::size_t(d)] = double(v[i][d]);
    return o;
  };
  s.u = flat(download_vec(buffer(step_, 0)));
  s.u_prev = flat(download_vec(buffer(step_, 2)));
  s.sliding_triangle = slide_triangle_.download();
  s.external_work = external_work();
  s.energy_reference = initial_energy_;
  return s;
}

template <typename T>
void CudaEngine<T>::restore(const State& s) {
  if (s.u.size() != 3 * n_ || s.u_prev.size() != 3 * n_)
    throw ConfigError("", "state.u",
                      format("state has %zu values, the model needs %zu", s.u.size(), 3 * n_));
  if (s.dt != dt_)
    throw ConfigError("", "state.dt",
                      format("state written with Δt = %.17g s, this run has %.17g s", s.dt, dt_));
  if (s.sliding_triangle.size() != slide_triangle_.size())
    throw ConfigError("", "state.sliding_triangle",
                      format("%zu entries, this run has %zu sliding nodes",
                             s.sliding_triangle.size(), slide_triangle_.size()));
  if (s.step < 0) throw ConfigError("", "state.step", "negative step");
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  step_ = s.step;
  upload_vec(buffer(step_, 0), s.u);
  upload_vec(buffer(step_, 2), s.u_prev);
  if (!s.sliding_triangle.empty()) {
    SINEW_CUDA_CHECK(cudaMemcpy(slide_triangle_.get(), s.sliding_triangle.data(),
                                slide_triangle_.bytes(), cudaMemcpyHostToDevice));
    SINEW_CUDA_CHECK(cudaMemcpy(slide_search_triangle_.get(), s.sliding_triangle.data(),
                                slide_search_triangle_.bytes(), cudaMemcpyHostToDevice));
  }
  SINEW_CUDA_CHECK(
      cudaMemcpy(work_base_.get(), &s.external_work, sizeof(double), cudaMemcpyHostToDevice));
  if (work_acc_.size()) work_acc_.zero();
  if (f_sum_.size()) f_sum_.zero();
  forget_slide_lists(stream_);
  SINEW_CUDA_CHECK(cudaDeviceSynchronize());
  initial_energy_ = s.energy_reference;
  update_bound();
}

template <typename T>
std::vector<float> CudaEngine<T>::timed_graph_launches(int launches) {
  while (step_ % align_ != 0) step(1);
  cudaEvent_t a, b;
  SINEW_CUDA_CHECK(cudaEventCreate(&a));
  SINEW_CUDA_CHECK(cudaEventCreate(&b));
  std::vector<float> ms;
  fill_scalars(step_, batch_, 0);
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
  for (int k = 0; k < launches; ++k) {
    SINEW_CUDA_CHECK(cudaEventRecord(a, stream_));
    SINEW_CUDA_CHECK(cudaGraphLaunch(graph_, stream_));
    SINEW_CUDA_CHECK(cudaEventRecord(b, stream_));
    SINEW_CUDA_CHECK(cudaEventSynchronize(b));
    float t = 0;
    SINEW_CUDA_CHECK(cudaEventElapsedTime(&t, a, b));
    ms.push_back(t);
    step_ += batch_;
  }
  SINEW_CUDA_CHECK(
      cudaMemcpy(status_host_.get(), status_.get(), sizeof(Status), cudaMemcpyDeviceToHost));
  cudaEventDestroy(a);
  cudaEventDestroy(b);
  if (status_host_.get()->bad_jacobian || status_host_.get()->bad_displacement)
    throw InstabilityError(
        "", "simulation",
        format("unstable during the timed steps (before step %lld)", (long long)step_));
  if (status_host_.get()->slide_miss)
    throw Error("", "sliding",
                "a sliding node left its candidate list during the timed steps (the timed "
                "results are not exact); time with a larger sliding_skin");
  return ms;
}

template <typename T>
double CudaEngine<T>::bytes_per_step() const {
  // Elements: 32 B of node ids + row id + (u of 8 nodes, shared with neighbours: counted once per
  // node below) + forces written (gather: 8 × 3 T) ; nodes: u, u(n−1) read, u(n+1) written,
  // inverse mass, incidence (gather: offsets + 8 entries per element read back) ...
  const double t = sizeof(T);
  double b = double(e_) * (32 + 4 + 4);            // node ids, collection list, row id
  b += double(n_) * (3 * t) * 3 + double(n_) * t;  // u, u(n−1), u(n+1), 1/M
  if (options_.assembly == ForceAssembly::tiled)
    b -= double(e_) * 36;  // no node-id lists and collection lists: the tile tables (below)
  if (options_.assembly == ForceAssembly::tiled)
    b += double(tile_window_.bytes() + tile_slot_.bytes() + tile_layers_.bytes());
  else if (options_.assembly == ForceAssembly::gather)
    b += double(e_) * 8 * 3 * t * 2 + double(e_) * 8 * 4 +
         double(n_) * 4;  // forces out + in, incidence
  else
    b += double(n_) * 3 * t * 2;  // atomic sums read and cleared (the adds hit L2)
  if (setup_.effects.gravity) b += double(n_) * 3 * t;
  if (setup_.effects.muscles)
    b += double(prep_.muscle_id.size()) * (4 + t + 3 * t) + double(e_) * 4;
  // Sliding nodes (constraint program, listed path): node id, offsets, op, surface, rest distance,
  // triangle read + written, list count, anchor, u(n+1) read + written, rest, the first two listed
  // ids and distances (most nodes test their warm start only; the triangles' corners come from L2
  // and are not counted).
  b += double(prep_.slide_node.size()) *
       (4 + 4 + 4 + 4 + t + 8 + 4 + 3 * t + 6 * t + 3 * t + 8 + 2 * t);
  return b;
}

}  // namespace

bool cuda_device_available() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();
    return false;
  }
  return count > 0;
}

std::string cuda_device_name() {
  if (!cuda_device_available()) return "";
  cudaDeviceProp p{};
  SINEW_CUDA_CHECK(cudaGetDeviceProperties(&p, 0));
  return format("%s (sm_%d%d, %d SMs, %.1f GiB)", p.name, p.major, p.minor, p.multiProcessorCount,
                double(p.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0));
}

namespace detail {
std::unique_ptr<Backend> make_cuda_engine(const formats::Model& model, const Setup& setup,
                                          Plan plan, const CudaOptions& options) {
  if (setup.precision == Precision::float32)
    return std::make_unique<CudaEngine<float>>(model, setup, std::move(plan), options);
  return std::make_unique<CudaEngine<double>>(model, setup, std::move(plan), options);
}
}  // namespace detail

double measure_copy_bandwidth(std::size_t bytes, int repeats) {
  DeviceArray<char> a, b;
  a.allocate(bytes);
  b.allocate(bytes);
  SINEW_CUDA_CHECK(cudaMemset(a.get(), 1, bytes));
  cudaEvent_t e0, e1;
  SINEW_CUDA_CHECK(cudaEventCreate(&e0));
  SINEW_CUDA_CHECK(cudaEventCreate(&e1));
  std::vector<float> ms;
  for (int k = 0; k < repeats + 3; ++k) {
    SINEW_CUDA_CHECK(cudaEventRecord(e0));
    SINEW_CUDA_CHECK(cudaMemcpy(b.get(), a.get(), bytes, cudaMemcpyDeviceToDevice));
    SINEW_CUDA_CHECK(cudaEventRecord(e1));
    SINEW_CUDA_CHECK(cudaEventSynchronize(e1));
    float t = 0;
    SINEW_CUDA_CHECK(cudaEventElapsedTime(&t, e0, e1));
    if (k >= 3) ms.push_back(t);
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  return 2.0 * double(bytes) / (double(ms[ms.size() / 2]) * 1e-3);
}

}  // namespace sinew::simulator
