#pragma once
// How the tools' idle OpenMP threads wait. On a machine with other load, OpenMP's default spinning
// wait made all cores run 1.5–5× slower than one thread (issue 34): spinning threads take the time
// slices the working ones need. Measured on the 2-core development machine with a busy loop beside
// (docs/development.md): 2 threads spinning 19.5 s, 2 threads waiting passively 7.9 s, 1 thread
// 21.0 s. So the tools (sinew-simulate, sinew-sweep, sinew-live, sinew-voxelize) keep OpenMP's
// thread count (every core) and wait passively unless the user set OMP_WAIT_POLICY.
#include <string>

namespace sinew::threads {

// Call first in main(), before anything uses OpenMP. libgomp reads OMP_WAIT_POLICY when it is
// loaded, before main() runs, so setting it later changes nothing: when the variable is unset this
// sets it to PASSIVE and executes the same program again (/proc/self/exe, same arguments) once.
// When the user set it, or the new start fails, the process goes on as it is.
void prefer_passive_wait(char** argv);

// "passive wait" (sinew's default), "active wait (OMP_WAIT_POLICY)" (the user's),
// "OpenMP's default wait" (not set: prefer_passive_wait() was not called or could not start).
std::string wait_policy_text();

// One line for --explain: "threads: 2 (OpenMP's default: every core; passive wait)", or, for a
// count from the command line, "threads: 4 (--threads; passive wait)".
std::string explain(int threads, bool from_command_line);

}  // namespace sinew::threads
