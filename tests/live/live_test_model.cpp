// live_test_model DIR: writes DIR/live_box.h5 and DIR/live_box.yaml, the small case of the
// sinew-live tests (live_support.hpp), for the headless-browser test and manual runs.
#include <cstdio>
#include <exception>

#include "live_support.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: live_test_model DIR\n");
    return 2;
  }
  try {
    sinew::live::testing::write_live_case(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "live_test_model: %s\n", e.what());
    return 1;
  }
  return 0;
}
