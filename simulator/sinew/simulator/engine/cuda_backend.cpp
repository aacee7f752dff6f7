// Host side of the CUDA backend's entry points (messages and logging live here: spdlog/fmt stay
// out of .cu files); the engine itself is in cuda/, or absent when built without CUDA.
#include "sinew/simulator/engine/cuda_backend.hpp"

#include <cmath>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"

namespace sinew::simulator {

#if defined(SINEW_CUDA_ENABLED)
std::string cuda_device_name() {
  detail::CudaDeviceProperties p;
  if (!detail::cuda_device_properties(p)) return "";
  return fmt::format("{} (sm_{}{}, {} SMs, {:.1f} GiB)", p.name, p.major, p.minor, p.sms,
                     p.bytes / (1024.0 * 1024.0 * 1024.0));
}

std::unique_ptr<Backend> make_cuda_backend(const formats::Model& model, const Setup& setup,
                                           const CudaOptions& options) {
  if (!cuda_device_available())
    throw ConfigError("", "device",
                      "the CUDA backend was requested but no CUDA device is available");
  if (options.sliding_refresh_interval < 1)
    throw ConfigError(
        "", "sliding_refresh_interval",
        fmt::format("must be at least 1 step, got {}", options.sliding_refresh_interval));
  if (options.tiles_per_sm < 1)
    throw ConfigError("", "tiles_per_sm",
                      fmt::format("must be at least 1, got {}", options.tiles_per_sm));
  if (!(options.sliding_skin > 0) || !std::isfinite(options.sliding_skin))
    throw ConfigError(
        "", "sliding_skin",
        fmt::format("must be a positive number of grid cells, got {}", options.sliding_skin));
  Plan plan = make_plan(model, setup);
  for (const auto& w : plan.warnings) log::warn("{}", w);
  return detail::make_cuda_engine(model, setup, std::move(plan), options);
}
#else
int cuda_device_count() {
  return 0;
}
bool cuda_device_available() {
  return false;
}
std::string cuda_device_name() {
  return "";
}

std::unique_ptr<Backend> make_cuda_backend(const formats::Model&, const Setup&,
                                           const CudaOptions&) {
  throw ConfigError("", "device",
                    "the CUDA backend was requested but sinew was built without CUDA "
                    "(configure with -DSINEW_WITH_CUDA=ON where nvcc is available)");
}

double measure_copy_bandwidth(std::size_t, int) {
  throw ConfigError("", "device", "sinew was built without CUDA");
}

void set_cuda_blocking_wait(int, bool) {}
#endif

}  // namespace sinew::simulator
