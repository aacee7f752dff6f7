#include "sinew/sweep/sweep_mpi.hpp"

#include <mpi.h>

#include <chrono>
#include <cstdlib>
#include <future>
#include <thread>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::sweep {

namespace {

// Messages: a worker asks for a run (kRequest), is given its index or −1 (kAssign), sends each
// finished run's row as JSON (kResult) and, when it has nothing left in flight, kDone.
constexpr int kRequest = 1, kAssign = 2, kResult = 3, kDone = 4;

int env_int(std::initializer_list<const char*> names, int fallback) {
  for (const char* n : names)
    if (const char* v = std::getenv(n)) return std::atoi(v);
  return fallback;
}

// Open MPI's blocking calls poll a core; the manager and idle workers sleep between polls instead
// (on a small machine the ranks share the cores with the runs).
void nap() {
  std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

SweepReport manage(const Sweep& sweep, const SweepOptions& options, int workers) {
  SweepReport report;
  const auto pending = start_sweep(sweep, options, report);
  SweepProgress progress(std::int64_t(pending.size()), report.skipped, options.quiet);
  std::size_t next = 0;
  int done = 0;
  auto last_table = std::chrono::steady_clock::now();
  while (done < workers) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    if (!flag) {
      nap();
      continue;
    }
    if (st.MPI_TAG == kRequest || st.MPI_TAG == kDone) {
      int unused = 0;
      MPI_Recv(&unused, 1, MPI_INT, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (st.MPI_TAG == kDone) {
        ++done;
        continue;
      }
      long long index = -1;
      if (next < pending.size() && !simulator::interrupt_requested())
        index = static_cast<long long>(pending[next++]);
      MPI_Send(&index, 1, MPI_LONG_LONG, st.MPI_SOURCE, kAssign, MPI_COMM_WORLD);
    } else if (st.MPI_TAG == kResult) {
      int length = 0;
      MPI_Get_count(&st, MPI_CHAR, &length);
      std::string text(std::size_t(length), '\0');
      MPI_Recv(text.data(), length, MPI_CHAR, st.MPI_SOURCE, kResult, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
      Row row = row_from_json(text);
      const auto i = std::size_t(row.index);
      if (i >= report.rows.size())
        throw FormatError(
            "", "row", fmt::format("rank {} sent run {}, out of range", st.MPI_SOURCE, row.index));
      report.rows[i] = std::move(row);
      ++report.ran;
      progress.finished(report.rows[i]);
      if (std::chrono::steady_clock::now() - last_table > std::chrono::seconds(2)) {
        write_table(sweep, report.rows, options.output_dir);
        last_table = std::chrono::steady_clock::now();
      }
    } else {
      throw FormatError(
          "", "mpi",
          fmt::format("unexpected message tag {} from rank {}", st.MPI_TAG, st.MPI_SOURCE));
    }
  }
  report.failed = progress.failed();
  report.interrupted = simulator::interrupt_requested() || next < pending.size();
  write_table(sweep, report.rows, options.output_dir);
  return report;
}

SweepReport work(const Sweep& sweep, const SweepOptions& options) {
  choose_gpu_wait(options);
  SweepReport report;
  const std::size_t slots = std::size_t(std::max(1, options.settings.concurrent));
  simulator::ModelCache models;  // each model file read once by this rank (outlives the runs)
  std::vector<std::future<Row>> running;
  bool more = true;
  while (more || !running.empty()) {
    while (more && running.size() < slots) {
      if (simulator::interrupt_requested()) {
        more = false;
        break;
      }
      int unused = 0;
      MPI_Send(&unused, 1, MPI_INT, 0, kRequest, MPI_COMM_WORLD);
      long long index = -1;
      MPI_Recv(&index, 1, MPI_LONG_LONG, 0, kAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (index < 0 || std::size_t(index) >= sweep.runs.size()) {
        more = false;
        break;
      }
      const auto& run = sweep.runs[std::size_t(index)];
      running.push_back(std::async(std::launch::async, [&sweep, &run, &options, &models] {
        return execute_run(sweep, run, options, &models);
      }));
    }
    bool any = false;
    for (auto it = running.begin(); it != running.end();) {
      if (it->wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
        ++it;
        continue;
      }
      const Row row = it->get();
      const auto text = row_to_json(row);
      MPI_Send(text.data(), int(text.size()), MPI_CHAR, 0, kResult, MPI_COMM_WORLD);
      ++report.ran;
      if (row.status != "completed") ++report.failed;
      it = running.erase(it);
      any = true;
    }
    if (!any && !running.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  int unused = 0;
  MPI_Send(&unused, 1, MPI_INT, 0, kDone, MPI_COMM_WORLD);
  report.interrupted = simulator::interrupt_requested();
  return report;
}

}  // namespace

bool launched_by_mpi() {
  for (const char* n : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(n)) return true;
  return false;
}

int local_rank() {
  return env_int({"OMPI_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID", "MPI_LOCALRANKID"}, 0);
}

int local_size() {
  return std::max(
      1, env_int({"OMPI_COMM_WORLD_LOCAL_SIZE", "SLURM_NTASKS_PER_NODE", "MPI_LOCALNRANKS"}, 1));
}

MpiSession::MpiSession(int* argc, char*** argv) {
  int provided = 0;
  // Only the main thread calls MPI; runs go on in other threads.
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  MPI_Finalize();
}

void MpiSession::abort(int code) const {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);
}

SweepReport run_sweep_mpi(const Sweep& sweep, SweepOptions options, const MpiSession& session) {
  if (session.size() < 2)
    throw ConfigError("", "mpirun -n", "an MPI sweep needs at least 2 ranks (rank 0 hands out)");
  if (session.rank() == 0) return manage(sweep, options, session.size() - 1);
  options.ranks_on_machine = local_size();
  if (const int gpus = simulator::cuda_device_count(); gpus > 0 && options.settings.device != "cpu")
    options.cuda_device = local_rank() % gpus;
  options.quiet = true;
  return work(sweep, options);
}

}  // namespace sinew::sweep
