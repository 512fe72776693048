#include "mesh/periodic_links.hpp"

#include <cstdio>
#include <string>
#include <unordered_map>

#include "core/error.hpp"

namespace cisamr::mesh {
namespace {

template <int Dim>
struct KeyHash {
  std::size_t operator()(const PeriodicKey<Dim>& key) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint64_t k : key) {  // splitmix64 steps
      h ^= k + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
      h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
      h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
      h ^= h >> 31;
    }
    return static_cast<std::size_t>(h);
  }
};

template <int Dim>
std::string node_text(const SimplexMesh<Dim>& m, std::size_t n) {
  const long long id = m.node_global_id.empty() ? static_cast<long long>(n) : static_cast<long long>(m.node_global_id[n]);
  std::string s = "node " + std::to_string(id) + " (" + (m.node_global_id.empty() ? "index" : "global id") + ") at (";
  for (int d = 0; d < Dim; ++d) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", m.coords[n * Dim + static_cast<std::size_t>(d)]);
    s += (d > 0 ? ", " : "") + std::string(buf);
  }
  return s + ")";
}

std::string axes_text(std::uint8_t shift) {
  std::string s;
  for (int a = 0; a < 3; ++a)
    if ((shift >> a) & 1) s += (s.empty() ? "" : "+") + std::string(1, "xyz"[a]);
  return s;
}

}  // namespace

template <int Dim>
PeriodicLinks<Dim> periodic_links(const SimplexMesh<Dim>& m, const Box<Dim>& faces, const std::array<bool, Dim>& axes,
                                  bool voids) {
  using Key = PeriodicKey<Dim>;
  PeriodicLinks<Dim> links;
  links.axes = axes;
  bool any = false;
  for (bool a : axes) any = any || a;
  if (!any) return links;
  const std::size_t nodes = m.node_count();
  // Candidate masters: the nodes on some periodic min face, by exact position.
  std::unordered_map<Key, LocalId, KeyHash<Dim>> on_min;
  for (std::size_t n = 0; n < nodes; ++n) {
    const double* p = &m.coords[n * Dim];
    if (periodic_shift<Dim>(p, faces, axes) != 0) {
      PeriodicSlave<Dim> s;
      s.node = static_cast<LocalId>(n);
      s.shift = periodic_shift<Dim>(p, faces, axes);
      links.slaves.push_back(s);
    }
    if (!on_periodic_min_face<Dim>(p, faces, axes)) continue;
    const auto [it, inserted] = on_min.emplace(periodic_key<Dim>(p, faces, 0, periodic_phase(m, n)), static_cast<LocalId>(n));
    if (!inserted)
      throw MeshingError("periodic links: " + node_text(m, n) + " and " +
                         node_text(m, static_cast<std::size_t>(it->second)) +
                         " lie at the same position on a min face: the mesh has duplicate nodes");
  }
  const auto find = [&](const PeriodicSlave<Dim>& s, std::uint8_t moved) {
    const double* p = &m.coords[static_cast<std::size_t>(s.node) * Dim];
    const auto it = on_min.find(periodic_key<Dim>(p, faces, moved, periodic_phase(m, static_cast<std::size_t>(s.node))));
    if (it != on_min.end()) return it->second;
    if (voids) return LocalId{-1};
    std::string where;
    for (int a = 0; a < Dim; ++a) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", (moved >> a) & 1 ? faces.min[a] : p[a]);
      where += (a > 0 ? ", " : "") + std::string(buf);
    }
    throw MeshingError("periodic links: " + node_text(m, static_cast<std::size_t>(s.node)) + " lies on the " +
                       axes_text(s.shift) + " max face" + (std::popcount(s.shift) > 1 ? "s" : "") +
                       " but no node lies at its translate (" + where + ") on the " + axes_text(moved) +
                       " min face" + (std::popcount(moved) > 1 ? "s" : "") + ": the mesh is not periodic");
  };
  for (PeriodicSlave<Dim>& s : links.slaves) {
    s.axis_master.fill(-1);
    for (int a = 0; a < Dim; ++a)
      if ((s.shift >> a) & 1) s.axis_master[static_cast<std::size_t>(a)] = find(s, static_cast<std::uint8_t>(1u << a));
    s.master = find(s, s.shift);
  }
  if (voids) {
    for (const PeriodicSlave<Dim>& s : links.slaves)
      if (s.master < 0) links.unpaired.push_back(s.node);
    std::erase_if(links.slaves, [](const PeriodicSlave<Dim>& s) { return s.master < 0; });
  }
  return links;
}

template PeriodicLinks<2> periodic_links<2>(const SimplexMesh<2>&, const Box<2>&, const std::array<bool, 2>&, bool);
template PeriodicLinks<3> periodic_links<3>(const SimplexMesh<3>&, const Box<3>&, const std::array<bool, 3>&, bool);

}  // namespace cisamr::mesh
