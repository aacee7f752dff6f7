#pragma once
// The CUDA engine: storage (device arrays, streams, the captured step graph) and scheduling (which
// kernel runs when, graph batches, replays) of the loop bodies in passes/, around the shared
// BackendCore (backend_core.hpp), which holds every host-side rule: the per-step scalars, the
// checks and their messages, the blow-up bound, restore checks. Design and measurements:
// docs/cuda-backend.md. Its members are defined in cuda_engine.cu (set-up), cuda_engine_step.cu
// (launches and the step loop) and cuda_engine_state.cu (queries and state).
#include <cuda_runtime.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/backend_core.hpp"
#include "sinew/simulator/engine/cuda/device_array.cuh"
#include "sinew/simulator/engine/cuda/launch.cuh"
#include "sinew/simulator/engine/cuda/tile_kernel.cuh"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/passes/constraint_program.hpp"

namespace sinew::simulator::cuda {

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
  const Plan& plan() const override { return core_.plan(); }
  void step(std::int64_t n) override;
  std::int64_t step_index() const override { return step_; }
  double time() const override { return core_.time(step_); }
  double dt() const override { return core_.dt(); }
  State state() const override;
  void restore(const State& s) override;
  std::vector<double> displacements() const override;
  std::vector<double> displacements(const std::vector<Index>& nodes) const override;
  std::vector<double> velocities() const override;
  std::vector<double> internal_forces() override;
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override;
  Energies energies() override;
  ElementFields element_fields() override;
  // Steering (docs/live.md): activation overrides reach the rows step() stages from the core.
  void set_activation_override(std::size_t m, std::optional<double> a) override {
    core_.set_activation_override(m, a, step_);
  }
  std::optional<double> activation_override(std::size_t m) const override {
    return core_.activation_override(m);
  }
  // Live force slots (docs/live.md): the core's program rebuilt and uploaded between calls; a new
  // node set recaptures the step graphs, a new force alone overwrites the per-set forces in place.
  std::size_t force_slot_count() const override { return core_.force_slot_count(); }
  void set_force_slot(std::size_t k, const std::vector<Index>& nodes,
                      const std::array<double, 3>& force) override;
  void clear_force_slot(std::size_t k) override;
  Frame frame(bool with_fields) override;
  bool host_idle_while_stepping() const override { return true; }

  // step() queues this many graph batches' worth of steps between host synchronisations.
  static constexpr int kQueuedBatches = 8;
  std::int64_t preferred_step_count() const override {
    return std::int64_t(kQueuedBatches) * batch_;
  }

  std::vector<float> timed_graph_launches(int launches) override;
  int graph_steps() const override { return batch_; }
  double bytes_per_step() const override;
  ForceAssembly assembly() const override { return options_.assembly; }

 private:
  Vec3<T>* buffer(std::int64_t step, int role) const {  // role 0: u(n), 1: u(n+1), 2: u(n−1)
    return buf_[std::size_t((step + role) % 3)].get();
  }
  void fill_scalars(std::int64_t first_step, int count, int slot0);
  void launch_elements(const Vec3<T>* u, const T* activation, int mode, cudaStream_t s,
                       bool programmatic = false);
  // energy_flag: the step's row flag of the blow-up test (null: no test in this launch).
  void launch_nodes(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                    const T* energy_flag, cudaStream_t s, bool programmatic = false);
  void launch_tiles(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                    const T* energy_flag, cudaStream_t s, bool programmatic = false);
  // ahead: the lists were refreshed from u(n) by slide_refresh_kernel (launch_step).
  // programmatic: a programmatic dependent launch (launch_kernel), as for the launches below.
  // lists_ready: no list refresh was forked for this step (constraint_kernel).
  // u: u(n) (the lips' contact reads its partners there).
  void launch_constraints(const T* factor, bool loads, Vec3<T>* un, const Vec3<T>* up,
                          const Vec3<T>* u, cudaStream_t s, bool ahead, bool programmatic = false,
                          bool lists_ready = false);
  // The sliding lists from u(n) for step n (anchors kept within s/2: slide_refresh_kernel).
  void launch_refresh(const Vec3<T>* u, cudaStream_t s);
  // ahead: sliding lists refreshed ahead on slide_stream_ (graph steps, stage timing); direct
  // steps refresh inline and never miss. programmatic: the kernels that follow a kernel in s are
  // programmatic dependent launches (graph steps with programmatic_). energy_tests: the kinetic
  // energy blow-up test runs where the slot's row flags it (steps ≡ 0 mod the energy interval).
  void launch_step(std::int64_t step, int slot, cudaStream_t s, bool ahead_slide,
                   bool energy_tests = false,
                   std::vector<std::pair<std::string, cudaEvent_t>>* marks = nullptr,
                   bool programmatic = false);
  std::vector<std::pair<std::string, float>> stage_times(int repeats) override;
  // ahead: the sliding lists refreshed ahead of the steps (slide_ahead_), else inline. reads_flags:
  // every step reads its energy test flag (else only slots ≡ 0 mod interval_ test, unread).
  cudaGraphExec_t capture_steps(int count, bool ahead, bool reads_flags);
  void build_graph();
  void destroy_graphs() {
    for (GraphSet* set : {&graphs_, &inline_graphs_}) {
      for (cudaGraphExec_t g : set->shorter)
        if (g) cudaGraphExecDestroy(g);  // null: never used
      set->shorter.clear();
      if (set->batch) cudaGraphExecDestroy(set->batch);
      set->batch = nullptr;
    }
  }
  // Graphs of batch_ steps and of 3 · 2^j < batch_ steps (the stretches shorter than a batch
  // between a run's outputs, or up to the next batch_align_ step: 72 steps are 48 + 24).
  struct GraphSet {
    bool ahead = true;  // the sliding lists refreshed ahead (capture_steps)
    cudaGraphExec_t batch = nullptr;
    std::vector<cudaGraphExec_t> shorter;  // 3 · 2^j steps; captured at their first use (null)
  };
  GraphSet capture_graph_set(bool ahead);
  // Queues steps from step_ to chunk_end: these graphs at steps ≡ 0 mod 3, single launches before
  // and after; true when a graph ran. read_status: the status flags after the queued work (syncs).
  bool queue_steps(std::int64_t chunk_end, GraphSet& graphs);
  StepStatus read_status();
  // After a force slot changed in the core: the program uploaded again (all of it when the slot's
  // nodes changed, then the graphs recaptured; else only the per-set forces, in place).
  void reload_program(bool nodes_changed);
  void run_direct_step();  // one step with its scalars, synchronised and checked
  void snapshot();
  void roll_back();
  std::vector<Vec3<T>> download_vec(const Vec3<T>* p) const;  // N vectors
  // N vectors through the pinned output buffer on the copy stream, after the steps queued so far.
  std::vector<Vec3<T>> download_pinned(const Vec3<T>* from) const;
  Energies energies_at(const std::vector<Vec3<T>>& u);  // u: u(n) on the host
  std::vector<Vec3<T>> download_vec_n(const Vec3<T>* p, std::size_t count) const;
  void compute_internal_forces();  // f_ at u(n), on the device
  // The vectors of the listed nodes (ids checked by the caller), gathered on the device and copied
  // back alone (CopyNodesBody).
  std::vector<Vec3<T>> pick(const Vec3<T>* from, const std::vector<Index>& nodes) const;
  void upload_vec(Vec3<T>* p, const std::vector<double>& flat);
  void compute_energy_terms(double& strain, double& elastic, double& hourglass);
  double kinetic_energy(const std::vector<Vec3<T>>& u, const std::vector<Vec3<T>>& up) const {
    return core_.kinetic_energy(u.data(), up.data(), arrays_.inverse_mass.data(), 0);
  }
  double external_work() const;
  void check_blowup(double work);
  void update_bound() {  // into the array the captured graphs read: never reallocated
    const BlowupBound b = core_.blowup_bound();
    SINEW_CUDA_CHECK(cudaMemcpyAsync(bound_.get(), &b, sizeof b, cudaMemcpyHostToDevice, stream_));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  }
  // The activations at the current step, in activation_now_ (energies and forces on demand); null
  // without muscles. In stream order: no allocation, no device-wide synchronisation.
  const T* upload_activation() {
    std::vector<T> host(core_.muscle_count());
    if (host.empty()) return nullptr;
    core_.activations(time(), host.data());
    if (activation_now_.size() != host.size()) activation_now_.allocate(host.size());
    SINEW_CUDA_CHECK(cudaMemcpyAsync(activation_now_.get(), host.data(), host.size() * sizeof(T),
                                     cudaMemcpyHostToDevice, stream_));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));  // `host` is read before it goes
    return activation_now_.get();
  }

  BackendCore core_;
  EngineArrays<T> arrays_;  // host copies: uploaded once; element fields and messages read them
  CudaOptions options_;
  T h_;
  std::size_t n_, e_;
  int batch_;
  physics::CentralDifference<T> cd_;
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
  GraphSet graphs_;
  // The same with the sliding lists refreshed inline, for replaying a chunk with a list miss;
  // captured at the first miss (recaptured after build_graph).
  GraphSet inline_graphs_;

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
  DeviceArray<double> element_energy_;    // 3 per element: strain, elastic, hourglass (J)
  DeviceArray<double> energy_chunk_sum_;  // the same 3 per chunk of each collection
  DeviceArray<T> activation_now_;         // upload_activation
  // per-step scalars: per slot [activation (M) | force factors (F) | prescribed factors (P) |
  // energy test flag (1)];
  // device slots 0 .. batch_ − 1 for the graph, slot batch_ for a single launched step; staged on
  // the host in a pinned ring of ring_rows_ rows (fill_scalars).
  std::size_t scalars_per_slot_ = 0;
  DeviceArray<T> scalars_;
  PinnedArray<T> scalars_host_;
  std::size_t ring_rows_ = 0, ring_next_ = 0;
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
  DeviceArray<std::int32_t> contact_partner_;
  DeviceArray<T> contact_share_;
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
            core_.setup().effects.gravity ? gravity_.get() : nullptr,
            std::int32_t(core_.prepared().forces.size()),
            arrays_.constraints.jaw_factor,
            contact_partner_.get(),
            contact_share_.get(),
            arrays_.constraints.contact_up};
  }
  StepSums step_sums() const {
    return {work_ ? work_acc_.get() : nullptr,
            work_base_.get(),
            work_partial_.get(),
            ke_partial_.get(),
            counters_.get(),
            bound_.get(),
            1.0 / core_.dt()};
  }
  // The kinetic-energy blow-up test on the device, at steps ≡ 0 mod energy_interval: each step's
  // row of scalars ends with its flag (energy_flag_: 1 or 0). The batch graph starts at steps
  // ≡ 0 mod batch_align_ = lcm(3, interval) and has its tests at fixed slots (kernels without
  // the test elsewhere: the step alone as fast as before); the shorter graphs start at any step
  // ≡ 0 mod 3 (the three u buffers' rotation) and read the flag at every step. An interval whose
  // lcm with 3 exceeds 1024 reads the flag in the batch graph too (batch_align_ 3).
  int interval_ = 10;
  std::int64_t batch_align_ = 3;
  bool batch_reads_flags_ = false;
  std::size_t energy_flag_ = 0;  // index of the flag in a row
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
  DeviceArray<StepStatus> status_;
  PinnedArray<StepStatus> status_host_;
  mutable PinnedArray<Vec3<T>> output_;
  // The node lists pick() was asked for (a run's probes: one list of displacement nodes and one
  // per reaction set, asked in turn at every row), each uploaded once (kPickedLists at most).
  struct PickedNodes {
    std::vector<Index> nodes;
    DeviceArray<std::int32_t> ids;
    DeviceArray<Vec3<T>> values;
  };
  static constexpr std::size_t kPickedLists = 8;
  mutable std::vector<PickedNodes> picked_;
  mutable std::size_t picked_next_ = 0;  // the entry replaced when all kPickedLists are taken
};

}  // namespace sinew::simulator::cuda
