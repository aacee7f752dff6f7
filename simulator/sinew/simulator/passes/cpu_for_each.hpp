#pragma once
// The CPU's launchers of the loop bodies in passes/ (the GPU's are the kernels in cuda/): OpenMP
// over fixed chunks of 1024 items. Reductions are summed per chunk and then chunk by chunk in
// order, so results never depend on the thread count.
#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "sinew/simulator/passes/chunks.hpp"
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#define SINEW_HAVE_MXCSR 1
#endif

namespace sinew::simulator {

// Float runs flush subnormals to zero (FTZ + DAZ) inside the engine's loops: displacements far
// from the loads start tiny and underflow into subnormals, which cost some CPUs 2× in float
// (measured on the GPU machine's CPU). Every thread uses the same mode, so results stay independent
// of the thread count; the caller's mode is restored at the end of each chunk. Double never gets
// there.
template <typename T>
struct DenormalGuard {
#ifdef SINEW_HAVE_MXCSR
  unsigned saved = 0;
  DenormalGuard() {
    if constexpr (std::is_same_v<T, float>) {
      saved = _mm_getcsr();
      _mm_setcsr(saved | 0x8040u);  // FTZ (bit 15) | DAZ (bit 6)
    }
  }
  ~DenormalGuard() {
    if constexpr (std::is_same_v<T, float>) _mm_setcsr(saved);
  }
  DenormalGuard(const DenormalGuard&) = delete;
  DenormalGuard& operator=(const DenormalGuard&) = delete;
#endif
};

enum class Schedule { even, balanced };  // static chunks, or chunks handed out as threads free up

// body(chunk, begin, end) for each chunk of [0, n), in scalar T's floating-point mode, on `threads`
// OpenMP threads (≤ 0: OpenMP's default).
template <typename T, typename Body>
void for_each_chunk(std::size_t n, int threads, Body&& body, Schedule schedule = Schedule::even) {
  const std::size_t chunks = chunk_count(n);
  const int t = threads > 0 ? threads : omp_get_max_threads();
  const bool parallel = n >= kParallelMin && t > 1;
  auto run = [&](std::size_t c) {
    DenormalGuard<T> guard;
    body(c, c * kChunk, std::min(n, (c + 1) * kChunk));
  };
  if (schedule == Schedule::balanced) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(t) if (parallel)
    for (std::size_t c = 0; c < chunks; ++c) run(c);
  } else {
#pragma omp parallel for schedule(static) num_threads(t) if (parallel)
    for (std::size_t c = 0; c < chunks; ++c) run(c);
  }
}

// body(i) for each i of [0, n): the CPU launcher of the generic one-item bodies (GatherBody, …),
// which the GPU runs with cuda/forall.cuh.
template <typename T, typename Body>
void cpu_for_each(std::size_t n, int threads, const Body& body) {
  for_each_chunk<T>(n, threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) body(std::int32_t(i));
  });
}

}  // namespace sinew::simulator
