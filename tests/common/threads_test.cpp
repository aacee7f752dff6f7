// The tools' OpenMP wait policy and its --explain line (issue 34: all cores with spinning waits
// ran 1.5–5× slower than one thread on a loaded machine).
#include "sinew/common/threads.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace {

using sinew::threads::explain;

TEST(Threads, TheExplainLineSaysWhereTheCountAndTheWaitCameFrom) {
  ::unsetenv("OMP_NUM_THREADS");
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);  // as ctest sets it (tests/CMakeLists.txt)
  ::unsetenv("SINEW_OMP_WAIT_POLICY_SET");
  EXPECT_EQ(explain(3, true), "threads: 3 (--threads; passive wait (OMP_WAIT_POLICY))");
  EXPECT_EQ(explain(2, false),
            "threads: 2 (OpenMP's default: every core; passive wait (OMP_WAIT_POLICY))");
  ::setenv("OMP_NUM_THREADS", "4", 1);
  EXPECT_EQ(explain(4, false), "threads: 4 (OMP_NUM_THREADS=4; passive wait (OMP_WAIT_POLICY))");
  ::unsetenv("OMP_NUM_THREADS");
}

TEST(Threads, APolicySetBySinewIsNamedAsItsDefault) {
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  ::setenv("SINEW_OMP_WAIT_POLICY_SET", "1", 1);
  EXPECT_EQ(explain(2, false), "threads: 2 (OpenMP's default: every core; passive wait)");
  ::unsetenv("SINEW_OMP_WAIT_POLICY_SET");
  ::unsetenv("OMP_WAIT_POLICY");
  EXPECT_EQ(sinew::threads::wait_policy_text(), "OpenMP's default wait");
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
}

TEST(Threads, AUserPolicyIsKept) {
  ::setenv("OMP_WAIT_POLICY", "active", 1);
  ::unsetenv("SINEW_OMP_WAIT_POLICY_SET");
  char name[] = "not-started-again";
  char* argv[] = {name, nullptr};
  sinew::threads::prefer_passive_wait(argv);  // returns: the user's policy stands
  EXPECT_STREQ(std::getenv("OMP_WAIT_POLICY"), "active");
  EXPECT_EQ(sinew::threads::wait_policy_text(), "active wait (OMP_WAIT_POLICY)");
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
}

}  // namespace
