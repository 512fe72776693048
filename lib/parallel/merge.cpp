#include "parallel/merge.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "grid/key_map.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace {

constexpr std::uint64_t kInterior = pipeline::Result2::kInteriorNode;

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
std::size_t home_rank(std::uint64_t key, int size) { return static_cast<std::size_t>(mix(key) % static_cast<std::uint64_t>(size)); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

struct Claim {  // one rank's claim on a face key, as the rendezvous rank sees it
  std::uint64_t key;
  std::int32_t partition;  // lowest partition of that rank emitting the key
  std::int32_t rank;
};

}  // namespace

NumberedPiece2 merge_and_number2(const Comm& comm, std::vector<PartitionOutput2>& parts,
                                 const grid::Lattice2& lattice) {
  const int size = comm.size();
  NumberedPiece2 piece;
  std::vector<std::int32_t> first_part;  // per merged node: lowest local partition emitting it
  std::vector<char> on_face;             // per merged node: on a partition face inside the domain
  std::vector<double> coords;
  std::vector<std::uint64_t> keys;
  mesh::Mesh2 cells;
  grid::KeyMap by_key(1024);

  // 1. Merge this rank's partitions by key (interior points are never shared).
  run_collectively(comm, [&] {
    const std::int64_t unit = lattice.units(0);
    const std::int64_t fx = lattice.coarse_cells[0] * unit, fy = lattice.coarse_cells[1] * unit;
    for (PartitionOutput2& part : parts) {
      const mesh::Mesh2& m = part.result.mesh;
      const std::int64_t x0 = part.box.lo[0] * unit, x1 = part.box.hi[0] * unit;
      const std::int64_t y0 = part.box.lo[1] * unit, y1 = part.box.hi[1] * unit;
      std::vector<std::int32_t> local(m.node_count());
      for (std::size_t n = 0; n < m.node_count(); ++n) {
        const std::uint64_t key = part.result.node_key[n];
        const double x = m.coords[2 * n], y = m.coords[2 * n + 1];
        const auto next = static_cast<std::int32_t>(keys.size());
        bool inserted = true;
        const std::int32_t id = key == kInterior ? next : by_key.insert(key, next, inserted);
        local[n] = id;
        if (!inserted) {
          if (!same_bits(coords[2 * static_cast<std::size_t>(id)], x) ||
              !same_bits(coords[2 * static_cast<std::size_t>(id) + 1], y))
            throw std::logic_error("partitions " + std::to_string(parts[static_cast<std::size_t>(first_part[static_cast<std::size_t>(id)])].partition) +
                                   " and " + std::to_string(part.partition) + " place lattice node (" +
                                   std::to_string(grid::key2_x(key)) + ", " + std::to_string(grid::key2_y(key)) +
                                   ") differently");
        } else {
          keys.push_back(key);
          coords.push_back(x);
          coords.push_back(y);
          first_part.push_back(static_cast<std::int32_t>(&part - parts.data()));
          on_face.push_back(0);
        }
        if (key != kInterior) {
          const std::int64_t kx = grid::key2_x(key), ky = grid::key2_y(key);
          const bool face = (kx == x0 && x0 != 0) || (kx == x1 && x1 != fx) || (ky == y0 && y0 != 0) ||
                            (ky == y1 && y1 != fy);
          if (face) on_face[static_cast<std::size_t>(id)] = 1;
        }
      }
      for (std::size_t c = 0; c < m.cell_count(); ++c) {
        for (int k = 0; k < 3; ++k) cells.cell_nodes.push_back(local[static_cast<std::size_t>(m.cell_nodes[3 * c + static_cast<std::size_t>(k)])]);
        cells.cell_phase.push_back(m.cell_phase[c]);
        cells.cell_partition.push_back(part.partition);
      }
      part.result = pipeline::Result2{};  // release the partition's copy early
    }
  });

  // 2. Face keys to their rendezvous rank, with the lowest local partition.
  const std::size_t node_count = keys.size();
  std::vector<Packer> requests(static_cast<std::size_t>(size));
  for (std::size_t n = 0; n < node_count; ++n)
    if (on_face[n]) {
      Packer& p = requests[home_rank(keys[n], size)];
      p.put(keys[n]);
      p.put<std::int32_t>(parts[static_cast<std::size_t>(first_part[n])].partition);
    }
  std::vector<Bytes> send(static_cast<std::size_t>(size));
  for (int r = 0; r < size; ++r) send[static_cast<std::size_t>(r)] = requests[static_cast<std::size_t>(r)].take();
  std::vector<Bytes> received = comm.alltoallv(send);

  // 3. Rendezvous: owner = lowest claiming partition; tell every claimant.
  std::vector<Claim> claims;
  run_collectively(comm, [&] {
    for (int r = 0; r < size; ++r) {
      Unpacker u(received[static_cast<std::size_t>(r)]);
      while (!u.done()) {
        const auto key = u.get<std::uint64_t>();
        const auto partition = u.get<std::int32_t>();
        claims.push_back({key, partition, r});
      }
    }
    std::sort(claims.begin(), claims.end(), [](const Claim& a, const Claim& b) {
      return a.key != b.key ? a.key < b.key : a.partition < b.partition;
    });
  });
  std::vector<Packer> replies(static_cast<std::size_t>(size));
  for (std::size_t i = 0; i < claims.size();) {
    std::size_t j = i;
    while (j < claims.size() && claims[j].key == claims[i].key) ++j;
    for (std::size_t k = i; k < j; ++k) {
      Packer& p = replies[static_cast<std::size_t>(claims[k].rank)];
      p.put(claims[k].key);
      p.put<std::int32_t>(claims[i].partition);
    }
    i = j;
  }
  for (int r = 0; r < size; ++r) send[static_cast<std::size_t>(r)] = replies[static_cast<std::size_t>(r)].take();
  received = comm.alltoallv(send);

  // 4. Owned nodes first, in creation order = (owner partition, kernel output order).
  std::vector<char> owned(node_count, 1);
  std::vector<std::int32_t> new_id(node_count, -1);
  run_collectively(comm, [&] {
    for (const Bytes& b : received) {
      Unpacker u(b);
      while (!u.done()) {
        const auto key = u.get<std::uint64_t>();
        const auto owner = u.get<std::int32_t>();
        const std::int32_t id = by_key.find(key);
        if (id < 0) throw std::logic_error("merge: a reply for a key this rank does not hold");
        owned[static_cast<std::size_t>(id)] = owner == parts[static_cast<std::size_t>(first_part[static_cast<std::size_t>(id)])].partition;
      }
    }
    std::int32_t next = 0;
    for (int pass = 1; pass >= 0; --pass)
      for (std::size_t n = 0; n < node_count; ++n)
        if (owned[n] == pass) new_id[n] = next++;
  });
  std::int64_t owned_count = 0;
  for (char o : owned) owned_count += o;
  const std::int64_t offset = comm.exclusive_scan_sum(owned_count);
  piece.owned_nodes = owned_count;
  piece.global_nodes = comm.allreduce_sum(owned_count);

  mesh::Mesh2& m = piece.mesh;
  m.coords.resize(2 * node_count);
  m.node_global_id.assign(node_count, -1);
  piece.node_key.resize(node_count);
  for (std::size_t n = 0; n < node_count; ++n) {
    const auto id = static_cast<std::size_t>(new_id[n]);
    m.coords[2 * id] = coords[2 * n];
    m.coords[2 * id + 1] = coords[2 * n + 1];
    piece.node_key[id] = keys[n];
    if (owned[n]) m.node_global_id[id] = offset + static_cast<std::int64_t>(id);
  }
  m.cell_nodes = std::move(cells.cell_nodes);
  for (auto& v : m.cell_nodes) v = new_id[static_cast<std::size_t>(v)];
  m.cell_phase = std::move(cells.cell_phase);
  m.cell_partition = std::move(cells.cell_partition);

  // 5. Owners send the global ids of face nodes to the rendezvous, which forwards them.
  std::vector<Packer> ids(static_cast<std::size_t>(size));
  for (std::size_t n = 0; n < node_count; ++n)
    if (on_face[n] && owned[n]) {
      Packer& p = ids[home_rank(keys[n], size)];
      p.put(keys[n]);
      p.put<std::int64_t>(m.node_global_id[static_cast<std::size_t>(new_id[n])]);
    }
  for (int r = 0; r < size; ++r) send[static_cast<std::size_t>(r)] = ids[static_cast<std::size_t>(r)].take();
  received = comm.alltoallv(send);
  std::vector<Packer> forward(static_cast<std::size_t>(size));
  run_collectively(comm, [&] {
    std::vector<std::pair<std::uint64_t, std::int64_t>> known;
    for (const Bytes& b : received) {
      Unpacker u(b);
      while (!u.done()) {
        const auto key = u.get<std::uint64_t>();
        known.emplace_back(key, u.get<std::int64_t>());
      }
    }
    std::sort(known.begin(), known.end());
    for (const Claim& c : claims) {
      const auto it = std::lower_bound(known.begin(), known.end(), std::make_pair(c.key, std::int64_t{-1}));
      if (it == known.end() || it->first != c.key) throw std::logic_error("merge: a face node without owner");
      Packer& p = forward[static_cast<std::size_t>(c.rank)];
      p.put(c.key);
      p.put(it->second);
    }
  });
  for (int r = 0; r < size; ++r) send[static_cast<std::size_t>(r)] = forward[static_cast<std::size_t>(r)].take();
  received = comm.alltoallv(send);
  run_collectively(comm, [&] {
    for (const Bytes& b : received) {
      Unpacker u(b);
      while (!u.done()) {
        const auto key = u.get<std::uint64_t>();
        const auto gid = u.get<std::int64_t>();
        m.node_global_id[static_cast<std::size_t>(new_id[static_cast<std::size_t>(by_key.find(key))])] = gid;
      }
    }
    for (GlobalId g : m.node_global_id)
      if (g < 0) throw std::logic_error("merge: a node was left without a global id");
  });
  return piece;
}

mesh::Mesh2 gather_mesh2(const Comm& comm, const NumberedPiece2& piece, int root) {
  const mesh::Mesh2& m = piece.mesh;
  Packer p;
  p.put_vector(m.node_global_id);
  p.put_vector(m.coords);
  std::vector<GlobalId> cell_gids(m.cell_nodes.size());
  for (std::size_t i = 0; i < cell_gids.size(); ++i)
    cell_gids[i] = m.node_global_id[static_cast<std::size_t>(m.cell_nodes[i])];
  p.put_vector(cell_gids);
  p.put_vector(m.cell_phase);
  p.put_vector(m.cell_partition);
  const std::vector<Bytes> all = gather_bytes(comm, p.take(), root);
  mesh::Mesh2 out;
  run_collectively(comm, [&] {
    if (comm.rank() != root) return;
    const auto n = static_cast<std::size_t>(piece.global_nodes);
    out.coords.assign(2 * n, 0.0);
    std::vector<char> seen(n, 0);
    for (const Bytes& b : all) {
      Unpacker u(b);
      const auto gids = u.get_vector<GlobalId>();
      const auto xy = u.get_vector<double>();
      const auto cg = u.get_vector<GlobalId>();
      const auto phase = u.get_vector<std::int32_t>();
      const auto partition = u.get_vector<std::int32_t>();
      for (std::size_t i = 0; i < gids.size(); ++i) {
        const auto g = static_cast<std::size_t>(gids[i]);
        if (g >= n) throw std::logic_error("gather: global id out of range");
        if (seen[g] && (!same_bits(out.coords[2 * g], xy[2 * i]) || !same_bits(out.coords[2 * g + 1], xy[2 * i + 1])))
          throw std::logic_error("gather: node " + std::to_string(g) + " has different coordinates on two ranks");
        seen[g] = 1;
        out.coords[2 * g] = xy[2 * i];
        out.coords[2 * g + 1] = xy[2 * i + 1];
      }
      for (GlobalId g : cg) out.cell_nodes.push_back(static_cast<LocalId>(g));
      out.cell_phase.insert(out.cell_phase.end(), phase.begin(), phase.end());
      out.cell_partition.insert(out.cell_partition.end(), partition.begin(), partition.end());
    }
    for (char s : seen)
      if (!s) throw std::logic_error("gather: a global id used by no rank");
    out.node_global_id.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.node_global_id[i] = static_cast<GlobalId>(i);
  });
  return out;
}

}  // namespace cisamr::parallel
