#include "parallel/periodic_masters.hpp"

#include <cstdio>
#include <cstring>
#include <string>
#include <unordered_map>

#include "core/error.hpp"
#include "mesh/periodic_links.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace periodic_detail {

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

template <int Dim>
struct KeyHash {
  std::size_t operator()(const mesh::PeriodicKey<Dim>& key) const {
    std::uint64_t h = 0;
    for (std::uint64_t k : key) h = mix(h ^ k);
    return static_cast<std::size_t>(h);
  }
};

template <int Dim>
std::string point_text(const double* p) {
  std::string s = "(";
  for (int d = 0; d < Dim; ++d) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", p[d]);
    s += (d > 0 ? ", " : "") + std::string(buf);
  }
  return s + ")";
}

}  // namespace periodic_detail
using namespace periodic_detail;

template <int Dim>
std::vector<GlobalId> periodic_masters(const Comm& comm, const mesh::SimplexMesh<Dim>& piece, const Box<Dim>& faces,
                                       const std::array<bool, Dim>& axes, bool voids) {
  using Key = mesh::PeriodicKey<Dim>;
  const int size = comm.size();
  const std::size_t nodes = piece.node_count();
  const auto home = [&](const Key& key) {
    return static_cast<std::size_t>(KeyHash<Dim>{}(key) % static_cast<std::uint64_t>(size));
  };
  const auto gid = [&](std::size_t n) { return piece.node_global_id.empty() ? GlobalId(n) : piece.node_global_id[n]; };
  std::vector<GlobalId> master(nodes, -1);

  // 1. To each rendezvous rank: the candidate masters it hashes (key, global id), then the
  // keys this rank's slaves ask for, in node order.
  std::vector<Packer> candidates(static_cast<std::size_t>(size)), requests(static_cast<std::size_t>(size));
  std::vector<std::uint64_t> candidate_count(static_cast<std::size_t>(size), 0);
  std::vector<std::vector<std::size_t>> asked(static_cast<std::size_t>(size));  // per rank: the slaves, in order
  for (std::size_t n = 0; n < nodes; ++n) {
    const double* p = &piece.coords[n * Dim];
    const std::uint8_t shift = mesh::periodic_shift<Dim>(p, faces, axes);
    if (shift != 0) {
      const Key key = mesh::periodic_key<Dim>(p, faces, shift, mesh::periodic_phase(piece, n));
      const std::size_t r = home(key);
      requests[r].put(key);
      asked[r].push_back(n);
    } else if (mesh::on_periodic_min_face<Dim>(p, faces, axes)) {
      const Key key = mesh::periodic_key<Dim>(p, faces, 0, mesh::periodic_phase(piece, n));
      const std::size_t r = home(key);
      candidates[r].put(key);
      candidates[r].put<std::int64_t>(gid(n));
      ++candidate_count[r];
    }
  }
  std::vector<Bytes> send(static_cast<std::size_t>(size));
  for (std::size_t r = 0; r < send.size(); ++r) {
    Packer p;
    p.put<std::uint64_t>(candidate_count[r]);
    Bytes& b = p.bytes();
    const Bytes c = candidates[r].take(), q = requests[r].take();
    b.insert(b.end(), c.begin(), c.end());
    b.insert(b.end(), q.begin(), q.end());
    send[r] = p.take();
  }
  std::vector<Bytes> received = comm.alltoallv(send);

  // 2. Rendezvous: the masters by key (copies of one node on several ranks agree), then
  // one answer per request, in the order asked (-1: no such master).
  std::vector<Packer> answers(static_cast<std::size_t>(size));
  run_collectively(comm, [&] {
    std::unordered_map<Key, GlobalId, KeyHash<Dim>> by_key;
    std::vector<std::size_t> request_start(static_cast<std::size_t>(size));
    for (int r = 0; r < size; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      const auto count = u.get<std::uint64_t>();
      for (std::uint64_t i = 0; i < count; ++i) {
        const Key key = u.get<Key>();
        const auto id = u.get<std::int64_t>();
        const auto [it, inserted] = by_key.emplace(key, id);
        if (!inserted && it->second != id)
          throw MeshingError("periodic masters: nodes with global ids " + std::to_string(it->second) + " and " +
                             std::to_string(id) + " lie at the same position on a min face: the mesh has duplicate nodes");
      }
      request_start[static_cast<std::size_t>(r)] = sizeof(std::uint64_t) + count * (sizeof(Key) + sizeof(std::int64_t));
    }
    for (int r = 0; r < size; ++r) {
      const Bytes& b = received[static_cast<std::size_t>(r)];
      for (std::size_t at = request_start[static_cast<std::size_t>(r)]; at + sizeof(Key) <= b.size(); at += sizeof(Key)) {
        Key key;
        std::memcpy(&key, b.data() + at, sizeof key);
        const auto it = by_key.find(key);
        answers[static_cast<std::size_t>(r)].put<std::int64_t>(it == by_key.end() ? -1 : it->second);
      }
    }
  });
  for (int r = 0; r < size; ++r) send[static_cast<std::size_t>(r)] = answers[static_cast<std::size_t>(r)].take();
  received = comm.alltoallv(send);

  // 3. The answers, in the order asked.
  run_collectively(comm, [&] {
    for (int r = 0; r < size; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      for (std::size_t n : asked[static_cast<std::size_t>(r)]) {
        master[n] = u.get<std::int64_t>();
        if (master[n] >= 0 || voids) continue;
        const double* p = &piece.coords[n * Dim];
        std::array<double, Dim> moved;
        const std::uint8_t shift = mesh::periodic_shift<Dim>(p, faces, axes);
        for (int a = 0; a < Dim; ++a) moved[static_cast<std::size_t>(a)] = (shift >> a) & 1 ? faces.min[a] : p[a];
        throw MeshingError("periodic masters: node " + std::to_string(gid(n)) + " (global id) at " + point_text<Dim>(p) +
                           " lies on a periodic max face but no rank holds a node at its translate " +
                           point_text<Dim>(moved.data()) + ": the mesh is not periodic");
      }
      if (!u.done()) throw std::logic_error("periodic masters: more answers than questions");
    }
  });
  return master;
}

template std::vector<GlobalId> periodic_masters<2>(const Comm&, const mesh::SimplexMesh<2>&, const Box<2>&,
                                                   const std::array<bool, 2>&, bool);
template std::vector<GlobalId> periodic_masters<3>(const Comm&, const mesh::SimplexMesh<3>&, const Box<3>&,
                                                   const std::array<bool, 3>&, bool);

}  // namespace cisamr::parallel
