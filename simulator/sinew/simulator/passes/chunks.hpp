#pragma once
// The fixed chunks of the CPU's loops and of every host-side reduction (energies, work): sums are
// taken per chunk of kChunk items and then chunk by chunk in order, so they do not depend on the
// thread count, and the CUDA engine's host sums use the same order.
#include <cstddef>

namespace sinew::simulator {

inline constexpr std::size_t kChunk = 1024;
// Below this many items a loop runs on the calling thread: a parallel region costs more than it
// saves, and spinning threads hurt on a shared machine. Results are identical either way.
inline constexpr std::size_t kParallelMin = 2 * kChunk;

inline std::size_t chunk_count(std::size_t n) {
  return (n + kChunk - 1) / kChunk;
}

}  // namespace sinew::simulator
