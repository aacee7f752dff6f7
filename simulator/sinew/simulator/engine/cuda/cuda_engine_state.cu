// The CUDA engine's queries and state: downloads, energies, the blow-up check at sync points,
// internal forces and reactions, element fields, checkpoint state and restore. The rules and
// messages are the BackendCore's; this file moves data.
#include "sinew/simulator/engine/cuda/cuda_engine.cuh"

#include <algorithm>
#include <cmath>

#include "sinew/simulator/passes/chunks.hpp"

namespace sinew::simulator::cuda {

template <typename T>
std::vector<Vec3<T>> CudaEngine<T>::download_vec(const Vec3<T>* p) const {
  return download_vec_n(p, n_);
}

template <typename T>
std::vector<Vec3<T>> CudaEngine<T>::download_vec_n(const Vec3<T>* p, std::size_t count) const {
  std::vector<Vec3<T>> v(count);
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  if (count)
    SINEW_CUDA_CHECK(cudaMemcpy(v.data(), p, count * sizeof(Vec3<T>), cudaMemcpyDeviceToHost));
  return v;
}

template <typename T>
void CudaEngine<T>::upload_vec(Vec3<T>* p, const std::vector<double>& flat) {
  const std::vector<Vec3<T>> v = unflatten<T>(flat);
  SINEW_CUDA_CHECK(
      cudaMemcpyAsync(p, v.data(), n_ * sizeof(Vec3<T>), cudaMemcpyHostToDevice, stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));  // `v` is read before it goes
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
void CudaEngine<T>::compute_energy_terms(double& strain, double& elastic, double& hourglass) {
  constexpr int kTerms = 3;  // strain, elastic, hourglass (element_kernel's mode 2)
  if (element_energy_.size() != kTerms * e_) element_energy_.allocate(kTerms * e_);
  if (!elem_force_.size()) elem_force_.allocate(e_ * 8);
  launch_elements(buffer(step_, 0), upload_activation(), 2, stream_);
  // Summed per collection in element-list order, chunk by chunk (the CPU's order): the chunks on
  // the device (ChunkSumBody, the host's additions in the host's order), only their sums copied
  // back and added here in order.
  std::size_t chunks = 0;
  for (const auto& c : collections_) chunks += chunk_count(c.elements.size());
  if (energy_chunk_sum_.size() != kTerms * chunks) energy_chunk_sum_.allocate(kTerms * chunks);
  std::size_t at = 0;
  for (const auto& c : collections_) {
    const std::size_t k = chunk_count(c.elements.size());
    if (k)
      forall(k, stream_,
             ChunkSumBody<kTerms>{c.elements.get(), std::int32_t(c.elements.size()),
                                  element_energy_.get(), energy_chunk_sum_.get() + kTerms * at});
    at += k;
  }
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const auto sums = energy_chunk_sum_.download(stream_);
  strain = elastic = hourglass = 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    strain += sums[kTerms * c];
    elastic += sums[kTerms * c + 1];
    hourglass += sums[kTerms * c + 2];
  }
}

template <typename T>
Energies CudaEngine<T>::energies() {
  return energies_at(download_vec(buffer(step_, 0)));
}

template <typename T>
Energies CudaEngine<T>::energies_at(const std::vector<Vec3<T>>& u) {
  Energies e;
  e.step = step_;
  e.time = time();
  compute_energy_terms(e.strain, e.elastic, e.hourglass);
  e.kinetic = kinetic_energy(u, download_pinned(buffer(step_, 2)));
  e.external_work = external_work();
  return e;
}

template <typename T>
void CudaEngine<T>::check_blowup(double work) {
  const auto u = download_vec(buffer(step_, 0)), up = download_vec(buffer(step_, 2));
  const double ke = kinetic_energy(u, up);
  double strain = 0, elastic = 0, hg = 0;
  compute_energy_terms(strain, elastic, hg);
  if (!core_.blown_up(ke, strain + hg, work)) return;
  double move = 0;
  const Index worst = core_.fastest_node(u.data(), up.data(), move);
  core_.fail_blowup(step_, ke, work, worst, std::sqrt(move) / dt());
}

template <typename T>
std::vector<Vec3<T>> CudaEngine<T>::download_pinned(const Vec3<T>* from) const {
  // Frames leave on the copy stream into pinned memory, after the step work queued so far.
  SINEW_CUDA_CHECK(cudaEventRecord(copy_ready_, stream_));
  SINEW_CUDA_CHECK(cudaStreamWaitEvent(copy_stream_, copy_ready_, 0));
  SINEW_CUDA_CHECK(cudaMemcpyAsync(output_.get(), from, n_ * sizeof(Vec3<T>),
                                   cudaMemcpyDeviceToHost, copy_stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(copy_stream_));
  return std::vector<Vec3<T>>(output_.get(), output_.get() + n_);
}

template <typename T>
std::vector<double> CudaEngine<T>::displacements() const {
  const auto u = download_pinned(buffer(step_, 0));
  return flatten(u.data(), n_);
}

template <typename T>
Frame CudaEngine<T>::frame(bool with_fields) {
  std::vector<Vec3<T>> u = download_pinned(buffer(step_, 0));
  Frame f{step_, time(), flatten(u.data(), n_), energies_at(u), {}};
  // The fields are computed by whoever calls f.fields (the runner's frame thread), from this
  // copy, with the same loop body as the CPU's: the GPU steps on meanwhile.
  if (with_fields) f.fields = core_.deferred_element_fields(arrays_, std::move(u), step_, 0);
  return f;
}

template <typename T>
std::vector<double> CudaEngine<T>::velocities() const {
  const auto u = download_vec(buffer(step_, 0)), up = download_vec(buffer(step_, 2));
  return core_.velocities(u.data(), up.data());
}

template <typename T>
std::vector<double> CudaEngine<T>::displacements(const std::vector<Index>& nodes) const {
  core_.check_node_ids(nodes, "nodes");
  const auto u = pick(buffer(step_, 0), nodes);
  return flatten(u.data(), u.size());
}

template <typename T>
std::vector<Vec3<T>> CudaEngine<T>::pick(const Vec3<T>* from,
                                         const std::vector<Index>& nodes) const {
  if (nodes.empty()) return {};
  // Probes ask for the same lists at every row: each is uploaded once (a new upload would free and
  // allocate, and cudaFree waits for the whole device).
  auto it = std::find_if(picked_.begin(), picked_.end(),
                         [&](const PickedNodes& p) { return p.nodes == nodes; });
  if (it == picked_.end()) {
    if (picked_.size() < kPickedLists) {
      picked_.emplace_back();
      it = picked_.end() - 1;
    } else {
      it = picked_.begin() + std::ptrdiff_t(picked_next_++ % kPickedLists);
    }
    it->nodes = nodes;
    it->ids.upload(nodes, stream_);
    it->values.allocate(nodes.size());
  }
  forall(nodes.size(), stream_, CopyNodesBody<T>{it->ids.get(), from, it->values.get()});
  return download_vec_n(it->values.get(), nodes.size());
}

template <typename T>
void CudaEngine<T>::compute_internal_forces() {
  if (!elem_force_.size()) elem_force_.allocate(e_ * 8);
  launch_elements(buffer(step_, 0), upload_activation(), 0, stream_);
  const NodeData<T> nodes{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                          std::int32_t(n_)};
  forall(n_, stream_, GatherBody<T>{nodes, elem_force_.get(), f_.get()});
}

template <typename T>
std::vector<double> CudaEngine<T>::internal_forces() {
  compute_internal_forces();
  const auto f = download_vec(f_.get());
  return flatten(f.data(), n_);
}

template <typename T>
std::array<double, 3> CudaEngine<T>::reaction(const std::vector<Index>& nodes) {
  core_.check_node_ids(nodes, "reaction");  // before any device work
  compute_internal_forces();
  const auto f = pick(f_.get(), nodes);  // only the set's forces leave the device
  return core_.reaction(arrays_, nodes, f.data(), step_);
}

template <typename T>
ElementFields CudaEngine<T>::element_fields() {
  // Output-interval work: computed on the host from u(n) with the same loop body as the CPU's.
  const auto u = download_vec(buffer(step_, 0));
  return core_.element_fields(arrays_, u.data(), step_, 0);
}

template <typename T>
State CudaEngine<T>::state() const {
  return core_.make_state(step_, download_vec(buffer(step_, 0)), download_vec(buffer(step_, 2)),
                          slide_triangle_.download(stream_), external_work());
}

template <typename T>
void CudaEngine<T>::restore(const State& s) {
  core_.check_state(s);
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  step_ = s.step;
  upload_vec(buffer(step_, 0), s.u);
  upload_vec(buffer(step_, 2), s.u_prev);
  if (!s.sliding_triangle.empty()) {
    SINEW_CUDA_CHECK(cudaMemcpyAsync(slide_triangle_.get(), s.sliding_triangle.data(),
                                     slide_triangle_.bytes(), cudaMemcpyHostToDevice, stream_));
    SINEW_CUDA_CHECK(cudaMemcpyAsync(slide_search_triangle_.get(), s.sliding_triangle.data(),
                                     slide_search_triangle_.bytes(), cudaMemcpyHostToDevice,
                                     stream_));
  }
  SINEW_CUDA_CHECK(cudaMemcpyAsync(work_base_.get(), &s.external_work, sizeof(double),
                                   cudaMemcpyHostToDevice, stream_));
  if (work_acc_.size()) work_acc_.zero(stream_);
  if (f_sum_.size()) f_sum_.zero(stream_);
  forget_slide_lists(stream_);
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  core_.set_energy_reference(s.energy_reference);
  update_bound();
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
  if (core_.setup().effects.gravity) b += double(n_) * 3 * t;
  if (core_.setup().effects.muscles)
    b += double(core_.prepared().muscle_id.size()) * (4 + t + 3 * t) + double(e_) * 4;
  // Sliding nodes (constraint program, listed path): node id, offsets, op, surface, rest distance,
  // triangle read + written, list count, anchor, u(n+1) read + written, rest, the first two listed
  // ids and distances (most nodes test their warm start only; the triangles' corners come from L2
  // and are not counted).
  b += double(core_.prepared().slide_node.size()) *
       (4 + 4 + 4 + 4 + t + 8 + 4 + 3 * t + 6 * t + 3 * t + 8 + 2 * t);
  return b;
}

template <typename T>
void CudaEngine<T>::set_force_slot(std::size_t k, const std::vector<Index>& nodes,
                                   const std::array<double, 3>& force) {
  const auto& forces = core_.prepared().forces;
  const std::size_t set = forces.size() - core_.force_slot_count() + k;
  const std::vector<Index> before =
      k < core_.force_slot_count() ? forces[set].nodes : std::vector<Index>{};
  const std::array<double, 3> force_before =
      k < core_.force_slot_count() ? forces[set].per_node : std::array<double, 3>{};
  core_.set_force_slot(k, nodes, force);  // checks k, the ids and the force
  // The slot's curve turns from 0 to 1 when it is first given nodes: the factor rows come from
  // the core at each step() call, so only the program needs the device.
  if (forces[set].nodes != before || forces[set].per_node != force_before)
    reload_program(forces[set].nodes != before);
}

template <typename T>
void CudaEngine<T>::clear_force_slot(std::size_t k) {
  const auto& forces = core_.prepared().forces;
  const bool had_nodes = k < core_.force_slot_count() &&
                         !forces[forces.size() - core_.force_slot_count() + k].nodes.empty();
  core_.clear_force_slot(k);
  if (had_nodes) reload_program(true);
}

template <typename T>
void CudaEngine<T>::reload_program(bool nodes_changed) {
  // The queued steps read the program: they finish first.
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  arrays_.constraints = make_constraint_program<T>(core_.prepared());
  const ConstraintArrays<T>& program = arrays_.constraints;
  if (!nodes_changed) {
    // Same sets, same size: the captured graphs keep reading this array.
    SINEW_CUDA_CHECK(cudaMemcpyAsync(force_per_node_.get(), program.force_per_node.data(),
                                     force_per_node_.bytes(), cudaMemcpyHostToDevice, stream_));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
    return;
  }
  node_op_offset_.upload(program.node_op_offset, stream_);
  con_node_.upload(program.node, stream_);
  con_offset_.upload(program.offset, stream_);
  con_op_.upload(program.op, stream_);
  force_per_node_.upload(program.force_per_node, stream_);
  // The graphs hold the old arrays and counts (constraint_data() by value): capture them again.
  build_graph();
}

// Each file of the engine instantiates the members it defines (cuda_engine.cuh).
template class CudaEngine<float>;
template class CudaEngine<double>;

}  // namespace sinew::simulator::cuda
