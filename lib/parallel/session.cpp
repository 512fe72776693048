// The only file that includes <mpi.h>: MpiComm implements core::Comm over MPI_COMM_WORLD.
#include "parallel/session.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#ifdef CISAMR_HAVE_MPI
#include <mpi.h>
#endif

namespace cisamr::parallel {
namespace {

const SerialComm kSerial;
const Comm* g_world = nullptr;
// Set on rank 0 by a RankProgress: what to do while a reduction waits for the other ranks.
std::function<void()> g_while_waiting;

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
    if (!g_while_waiting) {
      MPI_Allreduce(&v, &out, 1, type, op, MPI_COMM_WORLD);
      return out;
    }
    // Progress being reported (a RankProgress on every rank: a blocking and a non-blocking
    // reduction do not match, so all ranks poll): the same reduction, polled, so that rank 0
    // goes on reporting while the others are still working.
    MPI_Request request = MPI_REQUEST_NULL;
    MPI_Iallreduce(&v, &out, 1, type, op, MPI_COMM_WORLD, &request);
    int done = 0;
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    auto last_call = std::chrono::steady_clock::now();
    while (done == 0) {
      if (std::chrono::steady_clock::now() - last_call > std::chrono::milliseconds(50)) {
        g_while_waiting();
        last_call = std::chrono::steady_clock::now();
      }
      std::this_thread::sleep_for(std::chrono::microseconds(100));
      MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    }
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

#ifdef CISAMR_HAVE_MPI
// Open MPI with every rank on this node: choose the ob1 messaging layer (shared memory
// through its vader transport) unless the user chose one. The default probes UCX and the
// network layers first, which costs 0.2-0.3 s per start on a workstation (measured: a bare
// MPI_Init under `mpiexec -n 2`, 0.36 s against 0.12 s) for nothing a single node can use;
// the messages here are small, so across nodes the default is kept.
void prefer_shared_memory_on_one_node() {
  const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
  const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
  if (size == nullptr || local == nullptr || std::strcmp(size, local) != 0) return;
  if (env_set("OMPI_MCA_pml")) return;
  setenv("OMPI_MCA_pml", "ob1", 0);  // read by MPI_Init from the environment
}
#endif

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
    prefer_shared_memory_on_one_node();
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

struct RankProgress::Impl {
  Progress* renderer = nullptr;
  int rank = 0, size = 1;
  // This rank's state: phases begun, the current one's name and work done.
  struct State {
    std::int64_t ordinal = 0, done = 0, total = 0;
    std::string name;
    bool finished = false;
  };
  State own;
  int uncaught = 0;  // std::uncaught_exceptions() at construction
#ifdef CISAMR_HAVE_MPI
  static constexpr int kTag = 1;
  struct Message {
    std::int64_t ordinal, done, total, finished;
    char name[32];
  };
  MPI_Comm channel = MPI_COMM_NULL;
  MPI_Request pending = MPI_REQUEST_NULL;
  Message outgoing{};
  double last_sent = -1e300;
  std::vector<State> states;  // rank 0: every rank's latest
  int shown_rank = -1;
  std::int64_t shown_ordinal = -1, shown_done = -1;

  // Ranks other than 0: the latest state to rank 0, unless the last message is still in
  // flight or (`throttled`) less than a second old.
  void send(bool throttled) {
    const double now = MPI_Wtime();
    if (throttled && now - last_sent < 1.0) return;
    int free = 1;
    if (pending != MPI_REQUEST_NULL) MPI_Test(&pending, &free, MPI_STATUS_IGNORE);
    if (free == 0) return;
    outgoing = Message{own.ordinal, own.done, own.total, 0, {}};
    std::strncpy(outgoing.name, own.name.c_str(), sizeof outgoing.name - 1);
    MPI_Isend(&outgoing, sizeof outgoing, MPI_BYTE, 0, kTag, channel, &pending);
    last_sent = now;
  }
  void receive(bool wait) {
    MPI_Status status;
    int arrived = 1;
    if (!wait) MPI_Iprobe(MPI_ANY_SOURCE, kTag, channel, &arrived, &status);
    if (arrived == 0) return;
    Message m{};
    MPI_Recv(&m, sizeof m, MPI_BYTE, MPI_ANY_SOURCE, kTag, channel, &status);
    State& s = states[static_cast<std::size_t>(status.MPI_SOURCE)];
    s.ordinal = m.ordinal, s.done = m.done, s.total = m.total, s.finished = m.finished != 0;
    m.name[sizeof m.name - 1] = '\0';
    s.name = m.name;
  }
  // Rank 0: what has arrived, then the slowest unfinished rank's state to the renderer.
  void report() {
    for (;;) {
      int arrived = 0;
      MPI_Iprobe(MPI_ANY_SOURCE, kTag, channel, &arrived, MPI_STATUS_IGNORE);
      if (arrived == 0) break;
      receive(true);
    }
    states[0] = own;
    int slowest = -1;
    const auto share = [](const State& s) { return s.total > 0 ? double(s.done) / double(s.total) : 0.0; };
    for (int r = 0; r < size; ++r) {
      const State& s = states[static_cast<std::size_t>(r)];
      if (s.finished || s.ordinal == 0) continue;
      const State* b = slowest < 0 ? nullptr : &states[static_cast<std::size_t>(slowest)];
      if (b == nullptr || s.ordinal < b->ordinal || (s.ordinal == b->ordinal && share(s) < share(*b))) slowest = r;
    }
    if (slowest < 0 || renderer == nullptr) return;
    const State& s = states[static_cast<std::size_t>(slowest)];
    if (slowest != shown_rank || s.ordinal != shown_ordinal) {
      renderer->phase(s.name + " (slowest: rank " + std::to_string(slowest) + ")");
      shown_rank = slowest, shown_ordinal = s.ordinal, shown_done = -1;
    }
    if (s.total > 0 && s.done != shown_done) {
      renderer->advance(s.done, s.total);
      shown_done = s.done;
    }
  }
#endif
  void update(bool new_phase) {
#ifdef CISAMR_HAVE_MPI
    if (size > 1) {
      if (rank == 0)
        report();
      else
        send(!new_phase);  // a new phase is sent at once unless the last message is in flight
      return;
    }
#endif
    if (renderer == nullptr) return;
    if (new_phase) renderer->phase(own.name);
    else renderer->advance(own.done, own.total);
  }
};

RankProgress::RankProgress(const Comm& comm, Progress* renderer) : impl_(std::make_unique<Impl>()) {
  impl_->renderer = renderer;
  impl_->rank = comm.rank();
  impl_->size = comm.size();
  impl_->uncaught = std::uncaught_exceptions();
#ifdef CISAMR_HAVE_MPI
  if (impl_->size > 1) {
    MPI_Comm_dup(MPI_COMM_WORLD, &impl_->channel);
    if (impl_->rank == 0) {
      impl_->states.resize(static_cast<std::size_t>(impl_->size));
      g_while_waiting = [impl = impl_.get()] { impl->report(); };
    } else {
      g_while_waiting = [] {};  // polls like rank 0 (above); nothing to report meanwhile
    }
  }
#endif
}

RankProgress::~RankProgress() {
#ifdef CISAMR_HAVE_MPI
  Impl& p = *impl_;
  if (p.size > 1) {
    g_while_waiting = nullptr;
    if (std::uncaught_exceptions() > p.uncaught) {
      // Unwinding: the error may be this rank's alone (the job is about to be aborted), so
      // wait for nobody. What is in flight is a few bytes, sent eagerly.
      if (p.pending != MPI_REQUEST_NULL) MPI_Request_free(&p.pending);
      return;
    }
    // Every rank's last message is received before the channel goes: nothing stays in flight.
    if (p.rank == 0) {
      for (int r = 1; r < p.size; ++r)
        while (!p.states[static_cast<std::size_t>(r)].finished) p.receive(true);
    } else {
      if (p.pending != MPI_REQUEST_NULL) MPI_Wait(&p.pending, MPI_STATUS_IGNORE);
      Impl::Message last{p.own.ordinal, p.own.done, p.own.total, 1, {}};
      MPI_Send(&last, sizeof last, MPI_BYTE, 0, Impl::kTag, p.channel);
    }
    MPI_Comm_free(&p.channel);
  }
#endif
}

void RankProgress::phase(const std::string& name) {
  impl_->own = {impl_->own.ordinal + 1, 0, 0, name, false};
  impl_->update(true);
}

void RankProgress::advance(std::int64_t done, std::int64_t total) {
  impl_->own.done = done;
  impl_->own.total = total;
  impl_->update(false);
}

const Comm& world() { return g_world != nullptr ? *g_world : kSerial; }

}  // namespace cisamr::parallel
