#pragma once
// The CUDA backend (docs/cuda-backend.md): the Backend of backend.hpp on one NVIDIA GPU, calling
// the same physics functions (physics/element.hpp) as the CPU backend. Host-only API: no CUDA
// headers. Built when CMake's SINEW_CUDA_ENABLED is on; otherwise make_cuda_backend throws
// ConfigError ("built without CUDA") and cuda_device_available() is false.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/passes/sliding_lists.hpp"

namespace sinew::simulator {

// Force assembly. gather: each element writes its 8 nodal forces to an E × 8 buffer and
// each node sums its (element, corner) entries in a fixed order: bit-identical from run to run.
// atomic: elements add into the nodal forces with atomicAdd: no buffer, but the summation order,
// hence the last bits, change from run to run.
// tiled: gather inside lattice tiles (lattice_tiles.hpp): a block computes the elements around its
// tile's nodes into shared memory and sums them there, in gather's order; no E × 8 buffer in DRAM,
// elements on a tile's rim computed twice. Deterministic too; equal to gather up to the last bits
// where the compiler fuses multiply-adds differently (measured: ≤ 2e-13 relative after 700 steps).
// automatic (default): tiled where the tiles compute few elements twice (tiles_pay_off: thin dense
// slabs such as a face), else gather.
enum class ForceAssembly { gather, atomic, tiled, automatic };

struct CudaOptions {
  ForceAssembly assembly = ForceAssembly::automatic;
  // Steps per captured CUDA graph (rounded up to a multiple of 3, the displacement-buffer cycle);
  // status flags are read once per graph launch.
  int graph_steps = 96;
  int device = 0;
  // Skin s of the sliding nodes' candidate lists, in grid cells of the surface (about mean edges):
  // a node tests only its listed triangles (those within d1 + 2 s of where it last searched) until
  // it moves more than s, then searches the grid again. Exact for any s > 0; larger: longer lists,
  // rarer searches (docs/cuda-backend.md, Sliding; docs/performance.md has the sweep).
  double sliding_skin = kDefaultSlidingSkin;
  // Steps between refreshes of the candidate lists in graph steps (each refresh keeps a node's list
  // while it is within s/2 of its anchor), at the start of a run. Exact for any value: a node that
  // moves more than s/2 before the next refresh misses its list and the batch is replayed with
  // inline refreshes; after two such batches the interval is halved, and once refreshing every
  // step misses in two batches too, the graph refreshes inline.
  int sliding_refresh_interval = 16;
  // Tiled assembly: tiles wanted per SM. The node lattice is cut into columns of 15 × 15 nodes, and
  // those into z chunks only as far as needed for this many tiles (lattice_tiles.hpp): more, shorter
  // tiles fill the GPU better but compute more rim elements twice.
  int tiles_per_sm = 3;
  // Graph steps launch each kernel that follows another as a programmatic dependent launch (sm_90
  // and later; ignored below): its blocks start, and load what the kernel before it does not
  // write, while that kernel finishes (docs/cuda-backend.md, Launches). Same results either way.
  bool programmatic_launch = true;
};

// True when the CUDA runtime sees at least one device (false when built without CUDA).
bool cuda_device_available();
// The number of devices the CUDA runtime sees (0 when built without CUDA or without a device).
int cuda_device_count();
// "NVIDIA H200 (sm_90, 132 SMs, 139.8 GiB)" or "" without a device.
std::string cuda_device_name();

// How the host threads of this process wait for device `device` (cudaStreamSynchronize and the
// like): false, CUDA's default (spinning while the process has fewer contexts than the machine has
// cores); true, asleep on a synchronisation primitive (cudaDeviceScheduleBlockingSync). Many
// engines in threads of one process (sinew-sweep --concurrent K, K above the cores) wait most of
// the time: spinning, they would take the cores that the threads whose queues ran dry need to
// launch their next graphs. Throws sinew::Error on a CUDA failure; nothing without CUDA.
void set_cuda_blocking_wait(int device, bool blocking);

// The CUDA backend for the Setup's precision. Throws ConfigError on a bad Setup (make_plan), on a
// build without CUDA or without a device, and sinew::Error on CUDA runtime failures.
std::unique_ptr<Backend> make_cuda_backend(const formats::Model& model, const Setup& setup,
                                           const CudaOptions& options = {});

// Benchmark hooks of a CUDA backend (dynamic_cast a Backend made by make_cuda_backend).
class CudaTiming {
 public:
  virtual ~CudaTiming() = default;
  // Runs `launches` graph launches of graph_steps() steps each, timing each with CUDA events;
  // returns milliseconds per launch. Status flags are checked once at the end (InstabilityError).
  virtual std::vector<float> timed_graph_launches(int launches) = 0;
  virtual int graph_steps() const = 0;
  // Device time of each stage of one step (stage name, ms; median over `repeats` direct steps,
  // each stage bracketed by CUDA events, so launch gaps are excluded). Advances the state.
  virtual std::vector<std::pair<std::string, float>> stage_times(int repeats) = 0;
  // Bytes one step must move at least (each array read or written once), for bandwidth figures.
  virtual double bytes_per_step() const = 0;
  // The assembly in use (automatic resolved to gather or tiled).
  virtual ForceAssembly assembly() const = 0;
};

// Device-to-device copy bandwidth (bytes read + bytes written per second) over `bytes` bytes,
// median of `repeats` timed copies. Throws when built without CUDA.
double measure_copy_bandwidth(std::size_t bytes, int repeats = 20);

namespace detail {
// Between cuda_backend.cpp (checks, messages) and cuda/cuda_device.cu (the runtime).
std::unique_ptr<Backend> make_cuda_engine(const formats::Model& model, const Setup& setup,
                                          Plan plan, const CudaOptions& options);
struct CudaDeviceProperties {
  std::string name;
  int major = 0, minor = 0, sms = 0;
  double bytes = 0;  // global memory
};
bool cuda_device_properties(CudaDeviceProperties& out);  // false without a device
}  // namespace detail

}  // namespace sinew::simulator
