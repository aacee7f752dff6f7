// live_compare_results LIVE.h5 BATCH.h5: compares the frames the two results files share (by
// engine step) bit for bit: displacement, von Mises stress and J where present. Prints the count;
// exit 0 when at least 2 frames are shared and all are identical, 1 otherwise.
#include <cstdio>
#include <cstring>

#include "results_compare.hpp"

int main(int argc, char** argv) {
  using sinew::live::testing::frames_by_step;
  if (argc != 3) {
    std::fprintf(stderr, "usage: live_compare_results LIVE.h5 BATCH.h5\n");
    return 2;
  }
  std::size_t shared = 0, differ = 0;
  for (const char* name : {"/frames/displacement", "/frames/von_mises", "/frames/J"}) {
    const auto a = frames_by_step(argv[1], name), b = frames_by_step(argv[2], name);
    for (const auto& [step, v] : a) {
      const auto it = b.find(step);
      if (it == b.end()) continue;
      ++shared;
      if (v.size() != it->second.size() ||
          std::memcmp(v.data(), it->second.data(), v.size() * sizeof(double)) != 0) {
        std::printf("%s differs at step %lld\n", name, static_cast<long long>(step));
        ++differ;
      }
    }
  }
  std::printf("%zu frames compared, %zu differ\n", shared, differ);
  return shared >= 2 && differ == 0 ? 0 : 1;
}
