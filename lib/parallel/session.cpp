// The only file that includes <mpi.h>: MpiComm implements core::Comm over MPI_COMM_WORLD.
#include "parallel/session.hpp"

#include <climits>
#include <memory>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#ifdef CISAMR_HAVE_MPI
#include <mpi.h>
#endif

namespace cisamr::parallel {
namespace {

const SerialComm kSerial;
const Comm* g_world = nullptr;

#ifdef CISAMR_HAVE_MPI
class MpiComm final : public Comm {
 public:
  MpiComm() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void barrier() const override { MPI_Barrier(MPI_COMM_WORLD); }
  std::int64_t allreduce_max(std::int64_t v) const override { return reduce(v, MPI_INT64_T, MPI_MAX); }
  std::int64_t allreduce_sum(std::int64_t v) const override { return reduce(v, MPI_INT64_T, MPI_SUM); }
  double allreduce_max(double v) const override { return reduce(v, MPI_DOUBLE, MPI_MAX); }
  double allreduce_min(double v) const override { return reduce(v, MPI_DOUBLE, MPI_MIN); }
  double allreduce_sum(double v) const override { return reduce(v, MPI_DOUBLE, MPI_SUM); }
  std::int64_t exclusive_scan_sum(std::int64_t v) const override {
    std::int64_t out = 0;
    MPI_Exscan(&v, &out, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    return rank_ == 0 ? 0 : out;  // MPI leaves rank 0's result undefined
  }
  std::vector<std::vector<std::uint8_t>> alltoallv(
      const std::vector<std::vector<std::uint8_t>>& sendbufs) const override {
    const auto n = static_cast<std::size_t>(size_);
    if (sendbufs.size() != n) throw std::invalid_argument("alltoallv: one buffer per rank expected");
    std::vector<int> send_counts(n), recv_counts(n), send_displs(n), recv_displs(n);
    std::vector<std::uint8_t> send;
    for (std::size_t r = 0; r < n; ++r) {
      if (sendbufs[r].size() > static_cast<std::size_t>(INT_MAX) || send.size() + sendbufs[r].size() > INT_MAX)
        throw std::length_error("alltoallv: more than 2 GiB in one exchange");
      send_displs[r] = static_cast<int>(send.size());
      send_counts[r] = static_cast<int>(sendbufs[r].size());
      send.insert(send.end(), sendbufs[r].begin(), sendbufs[r].end());
    }
    MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::size_t total = 0;
    for (std::size_t r = 0; r < n; ++r) {
      recv_displs[r] = static_cast<int>(total);
      total += static_cast<std::size_t>(recv_counts[r]);
    }
    if (total > static_cast<std::size_t>(INT_MAX)) throw std::length_error("alltoallv: more than 2 GiB received");
    std::vector<std::uint8_t> recv(total);
    MPI_Alltoallv(send.data(), send_counts.data(), send_displs.data(), MPI_BYTE, recv.data(), recv_counts.data(),
                  recv_displs.data(), MPI_BYTE, MPI_COMM_WORLD);
    std::vector<std::vector<std::uint8_t>> out(n);
    for (std::size_t r = 0; r < n; ++r)
      out[r].assign(recv.begin() + recv_displs[r], recv.begin() + recv_displs[r] + recv_counts[r]);
    return out;
  }

 private:
  template <class T>
  static T reduce(T v, MPI_Datatype type, MPI_Op op) {
    T out{};
    MPI_Allreduce(&v, &out, 1, type, op, MPI_COMM_WORLD);
    return out;
  }
  int rank_ = 0, size_ = 1;
};
std::unique_ptr<MpiComm> g_mpi_comm;
#endif

bool env_set(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0';
}

}  // namespace

bool launched_by_mpi_launcher() {
  if (const char* force = std::getenv("CISAMR_MPI"); force != nullptr && *force != '\0')
    return std::strcmp(force, "0") != 0;
  return env_set("OMPI_COMM_WORLD_SIZE") || env_set("PMI_SIZE") || env_set("PMIX_RANK") ||
         env_set("MPI_LOCALNRANKS");
}

MpiSession::MpiSession(int& argc, char**& argv) {
  if (g_world != nullptr) throw std::logic_error("MpiSession: a session already exists");
  comm_ = &kSerial;
#ifdef CISAMR_HAVE_MPI
  if (launched_by_mpi_launcher()) {
    int provided = 0;
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
    uses_mpi_ = true;
    g_mpi_comm = std::make_unique<MpiComm>();
    comm_ = g_mpi_comm.get();
  }
#else
  (void)argc;
  (void)argv;
#endif
  g_world = comm_;
}

MpiSession::~MpiSession() {
  g_world = nullptr;
#ifdef CISAMR_HAVE_MPI
  if (uses_mpi_) {
    g_mpi_comm.reset();
    MPI_Finalize();
  }
#endif
}

void MpiSession::abort(int exit_code) const {
#ifdef CISAMR_HAVE_MPI
  if (uses_mpi_) MPI_Abort(MPI_COMM_WORLD, exit_code);
#endif
  std::exit(exit_code);
}

const Comm& world() { return g_world != nullptr ? *g_world : kSerial; }

}  // namespace cisamr::parallel
