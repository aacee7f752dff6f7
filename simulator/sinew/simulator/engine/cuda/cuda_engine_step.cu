// The CUDA engine's launches and step loop: the kernels of a step (elements, nodes, constraints;
// or tiles), the captured graph of a batch of steps, the replay of a batch whose status flags
// report a problem or a sliding list miss, and the timing hooks.
#include "sinew/simulator/engine/cuda/cuda_engine.cuh"

#include <algorithm>

#include "sinew/simulator/engine/cuda/constraint_kernels.cuh"
#include "sinew/simulator/engine/cuda/element_kernels.cuh"
#include "sinew/simulator/engine/cuda/node_kernels.cuh"
#include "sinew/simulator/passes/effect_dispatch.hpp"

namespace sinew::simulator::cuda {

// The constraint kernel after the node kernel (models with sliding), or alone for the initial
// constraints. ahead: the lists were refreshed from u(n) by slide_refresh_kernel (launch_step).
// lists_ready: no list refresh was forked for this step.
template <typename T>
void CudaEngine<T>::launch_constraints(const T* factor, bool loads, Vec3<T>* un, const Vec3<T>* up,
                                       const Vec3<T>* u, cudaStream_t s, bool ahead,
                                       bool programmatic, bool lists_ready) {
  const unsigned g = blocks_for(con_node_.size());
  ConstraintData<T> d = constraint_data();
  d.u_now = u;  // u(n), u(n−1): the lips' contact predicts the partner from them
  d.u_prev = up;
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
template <typename T>
void CudaEngine<T>::launch_refresh(const Vec3<T>* u, cudaStream_t s) {
  slide_refresh_kernel<T>
      <<<blocks_for(slide_node_.size()), kBlock, 0, s>>>(slide_data(), rest_.get(), u);
  SINEW_CUDA_LAUNCHED();
}

template <typename T>
void CudaEngine<T>::launch_elements(const Vec3<T>* u, const T* activation, int mode, cudaStream_t s,
                                    bool programmatic) {
  ElementData<T> d{elem_nodes_.get(),    row_.get(),           rows_.get(),
                   muscle_offset_.get(), muscle_id_.get(),     muscle_fraction_.get(),
                   muscle_fibre_.get(),  muscle_params_.get(), h_,
                   std::int32_t(e_)};
  const bool el = core_.setup().effects.elasticity, hg = core_.setup().effects.hourglass;
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
    dispatch_flags(
        [&](auto elastic, auto muscle, auto hourglass) {
          constexpr bool kE = decltype(elastic)::value, kM = decltype(muscle)::value,
                         kH = decltype(hourglass)::value;
          if (mode == 0)
            go(element_kernel<T, kE, kM, kH, 0>);
          else if (mode == 1)
            go(element_kernel<T, kE, kM, kH, 1>);
          else
            go(element_kernel<T, kE, kM, kH, 2>);
        },
        el, c.muscle, hg);
    SINEW_CUDA_LAUNCHED();
    if (ci > 0) {
      SINEW_CUDA_CHECK(cudaEventRecord(side_done_[ci - 1], cs));
      SINEW_CUDA_CHECK(cudaStreamWaitEvent(s, side_done_[ci - 1], 0));
    }
  }
}

template <typename T>
void CudaEngine<T>::launch_step(std::int64_t step, int slot, cudaStream_t s, bool ahead_slide,
                                bool energy_tests,
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
  const T* energy_flag = energy_tests ? sc + energy_flag_ : nullptr;
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
    launch_tiles(u, up, un, sc, energy_flag, s, first_programmatic);
    mark(program_in_node_ ? "elements + nodes in tiles (+ loads, constraints, work, KE test)"
                          : "elements + nodes in tiles (+ KE test)");
  } else {
    launch_elements(u, sc, options_.assembly == ForceAssembly::gather ? 0 : 1, s,
                    first_programmatic);
    mark("elements: F, S (+ muscles), forces, hourglass");
    // After element collections joined from side streams (events): a plain launch.
    launch_nodes(u, up, un, sc, energy_flag, s, programmatic && collections_.size() == 1);
    mark(program_in_node_ ? "nodes: force gather + update + loads, constraints, work (+ KE test)"
                          : "nodes: force gather + central-difference update (+ KE test)");
  }
  if (!program_in_node_ && con_node_.size()) {
    if (refresh) SINEW_CUDA_CHECK(cudaStreamWaitEvent(s, slide_done_, 0));  // join
    launch_constraints(sc + muscles_, true, un, up, u, s, ahead, programmatic, !refresh);
    mark("loads, sliding, planes, prescribed, rigid + external work");
  }
}

// The node kernel after the element kernels (gather or atomic assembly).
template <typename T>
void CudaEngine<T>::launch_nodes(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                                 const T* energy_flag, cudaStream_t s, bool programmatic) {
  const bool gather = options_.assembly == ForceAssembly::gather;
  NodeData<T> nd{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                 std::int32_t(n_)};
  const StepSums sums = step_sums();
  ConstraintData<T> program = constraint_data();
  program.u_now = u;
  program.u_prev = up;
  auto node = [&](auto kernel) {
    launch_kernel(kernel, blocks_for(n_), kBlock, 0, s, programmatic, nd, elem_force_.get(),
                  f_sum_.get(), u, up, un, status_.get(), sums, program, node_op_offset_.get(),
                  sc + muscles_, energy_flag);
  };
  const bool grav = core_.setup().effects.gravity, prog = program_in_node_;
  // Every combination is its own specialised kernel.
  dispatch_flags(
      [&](auto gathered, auto gravity, auto energy_test, auto program) {
        node(node_kernel<T, decltype(gathered)::value, decltype(gravity)::value,
                         decltype(energy_test)::value, decltype(program)::value>);
      },
      gather, grav, energy_flag != nullptr, prog);
  SINEW_CUDA_LAUNCHED();
}

template <typename T>
void CudaEngine<T>::launch_tiles(const Vec3<T>* u, const Vec3<T>* up, Vec3<T>* un, const T* sc,
                                 const T* energy_flag, cudaStream_t s, bool programmatic) {
  ElementData<T> ed{elem_nodes_.get(),    row_.get(),           rows_.get(),
                    muscle_offset_.get(), muscle_id_.get(),     muscle_fraction_.get(),
                    muscle_fibre_.get(),  muscle_params_.get(), h_,
                    std::int32_t(e_)};
  NodeData<T> nd{inverse_mass_.get(), gravity_.get(), inc_offset_.get(), inc_.get(), cd_,
                 std::int32_t(n_)};
  const StepSums sums = step_sums();
  ConstraintData<T> program = constraint_data();
  program.u_now = u;
  program.u_prev = up;
  const unsigned g = unsigned(tile_layers_.size());
  constexpr std::size_t bytes = tile_shared_bytes<T>();
  auto go = [&](auto kernel) {
    SINEW_CUDA_CHECK(
        cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes)));
    launch_kernel(kernel, g, kBlock, bytes, s, programmatic, tile_data_, ed, nd, u, sc, up, un,
                  status_.get(), sums, program, node_op_offset_.get(), sc + muscles_, energy_flag);
  };
  const Effects& fx = core_.setup().effects;
  const bool el = fx.elasticity, mu = fx.muscles, hg = fx.hourglass, gr = fx.gravity;
  const bool pr = program_in_node_;  // else the constraint kernel follows
  // Every effect combination is its own specialised kernel.
  dispatch_flags(
      [&](auto elastic, auto muscle, auto hourglass, auto gravity, auto program) {
        go(tile_kernel<T, decltype(elastic)::value, decltype(muscle)::value,
                       decltype(hourglass)::value, decltype(gravity)::value,
                       decltype(program)::value>);
      },
      el, mu, hg, gr, pr);
  SINEW_CUDA_LAUNCHED();
}

// Per-stage device time of direct (non-graph) steps: events between the stages of launch_step,
// medians over `repeats` steps (state advances; flags checked at the end).
template <typename T>
std::vector<std::pair<std::string, float>> CudaEngine<T>::stage_times(int repeats) {
  std::vector<std::string> names;
  std::vector<std::vector<float>> times;
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(StepStatus), stream_));
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

// The graph of a batch of `count` steps starting at a step ≡ 0 (mod 3): its scalars (and energy
// test flags) in slots 0 .. count − 1.
template <typename T>
cudaGraphExec_t CudaEngine<T>::capture_steps(int count, bool ahead, bool reads_flags) {
  // Captures of engines in several threads take turns (cuda_check.cuh).
  std::lock_guard lock(capture_mutex());
  cudaGraph_t g = nullptr;
  SINEW_CUDA_CHECK(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal));
  try {
    for (int k = 0; k < count; ++k)
      launch_step(k, k, stream_, ahead, reads_flags || k % interval_ == 0, nullptr, programmatic_);
  } catch (...) {
    cudaStreamEndCapture(stream_, &g);
    if (g) cudaGraphDestroy(g);
    throw;
  }
  SINEW_CUDA_CHECK(cudaStreamEndCapture(stream_, &g));
  cudaGraphExec_t exec = nullptr;
  const cudaError_t r = cudaGraphInstantiate(&exec, g, 0);
  cudaGraphDestroy(g);
  SINEW_CUDA_CHECK(r);
  return exec;
}

// The batch graph, and shorter ones of 3 · 2^j steps for the stretches shorter than a batch
// between a run's outputs (probe rows every 73 steps would otherwise leave most steps to single
// launches: with one short graph of 30 steps at steps ≡ 0 mod 30, a 73-step stretch ran 13 to 43
// of its steps as single launches, 29 on average over its phases; now at most 4).
template <typename T>
typename CudaEngine<T>::GraphSet CudaEngine<T>::capture_graph_set(bool ahead) {
  // The shorter graphs at their first use: a run without outputs between batches (a sweep's) needs
  // few of them, and captures of engines in several threads take turns (capture_mutex).
  GraphSet set;
  set.ahead = ahead;
  set.batch = capture_steps(batch_, ahead, batch_reads_flags_);
  for (int len = 3; len < batch_; len *= 2) set.shorter.push_back(nullptr);
  return set;
}

template <typename T>
void CudaEngine<T>::build_graph() {
  destroy_graphs();
  graphs_ = capture_graph_set(slide_ahead_);
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
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(StepStatus), stream_));
  if (f_sum_.size()) SINEW_CUDA_CHECK(cudaMemsetAsync(f_sum_.get(), 0, f_sum_.bytes(), stream_));
  forget_slide_lists(stream_);  // lists are a cache: the full search gives the same triangles
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

// One step launched directly, then synchronised and checked: the state stays at the last good
// step when it fails.
template <typename T>
void CudaEngine<T>::run_direct_step() {
  fill_scalars(step_, 1, int(batch_));
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(StepStatus), stream_));
  launch_step(step_, int(batch_), stream_, false);
  SINEW_CUDA_CHECK(cudaMemcpyAsync(status_host_.get(), status_.get(), sizeof(StepStatus),
                                   cudaMemcpyDeviceToHost, stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const StepStatus st = *status_host_.get();
  if (st.bad_jacobian) {
    // u(n+1) was written to the spare buffer only; u(n), u(n−1) are intact. Undo the work term,
    // the warm starts and the atomic sums of this step (the snapshot holds them).
    roll_back();
    const auto u = download_vec(buffer(step_, 0));
    double j = 0;
    const Index worst = core_.worst_element(arrays_, u.data(), j);
    core_.fail_element(step_, worst, j);
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
    core_.fail_displacement(step_ + 1, core_.first_non_finite(un.data()));
  }
  ++step_;
}

// Steps are queued without host synchronisation: graph batches where a batch fits at an aligned
// step, single launched steps elsewhere (their blow-up tests on the device, as in the graph), up to
// kQueuedBatches batches' worth, then one sync reads the status flags. A list miss alone replays
// the queued steps from the snapshot, queued again through graphs that refresh the sliding lists
// inline (no miss is possible there); any other flag (or one raised in that replay) replays them
// one by one with the host's checks at each step, so the failing step throws with the state at the
// last good step (as a step-by-step run would); a device energy sum that crossed the bound only by
// its summation order replays without failing. Results are the same bits as synchronising after
// every step: the same kernels run in the same order on the same data, and the lists are a cache.
template <typename T>
void CudaEngine<T>::step(std::int64_t n) {
  const std::int64_t end = step_ + n;
  while (step_ < end) {
    const std::int64_t chunk_start = step_;
    const std::int64_t chunk_end = std::min(end, step_ + std::int64_t(kQueuedBatches) * batch_);
    snapshot();
    SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(StepStatus), stream_));
    const bool graphs = queue_steps(chunk_end, graphs_);
    StepStatus st = read_status();
    bool failed = st.bad_jacobian || st.bad_displacement || st.blowup;
    if (st.slide_miss && !failed && graphs && ++slide_miss_batches_ >= 2) {
      // Nodes outrun the lists refreshed ahead: from now on the graph refreshes them twice as
      // often, and once every step did not suffice (nodes moving more than s/2 per step), inline
      // (grid searches on the step's path again). Same results either way.
      if (refresh_interval_ > 1)
        refresh_interval_ /= 2;
      else
        slide_ahead_ = false;
      slide_miss_batches_ = 0;
      build_graph();
    }
    if (st.slide_miss && !failed) {
      // The chunk again with the lists refreshed inline: at graph speed rather than as single
      // synchronised steps (a chunk is up to kQueuedBatches batches: on the 1 mm brow raise in
      // long calls, replays one by one tripled the run's step time; docs/cuda-backend.md).
      if (!inline_graphs_.batch) inline_graphs_ = capture_graph_set(false);
      step_ = chunk_start;
      roll_back();
      queue_steps(chunk_end, inline_graphs_);
      st = read_status();
      failed = st.bad_jacobian || st.bad_displacement || st.blowup || st.slide_miss;
    }
    if (failed) {
      // Direct steps refresh the sliding lists inline and check each step on the host.
      step_ = chunk_start;
      roll_back();
      while (step_ < chunk_end) {
        snapshot();
        run_direct_step();
      }
      continue;
    }
  }
}

template <typename T>
bool CudaEngine<T>::queue_steps(std::int64_t chunk_end, GraphSet& set) {
  bool graphs = false;
  while (step_ < chunk_end) {
    const std::int64_t left = chunk_end - step_;
    int len = 0;  // the longest graph that fits
    cudaGraphExec_t graph = nullptr;
    if (step_ % batch_align_ == 0 && left >= batch_) {
      len = batch_;
      graph = set.batch;
    } else if (step_ % 3 == 0) {
      // Up to the next step where a batch starts, when a batch fits after it.
      const std::int64_t next = (step_ / batch_align_ + 1) * batch_align_;
      const std::int64_t room = chunk_end - next >= batch_ ? std::min(left, next - step_) : left;
      for (std::size_t j = set.shorter.size(); j-- > 0 && !graph;)
        if (room >= (std::int64_t(3) << j)) {
          len = 3 << j;
          // Captured beside the queued steps (a capture records, it does not wait for them).
          if (!set.shorter[j]) set.shorter[j] = capture_steps(len, set.ahead, true);
          graph = set.shorter[j];
        }
    }
    if (graph) {
      fill_scalars(step_, len, 0);
      SINEW_CUDA_CHECK(cudaGraphLaunch(graph, stream_));
      step_ += len;
      graphs = true;
    } else {
      // Between the aligned stretches (outputs at any step): single launches, refreshing the
      // sliding lists inline. Measured on an H100 and dropped (docs/performance.md): these steps
      // with their lists refreshed ahead and programmatic launches (the 0.5 mm brow raise's
      // steps 13% slower), and graphs captured per (phase, length) for these stretches (the
      // 1 mm brow raise's steps 20% slower: about 60 captures; the 0.5 mm one unchanged).
      fill_scalars(step_, 1, int(batch_));
      launch_step(step_, int(batch_), stream_, false, step_ % interval_ == 0);
      ++step_;
    }
  }
  return graphs;
}

template <typename T>
StepStatus CudaEngine<T>::read_status() {
  SINEW_CUDA_CHECK(cudaMemcpyAsync(status_host_.get(), status_.get(), sizeof(StepStatus),
                                   cudaMemcpyDeviceToHost, stream_));
  SINEW_CUDA_CHECK(cudaStreamSynchronize(stream_));
  ring_next_ = 0;  // every staged copy has run
  return *status_host_.get();
}

template <typename T>
std::vector<float> CudaEngine<T>::timed_graph_launches(int launches) {
  while (step_ % batch_align_ != 0) step(1);
  cudaEvent_t a, b;
  SINEW_CUDA_CHECK(cudaEventCreate(&a));
  SINEW_CUDA_CHECK(cudaEventCreate(&b));
  std::vector<float> ms;
  fill_scalars(step_, batch_, 0);
  SINEW_CUDA_CHECK(cudaMemsetAsync(status_.get(), 0, sizeof(StepStatus), stream_));
  for (int k = 0; k < launches; ++k) {
    SINEW_CUDA_CHECK(cudaEventRecord(a, stream_));
    SINEW_CUDA_CHECK(cudaGraphLaunch(graphs_.batch, stream_));
    SINEW_CUDA_CHECK(cudaEventRecord(b, stream_));
    SINEW_CUDA_CHECK(cudaEventSynchronize(b));
    float t = 0;
    SINEW_CUDA_CHECK(cudaEventElapsedTime(&t, a, b));
    ms.push_back(t);
    step_ += batch_;
  }
  SINEW_CUDA_CHECK(
      cudaMemcpy(status_host_.get(), status_.get(), sizeof(StepStatus), cudaMemcpyDeviceToHost));
  cudaEventDestroy(a);
  cudaEventDestroy(b);
  if (status_host_.get()->bad_jacobian || status_host_.get()->bad_displacement)
    throw InstabilityError(
        "", "simulation",
        "unstable during the timed steps (before step " + std::to_string(step_) + ")");
  if (status_host_.get()->slide_miss)
    throw Error("", "sliding",
                "a sliding node left its candidate list during the timed steps (the timed "
                "results are not exact); time with a larger sliding_skin");
  return ms;
}

// Each file of the engine instantiates the members it defines (cuda_engine.cuh).
template class CudaEngine<float>;
template class CudaEngine<double>;

}  // namespace sinew::simulator::cuda
