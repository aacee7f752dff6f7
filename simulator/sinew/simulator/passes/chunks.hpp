#pragma once
// The fixed chunks of the CPU's loops and of every host-side reduction (energies, work): sums are
// taken per chunk of kChunk items and then chunk by chunk in order, so they do not depend on the
// thread count, and the CUDA engine's host sums use the same order.
#include <cstddef>
#include <cstdint>

#include "sinew/common/math.hpp"

namespace sinew::simulator {

inline constexpr std::size_t kChunk = 1024;
// Below this many items a loop runs on the calling thread: a parallel region costs more than it
// saves, and spinning threads hurt on a shared machine. Results are identical either way.
inline constexpr std::size_t kParallelMin = 2 * kChunk;

inline std::size_t chunk_count(std::size_t n) {
  return (n + kChunk - 1) / kChunk;
}

// Chunk c of a list of items, summed in list order: the kWidth values value[kWidth · i + v] of
// items i = list[k] for k in [c · kChunk, min(size, (c + 1) · kChunk)), into sum[kWidth · c + v].
// Additions only, in the host's order: a device running it gives the host's bits (the CUDA
// engine's strain, elastic and hourglass energies: only the chunk sums leave the device).
template <int kWidth>
struct ChunkSumBody {
  const std::int32_t* list;
  std::int32_t size;
  const double* value;
  double* sum;
  SINEW_HD void operator()(std::int32_t c) const {
    const std::int32_t begin = c * std::int32_t(kChunk);
    const std::int32_t end =
        begin + std::int32_t(kChunk) < size ? begin + std::int32_t(kChunk) : size;
    double a[kWidth] = {};
    for (std::int32_t k = begin; k < end; ++k)
      for (int v = 0; v < kWidth; ++v) a[v] += value[kWidth * std::size_t(list[k]) + v];
    for (int v = 0; v < kWidth; ++v) sum[kWidth * std::size_t(c) + v] = a[v];
  }
};

}  // namespace sinew::simulator
