#include "parallel/near_faces.hpp"

#include <algorithm>

#include "core/check.hpp"
#include "grid/tet_lattice.hpp"
#include "parallel/collective.hpp"
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

// The round trip of one exchange: ask[r] holds the questions for rank r, each led by the id
// of the partition asked; each rank answers what it received, one question at a time, after
// checking that the partition asked is its own (`answer(j, u, out)`: j its position in
// `mine`, the question's remaining fields read from u, the answer written to out). Returns,
// per rank, the answers to this rank's questions in their order. Each local step agrees on its errors (a check failing on one rank must not
// leave the others waiting in the next alltoallv).
template <class AnswerOne>
std::vector<Bytes> ask_and_answer(const Comm& comm, std::vector<Packer>& ask, std::span<SnappedPartition> mine,
                                  AnswerOne&& answer) {
  const int ranks = comm.size();
  std::vector<Bytes> questions(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) questions[static_cast<std::size_t>(r)] = ask[static_cast<std::size_t>(r)].take();
  const std::vector<Bytes> received = comm.alltoallv(questions);
  const int first = mine.empty() ? 0 : mine.front().id;
  std::vector<Bytes> answers(static_cast<std::size_t>(ranks));
  run_collectively(comm, [&] {
    for (int r = 0; r < ranks; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      Packer out;
      while (!u.done()) {
        const auto owner = u.get<std::int32_t>();
        const auto j = static_cast<std::size_t>(owner - first);
        CISAMR_CHECK(j < mine.size() && mine[j].id == owner, "exchange near faces: a question for another rank's partition");
        answer(j, u, out);
      }
      answers[static_cast<std::size_t>(r)] = out.take();
    }
  });
  return comm.alltoallv(answers);
}

// One round of questions and answers. `nodes_of(i)`: partition i's node table; `wanted(i, n)`:
// whether its node n (outside its closed box) is asked for; `answer(j, m)`: what partition j
// (the owner) says of its node m; `take(i, n, answer)`: partition i takes it. Returns the
// nodes taken.
template <class Answer, class NodesOf, class Wanted, class AnswerOf, class Take>
std::int64_t ask_owners(const Comm& comm, const grid::Lattice<3>& lattice, const std::vector<grid::CellRange<3>>& boxes,
                        std::span<SnappedPartition> mine, NodesOf&& nodes_of, Wanted&& wanted, AnswerOf&& answer_of,
                        Take&& take) {
  const int ranks = comm.size();
  const int partitions = static_cast<int>(boxes.size());
  std::vector<ClosedBox> closed;
  closed.reserve(boxes.size());
  for (const auto& b : boxes) closed.emplace_back(lattice, b);

  // Questions, per owner's rank: (owner partition, key); what each asked for: (position in
  // `mine`, node id), in the same order.
  std::vector<Packer> ask(static_cast<std::size_t>(ranks));
  std::vector<std::vector<std::array<std::int32_t, 2>>> asked(static_cast<std::size_t>(ranks));
  std::vector<int> neighbours;
  // Each local step agrees on its errors (a check failing on one rank must not leave the
  // others waiting in the next alltoallv).
  run_collectively(comm, [&] {
    for (std::size_t i = 0; i < mine.size(); ++i) {
      if (!mine[i].asks) continue;
      const radapt::Nodes3& nodes = nodes_of(i);
      const ClosedBox& own = closed[static_cast<std::size_t>(mine[i].id)];
      // The partitions whose closed box meets this one's forest, ascending ids.
      const ClosedBox forest(lattice, mine[i].snapped->grid->forest.range());
      neighbours.clear();
      for (int q = 0; q < partitions; ++q)
        if (q != mine[i].id && closed[static_cast<std::size_t>(q)].meets(forest)) neighbours.push_back(q);
      for (std::size_t n = 0; n < nodes.key.size(); ++n) {
        const grid::LatticePoint3 p = grid::key3_point(nodes.key[n]);
        if (own.holds(p) || !wanted(i, static_cast<std::int32_t>(n))) continue;
        const auto owner = std::find_if(neighbours.begin(), neighbours.end(),
                                        [&](int q) { return closed[static_cast<std::size_t>(q)].holds(p); });
        CISAMR_CHECK(owner != neighbours.end(), "exchange near faces: a node in no partition's box");
        const auto r = static_cast<std::size_t>(rank_of_partition(*owner, partitions, ranks));
        ask[r].put<std::int32_t>(*owner);
        ask[r].put<grid::LatticeKey3>(nodes.key[n]);
        asked[r].push_back({static_cast<std::int32_t>(i), static_cast<std::int32_t>(n)});
      }
    }
  });
  const std::vector<Bytes> replies = ask_and_answer(comm, ask, mine, [&](std::size_t j, Unpacker& u, Packer& out) {
    const std::int32_t m = nodes_of(j).id(u.get<grid::LatticeKey3>());
    CISAMR_CHECK(m >= 0, "exchange near faces: the owner lacks a node of its closed box");
    out.put(answer_of(j, m));
  });

  std::int64_t taken = 0;
  run_collectively(comm, [&] {
    for (int r = 0; r < ranks; ++r) {
      Unpacker u(replies[static_cast<std::size_t>(r)]);
      for (const auto& [i, n] : asked[static_cast<std::size_t>(r)]) {
        take(static_cast<std::size_t>(i), n, u.get<Answer>());
        ++taken;
      }
      CISAMR_CHECK(u.done(), "exchange near faces: more answers than questions");
    }
  });
  return taken;
}

struct Refusals {  // a node's first-pass refusals, bit j for its j-th option
  std::uint32_t bits;
  std::int32_t options;
};

struct Decision {
  Vec3 position;
  PhaseMask mask;
  radapt::NodeState state;
  std::uint8_t finest_level;
};

}  // namespace

std::vector<std::vector<samr::CubeRefinement>> exchange_forests(const Comm& comm,
                                                                const std::vector<grid::CellRange<3>>& boxes,
                                                                std::span<SnappedPartition> mine, std::int64_t& cubes) {
  const int ranks = comm.size();
  const int partitions = static_cast<int>(boxes.size());
  // Questions per owner's rank: (owner partition, cube); what each asked for: (position in
  // `mine`, cube), in the same order.
  std::vector<Packer> ask(static_cast<std::size_t>(ranks));
  std::vector<std::vector<std::pair<std::int32_t, std::array<std::int64_t, 3>>>> asked(static_cast<std::size_t>(ranks));
  run_collectively(comm, [&] {
    std::vector<int> neighbours;
    for (std::size_t i = 0; i < mine.size(); ++i) {
      if (!mine[i].asks) continue;
      const grid::CellRange<3>& own = boxes[static_cast<std::size_t>(mine[i].id)];
      const grid::CellRange<3>& range = mine[i].snapped->grid->forest.range();
      neighbours.clear();
      for (int q = 0; q < partitions; ++q)
        if (q != mine[i].id && boxes[static_cast<std::size_t>(q)].meets(range)) neighbours.push_back(q);
      for (std::int64_t ck = range.lo[2]; ck < range.hi[2]; ++ck)
        for (std::int64_t cj = range.lo[1]; cj < range.hi[1]; ++cj)
          for (std::int64_t ci = range.lo[0]; ci < range.hi[0]; ++ci) {
            const std::array<std::int64_t, 3> cube{ci, cj, ck};
            if (own.contains(cube)) continue;
            const auto owner = std::find_if(neighbours.begin(), neighbours.end(),
                                            [&](int q) { return boxes[static_cast<std::size_t>(q)].contains(cube); });
            CISAMR_CHECK(owner != neighbours.end(), "exchange near faces: a cube in no partition's box");
            const auto r = static_cast<std::size_t>(rank_of_partition(*owner, partitions, ranks));
            ask[r].put<std::int32_t>(*owner);
            ask[r].put(cube);
            asked[r].emplace_back(static_cast<std::int32_t>(i), cube);
          }
    }
  });
  std::vector<std::uint8_t> bits;
  const std::vector<Bytes> replies = ask_and_answer(comm, ask, mine, [&](std::size_t j, Unpacker& u, Packer& out) {
    const auto cube = u.get<std::array<std::int64_t, 3>>();
    const samr::RefinedGrid3& grid = *mine[j].snapped->grid;
    const std::int64_t at = grid.cube_index(cube[0], cube[1], cube[2]);
    CISAMR_CHECK(at >= 0 && boxes[static_cast<std::size_t>(mine[j].id)].contains(cube),
                 "exchange near faces: a cube outside its owner's box");
    bits.clear();
    for (int local = 0; local < 5; ++local) grid.forest.append_refinement(static_cast<std::int32_t>(5 * at + local), bits);
    out.put_vector(bits);
  });

  std::vector<std::vector<samr::CubeRefinement>> taken(mine.size());
  cubes = 0;
  run_collectively(comm, [&] {
    for (int r = 0; r < ranks; ++r) {
      Unpacker u(replies[static_cast<std::size_t>(r)]);
      for (const auto& [i, cube] : asked[static_cast<std::size_t>(r)]) {
        taken[static_cast<std::size_t>(i)].push_back({cube, u.get_vector<std::uint8_t>()});
        ++cubes;
      }
      CISAMR_CHECK(u.done(), "exchange near faces: more answers than questions");
    }
  });
  return taken;
}

std::int64_t exchange_first_pass_refusals(const Comm& comm, const grid::Lattice<3>& lattice,
                                          const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine) {
  // Per partition, the nodes the second pass's leaves hold.
  std::vector<std::vector<std::uint8_t>> read(mine.size());
  for (std::size_t i = 0; i < mine.size(); ++i) {
    if (!mine[i].asks) continue;
    const grid::TetForest& forest = mine[i].snapped->grid->forest;
    const radapt::Nodes3& nodes = mine[i].snapped->snapping->nodes();
    const grid::LeafWindow window =
        grid::LeafWindow::around(lattice, boxes[static_cast<std::size_t>(mine[i].id)], mine[i].second_pass_reach);
    read[i].assign(nodes.key.size(), 0);
    for (std::int32_t t = 0; t < static_cast<std::int32_t>(forest.size()); ++t)
      if (forest.is_leaf(t) && nodes.registered(t) && window.holds(forest, t))
        for (const std::int32_t n : nodes.tet_nodes[static_cast<std::size_t>(t)]) read[i][static_cast<std::size_t>(n)] = 1;
  }
  const auto snapping = [&](std::size_t i) -> radapt::Snapping3& { return *mine[i].snapped->snapping; };
  return ask_owners<Refusals>(
      comm, lattice, boxes, mine, [&](std::size_t i) -> const radapt::Nodes3& { return snapping(i).nodes(); },
      [&](std::size_t i, std::int32_t n) { return read[i][static_cast<std::size_t>(n)] != 0; },
      [&](std::size_t j, std::int32_t m) {
        return Refusals{snapping(j).first_pass_refusals(m), snapping(j).option_count(m)};
      },
      [&](std::size_t i, std::int32_t n, const Refusals& r) {
        // The owner built the node's options from the same leaves (all within the forest
        // both hold right).
        CISAMR_CHECK(r.options == snapping(i).option_count(n), "exchange near faces: a node's options differ from its owner's");
        snapping(i).set_first_pass_refusals(n, r.bits);
      });
}

std::int64_t exchange_decisions(const Comm& comm, const grid::Lattice<3>& lattice,
                                const std::vector<grid::CellRange<3>>& boxes, std::span<SnappedPartition> mine) {
  const auto nodes = [&](std::size_t i) -> radapt::Nodes3& { return mine[i].snapped->nodes; };
  return ask_owners<Decision>(
      comm, lattice, boxes, mine, nodes, [](std::size_t, std::int32_t) { return true; },
      [&](std::size_t j, std::int32_t m) {
        const auto k = static_cast<std::size_t>(m);
        const radapt::Nodes3& owner = nodes(j);
        return Decision{owner.position[k], owner.mask[k], owner.state[k], owner.finest_level[k]};
      },
      [&](std::size_t i, std::int32_t n, const Decision& d) {
        radapt::Nodes3& own = nodes(i);
        const auto k = static_cast<std::size_t>(n);
        own.position[k] = d.position, own.mask[k] = d.mask, own.state[k] = d.state, own.finest_level[k] = d.finest_level;
      });
}

}  // namespace cisamr::parallel
