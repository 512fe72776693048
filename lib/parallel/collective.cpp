#include "parallel/collective.hpp"

#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace {

enum Kind : std::int32_t { kNone = 0, kInput = 1, kMeshing = 2, kInternal = 3 };

struct LocalError {
  Kind kind = kNone;
  std::string file, field, problem;  // InputError parts; `problem` alone otherwise
};

}  // namespace

void run_collectively(const Comm& comm, const std::function<void()>& stage) {
  LocalError error;
  try {
    stage();
  } catch (const CollectiveFailure&) {
    throw;  // already agreed by a nested stage: every rank is throwing it
  } catch (const InputError& e) {
    error = {kInput, e.file(), e.field(), e.problem()};
  } catch (const MeshingError& e) {
    error = {kMeshing, "", "", e.what()};
  } catch (const std::exception& e) {
    error = {kInternal, "", "", e.what()};
  } catch (...) {
    error = {kInternal, "", "", "unknown exception"};
  }
  if (comm.allreduce_max(std::int64_t{error.kind != kNone}) == 0) return;

  // Someone failed: everybody learns every rank's error and keeps the lowest rank's.
  Packer p;
  p.put<std::int32_t>(error.kind);
  p.put_string(error.file);
  p.put_string(error.field);
  p.put_string(error.problem);
  const std::vector<Bytes> all = allgather_bytes(comm, p.bytes());
  for (std::size_t r = 0; r < all.size(); ++r) {
    Unpacker u(all[r]);
    const auto kind = static_cast<Kind>(u.get<std::int32_t>());
    if (kind == kNone) continue;
    std::string file = u.get_string(), field = u.get_string(), problem = u.get_string();
    const int rank = static_cast<int>(r);
    switch (kind) {
      case kInput: {
        CollectiveInputError e(std::move(file), std::move(field), std::move(problem));
        e.failed_rank = rank;
        throw e;
      }
      case kMeshing: {
        CollectiveMeshingError e(problem);
        e.failed_rank = rank;
        throw e;
      }
      default: {
        CollectiveInternalError e(problem);
        e.failed_rank = rank;
        throw e;
      }
    }
  }
}

}  // namespace cisamr::parallel
