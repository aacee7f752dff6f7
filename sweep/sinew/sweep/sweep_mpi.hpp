#pragma once
// A sweep over MPI ranks (built when CMake finds MPI: SINEW_WITH_MPI). Rank 0 is the manager: it
// skips the finished runs, hands out the others one at a time to the ranks that ask (each rank
// runs `concurrent` at once, as run_sweep does), gathers their rows and writes the table. A rank
// that dies loses only the runs it had in flight: every finished run is already in its folder,
// and a rerun redoes the rest (Open MPI's mpirun ends the whole job when a rank dies).
//
// The results folder must be one folder for all ranks (a shared file system on a cluster).
// Each rank on a machine with GPUs takes GPU (local rank mod GPU count); the local rank comes
// from the launcher's environment (OMPI_COMM_WORLD_LOCAL_RANK, SLURM_LOCALID, MPI_LOCALRANKID).
// docs/sweep-format.md, Many GPUs and machines.
#include "sinew/sweep/run_sweep.hpp"

namespace sinew::sweep {

// True when this process was started by an MPI launcher (mpirun, srun with PMI or PMIx): only
// then does sinew-sweep initialise MPI (a plain start stays a single process, with no MPI cost).
bool launched_by_mpi();

// MPI_Init_thread / MPI_Finalize around a sweep.
class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  // Ends every rank (a fatal error on one rank must not leave the others waiting).
  [[noreturn]] void abort(int code) const;

 private:
  int rank_ = 0, size_ = 1;
};

// Runs the sweep over the session's ranks (at least 2: rank 0 hands out, the others run).
// Rank 0 returns the report with every row; the other ranks return their counts only.
SweepReport run_sweep_mpi(const Sweep& sweep, SweepOptions options, const MpiSession& session);

// The launcher's local rank and local size of this process (0 and 1 when none says).
int local_rank();
int local_size();

}  // namespace sinew::sweep
