// CUDA backend: kernels are thin entry points (index -> physics/element.hpp call); the host class
// mirrors CpuEngine's step, checks and state. Design and measurements: docs/cuda-backend.md.
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
  return s[0];
}

// printf-style formatting for messages (fmt's compile-time format strings do not pass nvcc).
template <typename... A>
std::string format(const char* f, A... a) {
  const int n = std::snprintf(nullptr, 0, f, a...);
  std::string s(std::size_t(n > 0 ? n : 0), '\0');
  std::snprintf(s.data(), s.size() + 1, f, a...);
  return s;
}
inline unsigned blocks_for(std::size_t n) {
  return unsigned((n + kBlock - 1) / kBlock);
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
  Vec3<T> ue[8];
#pragma unroll
  for (int a = 0; a < 8; ++a) ue[a] = u[ids[a]];
  const physics::ElementRow<T> row = d.rows[d.row[e]];
  physics::MuscleEntries<T> m{
      d.muscle_id, d.muscle_fraction, d.muscle_fibre, d.muscle_params, activation, 0, 0};
  if constexpr (kMuscle) {
    m.begin = d.muscle_offset[e];
    m.end = d.muscle_offset[e + 1];
  }
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

// Gather (or read and clear the atomic sums) + central-difference update + finite check.
template <typename T, bool kGather, bool kGravity>
__global__ void __launch_bounds__(kBlock)
    node_kernel(NodeData<T> d, const Vec3<T>* __restrict__ element_force,
                Vec3<T>* __restrict__ f_sum, const Vec3<T>* __restrict__ u,
                const Vec3<T>* __restrict__ up, Vec3<T>* __restrict__ un, Status* status) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= d.n) return;
  Vec3<T> f;
  if constexpr (kGather) {
    f = physics::gather_node_force(element_force, d.inc, d.offset[i], d.offset[i + 1]);
  } else {
    f = f_sum[i];
    f_sum[i] = Vec3<T>{T(0), T(0), T(0)};
  }
  Vec3<T> g{T(0), T(0), T(0)};
  if constexpr (kGravity) g = d.gravity[i];
  const Vec3<T> v = physics::node_update<T, kGravity>(d.cd, d.inverse_mass[i], f, g, u[i], up[i]);
  un[i] = v;
  if (!(isfinite(v.x) && isfinite(v.y) && isfinite(v.z))) status->bad_displacement = 1;
}

// Nodal forces of one set: u(n+1) += A · factor · per_node.
template <typename T>
__global__ void force_kernel(const std::int32_t* nodes, std::int32_t count, const T* inverse_mass,
                             physics::CentralDifference<T> cd, Vec3<T> per_node, const T* factor,
                             Vec3<T>* un) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= count) return;
  const std::int32_t i = nodes[k];
  physics::add_nodal_force(cd, inverse_mass[i], *factor * per_node, un[i]);
}

template <typename T>
__global__ void capture_kernel(const std::int32_t* nodes, std::int32_t count, const Vec3<T>* un,
                               Vec3<T>* out) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k < count) out[k] = un[nodes[k]];
}

template <typename T>
__global__ void sliding_kernel(const std::int32_t* nodes, const std::int32_t* surface,
                               const T* distance, std::int32_t* triangle, std::int32_t count,
                               const SurfaceView<T>* views, const Vec3<T>* rest, Vec3<T>* un) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= count) return;
  const std::int32_t i = nodes[k];
  std::int32_t t = triangle[k];
  un[i] = physics::slide_node(views[surface[k]], rest[i], un[i], distance[k], t);
  triangle[k] = t;
}

// One thread per constrained node applies its planes in the order listed (as the CPU loop does):
// a node on several planes (an edge of symmetry planes) must not race with itself.
template <typename T>
__global__ void plane_kernel(const std::int32_t* nodes, const std::int32_t* offset,
                             const Vec3<T>* normals, std::int32_t count, Vec3<T>* un) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= count) return;
  Vec3<T> v = un[nodes[k]];
  for (std::int32_t q = offset[k]; q < offset[k + 1]; ++q)
    v = physics::project_to_plane(v, normals[q]);
  un[nodes[k]] = v;
}

// Kinetic energy ½ Σ M |v|², v = (u − u(n−1))/Δt, in double: block sums in a fixed tree order.
template <typename T>
__global__ void __launch_bounds__(kBlock)
    kinetic_kernel(std::int32_t n, const T* inverse_mass, const Vec3<T>* u, const Vec3<T>* up,
                   double inv_dt, double* partial) {
  __shared__ double s[kBlock];
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  double e = 0;
  if (i < n) {
    const double vx = (double(u[i].x) - double(up[i].x)) * inv_dt;
    const double vy = (double(u[i].y) - double(up[i].y)) * inv_dt;
    const double vz = (double(u[i].z) - double(up[i].z)) * inv_dt;
    e = 0.5 / double(inverse_mass[i]) * (vx * vx + vy * vy + vz * vz);
  }
  const double sum = block_sum(e, s, int(threadIdx.x));
  if (threadIdx.x == 0) partial[blockIdx.x] = sum;
}

__global__ void __launch_bounds__(kBlock)
    blowup_kernel(const double* partial, int count, const double* work, const BlowupBound* bound,
                  Status* status) {
  __shared__ double s[kBlock];
  double w = 0;
  for (int k = int(threadIdx.x); k < count; k += kBlock) w += partial[k];
  const double sum = block_sum(w, s, int(threadIdx.x));
  if (threadIdx.x == 0) {
    const double ke = sum;
    if (!isfinite(ke) || ke > bound->factor * (bound->base + fabs(*work))) status->blowup = 1;
  }
}

template <typename T>
__global__ void prescribe_kernel(const std::int32_t* nodes, std::int32_t count, Vec3<T> value,
                                 bool cx, bool cy, bool cz, const T* factor, Vec3<T>* un) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= count) return;
  const bool comps[3] = {cx, cy, cz};
  physics::prescribe(*factor, value, comps, un[nodes[k]]);
}

template <typename T>
__global__ void rigid_kernel(const std::int32_t* nodes, std::int32_t count, Vec3<T>* un) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k < count) un[nodes[k]] = Vec3<T>{T(0), T(0), T(0)};
}

// External work of one step, centred: Σ R · (u(n+1) − u(n−1)) / 2 over gravity (every node),
// nodal-force entries and prescribed entries (constraint force (u − u*)/A). Per-block sums in a
// fixed tree order, then one block adds the block sums in order: deterministic.
template <typename T>
struct WorkData {
  std::int32_t n_gravity;  // N or 0
  const Vec3<T>* gravity;
  std::int32_t n_force;
  const std::int32_t* force_node;
  const std::int32_t* force_set;
  const Vec3<T>* force_per_node;  // per set
  std::int32_t n_prescribed;
  const std::int32_t* prescribed_node;
  const Vec3<T>* prescribed_free;
  const T* inverse_mass;
  double a_over_inverse_mass;
};

template <typename T>
__global__ void __launch_bounds__(kBlock)
    work_kernel(WorkData<T> d, const T* force_factor, const Vec3<T>* un, const Vec3<T>* up,
                double* partial) {
  __shared__ double s[kBlock];
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  double w = 0;
  if (k < d.n_gravity) {
    for (int c = 0; c < 3; ++c)
      w += double(d.gravity[k][c]) * 0.5 * (double(un[k][c]) - double(up[k][c]));
  } else if (k < d.n_gravity + d.n_force) {
    const std::int32_t q = k - d.n_gravity, i = d.force_node[q], set = d.force_set[q];
    const double f = double(force_factor[set]);
    for (int c = 0; c < 3; ++c)
      w += f * double(d.force_per_node[set][c]) * 0.5 * (double(un[i][c]) - double(up[i][c]));
  } else if (k < d.n_gravity + d.n_force + d.n_prescribed) {
    const std::int32_t q = k - d.n_gravity - d.n_force, i = d.prescribed_node[q];
    const double a = d.a_over_inverse_mass * double(d.inverse_mass[i]);
    for (int c = 0; c < 3; ++c) {
      const double fc = (double(un[i][c]) - double(d.prescribed_free[q][c])) / a;
      w += fc * 0.5 * (double(un[i][c]) - double(up[i][c]));
    }
  }
  const double sum = block_sum(w, s, int(threadIdx.x));
  if (threadIdx.x == 0) partial[blockIdx.x] = sum;
}

__global__ void __launch_bounds__(kBlock)
    work_total_kernel(const double* partial, int count, double* total) {
  __shared__ double s[kBlock];
  double w = 0;
  for (int k = int(threadIdx.x); k < count; k += kBlock) w += partial[k];
  const double sum = block_sum(w, s, int(threadIdx.x));
  if (threadIdx.x == 0) *total += sum;
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
  DeviceArray<Vec3<T>> entry_corners, cell_boxes;
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

 private:
  Vec3<T>* buffer(std::int64_t step, int role) const {  // role 0: u(n), 1: u(n+1), 2: u(n−1)
    return buf_[std::size_t((step + role) % 3)].get();
  }
  double curve_time(double t) const { return t / setup_.time_scaling; }
  void fill_scalars(std::int64_t first_step, int count, int slot0);
  void launch_elements(const Vec3<T>* u, const T* activation, int mode, cudaStream_t s);
  void launch_step(std::int64_t step, int slot, cudaStream_t s, bool blowup_test = false,
                   std::vector<std::pair<std::string, cudaEvent_t>>* marks = nullptr);
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
  std::vector<DeviceArray<std::int32_t>> force_nodes_, prescribed_nodes_;
  DeviceArray<std::int32_t> force_node_all_, force_set_all_, prescribed_node_all_;
  DeviceArray<Vec3<T>> force_per_node_, prescribed_free_;
  std::vector<std::size_t> prescribed_start_;
  DeviceArray<std::int32_t> plane_nodes_, plane_offset_, rigid_;
  DeviceArray<Vec3<T>> plane_normals_;
  // kinetic-energy blow-up test inside graphs (at steps ≡ 0 mod energy_interval)
  int interval_ = 10;
  std::int64_t align_ = 3;  // graphs start at steps ≡ 0 mod align_ (3, or lcm(3, interval))
  bool graph_blowup_ = false;
  DeviceArray<double> ke_partial_;
  DeviceArray<BlowupBound> bound_;
  std::vector<std::unique_ptr<DeviceSurface<T>>> surfaces_;
  DeviceArray<SurfaceView<T>> views_;
  DeviceArray<std::int32_t> slide_node_, slide_surface_, slide_triangle_, snap_triangle_;
  DeviceArray<T> slide_distance_;
  bool work_ = false;
  std::size_t work_items_ = 0;
  DeviceArray<double> work_partial_, work_total_;
  double snap_work_ = 0;
  // status and output
  DeviceArray<Status> status_;
  PinnedArray<Status> status_host_;
  mutable PinnedArray<Vec3<T>> output_;
};

template <typename T>
CudaEngine<T>::CudaEngine(const formats::Model& model, const Setup& setup, Plan plan,
                          const CudaOptions& options)
    : setup_(setup), plan_(std::move(plan)), options_(options) {
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
  if (options.assembly == ForceAssembly::gather) {
    elem_force_.allocate(e_ * 8);
  } else {
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

  // Loads and constraints.
  std::vector<std::int32_t> fn_all, fs_all, pn_all;
  std::vector<Vec3<T>> fpn;
  for (std::size_t s = 0; s < prep_.forces.size(); ++s) {
    force_nodes_.emplace_back();
    force_nodes_.back().upload(to_i32(prep_.forces[s].nodes));
    for (auto nd : prep_.forces[s].nodes) {
      fn_all.push_back(nd);
      fs_all.push_back(std::int32_t(s));
    }
    fpn.push_back(to_vec<T>(prep_.forces[s].per_node));
  }
  for (const auto& p : prep_.prescribed) {
    prescribed_start_.push_back(pn_all.size());
    prescribed_nodes_.emplace_back();
    prescribed_nodes_.back().upload(to_i32(p.nodes));
    for (auto nd : p.nodes) pn_all.push_back(nd);
  }
  force_node_all_.upload(fn_all);
  force_set_all_.upload(fs_all);
  force_per_node_.upload(fpn);
  prescribed_node_all_.upload(pn_all);
  prescribed_free_.allocate(pn_all.size());
  {
    // Planes grouped by node, nodes in order of first appearance, each node's planes in list order.
    std::vector<std::int32_t> order;
    std::vector<std::vector<std::size_t>> entries(n_);
    for (std::size_t k = 0; k < prep_.plane_nodes.size(); ++k) {
      const auto nd = std::size_t(prep_.plane_nodes[k]);
      if (entries[nd].empty()) order.push_back(std::int32_t(nd));
      entries[nd].push_back(k);
    }
    std::vector<std::int32_t> offset{0};
    std::vector<Vec3<T>> pn;
    for (auto nd : order) {
      for (auto k : entries[std::size_t(nd)]) pn.push_back(to_vec<T>(prep_.plane_normals[k]));
      offset.push_back(std::int32_t(pn.size()));
    }
    plane_nodes_.upload(order);
    plane_offset_.upload(offset);
    plane_normals_.upload(pn);
  }
  rigid_.upload(to_i32(prep_.rigid));
  if (!prep_.surfaces.empty()) {
    std::vector<SurfaceView<T>> views;
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
      views.push_back(view);
      surfaces_.push_back(std::move(ds));
    }
    views_.upload(views);
    slide_node_.upload(to_i32(prep_.slide_node));
    slide_surface_.upload(prep_.slide_surface);
    slide_triangle_.upload(prep_.slide_triangle);
    snap_triangle_.allocate(prep_.slide_triangle.size());
    std::vector<T> d(prep_.slide_distance.begin(), prep_.slide_distance.end());
    slide_distance_.upload(d);
  }
  work_ = fx.gravity || !fn_all.empty() || !pn_all.empty();
  work_items_ = (fx.gravity ? n_ : 0) + fn_all.size() + pn_all.size();
  work_partial_.allocate(std::max<std::size_t>(1, blocks_for(work_items_)));
  work_total_.allocate(1);
  work_total_.zero();

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
    if (slide_node_.size())
      sliding_kernel<T><<<blocks_for(slide_node_.size()), kBlock, 0, stream_>>>(
          slide_node_.get(), slide_surface_.get(), slide_distance_.get(), slide_triangle_.get(),
          std::int32_t(slide_node_.size()), views_.get(), rest_.get(), u0);
    if (plane_nodes_.size())
      plane_kernel<T><<<blocks_for(plane_nodes_.size()), kBlock, 0, stream_>>>(
          plane_nodes_.get(), plane_offset_.get(), plane_normals_.get(),
          std::int32_t(plane_nodes_.size()), u0);
    for (std::size_t s = 0; s < prep_.prescribed.size(); ++s) {
      const auto& p = prep_.prescribed[s];
      prescribe_kernel<T><<<blocks_for(p.nodes.size()), kBlock, 0, stream_>>>(
          prescribed_nodes_[s].get(), std::int32_t(p.nodes.size()), to_vec<T>(p.per_node),
          p.components[0], p.components[1], p.components[2],
          sc + muscles_ + prep_.forces.size() + s, u0);
    }
    if (rigid_.size())
      rigid_kernel<T><<<blocks_for(rigid_.size()), kBlock, 0, stream_>>>(
          rigid_.get(), std::int32_t(rigid_.size()), u0);
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
  ke_partial_.allocate(std::max<std::size_t>(1, blocks_for(n_)));
  bound_.upload({BlowupBound{0, 0}});
  update_bound();
  build_graph();
}

template <typename T>
CudaEngine<T>::~CudaEngine() {
  if (graph_) cudaGraphExecDestroy(graph_);
  if (copy_ready_) cudaEventDestroy(copy_ready_);
  if (stream_) cudaStreamDestroy(stream_);
  if (copy_stream_) cudaStreamDestroy(copy_stream_);
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
void CudaEngine<T>::launch_elements(const Vec3<T>* u, const T* activation, int mode,
                                    cudaStream_t s) {
  ElementData<T> d{elem_nodes_.get(),    row_.get(),           rows_.get(),
                   muscle_offset_.get(), muscle_id_.get(),     muscle_fraction_.get(),
                   muscle_fibre_.get(),  muscle_params_.get(), h_,
                   std::int32_t(e_)};
  const bool el = setup_.effects.elasticity, hg = setup_.effects.hourglass;
  Vec3<T>* out = mode == 1 ? f_sum_.get() : elem_force_.get();
  for (const auto& c : collections_) {
    const auto count = std::int32_t(c.elements.size());
    const unsigned g = blocks_for(c.elements.size());
    auto go = [&](auto kernel) {
      kernel<<<g, kBlock, 0, s>>>(d, c.elements.get(), count, u, activation, out,
                                  element_energy_.get(), status_.get());
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
  }
}

template <typename T>
void CudaEngine<T>::launch_step(std::int64_t step, int slot, cudaStream_t s, bool blowup_test,
                                std::vector<std::pair<std::string, cudaEvent_t>>* marks) {
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
  if (blowup_test) {
    const unsigned kb = blocks_for(n_);
    kinetic_kernel<T><<<kb, kBlock, 0, s>>>(std::int32_t(n_), inverse_mass_.get(), u, up, 1.0 / dt_,
                                            ke_partial_.get());
    blowup_kernel<<<1, kBlock, 0, s>>>(ke_partial_.get(), int(kb), work_total_.get(), bound_.get(),
                                       status_.get());
    mark("kinetic-energy test (every energy_interval steps)");
  }
  const T* sc = scalars_.get() + scalars_per_slot_ * std::size_t(slot);
  const bool gather = options_.assembly == ForceAssembly::gather;
  launch_elements(u, sc, gather ? 0 : 1, s);
  mark("elements: F, S (+ muscles), forces, hourglass");
  NodeData<T> nd{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                 std::int32_t(n_)};
  const unsigned g = blocks_for(n_);
  const bool grav = setup_.effects.gravity;
  if (gather && grav)
    node_kernel<T, true, true>
        <<<g, kBlock, 0, s>>>(nd, elem_force_.get(), f_sum_.get(), u, up, un, status_.get());
  else if (gather)
    node_kernel<T, true, false>
        <<<g, kBlock, 0, s>>>(nd, elem_force_.get(), f_sum_.get(), u, up, un, status_.get());
  else if (grav)
    node_kernel<T, false, true>
        <<<g, kBlock, 0, s>>>(nd, elem_force_.get(), f_sum_.get(), u, up, un, status_.get());
  else
    node_kernel<T, false, false>
        <<<g, kBlock, 0, s>>>(nd, elem_force_.get(), f_sum_.get(), u, up, un, status_.get());
  SINEW_CUDA_LAUNCHED();
  mark("nodes: force gather + central-difference update");
  for (std::size_t k = 0; k < prep_.forces.size(); ++k) {
    const auto cnt = force_nodes_[k].size();
    force_kernel<T><<<blocks_for(cnt), kBlock, 0, s>>>(
        force_nodes_[k].get(), std::int32_t(cnt), inverse_mass_.get(), cd_,
        to_vec<T>(prep_.forces[k].per_node), sc + muscles_ + k, un);
  }
  if (!prep_.forces.empty()) mark("nodal forces");
  if (prescribed_node_all_.size())
    capture_kernel<T><<<blocks_for(prescribed_node_all_.size()), kBlock, 0, s>>>(
        prescribed_node_all_.get(), std::int32_t(prescribed_node_all_.size()), un,
        prescribed_free_.get());
  if (slide_node_.size())
    sliding_kernel<T><<<blocks_for(slide_node_.size()), kBlock, 0, s>>>(
        slide_node_.get(), slide_surface_.get(), slide_distance_.get(), slide_triangle_.get(),
        std::int32_t(slide_node_.size()), views_.get(), rest_.get(), un);
  if (slide_node_.size()) mark("sliding");
  if (plane_nodes_.size())
    plane_kernel<T><<<blocks_for(plane_nodes_.size()), kBlock, 0, s>>>(
        plane_nodes_.get(), plane_offset_.get(), plane_normals_.get(),
        std::int32_t(plane_nodes_.size()), un);
  for (std::size_t k = 0; k < prep_.prescribed.size(); ++k) {
    const auto& p = prep_.prescribed[k];
    prescribe_kernel<T><<<blocks_for(p.nodes.size()), kBlock, 0, s>>>(
        prescribed_nodes_[k].get(), std::int32_t(p.nodes.size()), to_vec<T>(p.per_node),
        p.components[0], p.components[1], p.components[2], sc + muscles_ + prep_.forces.size() + k,
        un);
  }
  if (rigid_.size())
    rigid_kernel<T><<<blocks_for(rigid_.size()), kBlock, 0, s>>>(rigid_.get(),
                                                                 std::int32_t(rigid_.size()), un);
  mark("planes, prescribed, rigid");
  if (work_) {
    WorkData<T> w{setup_.effects.gravity ? std::int32_t(n_) : 0,
                  gravity_.get(),
                  std::int32_t(force_node_all_.size()),
                  force_node_all_.get(),
                  force_set_all_.get(),
                  force_per_node_.get(),
                  std::int32_t(prescribed_node_all_.size()),
                  prescribed_node_all_.get(),
                  prescribed_free_.get(),
                  inverse_mass_.get(),
                  double(cd_.a_over_inverse_mass)};
    const unsigned wb = blocks_for(work_items_);
    work_kernel<T><<<wb, kBlock, 0, s>>>(w, sc + muscles_, un, up, work_partial_.get());
    work_total_kernel<<<1, kBlock, 0, s>>>(work_partial_.get(), int(wb), work_total_.get());
    mark("external work");
  }
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
    launch_step(step_, int(batch_), stream_, true, &marks);
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
      launch_step(k, k, stream_, graph_blowup_ && k % interval_ == 0);
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
  snap_work_ = external_work();
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
  SINEW_CUDA_CHECK(cudaMemcpyAsync(work_total_.get(), &snap_work_, sizeof(double),
                                   cudaMemcpyHostToDevice, stream_));
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(Status), stream_));
  if (f_sum_.size()) SINEW_CUDA_CHECK(cudaMemsetAsync(f_sum_.get(), 0, f_sum_.bytes(), stream_));
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
double CudaEngine<T>::external_work() const {
  double w = 0;
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  SINEW_CUDA_CHECK(cudaMemcpy(&w, work_total_.get(), sizeof(double), cudaMemcpyDeviceToHost));
  return w;
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
                                  "Δt = %.6g s",
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
  launch_step(step_, int(batch_), stream_);
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
      check_blowup(snap_work_);
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
    if (st.bad_jacobian || st.bad_displacement || st.blowup) {
      // Replay the batch step by step from the snapshot with the CPU's checks at each step: the
      // failing step throws with the state at the last good step. (A device energy sum that
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
  if (!s.sliding_triangle.empty())
    SINEW_CUDA_CHECK(cudaMemcpy(slide_triangle_.get(), s.sliding_triangle.data(),
                                slide_triangle_.bytes(), cudaMemcpyHostToDevice));
  SINEW_CUDA_CHECK(
      cudaMemcpy(work_total_.get(), &s.external_work, sizeof(double), cudaMemcpyHostToDevice));
  if (f_sum_.size()) f_sum_.zero();
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
  if (options_.assembly == ForceAssembly::gather)
    b += double(e_) * 8 * 3 * t * 2 + double(e_) * 8 * 4 +
         double(n_) * 4;  // forces out + in, incidence
  else
    b += double(n_) * 3 * t * 2;  // atomic sums read and cleared (the adds hit L2)
  if (setup_.effects.gravity) b += double(n_) * 3 * t;
  if (setup_.effects.muscles)
    b += double(prep_.muscle_id.size()) * (4 + t + 3 * t) + double(e_) * 4;
  b += double(prep_.slide_node.size()) * (4 + 4 + t + 4 + 2 * 3 * t);
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
