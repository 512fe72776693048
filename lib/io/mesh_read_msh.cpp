// Gmsh MSH reader: 4.1 and 2.2, ASCII and binary.

#include "core/error.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io::detail {
namespace {

const char* gmsh_type_name(long long type) {
  switch (type) {
    case 3: return "quadrangle";
    case 5: return "hexahedron";
    case 6: return "prism";
    case 7: return "pyramid";
    case 8: return "3-node line";
    case 9: return "6-node triangle";
    case 10: return "9-node quadrangle";
    case 11: return "10-node tetrahedron";
    default: return nullptr;
  }
}

// Node count of the element types we read or skip; 0 = unsupported.
int gmsh_node_count(long long type) {
  switch (type) {
    case 15: return 1;  // point
    case 1: return 2;   // line
    case 8: return 3;   // second-order line: boundary of a 2D mesh, skipped
    case 2: return 3;   // triangle
    case 4: return 4;   // tetrahedron
    default: return 0;
  }
}

[[noreturn]] void unsupported_gmsh_type(const Scanner& s, long long type) {
  const char* name = gmsh_type_name(type);
  s.fail("unsupported element type " + std::to_string(type) +
         (name ? std::string(" (") + name + ")" : "") + ": only triangles and tetrahedra are read");
}

void add_gmsh_cell(TaggedCells& cells, const Scanner& s, long long type, long long tag,
                   std::int32_t phase, const std::array<long long, 4>& nodes) {
  if (type == 2) cells.triangles.push_back({tag, phase, nodes});
  else if (type == 4) cells.tetrahedra.push_back({tag, phase, nodes});
  else if (gmsh_node_count(type) == 0) unsupported_gmsh_type(s, type);
}

// Names by (dimension, physical tag): tags are numbered per dimension.
using PhysicalNames = std::map<std::pair<int, int>, std::string>;

// Quadrangles (2D) and prisms (3D) are cells only in a physical group named COH_*: the
// cohesive cells our writer puts there. Sets are numbered in order of first use here, and
// renumbered once the mesh's dimension is known (resolve_cohesive_sets).
struct CohesiveGroups {
  std::map<std::pair<int, int>, std::int32_t> set_of;  // (dimension, physical tag) → set
  std::vector<std::pair<int, int>> groups;             // per set: (dimension, physical tag)

  static int dimension_of(long long type) { return type == 3 ? 2 : type == 6 ? 3 : -1; }
  // The set of an element of `type` whose first physical tag is `physical`, or -1 when it
  // is no cohesive cell.
  std::int32_t set_for(long long type, long long physical, const PhysicalNames& names) {
    const int dimension = dimension_of(type);
    if (dimension < 0 || physical < std::numeric_limits<int>::min() || physical > std::numeric_limits<int>::max()) return -1;
    const std::pair<int, int> key{dimension, static_cast<int>(physical)};
    const auto name = names.find(key);
    if (name == names.end() || !names_cohesive_set(name->second)) return -1;
    const auto [it, added] = set_of.emplace(key, static_cast<std::int32_t>(groups.size()));
    if (added) groups.push_back(key);
    return it->second;
  }
};

void add_cohesive_cell(TaggedCells& cells, long long type, long long tag, std::int32_t set, bool several_sets,
                       const std::array<long long, 6>& file_nodes) {
  TaggedCells::CohesiveCell c{tag, set, several_sets, {0, 0}, type == 3 ? 4 : 6, {}};
  cohesive_to_internal(c.corners, CohesiveFileOrder::gmsh, file_nodes.data(), c.nodes.data());
  cells.cohesive.push_back(c);
}

// The cohesive sets of the mesh's dimension: every COH_* physical group of that dimension
// (used or not, ascending tag), each with the phase pairs its name denotes; a cell's phases
// are the one pair its set's name denotes ({0, 0} when none or several fit).
void resolve_cohesive_sets(RawMesh& raw, TaggedCells& cells, const CohesiveGroups& found, const PhysicalNames& names) {
  const int dimension = cells.tetrahedra.empty() ? 2 : 3;
  std::map<int, std::string> phase_names;
  for (const auto& [key, name] : names)
    if (key.first == dimension) phase_names[key.second] = name;
  const std::map<int, std::string> phases = cells.used_phase_names(phase_names);
  std::map<std::pair<int, int>, std::int32_t> final_set;
  for (const auto& [key, name] : names)
    if (key.first == dimension && names_cohesive_set(name)) {
      final_set.emplace(key, static_cast<std::int32_t>(raw.cohesive_sets.size()));
      raw.cohesive_sets.push_back({name, cohesive_pairs_named(name, phases)});
    }
  for (TaggedCells::CohesiveCell& c : cells.cohesive) {
    const auto it = final_set.find(found.groups[static_cast<std::size_t>(c.set)]);
    if (it == final_set.end()) {  // a group of the other dimension: finish() refuses the mix
      c.set = LoadedMesh::kNoCohesiveSet;
      continue;
    }
    c.set = it->second;
    const auto& pairs = raw.cohesive_sets[static_cast<std::size_t>(c.set)].named_pairs;
    if (pairs.size() == 1) c.phases = pairs.front();
  }
}

void read_physical_names(Scanner& s, PhysicalNames& names) {
  const std::size_t count = s.count("$PhysicalNames", 3);
  for (std::size_t i = 0; i < count; ++i) {
    const long long dimension = s.integer();
    const long long tag = s.integer();
    std::string_view name = trim(s.rest_of_line());
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    if (tag < std::numeric_limits<int>::min() || tag > std::numeric_limits<int>::max())
      s.fail("physical tag " + std::to_string(tag) + " is out of range");
    names[{static_cast<int>(dimension), static_cast<int>(tag)}] = std::string(name);
  }
  s.expect("$EndPhysicalNames");
}

// The numbers of an MSH 4.1 section, ASCII tokens or binary values (int: 4 bytes, size_t:
// the file's data size). The sections list the same numbers in the same order either way.
class MshValues {
 public:
  MshValues(Scanner& s, bool binary, int size_bytes, const std::string& path, const char* section)
      : s_(s), binary_(binary), size_bytes_(size_bytes),
        cursor_(s.text(), binary ? s.position() + 1 : 0, path, section) {}  // binary starts after '\n'

  long long integer() { return binary_ ? cursor_.read<std::int32_t>() : s_.integer(); }
  double real() { return binary_ ? cursor_.read<double>() : s_.real(); }
  long long size() {
    if (!binary_) return s_.integer();
    const std::uint64_t v = size_bytes_ == 8 ? cursor_.read<std::uint64_t>() : cursor_.read<std::uint32_t>();
    if (v > static_cast<std::uint64_t>(std::numeric_limits<long long>::max())) fail("value " + std::to_string(v) + " out of range");
    return static_cast<long long>(v);
  }
  // A count of entries of `values` numbers each, checked against the rest of the file.
  long long count(const char* what, int values) {
    if (!binary_) return static_cast<long long>(s_.count(what, values));
    const long long n = size();
    return static_cast<long long>(cursor_.count(static_cast<std::uint64_t>(n), static_cast<std::size_t>(values) * 4));
  }
  // Hands the position back to the scanner for the closing keyword.
  void done() {
    if (binary_) s_.seek(cursor_.position());
  }
  [[noreturn]] void fail(const std::string& problem) { s_.fail(problem); }

 private:
  Scanner& s_;
  bool binary_;
  int size_bytes_;
  BinaryCursor cursor_;
};

}  // namespace

LoadedMesh read_msh(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  Scanner s(text, path);
  if (s.at_end() || s.token() != "$MeshFormat")
    throw InputError(path, "", "not a Gmsh file (it must start with $MeshFormat)");
  const std::string_view version = s.token();
  const long long file_type = s.integer();
  const long long data_size = s.integer();
  const bool v4 = version.substr(0, 2) == "4.";
  if ((v4 && version != "4.1") || (!v4 && version.substr(0, 2) != "2."))
    s.fail("unsupported MSH version " + std::string(version.substr(0, 20)) + " (4.1 and 2.2 are read)");
  if (file_type != 0 && file_type != 1) s.fail("file type must be 0 (ASCII) or 1 (binary)");
  const bool binary = file_type == 1;
  if (binary) {
    if (data_size != 8 && data_size != 4) s.fail("unsupported data size " + std::to_string(data_size));
    s.rest_of_line();
    BinaryCursor one(text, s.position(), path, "$MeshFormat");
    if (one.read<std::int32_t>() != 1)
      s.fail("binary MSH written on a big-endian machine is not supported");
    s.seek(one.position());
  }
  s.skip_past("$EndMeshFormat");

  RawMesh raw;
  TaggedCells cells;
  std::vector<long long> node_tags;
  PhysicalNames physical_names;
  // (dimension, entity tag) → first physical tag (0 when none) and how many it has.
  std::map<std::pair<int, long long>, std::pair<int, long long>> entity_physical;
  CohesiveGroups cohesive_groups;
  bool seen_nodes = false, seen_elements = false;
  struct PeriodicTags {
    int entity_dimension = 0, entity = 0, master_entity = 0;
    std::vector<double> affine;
    std::vector<std::pair<long long, long long>> nodes;  // file node tags
  };
  std::vector<PeriodicTags> periodic;

  auto read_nodes = [&](auto& nodes, int n, MshValues& v) {
    for (int k = 0; k < n; ++k) {
      const long long node = v.size();
      if (static_cast<std::size_t>(k) < nodes.size()) nodes[static_cast<std::size_t>(k)] = node;
    }
  };

  while (!s.at_end()) {
    const std::string_view section = s.token();
    if (section == "$PhysicalNames") {
      read_physical_names(s, physical_names);
    } else if (section == "$Entities" && v4) {
      MshValues v(s, binary, static_cast<int>(data_size), path, "$Entities");
      long long counts[4];
      for (auto& c : counts) c = v.count("$Entities", 5);
      for (int dim = 0; dim < 4; ++dim)
        for (long long e = 0; e < counts[dim]; ++e) {
          const long long tag = v.integer();
          for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) v.real();
          const long long physical_count = v.count("physical tags", 1);
          int physical = 0;
          for (long long k = 0; k < physical_count; ++k) {
            const long long p = v.integer();
            if (k == 0) physical = static_cast<int>(std::clamp<long long>(p, std::numeric_limits<int>::min(),
                                                                           std::numeric_limits<int>::max()));
          }
          if (dim > 0) {
            const long long bounding = v.count("bounding entities", 1);
            for (long long k = 0; k < bounding; ++k) v.integer();
          }
          entity_physical[{dim, tag}] = {physical, physical_count};
        }
      v.done();
      s.expect("$EndEntities");
    } else if (section == "$Nodes") {
      seen_nodes = true;
      if (v4) {
        MshValues v(s, binary, static_cast<int>(data_size), path, "$Nodes");
        const long long blocks = v.count("$Nodes blocks", 4);
        const long long total = v.count("$Nodes", 4);  // a tag and 3 coordinates each
        v.size(), v.size();
        node_tags.reserve(static_cast<std::size_t>(total));
        raw.coords.reserve(3 * static_cast<std::size_t>(total));
        for (long long b = 0; b < blocks; ++b) {
          const long long entity_dim = v.integer();
          v.integer();  // entity tag
          const long long parametric = v.integer();
          const long long count = v.count("nodes in a block", 4);
          for (long long i = 0; i < count; ++i) node_tags.push_back(v.size());
          for (long long i = 0; i < count; ++i) {
            for (int d = 0; d < 3; ++d) raw.coords.push_back(v.real());
            if (parametric) for (long long k = 0; k < std::clamp(entity_dim, 0LL, 2LL); ++k) v.real();
          }
        }
        v.done();
      } else {
        const long long count = static_cast<long long>(s.count("$Nodes", 4));
        if (binary) {
          BinaryCursor c(text, s.position() + 1, path, "$Nodes");
          c.count(static_cast<std::uint64_t>(count), 28);  // int tag + 3 doubles
          for (long long i = 0; i < count; ++i) {
            node_tags.push_back(c.read<std::int32_t>());
            for (int d = 0; d < 3; ++d) raw.coords.push_back(c.read<double>());
          }
          s.seek(c.position());
        } else {
          for (long long i = 0; i < count; ++i) {
            node_tags.push_back(s.integer());
            for (int d = 0; d < 3; ++d) raw.coords.push_back(s.real());
          }
        }
      }
      s.expect("$EndNodes");
    } else if (section == "$Elements") {
      seen_elements = true;
      if (v4) {
        MshValues v(s, binary, static_cast<int>(data_size), path, "$Elements");
        const long long blocks = v.count("$Elements blocks", 4);
        v.size(), v.size(), v.size();
        for (long long b = 0; b < blocks; ++b) {
          const int entity_dim = static_cast<int>(v.integer());
          const long long entity_tag = v.integer();
          const long long type = v.integer();
          const long long count = v.count("elements in a block", 2);
          const auto it = entity_physical.find({entity_dim, entity_tag});
          const std::int32_t phase = it != entity_physical.end() && it->second.first != 0 ? it->second.first : 1;
          const std::int32_t cohesive_set =
              it == entity_physical.end() ? -1 : cohesive_groups.set_for(type, it->second.first, physical_names);
          if (cohesive_set >= 0) {
            for (long long i = 0; i < count; ++i) {
              const long long tag = v.size();
              std::array<long long, 6> nodes{};
              read_nodes(nodes, type == 3 ? 4 : 6, v);
              add_cohesive_cell(cells, type, tag, cohesive_set, it->second.second > 1, nodes);
            }
            continue;
          }
          const int n = gmsh_node_count(type);
          if (n == 0) unsupported_gmsh_type(s, type);
          for (long long i = 0; i < count; ++i) {
            const long long tag = v.size();
            std::array<long long, 4> nodes{};
            read_nodes(nodes, n, v);
            add_gmsh_cell(cells, s, type, tag, phase, nodes);
          }
        }
        v.done();
      } else if (binary) {
        // MSH 2.2 binary: runs of elements of one type, each run led by (type, count, tags).
        const long long count = static_cast<long long>(s.count("$Elements", 2));
        BinaryCursor c(text, s.position() + 1, path, "$Elements");
        for (long long read = 0; read < count;) {
          const long long type = c.read<std::int32_t>();
          const long long following = c.read<std::int32_t>();
          const long long tag_count = c.read<std::int32_t>();
          const bool maybe_cohesive = CohesiveGroups::dimension_of(type) > 0;  // decided per element by its tag
          const int n = maybe_cohesive ? (type == 3 ? 4 : 6) : gmsh_node_count(type);
          if (n == 0) unsupported_gmsh_type(s, type);
          if (following <= 0 || following > count - read || tag_count < 0)
            throw InputError(path, "$Elements", "bad element run header (" + std::to_string(following) + " elements, " +
                                                    std::to_string(tag_count) + " tags)");
          c.count(static_cast<std::uint64_t>(following), 4 * static_cast<std::size_t>(1 + tag_count + n));
          for (long long i = 0; i < following; ++i) {
            const long long tag = c.read<std::int32_t>();
            std::int32_t phase = 1;
            long long physical = 0;
            for (long long k = 0; k < tag_count; ++k) {
              const std::int32_t t = c.read<std::int32_t>();
              if (k == 0) physical = t;
              if (k == 0 && t != 0) phase = t;
            }
            std::array<long long, 6> nodes{};
            for (int k = 0; k < n; ++k) nodes[static_cast<std::size_t>(k)] = c.read<std::int32_t>();
            const std::int32_t cohesive_set = maybe_cohesive ? cohesive_groups.set_for(type, physical, physical_names) : -1;
            if (cohesive_set >= 0) add_cohesive_cell(cells, type, tag, cohesive_set, false, nodes);
            else add_gmsh_cell(cells, s, type, tag, phase, {nodes[0], nodes[1], nodes[2], nodes[3]});
          }
          read += following;
        }
        s.seek(c.position());
      } else {
        const long long count = static_cast<long long>(s.count("$Elements", 5));
        for (long long i = 0; i < count; ++i) {
          const long long tag = s.integer();
          const long long type = s.integer();
          const long long tag_count = s.integer();
          std::int32_t phase = 1;
          long long physical = 0;
          for (long long k = 0; k < tag_count; ++k) {
            const long long t = s.integer();
            if (k == 0) physical = t;
            if (k == 0 && t != 0)
              phase = static_cast<std::int32_t>(std::clamp<long long>(t, std::numeric_limits<std::int32_t>::min(),
                                                                      std::numeric_limits<std::int32_t>::max()));
          }
          const std::int32_t cohesive_set = cohesive_groups.set_for(type, physical, physical_names);
          const int n = cohesive_set >= 0 ? (type == 3 ? 4 : 6) : gmsh_node_count(type);
          if (n == 0) unsupported_gmsh_type(s, type);
          std::array<long long, 6> nodes{};
          for (int k = 0; k < n; ++k) nodes[static_cast<std::size_t>(k)] = s.integer();
          if (cohesive_set >= 0) add_cohesive_cell(cells, type, tag, cohesive_set, false, nodes);
          else add_gmsh_cell(cells, s, type, tag, phase, {nodes[0], nodes[1], nodes[2], nodes[3]});
        }
      }
      s.expect("$EndElements");
    } else if (section == "$Periodic" && v4) {
      // numLinks; per link: entityDim entityTag entityTagMaster, numAffine values...,
      // numCorrespondingNodes, then (node, master node) pairs.
      MshValues v(s, binary, static_cast<int>(data_size), path, "$Periodic");
      const long long links = v.count("$Periodic", 4);
      for (long long l = 0; l < links; ++l) {
        PeriodicTags link;
        link.entity_dimension = static_cast<int>(v.integer());
        link.entity = static_cast<int>(v.integer());
        link.master_entity = static_cast<int>(v.integer());
        const long long affine = v.size();
        if (affine != 0 && affine != 16) v.fail("$Periodic: " + std::to_string(affine) + " affine values (0 or 16 expected)");
        for (long long k = 0; k < affine; ++k) link.affine.push_back(v.real());
        const long long pairs = v.count("periodic node pairs", 2);
        link.nodes.reserve(static_cast<std::size_t>(pairs));
        for (long long k = 0; k < pairs; ++k) {
          const long long slave = v.size();
          link.nodes.emplace_back(slave, v.size());
        }
        periodic.push_back(std::move(link));
      }
      v.done();
      s.expect("$EndPeriodic");
    } else if (!section.empty() && section[0] == '$') {
      s.skip_past("$End" + std::string(section.substr(1)));  // $NodeData, 2.2's $Periodic, ...
    } else {
      s.fail("expected a section such as $Nodes, got '" + std::string(section.substr(0, 40)) + "'");
    }
  }
  if (!seen_nodes || !seen_elements) throw InputError(path, "", "missing $Nodes or $Elements");
  const TagMap map = sort_nodes_by_tag(raw, node_tags, path);
  if (!cells.cohesive.empty()) resolve_cohesive_sets(raw, cells, cohesive_groups, physical_names);
  cells.finish(raw, map, path);
  for (const PeriodicTags& link : periodic) {
    LoadedMesh::PeriodicLink out{link.entity_dimension, link.entity, link.master_entity, link.affine, {}};
    out.nodes.reserve(link.nodes.size());
    for (const auto& [slave, master] : link.nodes) {
      const std::int64_t a = map.index(slave), b = map.index(master);
      if (a < 0 || b < 0)
        throw InputError(path, "$Periodic", "node " + std::to_string(a < 0 ? slave : master) + " is not defined");
      out.nodes.emplace_back(static_cast<LocalId>(a), static_cast<LocalId>(b));
    }
    raw.periodic_links.push_back(std::move(out));
  }
  // The names of the cells' dimension: a boundary group may reuse a phase's tag.
  const int cell_dimension = raw.corners - 1;
  for (const auto& [key, name] : physical_names)
    if (key.first == cell_dimension) raw.phase_names[key.second] = name;
  return finish(std::move(raw), path);
}

}  // namespace cisamr::io::detail
