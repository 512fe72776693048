#pragma once
// The MPI session of one process (RAII), created once in main. This header does not
// include <mpi.h>: only lib/parallel's session.cpp does.
#include "core/comm.hpp"

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

// The communicator of the live session (all processes of the job), or a SerialComm when
// no session exists (tests, library use).
const Comm& world();

}  // namespace cisamr::parallel
