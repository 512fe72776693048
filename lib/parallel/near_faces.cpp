#include "parallel/near_faces.hpp"

#include <algorithm>

#include "core/check.hpp"
#include "grid/tet_lattice.hpp"
#include "parallel/distributed.hpp"
#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace {

// The closed box of coarse cells `box`, in fine lattice units.
struct ClosedBox {
  grid::LatticePoint3 lo{}, hi{};
  ClosedBox(const grid::Lattice<3>& lattice, const grid::CellRange<3>& box) {
    for (int d = 0; d < 3; ++d) lo[d] = box.lo[d] * lattice.units(0), hi[d] = box.hi[d] * lattice.units(0);
  }
  bool holds(const grid::LatticePoint3& p) const {
    for (int d = 0; d < 3; ++d)
      if (p[d] < lo[d] || p[d] > hi[d]) return false;
    return true;
  }
  bool meets(const ClosedBox& o) const {
    for (int d = 0; d < 3; ++d)
      if (o.hi[d] < lo[d] || o.lo[d] > hi[d]) return false;
    return true;
  }
};

struct Decision {  // what the owner sends for one node
  Vec3 position;
  PhaseMask mask;
  radapt::NodeState state;
};

}  // namespace

std::int64_t exchange_near_faces(const Comm& comm, const grid::Lattice<3>& lattice,
                                 const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine) {
  const int ranks = comm.size();
  const int partitions = static_cast<int>(boxes.size());
  std::vector<ClosedBox> closed;
  closed.reserve(boxes.size());
  for (const auto& b : boxes) closed.emplace_back(lattice, b);

  // Requests, per owner's rank: (owner partition, key); what each asked for: (partition of
  // this rank by position in `mine`, node id), in the same order.
  std::vector<Packer> ask(static_cast<std::size_t>(ranks));
  std::vector<std::vector<std::array<std::int32_t, 2>>> asked(static_cast<std::size_t>(ranks));
  std::vector<int> neighbours;
  for (std::size_t i = 0; i < mine.size(); ++i) {
    if (!mine[i].asks) continue;
    const radapt::Nodes3& nodes = mine[i].snapped->nodes;
    const ClosedBox& own = closed[static_cast<std::size_t>(mine[i].id)];
    // The partitions whose closed box meets this one's forest, ascending ids.
    const ClosedBox forest(lattice, mine[i].snapped->grid.forest.range());
    neighbours.clear();
    for (int q = 0; q < partitions; ++q)
      if (q != mine[i].id && closed[static_cast<std::size_t>(q)].meets(forest)) neighbours.push_back(q);
    for (std::size_t n = 0; n < nodes.key.size(); ++n) {
      const grid::LatticePoint3 p = grid::key3_point(nodes.key[n]);
      if (own.holds(p)) continue;
      int owner = -1;
      for (int q : neighbours)
        if (closed[static_cast<std::size_t>(q)].holds(p)) {
          owner = q;
          break;
        }
      CISAMR_CHECK(owner >= 0, "exchange_near_faces: a node in no partition's box");
      const auto r = static_cast<std::size_t>(rank_of_partition(owner, partitions, ranks));
      ask[r].put<std::int32_t>(owner);
      ask[r].put<grid::LatticeKey3>(nodes.key[n]);
      asked[r].push_back({static_cast<std::int32_t>(i), static_cast<std::int32_t>(n)});
    }
  }
  std::vector<Bytes> requests(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) requests[static_cast<std::size_t>(r)] = ask[static_cast<std::size_t>(r)].take();
  const std::vector<Bytes> received = comm.alltoallv(requests);

  // Answers, in the order asked; no node is written before every answer is read.
  const int first = mine.empty() ? 0 : mine.front().id;
  std::vector<Bytes> answers(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    Unpacker u(received[static_cast<std::size_t>(r)]);
    Packer answer;
    while (!u.done()) {
      const auto owner = u.get<std::int32_t>();
      const auto key = u.get<grid::LatticeKey3>();
      const auto at = static_cast<std::size_t>(owner - first);
      CISAMR_CHECK(at < mine.size() && mine[at].id == owner, "exchange_near_faces: a request for another rank's partition");
      const radapt::Nodes3& nodes = mine[at].snapped->nodes;
      const std::int32_t n = nodes.id(key);
      CISAMR_CHECK(n >= 0, "exchange_near_faces: the owner lacks a node of its closed box");
      const auto k = static_cast<std::size_t>(n);
      answer.put(Decision{nodes.position[k], nodes.mask[k], nodes.state[k]});
    }
    answers[static_cast<std::size_t>(r)] = answer.take();
  }
  const std::vector<Bytes> replies = comm.alltoallv(answers);

  std::int64_t taken = 0;
  for (int r = 0; r < ranks; ++r) {
    Unpacker u(replies[static_cast<std::size_t>(r)]);
    for (const auto& [i, n] : asked[static_cast<std::size_t>(r)]) {
      const auto d = u.get<Decision>();
      radapt::Nodes3& nodes = mine[static_cast<std::size_t>(i)].snapped->nodes;
      const auto k = static_cast<std::size_t>(n);
      nodes.position[k] = d.position, nodes.mask[k] = d.mask, nodes.state[k] = d.state;
      ++taken;
    }
    CISAMR_CHECK(u.done(), "exchange_near_faces: more answers than questions");
  }
  return taken;
}

}  // namespace cisamr::parallel
