#include "parallel/merge.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "grid/key_map.hpp"
#include "grid/tet_lattice.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"

namespace cisamr::parallel {
// Not an anonymous namespace: the exported templates below capture these types.
namespace merge_detail {

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
std::uint64_t hash_of(std::uint64_t key) { return mix(key); }
std::uint64_t hash_of(const std::array<std::uint64_t, 2>& key) { return mix(mix(key[0]) ^ key[1]); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// What differs between 2D and 3D: which identities lie on a partition face, and how an
// error names a node.
template <int Dim>
struct Identities;

template <>
struct Identities<2> {
  using Key = std::uint64_t;
  static std::array<std::int64_t, 2> point(std::uint64_t k) { return {grid::key2_x(k), grid::key2_y(k)}; }
  static std::array<std::uint64_t, 1> lattice_keys(Key k) { return {k}; }
  static std::string name(Key k) {
    return "lattice node (" + std::to_string(grid::key2_x(k)) + ", " + std::to_string(grid::key2_y(k)) + ")";
  }
};

template <>
struct Identities<3> {
  using Key = std::array<std::uint64_t, 2>;
  static std::array<std::int64_t, 3> point(std::uint64_t k) { return grid::key3_point(k); }
  // A cut node lies on a face iff its whole edge does: both ends must be on one.
  static Key lattice_keys(const Key& k) { return k; }
  static std::string name(const Key& k) {
    const auto text = [](std::uint64_t key) {
      const auto p = grid::key3_point(key);
      return "(" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " + std::to_string(p[2]) + ")";
    };
    return k[0] == k[1] ? "lattice node " + text(k[0]) : "cut node on edge " + text(k[0]) + "-" + text(k[1]);
  }
};

// With cohesive cells a node is one copy per phase: the merge key is (identity, phase).
template <class Id>
struct SidedKey {
  Id id;
  std::int64_t side;  // the copy's phase (64 bits: no padding in the bytes exchanged)
  auto operator<=>(const SidedKey&) const = default;
};
std::uint64_t hash_of(const SidedKey<std::uint64_t>& key) { return mix(hash_of(key.id) ^ static_cast<std::uint64_t>(key.side)); }
std::uint64_t hash_of(const SidedKey<std::array<std::uint64_t, 2>>& key) {
  return mix(hash_of(key.id) ^ static_cast<std::uint64_t>(key.side));
}
inline std::uint64_t identity_part(std::uint64_t k) { return k; }
inline const std::array<std::uint64_t, 2>& identity_part(const std::array<std::uint64_t, 2>& k) { return k; }
template <class Id>
const Id& identity_part(const SidedKey<Id>& k) { return k.id; }
inline std::int32_t side_of(std::uint64_t) { return 0; }
inline std::int32_t side_of(const std::array<std::uint64_t, 2>&) { return 0; }
template <class Id>
std::int32_t side_of(const SidedKey<Id>& k) { return static_cast<std::int32_t>(k.side); }
template <int Dim, class Key>
std::string key_name(const Key& key) {
  std::string text = Identities<Dim>::name(identity_part(key));
  if constexpr (!std::is_same_v<Key, typename Identities<Dim>::Key>) text += " (phase " + std::to_string(key.side) + " copy)";
  return text;
}

struct IdentityHash {
  template <class Key>
  std::uint64_t operator()(const Key& key) const { return hash_of(key); }
};
// From an identity to a local id.
template <class Key>
using IdentityMap = grid::OpenKeyMap<Key, IdentityHash>;

template <class Key>
struct Claim {  // one rank's claim on a face identity, as the rendezvous rank sees it
  Key key;
  std::int32_t partition;  // lowest partition of that rank emitting the key
  std::int32_t rank;
};

// A lattice point on a face of `box` that is not the domain's boundary.
template <int Dim>
bool on_inner_face_of(std::uint64_t key, const grid::CellRange<Dim>& box, const grid::Lattice<Dim>& lattice,
                      std::int64_t unit) {
  const auto p = Identities<Dim>::point(key);
  for (int d = 0; d < Dim; ++d) {
    const std::int64_t lo = box.lo[d] * unit, hi = box.hi[d] * unit;
    if ((p[d] == lo && box.lo[d] != 0) || (p[d] == hi && box.hi[d] != lattice.coarse_cells[d])) return true;
  }
  return false;
}

// May another partition emit the node `id` of a partition with box `box`? Two boxes share
// only the plane between them, an inner face of both: a lattice node must lie on one, a cut
// node's edge too (both ends), a closure Steiner point never is shared.
template <int Dim>
bool on_inner_faces(const typename Identities<Dim>::Key& id, const grid::CellRange<Dim>& box,
                    const grid::Lattice<Dim>& lattice, std::int64_t unit) {
  if (id == pipeline::Result<Dim>::kUnshared) return false;
  for (std::uint64_t k : Identities<Dim>::lattice_keys(id))
    if (!on_inner_face_of<Dim>(k, box, lattice, unit)) return false;
  return true;
}

// The (key, value) pairs packed one after another in every rank's bytes.
template <class Key, class Value>
std::vector<std::pair<Key, Value>> unpack_pairs(const std::vector<Bytes>& received) {
  std::vector<std::pair<Key, Value>> out;
  for (const Bytes& b : received) {
    Unpacker u(b);
    while (!u.done()) {
      const auto key = u.get<Key>();
      out.emplace_back(key, u.get<Value>());
    }
  }
  return out;
}

template <class Key>
std::size_t home_rank(const Comm& comm, const Key& key) {
  return static_cast<std::size_t>(hash_of(key) % static_cast<std::uint64_t>(comm.size()));
}

// Collective. Each rank's claims (key, partition) meet at the key's home rank (a hash of the
// key), which answers every claim with the lowest partition claiming the key anywhere;
// `held` keeps what the home rank received (for forward_ids). Returns this rank's answers,
// (key, lowest partition), one per claim, in no particular order.
template <class Key>
std::vector<std::pair<Key, std::int32_t>> lowest_claims(const Comm& comm, const std::vector<std::pair<Key, std::int32_t>>& mine,
                                                        std::vector<Claim<Key>>& held) {
  const auto size = static_cast<std::size_t>(comm.size());
  std::vector<Packer> requests(size);
  for (const auto& [key, partition] : mine) {
    Packer& p = requests[home_rank(comm, key)];
    p.put(key);
    p.put<std::int32_t>(partition);
  }
  std::vector<Bytes> send(size);
  for (std::size_t r = 0; r < size; ++r) send[r] = requests[r].take();
  std::vector<Bytes> received = comm.alltoallv(send);
  held.clear();
  run_collectively(comm, [&] {
    for (std::size_t r = 0; r < size; ++r) {
      Unpacker u(received[r]);
      while (!u.done()) {
        const auto key = u.get<Key>();
        const auto partition = u.get<std::int32_t>();
        held.push_back({key, partition, static_cast<std::int32_t>(r)});
      }
    }
    std::sort(held.begin(), held.end(), [](const Claim<Key>& a, const Claim<Key>& b) {
      return a.key != b.key ? a.key < b.key : a.partition < b.partition;
    });
  });
  std::vector<Packer> replies(size);
  for (std::size_t i = 0; i < held.size();) {
    std::size_t j = i;
    while (j < held.size() && held[j].key == held[i].key) ++j;
    for (std::size_t k = i; k < j; ++k) {
      Packer& p = replies[static_cast<std::size_t>(held[k].rank)];
      p.put(held[k].key);
      p.put<std::int32_t>(held[i].partition);
    }
    i = j;
  }
  for (std::size_t r = 0; r < size; ++r) send[r] = replies[r].take();
  received = comm.alltoallv(send);
  return unpack_pairs<Key, std::int32_t>(received);
}

// Collective. The owners' (key, global id) reach every claimant of the key (lowest_claims'
// `held`) through the key's home rank. Returns this rank's (key, global id), one per claim.
template <class Key>
std::vector<std::pair<Key, std::int64_t>> forward_ids(const Comm& comm, const std::vector<std::pair<Key, std::int64_t>>& owned,
                                                      const std::vector<Claim<Key>>& held) {
  const auto size = static_cast<std::size_t>(comm.size());
  std::vector<Packer> ids(size);
  for (const auto& [key, gid] : owned) {
    Packer& p = ids[home_rank(comm, key)];
    p.put(key);
    p.put<std::int64_t>(gid);
  }
  std::vector<Bytes> send(size);
  for (std::size_t r = 0; r < size; ++r) send[r] = ids[r].take();
  std::vector<Bytes> received = comm.alltoallv(send);
  std::vector<Packer> forward(size);
  run_collectively(comm, [&] {
    std::vector<std::pair<Key, std::int64_t>> known = unpack_pairs<Key, std::int64_t>(received);
    std::sort(known.begin(), known.end());
    for (const Claim<Key>& c : held) {
      const auto it = std::lower_bound(known.begin(), known.end(), std::make_pair(c.key, std::int64_t{-1}));
      if (it == known.end() || it->first != c.key) throw std::logic_error("merge: a face node without owner");
      Packer& p = forward[static_cast<std::size_t>(c.rank)];
      p.put(c.key);
      p.put(it->second);
    }
  });
  for (std::size_t r = 0; r < size; ++r) send[r] = forward[r].take();
  received = comm.alltoallv(send);
  return unpack_pairs<Key, std::int64_t>(received);
}

}  // namespace merge_detail
using namespace merge_detail;

template <int Dim, class Key>
NumberedPiece<Dim> merge_keys(const Comm& comm, std::vector<PartitionOutput<Dim>>& parts,
                              const grid::Lattice<Dim>& lattice) {
  using Id = Identities<Dim>;
  constexpr bool kSided = !std::is_same_v<Key, typename Id::Key>;
  constexpr int kCorners = Dim + 1;
  NumberedPiece<Dim> piece;
  std::vector<std::int32_t> first_part;  // per merged node: lowest local partition emitting it
  std::vector<char> on_face;             // per merged node: on a partition face inside the domain
  std::vector<double> coords;
  std::vector<Key> keys;
  mesh::SimplexMesh<Dim> cells;
  IdentityMap<Key> by_key(1024);

  // 1. Merge this rank's partitions by identity (nodes off the inner faces get ids without lookup).
  run_collectively(comm, [&] {
    const std::int64_t unit = lattice.units(0);
    // Sized once (without cohesive cells: after the first partition's tables are moved in,
    // which costs one copy of those when the rank holds more partitions): the tables do not
    // grow by doubling (nor hold up to twice their size at the peak).
    std::size_t total_nodes = 0, total_cells = 0;
    for (const PartitionOutput<Dim>& part : parts)
      total_nodes += part.result.mesh.node_count(), total_cells += part.result.mesh.cell_count();
    first_part.reserve(total_nodes);
    on_face.reserve(total_nodes);
    cells.cell_partition.reserve(total_cells);
    if constexpr (kSided) {
      keys.reserve(total_nodes);
      coords.reserve(Dim * total_nodes);
      cells.cell_nodes.reserve(kCorners * total_cells);
      cells.cell_phase.reserve(total_cells);
    }
    for (PartitionOutput<Dim>& part : parts) {
      auto& m = part.result.mesh;
      const auto may_be_shared = [&](const typename Id::Key& id) { return on_inner_faces<Dim>(id, part.box, lattice, unit); };
      if constexpr (!kSided) {
        // A rank's first partition emits each identity once: its nodes and cells keep their
        // ids, so they are moved here instead of copied (the whole merge of one partition
        // per rank); only its face identities enter the table.
        if (keys.empty()) {
          if (m.cohesive.count() != 0 || !m.node_phase.empty())
            throw std::logic_error("merge: cohesive cells in a merge without cohesive keys");
          const std::size_t nodes = m.node_count();
          keys = std::move(part.result.node_identity);
          coords = std::move(m.coords);
          first_part.assign(nodes, static_cast<std::int32_t>(&part - parts.data()));
          on_face.assign(nodes, 0);
          for (std::size_t n = 0; n < nodes; ++n) {
            if (!may_be_shared(keys[n])) continue;
            on_face[n] = 1;
            bool inserted = false;
            by_key.insert(keys[n], static_cast<std::int32_t>(n), inserted);
            if (!inserted)
              throw std::logic_error("partition " + std::to_string(part.partition) + " emits " +
                                     key_name<Dim>(keys[n]) + " twice");
          }
          cells.cell_nodes = std::move(m.cell_nodes);
          cells.cell_phase = std::move(m.cell_phase);
          cells.cell_partition.assign(cells.cell_phase.size(), part.partition);
          cells.cell_nodes.reserve(kCorners * total_cells);
          cells.cell_phase.reserve(total_cells);
          cells.cell_partition.reserve(total_cells);
          keys.reserve(total_nodes);
          coords.reserve(Dim * total_nodes);
          part.result = pipeline::Result<Dim>{};
          continue;
        }
      }
      std::vector<std::int32_t> local(m.node_count());
      if (kSided && m.node_phase.size() != m.node_count())
        throw std::logic_error("merge: a cohesive partition without node phases");
      for (std::size_t n = 0; n < m.node_count(); ++n) {
        Key key;
        if constexpr (kSided)
          key = {part.result.node_identity[n], m.node_phase[n]};
        else
          key = part.result.node_identity[n];
        // Only nodes another partition may emit are looked up (and exchanged); the others get new ids.
        const bool face = may_be_shared(identity_part(key));
        const auto next = static_cast<std::int32_t>(keys.size());
        bool inserted = true;
        const std::int32_t id = face ? by_key.insert(key, next, inserted) : next;
        local[n] = id;
        if (!inserted) {
          for (int d = 0; d < Dim; ++d)
            if (!same_bits(coords[Dim * static_cast<std::size_t>(id) + d], m.coords[Dim * n + d]))
              throw std::logic_error(
                  "partitions " + std::to_string(parts[static_cast<std::size_t>(first_part[static_cast<std::size_t>(id)])].partition) +
                  " and " + std::to_string(part.partition) + " place " + key_name<Dim>(key) + " differently");
        } else {
          keys.push_back(key);
          for (int d = 0; d < Dim; ++d) coords.push_back(m.coords[Dim * n + d]);
          first_part.push_back(static_cast<std::int32_t>(&part - parts.data()));
          on_face.push_back(face ? 1 : 0);
        }
      }
      for (std::size_t c = 0; c < m.cell_count(); ++c) {
        for (int k = 0; k < kCorners; ++k)
          cells.cell_nodes.push_back(local[static_cast<std::size_t>(m.cell_nodes[kCorners * c + static_cast<std::size_t>(k)])]);
        cells.cell_phase.push_back(m.cell_phase[c]);
        cells.cell_partition.push_back(part.partition);
      }
      for (LocalId n : m.cohesive.nodes) cells.cohesive.nodes.push_back(local[static_cast<std::size_t>(n)]);
      cells.cohesive.phase.insert(cells.cohesive.phase.end(), m.cohesive.phase.begin(), m.cohesive.phase.end());
      cells.cohesive.partition.insert(cells.cohesive.partition.end(), m.cohesive.partition.begin(),
                                      m.cohesive.partition.end());
      part.result = pipeline::Result<Dim>{};  // release the partition's copy early
    }
  });

  // 2. Face identities to their rendezvous rank, with the lowest local partition; the
  //    lowest claiming partition owns each.
  const std::size_t node_count = keys.size();
  std::vector<Claim<Key>> claims;
  std::vector<std::pair<Key, std::int32_t>> mine;
  for (std::size_t n = 0; n < node_count; ++n)
    if (on_face[n]) mine.emplace_back(keys[n], parts[static_cast<std::size_t>(first_part[n])].partition);
  const std::vector<std::pair<Key, std::int32_t>> owners = lowest_claims(comm, mine, claims);
  std::vector<std::pair<Key, std::int32_t>>().swap(mine);

  // 4. Owned nodes first, in creation order = (owner partition, kernel output order).
  std::vector<char> owned(node_count, 1);
  std::vector<std::int32_t> new_id(node_count, -1);
  run_collectively(comm, [&] {
    for (const auto& [key, owner] : owners) {
      const std::int32_t id = by_key.find(key);
      if (id < 0) throw std::logic_error("merge: a reply for a key this rank does not hold");
      owned[static_cast<std::size_t>(id)] = owner == parts[static_cast<std::size_t>(first_part[static_cast<std::size_t>(id)])].partition;
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

  auto& m = piece.mesh;
  m.coords.resize(Dim * node_count);
  m.node_global_id.assign(node_count, -1);
  piece.node_key.resize(node_count);
  if (kSided) m.node_phase.resize(node_count);
  for (std::size_t n = 0; n < node_count; ++n) {
    const auto id = static_cast<std::size_t>(new_id[n]);
    for (int d = 0; d < Dim; ++d) m.coords[Dim * id + d] = coords[Dim * n + d];
    piece.node_key[id] = identity_part(keys[n]);
    if (kSided) m.node_phase[id] = side_of(keys[n]);
    if (owned[n]) m.node_global_id[id] = offset + static_cast<std::int64_t>(id);
  }
  m.cell_nodes = std::move(cells.cell_nodes);
  for (auto& v : m.cell_nodes) v = new_id[static_cast<std::size_t>(v)];
  m.cell_phase = std::move(cells.cell_phase);
  m.cell_partition = std::move(cells.cell_partition);
  m.cohesive = std::move(cells.cohesive);
  for (auto& v : m.cohesive.nodes) v = new_id[static_cast<std::size_t>(v)];

  // 5. Owners send the global ids of face nodes to the rendezvous, which forwards them.
  std::vector<std::pair<Key, std::int64_t>> owned_ids;
  for (std::size_t n = 0; n < node_count; ++n)
    if (on_face[n] && owned[n]) owned_ids.emplace_back(keys[n], m.node_global_id[static_cast<std::size_t>(new_id[n])]);
  const std::vector<std::pair<Key, std::int64_t>> forwarded = forward_ids(comm, owned_ids, claims);
  run_collectively(comm, [&] {
    for (const auto& [key, gid] : forwarded)
      m.node_global_id[static_cast<std::size_t>(new_id[static_cast<std::size_t>(by_key.find(key))])] = gid;
    for (GlobalId g : m.node_global_id)
      if (g < 0) throw std::logic_error("merge: a node was left without a global id");
  });
  return piece;
}

template <int Dim>
NumberedPiece<Dim> merge_and_number(const Comm& comm, std::vector<PartitionOutput<Dim>>& parts,
                                    const grid::Lattice<Dim>& lattice, bool cohesive) {
  using Id = typename Identities<Dim>::Key;
  return cohesive ? merge_keys<Dim, SidedKey<Id>>(comm, parts, lattice) : merge_keys<Dim, Id>(comm, parts, lattice);
}

template <int Dim>
PartitionFaces<Dim> partition_faces(const PartitionOutput<Dim>& part, const grid::Lattice<Dim>& lattice) {
  PartitionFaces<Dim> out;
  out.partition = part.partition;
  out.nodes = static_cast<std::int64_t>(part.result.mesh.node_count());
  const std::int64_t unit = lattice.units(0);
  for (std::size_t n = 0; n < part.result.node_identity.size(); ++n) {
    const auto& key = part.result.node_identity[n];
    if (!on_inner_faces<Dim>(key, part.box, lattice, unit)) continue;
    out.local.push_back(static_cast<std::int32_t>(n));
    out.identity.push_back(key);
  }
  return out;
}

template <int Dim>
StreamNumbering<Dim> number_streamed(const Comm& comm, const std::vector<PartitionFaces<Dim>>& parts, int partitions) {
  using Key = typename Identities<Dim>::Key;
  StreamNumbering<Dim> out;
  // 1. The owner of each face node: the lowest partition claiming it.
  std::vector<std::pair<Key, std::int32_t>> mine;
  for (const PartitionFaces<Dim>& p : parts)
    for (const Key& key : p.identity) mine.emplace_back(key, p.partition);
  std::vector<Claim<Key>> held;
  std::vector<std::pair<Key, std::int32_t>> owners = lowest_claims(comm, mine, held);
  std::vector<std::pair<Key, std::int32_t>>().swap(mine);
  std::sort(owners.begin(), owners.end());
  owners.erase(std::unique(owners.begin(), owners.end()), owners.end());
  const auto owner_of = [&](const Key& key) {
    const auto it = std::lower_bound(owners.begin(), owners.end(), std::make_pair(key, std::int32_t{-1}));
    if (it == owners.end() || it->first != key) throw std::logic_error("merge: a face node without a claim");
    return it->second;
  };
  // 2. Owned counts of every partition, their offsets in partition order.
  std::vector<std::vector<char>> owned(parts.size());
  std::vector<std::array<std::int64_t, 2>> counts;  // (partition, owned nodes)
  for (std::size_t k = 0; k < parts.size(); ++k) {
    std::int64_t copies = 0;
    for (const Key& key : parts[k].identity) {
      owned[k].push_back(owner_of(key) == parts[k].partition);
      copies += owned[k].back() ? 0 : 1;
    }
    counts.push_back({parts[k].partition, parts[k].nodes - copies});
    out.owned_nodes += parts[k].nodes - copies;
  }
  std::vector<std::int64_t> first(static_cast<std::size_t>(partitions) + 1, 0);
  for (const auto& [partition, count] : allgather_vector(comm, counts)) first[static_cast<std::size_t>(partition) + 1] = count;
  for (std::size_t p = 1; p < first.size(); ++p) first[p] += first[p - 1];
  out.global_nodes = first.back();
  // 3. Owned face nodes get their ids here; the others learn them from their owners.
  std::vector<std::pair<Key, std::int64_t>> owned_ids;
  out.face_ids.resize(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    out.offset.push_back(first[static_cast<std::size_t>(parts[k].partition)]);
    out.face_ids[k].assign(parts[k].local.size(), -1);
    std::int64_t copies_before = 0;
    for (std::size_t j = 0; j < parts[k].local.size(); ++j) {
      if (!owned[k][j]) {
        ++copies_before;
        continue;
      }
      const GlobalId gid = out.offset[k] + parts[k].local[j] - copies_before;
      out.face_ids[k][j] = gid;
      owned_ids.emplace_back(parts[k].identity[j], gid);
    }
  }
  std::vector<std::pair<Key, std::int64_t>> known = forward_ids(comm, owned_ids, held);
  std::sort(known.begin(), known.end());
  run_collectively(comm, [&] {
    for (std::size_t k = 0; k < parts.size(); ++k)
      for (std::size_t j = 0; j < parts[k].local.size(); ++j) {
        if (owned[k][j]) continue;
        const Key& key = parts[k].identity[j];
        const auto it = std::lower_bound(known.begin(), known.end(), std::make_pair(key, std::int64_t{-1}));
        if (it == known.end() || it->first != key) throw std::logic_error("merge: a face node without a global id");
        out.face_ids[k][j] = it->second;
      }
  });
  return out;
}

template <int Dim>
std::vector<GlobalId> global_ids_of(const PartitionFaces<Dim>& part, std::int64_t offset,
                                    const std::vector<GlobalId>& face_ids) {
  std::vector<GlobalId> ids(static_cast<std::size_t>(part.nodes));
  std::size_t j = 0;
  std::int64_t copies_before = 0;
  for (std::size_t n = 0; n < ids.size(); ++n) {
    if (j < part.local.size() && static_cast<std::size_t>(part.local[j]) == n) {
      ids[n] = face_ids[j];
      // A copy (its owner is a lower partition, whose ids are below `offset`) takes no id of
      // this partition's.
      if (face_ids[j] < offset) ++copies_before;
      ++j;
      continue;
    }
    ids[n] = offset + static_cast<std::int64_t>(n) - copies_before;
  }
  return ids;
}

template <int Dim>
mesh::SimplexMesh<Dim> gather_mesh(const Comm& comm, const NumberedPiece<Dim>& piece, int root) {
  const auto& m = piece.mesh;
  Packer p;
  p.put_vector(m.node_global_id);
  p.put_vector(m.coords);
  std::vector<GlobalId> cell_gids(m.cell_nodes.size());
  for (std::size_t i = 0; i < cell_gids.size(); ++i)
    cell_gids[i] = m.node_global_id[static_cast<std::size_t>(m.cell_nodes[i])];
  p.put_vector(cell_gids);
  p.put_vector(m.cell_phase);
  p.put_vector(m.cell_partition);
  std::vector<GlobalId> cohesive_gids(m.cohesive.nodes.size());
  for (std::size_t i = 0; i < cohesive_gids.size(); ++i)
    cohesive_gids[i] = m.node_global_id[static_cast<std::size_t>(m.cohesive.nodes[i])];
  p.put_vector(cohesive_gids);
  p.put_vector(m.cohesive.phase);
  p.put_vector(m.cohesive.partition);
  p.put_vector(m.node_phase);
  const std::vector<Bytes> all = gather_bytes(comm, p.take(), root);
  mesh::SimplexMesh<Dim> out;
  run_collectively(comm, [&] {
    if (comm.rank() != root) return;
    const auto n = static_cast<std::size_t>(piece.global_nodes);
    out.coords.assign(Dim * n, 0.0);
    std::vector<char> seen(n, 0);
    for (const Bytes& b : all) {
      Unpacker u(b);
      const auto gids = u.get_vector<GlobalId>();
      const auto xyz = u.get_vector<double>();
      const auto cg = u.get_vector<GlobalId>();
      const auto phase = u.get_vector<std::int32_t>();
      const auto partition = u.get_vector<std::int32_t>();
      const auto cohesive_gids = u.get_vector<GlobalId>();
      const auto cohesive_phase = u.get_vector<std::int32_t>();
      const auto cohesive_partition = u.get_vector<std::int32_t>();
      const auto node_phase = u.get_vector<std::int32_t>();
      if (!node_phase.empty()) {
        if (out.node_phase.empty()) out.node_phase.assign(n, 0);
        for (std::size_t i = 0; i < gids.size() && i < node_phase.size(); ++i)
          if (static_cast<std::size_t>(gids[i]) < n) out.node_phase[static_cast<std::size_t>(gids[i])] = node_phase[i];
      }
      for (GlobalId g : cohesive_gids) out.cohesive.nodes.push_back(static_cast<LocalId>(g));
      out.cohesive.phase.insert(out.cohesive.phase.end(), cohesive_phase.begin(), cohesive_phase.end());
      out.cohesive.partition.insert(out.cohesive.partition.end(), cohesive_partition.begin(), cohesive_partition.end());
      for (std::size_t i = 0; i < gids.size(); ++i) {
        const auto g = static_cast<std::size_t>(gids[i]);
        if (g >= n) throw std::logic_error("gather: global id out of range");
        for (int d = 0; d < Dim; ++d)
          if (seen[g] && !same_bits(out.coords[Dim * g + d], xyz[Dim * i + d]))
            throw std::logic_error("gather: node " + std::to_string(g) + " has different coordinates on two ranks");
        seen[g] = 1;
        for (int d = 0; d < Dim; ++d) out.coords[Dim * g + d] = xyz[Dim * i + d];
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

template NumberedPiece<2> merge_and_number<2>(const Comm&, std::vector<PartitionOutput<2>>&, const grid::Lattice<2>&, bool);
template NumberedPiece<3> merge_and_number<3>(const Comm&, std::vector<PartitionOutput<3>>&, const grid::Lattice<3>&, bool);
template mesh::SimplexMesh<2> gather_mesh<2>(const Comm&, const NumberedPiece<2>&, int);
template mesh::SimplexMesh<3> gather_mesh<3>(const Comm&, const NumberedPiece<3>&, int);

template PartitionFaces<2> partition_faces<2>(const PartitionOutput<2>&, const grid::Lattice<2>&);
template PartitionFaces<3> partition_faces<3>(const PartitionOutput<3>&, const grid::Lattice<3>&);
template StreamNumbering<2> number_streamed<2>(const Comm&, const std::vector<PartitionFaces<2>>&, int);
template StreamNumbering<3> number_streamed<3>(const Comm&, const std::vector<PartitionFaces<3>>&, int);
template std::vector<GlobalId> global_ids_of<2>(const PartitionFaces<2>&, std::int64_t, const std::vector<GlobalId>&);
template std::vector<GlobalId> global_ids_of<3>(const PartitionFaces<3>&, std::int64_t, const std::vector<GlobalId>&);

}  // namespace cisamr::parallel
