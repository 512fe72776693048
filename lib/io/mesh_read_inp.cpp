// Abaqus INP reader.

#include <set>

#include "core/error.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io::detail {
namespace {

void split_commas(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (!fields.empty() && fields.back().empty()) fields.pop_back();  // trailing comma
}

// Element sets: the phases of an Abaqus mesh. A set is named by an *ELEMENT block's ELSET=
// or by an *ELSET block (ids, GENERATE ranges, names of earlier sets).
struct ElementSets {
  std::vector<std::string> names;          // in order of appearance
  std::map<std::string, int> index;        // upper-case name → index
  std::unordered_map<long long, int> first_listing;  // element id → first *ELSET listing it
  struct Range { int set; long long first, last, step; };
  std::vector<Range> ranges;                // GENERATE lines
  std::map<int, std::pair<int, std::string>> announced;  // set → (id, name) from "** cisamr phase"
  // Cohesive sets: the ELSETs of COH2D4/COH3D6 blocks and the *ELSETs named COH_*, with
  // the ids those *ELSETs list (a cell may be in its block's set and in such a listing).
  std::vector<bool> cohesive;  // per set
  std::vector<std::pair<long long, int>> cohesive_listings;  // (element id, set)

  void mark_cohesive(int set) {
    if (cohesive.size() <= static_cast<std::size_t>(set)) cohesive.resize(static_cast<std::size_t>(set) + 1, false);
    cohesive[static_cast<std::size_t>(set)] = true;
  }
  bool is_cohesive(int set) const { return static_cast<std::size_t>(set) < cohesive.size() && cohesive[static_cast<std::size_t>(set)]; }

  int add(const std::string& name) {
    const auto [it, inserted] = index.emplace(upper(name), static_cast<int>(names.size()));
    if (inserted) names.push_back(name);
    return it->second;
  }
  // The first *ELSET listing `element` (by id or by a range), or -1. A set named in an
  // *ELSET's data comes earlier in the file, so it never decides over its own listing.
  int listing(long long element) const {
    const auto it = first_listing.find(element);
    int best = it == first_listing.end() ? -1 : it->second;
    for (const Range& r : ranges)
      if ((best < 0 || r.set < best) && element >= r.first && element <= r.last &&
          (static_cast<unsigned long long>(element) - static_cast<unsigned long long>(r.first)) %
                  static_cast<unsigned long long>(r.step) ==
              0)
        best = r.set;
    return best;
  }
};

// The cohesive cells' sets and phases, once the phases have their ids: each cell's sets
// are its block's ELSET and every COH_* *ELSET listing it; its phases are what the
// "** cisamr cohesive P Q NAME" comment before its block claims, else the one pair its one
// set's name denotes.
void resolve_cohesive_sets(RawMesh& raw, TaggedCells& cells, const ElementSets& sets) {
  const std::map<int, std::string> phases = cells.used_phase_names(raw.phase_names);
  std::vector<std::int32_t> final_set(sets.names.size(), LoadedMesh::kNoCohesiveSet);
  for (std::size_t k = 0; k < sets.names.size(); ++k)
    if (sets.is_cohesive(static_cast<int>(k))) {
      final_set[k] = static_cast<std::int32_t>(raw.cohesive_sets.size());
      raw.cohesive_sets.push_back({sets.names[k], cohesive_pairs_named(sets.names[k], phases)});
    }
  std::unordered_multimap<long long, int> listed(sets.cohesive_listings.begin(), sets.cohesive_listings.end());
  std::vector<int> in;  // the cell's sets
  for (TaggedCells::CohesiveCell& c : cells.cohesive) {
    in.clear();
    if (c.set >= 0) in.push_back(c.set);
    const auto [first, last] = listed.equal_range(c.tag);
    for (auto it = first; it != last; ++it) in.push_back(it->second);
    for (const ElementSets::Range& r : sets.ranges)
      if (sets.is_cohesive(r.set) && c.tag >= r.first && c.tag <= r.last &&
          (static_cast<unsigned long long>(c.tag) - static_cast<unsigned long long>(r.first)) %
                  static_cast<unsigned long long>(r.step) == 0)
        in.push_back(r.set);
    std::sort(in.begin(), in.end());
    in.erase(std::unique(in.begin(), in.end()), in.end());
    c.set = in.empty() ? LoadedMesh::kNoCohesiveSet : final_set[static_cast<std::size_t>(in.front())];
    c.several_sets = in.size() > 1;
    const bool claimed = c.phases[0] != 0 || c.phases[1] != 0;
    if (!claimed && in.size() == 1) {
      const auto& pairs = raw.cohesive_sets[static_cast<std::size_t>(c.set)].named_pairs;
      if (pairs.size() == 1) c.phases = pairs.front();
    }
  }
}

}  // namespace

// An element's phase is the ELSET= of its *ELEMENT block, or when that has none, the first
// *ELSET block (in file order) that lists it; sets get ids in order of appearance unless our writer's
// "** cisamr phase ID NAME" comment gives one. *NSET, *SURFACE, materials, steps etc. are
// ignored; *INCLUDE is refused (the included file would hold part of the mesh). The nodes
// our writer lists in a "** cisamr periodic reference nodes ID..." comment (REF_X ... of a
// periodic mesh, in no element) are dropped, and their sets REF_X, REF_Y, REF_Z give the
// periodic axes; *EQUATION constraints are ignored. COH2D4 and COH3D6 elements are the
// cohesive cells (resolve_cohesive_sets).
LoadedMesh read_inp(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  RawMesh raw;
  TaggedCells cells;
  std::vector<long long> node_tags;
  std::vector<int> cell_block_set;  // per cell (file order of triangles, then tetrahedra): -1 none
  ElementSets sets;
  std::optional<std::pair<int, std::string>> announced;  // from "** cisamr phase ID NAME"
  std::optional<std::array<std::int32_t, 2>> announced_cohesive;  // from "** cisamr cohesive P Q NAME"
  std::array<std::int32_t, 2> block_cohesive_phases{};
  int block_cohesive_corners = 0;
  enum class Block { none, nodes, triangles, tetrahedra, cohesive, elset } block = Block::none;
  int block_set = -1;
  bool generate = false;
  // Our writer's periodic REF nodes (ids announced by a comment) belong to no element: dropped.
  std::set<long long> reference_nodes;
  std::size_t line_number = 0, pos = 0;
  std::vector<std::string_view> fields;  // reused: one allocation for the whole file

  auto fail = [&](const std::string& problem) -> void {
    throw InputError(path, "line " + std::to_string(line_number), problem);
  };
  auto parse_int = [&](std::string_view field) {
    long long v = 0;
    const auto r = std::from_chars(field.data(), field.data() + field.size(), v);
    if (r.ec != std::errc() || r.ptr != field.data() + field.size())
      fail("expected an integer, got '" + std::string(field.substr(0, 40)) + "'");
    return v;
  };
  auto parse_real = [&](std::string_view field) {
    double v = 0;
    const char* begin = field.data() + (!field.empty() && field[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(begin, field.data() + field.size(), v);
    if (r.ec != std::errc() || r.ptr != field.data() + field.size())
      fail("expected a number, got '" + std::string(field.substr(0, 40)) + "'");
    return v;
  };

  // Plane and axisymmetric triangles, and the surface triangles other tools use for a
  // plain triangle mesh (meshio writes R3D3); a non-flat one is rejected by finish().
  static const char* const kTriangleTypes[] = {"CPS3", "CPE3", "CPE3H", "CAX3", "CAX3H", "DC2D3", "CPS3T",
                                               "CPE3T", "S3", "S3R", "R3D3", "M3D3", "STRI3", "DS3"};
  static const char* const kTetTypes[] = {"C3D4", "C3D4H", "C3D4T", "DC3D4"};
  // Cohesive elements (mesh::CohesiveOrder): the only quads and prisms read.
  const auto cohesive_corners = [](const std::string& type) { return type == "COH2D4" ? 4 : type == "COH3D6" ? 6 : 0; };
  const auto phase_id = [&](std::string_view field) {
    const long long id = parse_int(field);
    if (id < std::numeric_limits<std::int32_t>::min() || id > std::numeric_limits<std::int32_t>::max())
      fail("phase id " + std::to_string(id) + " is out of range");
    return static_cast<std::int32_t>(id);
  };

  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = trim(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    if (line.empty()) continue;
    if (line.substr(0, 2) == "**") {
      constexpr std::string_view kMarker = "** cisamr phase ";
      constexpr std::string_view kCohesiveMarker = "** cisamr cohesive ";
      constexpr std::string_view kReference = "** cisamr periodic reference nodes";
      if (line.substr(0, kCohesiveMarker.size()) == kCohesiveMarker) {
        const std::string_view rest = trim(line.substr(kCohesiveMarker.size()));
        const std::size_t space = rest.find(' ');
        if (space == std::string_view::npos) fail("'** cisamr cohesive' needs two phase ids");
        const std::string_view after = trim(rest.substr(space));
        const std::int32_t lower = phase_id(rest.substr(0, space));
        announced_cohesive = std::array<std::int32_t, 2>{lower, phase_id(after.substr(0, after.find(' ')))};
        continue;
      }
      if (line.substr(0, kReference.size()) == kReference) {
        std::string_view rest = line.substr(kReference.size());
        while (!(rest = trim(rest)).empty()) {
          const std::size_t space = rest.find(' ');
          reference_nodes.insert(parse_int(rest.substr(0, space)));
          rest = space == std::string_view::npos ? std::string_view() : rest.substr(space);
        }
        continue;
      }
      if (line.substr(0, kMarker.size()) == kMarker) {
        std::string_view rest = line.substr(kMarker.size());
        const std::size_t space = rest.find(' ');
        const long long id = parse_int(rest.substr(0, space));
        if (id < std::numeric_limits<std::int32_t>::min() || id > std::numeric_limits<std::int32_t>::max())
          fail("phase id " + std::to_string(id) + " is out of range");
        announced = std::make_pair(static_cast<int>(id), space == std::string_view::npos
                                                              ? "phase" + std::to_string(id)
                                                              : std::string(trim(rest.substr(space + 1))));
      }
      continue;
    }
    if (line[0] == '*') {
      split_commas(line.substr(1), fields);
      const std::string keyword = upper(fields.empty() ? std::string_view() : fields[0]);
      std::map<std::string, std::string> params;
      for (std::size_t i = 1; i < fields.size(); ++i) {
        const std::size_t eq = fields[i].find('=');
        params[upper(trim(fields[i].substr(0, eq)))] =
            eq == std::string_view::npos ? "" : std::string(trim(fields[i].substr(eq + 1)));
      }
      block = Block::none;
      if (keyword == "INCLUDE") {
        fail("*INCLUDE is not followed: merge the included file into this one");
      } else if (keyword == "NODE") {
        block = Block::nodes;
      } else if (keyword == "ELEMENT") {
        const std::string type = upper(params["TYPE"]);
        if (std::find(std::begin(kTriangleTypes), std::end(kTriangleTypes), type) != std::end(kTriangleTypes))
          block = Block::triangles;
        else if (std::find(std::begin(kTetTypes), std::end(kTetTypes), type) != std::end(kTetTypes))
          block = Block::tetrahedra;
        else if ((block_cohesive_corners = cohesive_corners(type)) != 0)
          block = Block::cohesive;
        else
          fail("unsupported element type '" + params["TYPE"] + "': only triangles and tetrahedra are read");
        const std::string elset = params["ELSET"];
        block_set = elset.empty() ? -1 : sets.add(elset);
        if (block == Block::cohesive) {
          if (block_set >= 0) sets.mark_cohesive(block_set);
          block_cohesive_phases = announced_cohesive.value_or(std::array<std::int32_t, 2>{0, 0});
        } else if (announced && block_set >= 0) {
          sets.announced.emplace(block_set, *announced);
        }
        announced.reset();
        announced_cohesive.reset();
      } else if (keyword == "NSET" && !reference_nodes.empty()) {
        // Our periodic meshes' REF_X, REF_Y, REF_Z: the periodic axes.
        const std::string nset = upper(params["NSET"]);
        for (int a = 0; a < 3; ++a)
          if (nset == std::string("REF_") + "XYZ"[a]) raw.periodic_axes[static_cast<std::size_t>(a)] = true;
      } else if (keyword == "ELSET") {
        const std::string elset = params["ELSET"];
        if (elset.empty()) fail("*ELSET without ELSET=");
        block = Block::elset;
        block_set = sets.add(elset);
        if (names_cohesive_set(elset)) sets.mark_cohesive(block_set);
        generate = params.count("GENERATE") > 0;
      }
      continue;
    }
    if (block == Block::none) continue;  // data of a keyword we do not read
    split_commas(line, fields);
    if (block == Block::nodes) {
      if (fields.size() != 3 && fields.size() != 4) fail("a node line needs an id and 2 or 3 coordinates");
      node_tags.push_back(parse_int(fields[0]));
      for (std::size_t d = 1; d < 4; ++d) raw.coords.push_back(d < fields.size() ? parse_real(fields[d]) : 0.0);
    } else if (block == Block::elset) {
      if (generate) {
        if (fields.size() != 2 && fields.size() != 3) fail("a GENERATE line needs first, last[, step]");
        const long long first = parse_int(fields[0]), last = parse_int(fields[1]);
        const long long step = fields.size() == 3 ? parse_int(fields[2]) : 1;
        if (step <= 0 || last < first) fail("a GENERATE line needs first <= last and a positive step");
        sets.ranges.push_back({block_set, first, last, step});
      } else {
        for (const std::string_view field : fields) {
          if (field.empty()) continue;
          long long id = 0;
          const auto r = std::from_chars(field.data(), field.data() + field.size(), id);
          if (r.ec == std::errc() && r.ptr == field.data() + field.size()) {
            sets.first_listing.emplace(id, block_set);
            if (sets.is_cohesive(block_set)) sets.cohesive_listings.emplace_back(id, block_set);
          } else {
            const auto named = sets.index.find(upper(field));
            if (named == sets.index.end() || named->second == block_set)
              fail("*ELSET " + sets.names[static_cast<std::size_t>(block_set)] + " lists '" +
                   std::string(field.substr(0, 40)) + "', neither an element id nor an earlier set");
          }
        }
      }
    } else if (block == Block::cohesive) {
      const auto n = static_cast<std::size_t>(block_cohesive_corners);
      if (fields.size() != n + 1) fail("an element line needs an id and " + std::to_string(n) + " nodes");
      std::array<long long, 6> file_nodes{};
      for (std::size_t k = 0; k < n; ++k) file_nodes[k] = parse_int(fields[k + 1]);
      TaggedCells::CohesiveCell c{parse_int(fields[0]), block_set, false, block_cohesive_phases, block_cohesive_corners, {}};
      cohesive_to_internal(c.corners, CohesiveFileOrder::abaqus, file_nodes.data(), c.nodes.data());
      cells.cohesive.push_back(c);
    } else {
      const std::size_t n = block == Block::triangles ? 3 : 4;
      if (fields.size() != n + 1)
        fail("an element line needs an id and " + std::to_string(n) + " nodes");
      std::array<long long, 4> nodes{};
      for (std::size_t k = 0; k < n; ++k) nodes[k] = parse_int(fields[k + 1]);
      // The phase is decided once every set is known: the block's set for now.
      (block == Block::triangles ? cells.triangles : cells.tetrahedra).push_back({parse_int(fields[0]), block_set, nodes});
    }
  }

  // Phases: each cell's deciding set, then ids for the sets that decide any cell.
  std::vector<int> set_id(sets.names.size(), 0);
  std::vector<bool> used(sets.names.size(), false);
  std::vector<TaggedCells::Cell>& kept = cells.tetrahedra.empty() ? cells.triangles : cells.tetrahedra;
  // Each cell without a block set is tested against every GENERATE range: bounded.
  if (!sets.ranges.empty() && kept.size() > 2'000'000'000 / sets.ranges.size())
    throw InputError(path, "*ELSET", std::to_string(sets.ranges.size()) + " GENERATE ranges for " +
                                         std::to_string(kept.size()) + " elements are too many to resolve");
  bool unset = false;
  for (TaggedCells::Cell& c : kept) {
    if (c.phase < 0) c.phase = sets.listing(c.tag);
    if (c.phase >= 0) used[static_cast<std::size_t>(c.phase)] = true;
    else unset = true;
  }
  std::map<int, bool> id_taken;  // ids given by comments first, then the next free ones
  for (const auto& [set, announced_id] : sets.announced)
    if (used[static_cast<std::size_t>(set)]) id_taken[announced_id.first] = true;
  int next_id = 1;
  auto next_free = [&] {
    while (id_taken.count(next_id)) ++next_id;
    id_taken[next_id] = true;
    return next_id;
  };
  for (std::size_t k = 0; k < sets.names.size(); ++k) {
    if (!used[k]) continue;
    const auto a = sets.announced.find(static_cast<int>(k));
    if (a != sets.announced.end()) {
      set_id[k] = a->second.first;
      raw.phase_names[a->second.first] = a->second.second;
    } else {
      set_id[k] = next_free();
      raw.phase_names[set_id[k]] = sets.names[k];
    }
  }
  const int unset_id = unset ? next_free() : 0;
  for (TaggedCells::Cell& c : kept) c.phase = c.phase >= 0 ? set_id[static_cast<std::size_t>(c.phase)] : unset_id;
  if (!reference_nodes.empty()) {
    std::size_t kept_nodes = 0;
    for (std::size_t i = 0; i < node_tags.size(); ++i) {
      if (reference_nodes.count(node_tags[i])) continue;
      node_tags[kept_nodes] = node_tags[i];
      for (std::size_t d = 0; d < 3; ++d) raw.coords[3 * kept_nodes + d] = raw.coords[3 * i + d];
      ++kept_nodes;
    }
    node_tags.resize(kept_nodes);
    raw.coords.resize(3 * kept_nodes);
  }
  if (!cells.cohesive.empty()) resolve_cohesive_sets(raw, cells, sets);
  const TagMap map = sort_nodes_by_tag(raw, node_tags, path);
  cells.finish(raw, map, path);
  return finish(std::move(raw), path);
}

}  // namespace cisamr::io::detail
