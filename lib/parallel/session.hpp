#pragma once
// The MPI session of one process (RAII), created once in main. This header does not
// include <mpi.h>: only lib/parallel's session.cpp does.
#include <cstdint>
#include <memory>
#include <string>

#include "core/comm.hpp"
#include "core/progress.hpp"

namespace cisamr::parallel {

// True when an MPI launcher (mpiexec/mpirun of OpenMPI or MPICH, srun with PMI/PMIx)
// started this process. CISAMR_MPI=0 or 1 in the environment overrides the detection.
bool launched_by_mpi_launcher();

class MpiSession {
 public:
  // Initialises MPI (MPI_Init_thread, MPI_THREAD_FUNNELED) when the process was started by
  // an MPI launcher and the module was built with MPI; otherwise the session is serial and
  // a plain `cisamr mesh` never touches MPI. At most one session at a time.
  MpiSession(int& argc, char**& argv);
  ~MpiSession();  // MPI_Finalize
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  bool uses_mpi() const { return uses_mpi_; }
  const Comm& comm() const { return *comm_; }

  // Ends every process of the job now (MPI_Abort): for an error only this rank has seen,
  // outside a collective, so that the others do not wait for it forever.
  [[noreturn]] void abort(int exit_code) const;

 private:
  bool uses_mpi_ = false;
  const Comm* comm_ = nullptr;
};

// Progress of a job, reported by rank 0 for the slowest rank (DESIGN.md §6). Created on every
// rank of `comm` (collective), handed to the library as its Progress. Every rank follows the
// same phases; the slowest is the one with the fewest phases begun, then the smallest share
// of its phase done. Ranks other than 0 send their latest phase and progress to rank 0 with
// non-blocking messages, at most once a second, on a communicator of their own (nothing else
// matches them); rank 0 receives what has arrived whenever it reports and, while it waits in
// a reduction for the others, every few milliseconds (the reduction is polled), and tells
// `renderer` the slowest rank's state. At the end (the destructor, on every rank) each rank
// sends a last message and rank 0 receives all of them, so nothing is left in flight at
// MPI_Finalize; a destructor run by an exception waits for nobody (the error may be this
// rank's alone, about to abort the job). Messages never touch the mesh. On one process, `renderer` is told directly.
class RankProgress final : public Progress {
 public:
  RankProgress(const Comm& comm, Progress* renderer);  // renderer: rank 0's, nullptr elsewhere
  ~RankProgress() override;
  RankProgress(const RankProgress&) = delete;
  RankProgress& operator=(const RankProgress&) = delete;
  void phase(const std::string& name) override;
  void advance(std::int64_t done, std::int64_t total) override;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The communicator of the live session (all processes of the job), or a SerialComm when
// no session exists (tests, library use).
const Comm& world();

}  // namespace cisamr::parallel
