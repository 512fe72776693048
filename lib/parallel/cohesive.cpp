#include "parallel/cohesive.hpp"

#include <algorithm>
#include <stdexcept>

#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "pipeline/cohesive.hpp"

namespace cisamr::parallel {
namespace {

template <int Dim>
std::size_t facet_home(const pipeline::FacetClaim<Dim>& claim, int size) {
  std::uint64_t h = 0;
  for (const auto& id : claim.key) h = pipeline::identity_hash<Dim>(id) ^ (h * 0x9e3779b97f4a7c15ull);
  return static_cast<std::size_t>(h % static_cast<std::uint64_t>(size));
}

template <int Dim>
PartitionOutput<Dim>& partition_named(std::vector<PartitionOutput<Dim>>& parts, std::int32_t id) {
  for (PartitionOutput<Dim>& part : parts)
    if (part.partition == id) return part;
  throw std::logic_error("cohesive: a decision for partition " + std::to_string(id) + ", not on this rank");
}

std::vector<Bytes> take_all(std::vector<Packer>& packers) {
  std::vector<Bytes> out(packers.size());
  for (std::size_t r = 0; r < packers.size(); ++r) out[r] = packers[r].take();
  return out;
}

}  // namespace

template <int Dim>
void join_cohesive(const Comm& comm, std::vector<PartitionOutput<Dim>>& parts, const grid::Lattice<Dim>& lattice) {
  const int size = comm.size();
  const auto ranks = static_cast<std::size_t>(size);

  // 1. Split and insert the local cells; the open facets' claims to their rendezvous.
  std::vector<Packer> out(ranks);
  run_collectively(comm, [&] {
    for (PartitionOutput<Dim>& part : parts)
      for (const pipeline::FacetClaim<Dim>& c : pipeline::split_and_claim(part.result, lattice, part.box, part.partition)) {
        Packer& p = out[facet_home(c, size)];
        p.put(c.key);
        p.put(c.phase);
        p.put(c.partition);
        p.put(c.cell);
        p.put(c.opposite);
        p.put(c.lo_side);
      }
  });
  std::vector<Bytes> received = comm.alltoallv(take_all(out));

  // 2. Pair them; each join to its emitter's rank.
  out.assign(ranks, Packer{});
  run_collectively(comm, [&] {
    std::vector<pipeline::FacetClaim<Dim>> claims;
    for (int r = 0; r < size; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      while (!u.done()) {
        pipeline::FacetClaim<Dim> c;
        c.key = u.get<decltype(c.key)>();
        c.phase = u.get<std::int32_t>();
        c.partition = u.get<std::int32_t>();
        c.cell = u.get<std::int64_t>();
        c.opposite = u.get<std::int32_t>();
        c.lo_side = u.get<std::int32_t>();
        c.rank = r;
        claims.push_back(c);
      }
    }
    for (const pipeline::FacetJoin& j : pipeline::pair_facet_claims(std::move(claims))) {
      Packer& p = out[static_cast<std::size_t>(j.rank)];
      p.put(j.partition);
      p.put(j.cell);
      p.put(j.opposite);
      p.put(j.other_phase);
    }
  });
  received = comm.alltoallv(take_all(out));

  // 3. The emitters build their cells, in an order that does not depend on the ranks.
  run_collectively(comm, [&] {
    std::vector<pipeline::FacetJoin> joins;
    for (const Bytes& b : received) {
      Unpacker u(b);
      while (!u.done()) {
        pipeline::FacetJoin j;
        j.partition = u.get<std::int32_t>();
        j.cell = u.get<std::int64_t>();
        j.opposite = u.get<std::int32_t>();
        j.other_phase = u.get<std::int32_t>();
        joins.push_back(j);
      }
    }
    std::sort(joins.begin(), joins.end());
    for (std::size_t i = 0; i < joins.size();) {
      std::size_t k = i;
      while (k < joins.size() && joins[k].partition == joins[i].partition) ++k;
      pipeline::apply_facet_joins<Dim>(partition_named(parts, joins[i].partition).result,
                                       std::span<const pipeline::FacetJoin>(joins.data() + i, k - i));
      i = k;
    }
  });
  if (!lattice.any_periodic()) return;

  // 4. Periodic: every copy on a periodic plane to the rendezvous of its canonical node,
  // which names the masters missing; their holders add them.
  out.assign(ranks, Packer{});
  run_collectively(comm, [&] {
    for (PartitionOutput<Dim>& part : parts)
      for (const pipeline::CopyClaim<Dim>& c : pipeline::copy_claims(part.result, lattice, part.partition)) {
        Packer& p = out[static_cast<std::size_t>(pipeline::identity_hash<Dim>(c.canonical) % static_cast<std::uint64_t>(size))];
        p.put(c.canonical);
        p.put(c.image);
        p.put(c.phase);
        p.put(c.partition);
      }
  });
  received = comm.alltoallv(take_all(out));
  out.assign(ranks, Packer{});
  run_collectively(comm, [&] {
    std::vector<pipeline::CopyClaim<Dim>> claims;
    for (int r = 0; r < size; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      while (!u.done()) {
        pipeline::CopyClaim<Dim> c;
        c.canonical = u.get<decltype(c.canonical)>();
        c.image = u.get<std::uint8_t>();
        c.phase = u.get<std::int32_t>();
        c.partition = u.get<std::int32_t>();
        c.rank = r;
        claims.push_back(c);
      }
    }
    for (const pipeline::CopyNeed<Dim>& need : pipeline::missing_copies(std::move(claims))) {
      Packer& p = out[static_cast<std::size_t>(need.rank)];
      p.put(need.partition);
      p.put(need.canonical);
      p.put(need.image);
      p.put(need.phase);
    }
  });
  received = comm.alltoallv(take_all(out));
  run_collectively(comm, [&] {
    std::vector<pipeline::CopyNeed<Dim>> needs;
    for (const Bytes& b : received) {
      Unpacker u(b);
      while (!u.done()) {
        pipeline::CopyNeed<Dim> need;
        need.partition = u.get<std::int32_t>();
        need.canonical = u.get<decltype(need.canonical)>();
        need.image = u.get<std::uint8_t>();
        need.phase = u.get<std::int32_t>();
        needs.push_back(need);
      }
    }
    std::sort(needs.begin(), needs.end());
    for (std::size_t i = 0; i < needs.size();) {
      std::size_t k = i;
      while (k < needs.size() && needs[k].partition == needs[i].partition) ++k;
      pipeline::apply_copy_needs<Dim>(partition_named(parts, needs[i].partition).result, lattice,
                                      std::span<const pipeline::CopyNeed<Dim>>(needs.data() + i, k - i));
      i = k;
    }
  });
}

template void join_cohesive<2>(const Comm&, std::vector<PartitionOutput<2>>&, const grid::Lattice<2>&);
template void join_cohesive<3>(const Comm&, std::vector<PartitionOutput<3>>&, const grid::Lattice<3>&);

}  // namespace cisamr::parallel
