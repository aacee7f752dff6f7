// The CUDA engine's set-up: the shared EngineArrays uploaded once, streams and events, the choice
// of assembly, the initial state and the first graph capture.
#include "sinew/simulator/engine/cuda/cuda_engine.cuh"

#include <algorithm>
#include <limits>
#include <numeric>

namespace sinew::simulator::cuda {

template <typename T>
CudaEngine<T>::CudaEngine(const formats::Model& model, const Setup& setup, Plan plan,
                          const CudaOptions& options)
    : core_(model, setup, std::move(plan)), options_(options) {
  // The options were checked by make_cuda_backend (cuda_backend.cpp).
  refresh_interval_ = options.sliding_refresh_interval;
  SINEW_CUDA_CHECK(cudaSetDevice(options.device));
  arrays_ = make_engine_arrays<T>(core_.prepared(), options.sliding_skin);
  const EngineArrays<T>& a = arrays_;
  h_ = a.h;
  n_ = a.nodes;
  e_ = a.elements;
  interval_ = std::max(1, setup.energy_interval);
  {
    // Batch graphs start at steps ≡ 0 mod lcm(3, interval) with the blow-up tests at fixed slots;
    // the shorter graphs read each step's flag (cuda_engine.cuh).
    const std::int64_t lcm = std::lcm<std::int64_t>(3, interval_);
    batch_reads_flags_ = lcm > 1024;
    batch_align_ = batch_reads_flags_ ? 3 : lcm;
    const std::int64_t want = std::max<std::int64_t>(options.graph_steps, batch_align_);
    batch_ = int((want + batch_align_ - 1) / batch_align_ * batch_align_);
  }
  const Effects& fx = setup.effects;
  cd_ = physics::central_difference<T>(dt(), fx.damping ? setup.damping_alpha : 0.0);

  SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
  SINEW_CUDA_CHECK(cudaStreamCreateWithFlags(&copy_stream_, cudaStreamNonBlocking));
  SINEW_CUDA_CHECK(cudaEventCreateWithFlags(&copy_ready_, cudaEventDisableTiming));

  elem_nodes_.upload(a.element_nodes, stream_);
  row_.upload(a.row, stream_);
  rows_.upload(a.rows, stream_);
  for (const auto& c : core_.plan().collections) {
    DeviceCollection dc;
    dc.muscle = c.muscle;
    dc.elements.upload(c.elements, stream_);
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
    muscle_offset_.upload(a.muscle_offset, stream_);
    muscle_id_.upload(a.muscle_id, stream_);
    muscle_fraction_.upload(a.muscle_fraction, stream_);
    muscle_fibre_.upload(a.muscle_fibre, stream_);
    muscle_params_.upload(a.muscle_params, stream_);
    muscles_ = a.muscle_params.size();
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
      tile_layers_.upload(tiles.tile_layers, stream_);
      tile_window_.upload(tiles.window_node, stream_);
      tile_slot_.upload(tiles.slot_element, stream_);
      tile_data_ = {tile_layers_.get(), tile_window_.get(), tile_slot_.get(),
                    std::int64_t(tiles.window_stride()), std::int64_t(tiles.slot_stride())};
    }
  }
  if (options_.assembly == ForceAssembly::gather) {
    elem_force_.allocate(e_ * 8);
  } else if (options_.assembly == ForceAssembly::atomic) {
    f_sum_.allocate(n_);
    f_sum_.zero(stream_);
  }
  inc_offset_.upload(a.incidence_offset, stream_);
  {
    // The gather reads the corner-major buffer: entry e · 8 + a of the incidence becomes a · E + e
    // (same entries, same order: the summation order is the CPU's).
    std::vector<std::int32_t> inc(a.incidence.size());
    for (std::size_t k = 0; k < inc.size(); ++k) {
      const auto v = std::size_t(a.incidence[k]);
      inc[k] = std::int32_t((v % 8) * e_ + v / 8);
    }
    inc_.upload(inc, stream_);
  }
  f_.allocate(n_);
  inverse_mass_.upload(a.inverse_mass, stream_);
  rest_.upload(a.rest, stream_);
  if (fx.gravity) gravity_.upload(a.gravity, stream_);
  for (auto& b : buf_) b.allocate(n_);
  snap_u_.allocate(n_);
  snap_up_.allocate(n_);

  // Loads and constraints: the constraint program of the core (per node its ops in the one order).
  const ConstraintArrays<T>& program = a.constraints;
  node_op_offset_.upload(program.node_op_offset, stream_);
  con_node_.upload(program.node, stream_);
  con_offset_.upload(program.offset, stream_);
  con_op_.upload(program.op, stream_);
  force_per_node_.upload(program.force_per_node, stream_);
  prescribed_value_.upload(program.prescribed_value, stream_);
  prescribed_mask_.upload(program.prescribed_mask, stream_);
  prescribed_set_.upload(program.prescribed_set, stream_);
  prescribed_free_.allocate(program.prescribed_set.size());
  plane_normals_.upload(program.plane_normal, stream_);
  contact_partner_.upload(program.contact_partner, stream_);
  contact_share_.upload(program.contact_share, stream_);
  if (!a.surfaces.empty()) {
    std::vector<SlideSurface<T>> views;
    for (const auto& s : a.surfaces) {
      auto ds = std::make_unique<DeviceSurface<T>>();
      ds->vertices.upload(s.vertices, stream_);
      ds->normals.upload(s.normals, stream_);
      ds->triangles.upload(s.triangles, stream_);
      ds->cell_offsets.upload(s.grid.cell_offsets, stream_);
      ds->cell_triangles.upload(s.grid.cell_triangles, stream_);
      ds->entry_corners.upload(s.lists.corners, stream_);
      ds->cell_boxes.upload(s.lists.cell, stream_);
      ds->triangle_corners.upload(s.triangle_corners, stream_);
      SurfaceView<T> view = s.view();  // the host view's grid, with device pointers
      view.vertices = ds->vertices.get();
      view.triangles = ds->triangles.get();
      view.normals = ds->normals.get();
      view.cell_offsets = ds->cell_offsets.get();
      view.cell_triangles = ds->cell_triangles.get();
      view.entry_corners = ds->entry_corners.get();
      view.cell_boxes = ds->cell_boxes.get();
      views.push_back({view, ds->triangle_corners.get(), s.skin});
      surfaces_.push_back(std::move(ds));
    }
    slide_surfaces_.upload(views, stream_);
    const std::size_t slides = a.slide_node.size();
    slide_node_.upload(a.slide_node, stream_);
    slide_surface_.upload(a.slide_surface, stream_);
    slide_triangle_.upload(a.slide_triangle, stream_);
    snap_triangle_.allocate(slides);
    slide_search_triangle_.upload(a.slide_triangle, stream_);
    slide_list_count_.allocate(slides);
    slide_list_.allocate(slides * kCandidates);
    slide_list_distance_.allocate(slides * kCandidates);
    slide_anchor_.allocate(slides);
    forget_slide_lists(stream_);
    slide_distance_.upload(a.slide_distance, stream_);
  }
  const PreparedModel& prep = core_.prepared();
  // Work: loads, prescribed sets and projections (sliding, planes), as run_program counts it.
  work_ = fx.gravity || !prep.forces.empty() || !program.prescribed_set.empty() ||
          !prep.slide_node.empty() || !prep.plane_nodes.empty();
  program_in_node_ = prep.slide_node.empty() && (con_node_.size() || work_);
  work_base_.allocate(1);
  work_base_.zero(stream_);
  if (work_) {
    work_acc_.allocate(n_);
    work_acc_.zero(stream_);
    snap_work_acc_.allocate(n_);
  }
  work_partial_.allocate(std::max<std::size_t>(blocks_for(n_), tile_layers_.size()));
  ke_partial_.allocate(std::max<std::size_t>(blocks_for(n_), tile_layers_.size()));
  counters_.allocate(1);
  counters_.zero(stream_);
  bound_.upload({BlowupBound{0, 0}}, stream_);

  energy_flag_ = core_.step_scalar_count();
  scalars_per_slot_ = energy_flag_ + 1;
  scalars_.allocate(scalars_per_slot_ * std::size_t(batch_ + 1));
  ring_rows_ = std::size_t(kQueuedBatches + 1) * std::size_t(batch_ + 1);
  scalars_host_.allocate(scalars_per_slot_ * ring_rows_);
  status_.allocate(1);
  status_.zero(stream_);
  status_host_.allocate(1);
  output_.allocate(n_);

  // Initial state: u(0) = 0 with the constraints at t = 0; u(−1) = u(0) − v0 Δt (as the CPU).
  {
    buf_[0].zero(stream_);
    // Constraints at t = 0 on the host path of the device kernels: run them on buffer 0.
    fill_scalars(-1, 1, int(batch_));  // slot `batch_`: prescribed factors at t = 0
    Vec3<T>* u0 = buf_[0].get();
    const T* sc = scalars_.get() + scalars_per_slot_ * std::size_t(batch_);
    if (con_node_.size()) launch_constraints(sc + muscles_, false, u0, u0, u0, stream_, false);
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    std::vector<Vec3<T>> u = download_vec(u0), up = u;
    for (const auto& v : setup.initial_velocities)
      for (auto nd : v.nodes)
        for (int k = 0; k < 3; ++k)
          up[std::size_t(nd)][k] = u[std::size_t(nd)][k] - T(v.velocity[std::size_t(k)] * dt());
    for (auto nd : prep.rigid) up[std::size_t(nd)] = u[std::size_t(nd)];
    SINEW_CUDA_CHECK(cudaMemcpyAsync(buf_[2].get(), up.data(), n_ * sizeof(Vec3<T>),
                                     cudaMemcpyHostToDevice, stream_));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  }
  core_.set_initial_energy(energies());
  update_bound();
  build_graph();
}

template <typename T>
CudaEngine<T>::~CudaEngine() {
  // The arrays are freed after this body, without waiting for the device (DeviceArray): nothing of
  // this engine may still run then.
  for (cudaStream_t st : {stream_, copy_stream_, slide_stream_})
    if (st) cudaStreamSynchronize(st);
  for (cudaStream_t st : side_streams_) cudaStreamSynchronize(st);
  destroy_graphs();
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

// Scalars of steps first_step .. first_step + count − 1 into slots slot0 ... (BackendCore::
// step_scalars; a step of −1 gives the prescribed factors at t = 0, the initial constraints).
template <typename T>
void CudaEngine<T>::fill_scalars(std::int64_t first_step, int count, int slot0) {
  // The copy runs in stream order: the host may not rewrite its staging rows before then, so each
  // fill takes the next free rows of the ring, and a full ring first waits for the stream.
  if (ring_next_ + std::size_t(count) > ring_rows_) {
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    ring_next_ = 0;
  }
  T* h = scalars_host_.get() + scalars_per_slot_ * ring_next_;
  ring_next_ += std::size_t(count);
  for (int k = 0; k < count; ++k) {
    T* row = h + scalars_per_slot_ * std::size_t(k);
    core_.step_scalars(first_step + k, row);
    row[energy_flag_] = T((first_step + k) >= 0 && (first_step + k) % interval_ == 0 ? 1 : 0);
  }
  SINEW_CUDA_CHECK(cudaMemcpyAsync(scalars_.get() + scalars_per_slot_ * std::size_t(slot0), h,
                                   scalars_per_slot_ * std::size_t(count) * sizeof(T),
                                   cudaMemcpyHostToDevice, stream_));
}

template class CudaEngine<float>;
template class CudaEngine<double>;

}  // namespace sinew::simulator::cuda
