#pragma once
// Failure handling across ranks (DESIGN.md §8: reduce the error status before branching).
// A stage runs on every rank; then every rank learns whether any failed. If one did, every
// rank throws the same error: the one of the lowest failing rank, with its kind kept
// (InputError and MeshingError → exit 2, anything else → internal error, exit 1). So an
// error on one rank never leaves the others waiting in the next collective.
#include <functional>
#include <stdexcept>
#include <string>

#include "core/comm.hpp"
#include "core/error.hpp"

namespace cisamr::parallel {

// Marks an error that every rank of the job throws at the same point (the app prints it
// once, on rank 0, and every rank ends normally with the same exit status).
struct CollectiveFailure {
  virtual ~CollectiveFailure() = default;
  int failed_rank = 0;  // the lowest rank that saw the error first
};
class CollectiveInputError : public InputError, public CollectiveFailure {
 public:
  using InputError::InputError;
};
class CollectiveMeshingError : public MeshingError, public CollectiveFailure {
 public:
  using MeshingError::MeshingError;
};
class CollectiveInternalError : public std::runtime_error, public CollectiveFailure {
 public:
  using std::runtime_error::runtime_error;
};

inline bool is_collective(const std::exception& e) { return dynamic_cast<const CollectiveFailure*>(&e) != nullptr; }

// Collective. Runs `stage` here, then agrees on the outcome with every rank (one
// allreduce when all succeed). Throws the agreed Collective* error on every rank when any
// rank's stage threw.
void run_collectively(const Comm& comm, const std::function<void()>& stage);

}  // namespace cisamr::parallel
