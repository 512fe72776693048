#pragma once
// What the mesh readers share (not installed: mesh_read*.cpp only). Each reader fills a
// RawMesh (3 coordinates per node, 0-based cells of the top dimension found in the file);
// finish() decides the dimension, checks indices and applies defaults.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <string_view>
#include <type_traits>
#include <unordered_map>

#include "core/error.hpp"
#include "io/mesh_io.hpp"
#include "mesh/cohesive.hpp"

namespace cisamr::io::detail {


// The file's bytes, mapped read-only (no copy: meshes run to gigabytes).
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw InputError(path, "", std::string("cannot read: ") + std::strerror(errno));
    struct stat info {};
    if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
      ::close(fd);
      throw InputError(path, "", "cannot read: not a regular file");
    }
    size_ = static_cast<std::size_t>(info.st_size);
    if (size_ > 0) {
      void* data = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      const int error_number = errno;
      ::close(fd);
      if (data == MAP_FAILED)
        throw InputError(path, "", std::string("cannot read: ") + std::strerror(error_number));
      data_ = static_cast<const char*>(data);
    } else {
      ::close(fd);
    }
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::string_view view() const { return data_ ? std::string_view(data_, size_) : std::string_view(); }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

// Blanks and control characters separate tokens (a plain compare: std::isspace goes
// through the locale and was most of the reading time).
inline bool is_blank(char c) { return static_cast<unsigned char>(c) <= ' '; }

inline std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// What every reader produces before the common checks.
struct RawMesh {
  std::vector<double> coords;  // 3 per node
  int corners = 0;             // 3 (triangles) or 4 (tetrahedra); 0 = no cells
  std::vector<LocalId> cell_nodes;  // 0-based, `corners` per cell
  std::vector<std::int32_t> cell_phase;
  std::vector<std::int32_t> cell_partition;  // empty = all 0
  std::vector<GlobalId> node_global_id;     // empty = node index
  std::map<int, std::string> phase_names;   // from the file, when it has them
  std::vector<LoadedMesh::PeriodicLink> periodic_links;  // .msh $Periodic (node indices)
  std::vector<GlobalId> periodic_master;     // .vtu point data; empty = absent
  // Cohesive cells (cohesive_to_internal): 0-based, in the internal order b0.. t0..
  int cohesive_corners = 0;                  // 4 (quads, 2D) or 6 (wedges, 3D); 0 = none
  std::vector<LocalId> cohesive_nodes;
  std::vector<std::int32_t> cohesive_phase;      // 2 per cell: as the file claims, 0 = unsaid
  std::vector<std::int32_t> cohesive_partition;  // empty = all 0
  std::vector<LoadedMesh::CohesiveSet> cohesive_sets;
  std::vector<std::int32_t> cohesive_set_of_cell;  // empty = the format names no sets
  std::vector<std::int32_t> node_phase;          // .vtu point data; empty = absent
  std::array<bool, 3> periodic_axes{};           // .inp: its REF_X, REF_Y, REF_Z sets
};

// Which format's cohesive node order a file uses (mesh::CohesiveOrder).
enum class CohesiveFileOrder { vtk, gmsh, abaqus };

// A cohesive cell's nodes from the file's order to the internal one: position i of the
// file's element holds internal node order[i] (mesh/cohesive.hpp), so internal[order[i]] =
// file[i]. `corners` is 4 or 6.
template <class T>
void cohesive_to_internal(int corners, CohesiveFileOrder format, const T* file, T* internal) {
  const auto apply = [&](const auto& order) {
    for (std::size_t i = 0; i < order.size(); ++i) internal[order[i]] = file[i];
  };
  using O2 = mesh::CohesiveOrder<2>;
  using O3 = mesh::CohesiveOrder<3>;
  if (corners == 4) apply(format == CohesiveFileOrder::vtk ? O2::vtk : format == CohesiveFileOrder::gmsh ? O2::gmsh : O2::abaqus);
  else apply(format == CohesiveFileOrder::vtk ? O3::vtk : format == CohesiveFileOrder::gmsh ? O3::gmsh : O3::abaqus);
}

// The phase pairs (p < q) a cohesive set's name denotes among `phases` (id → name, "phase<id>"
// for a phase the file does not name), case ignored: the writers' name for the pair
// (cohesive_set_name: COH_<A>_<B>), or COH_<p>_<q> with the ids. Every fitting pair, ascending.
inline std::vector<std::array<std::int32_t, 2>> cohesive_pairs_named(std::string_view set_name,
                                                                    const std::map<int, std::string>& phases) {
  std::vector<geometry::Phase> named;
  for (const auto& [id, name] : phases) named.push_back({id, name, false});
  std::vector<std::array<std::int32_t, 2>> pairs;
  const std::string wanted = upper(set_name);
  for (auto p = phases.begin(); p != phases.end(); ++p)
    for (auto q = std::next(p); q != phases.end(); ++q)
      if (upper(cohesive_set_name(named, p->first, q->first)) == wanted ||
          "COH_" + std::to_string(p->first) + "_" + std::to_string(q->first) == wanted)
        pairs.push_back({p->first, q->first});
  return pairs;
}

inline bool names_cohesive_set(std::string_view name) { return name.size() >= 4 && upper(name.substr(0, 4)) == "COH_"; }

// Whitespace-separated tokens with line numbers for errors.
class Scanner {
 public:
  Scanner(std::string_view text, const std::string& path, bool hash_comments = false,
          std::size_t base_offset = 0, std::string_view whole = {})
      : text_(text), path_(path), hash_comments_(hash_comments), base_(base_offset),
        whole_(whole) {}

  bool at_end() {
    skip_space();
    return pos_ >= text_.size();
  }
  std::string_view token() {
    skip_space();
    if (pos_ >= text_.size()) fail("unexpected end of file");
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_blank(text_[pos_])) ++pos_;
    return text_.substr(start, pos_ - start);
  }
  double real() {
    const std::string_view t = token();
    double value = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), value);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size()) {
      // from_chars rejects a leading '+', "inf" spelled differently etc.; retry leniently.
      if (!t.empty() && t[0] == '+') {
        const auto r2 = std::from_chars(t.data() + 1, t.data() + t.size(), value);
        if (r2.ec == std::errc() && r2.ptr == t.data() + t.size()) return value;
      }
      fail_at(t, "expected a number, got '" + std::string(t.substr(0, 40)) + "'");
    }
    return value;
  }
  long long integer() {
    const std::string_view t = token();
    long long value = 0;
    const char* begin = t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(begin, t.data() + t.size(), value);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail_at(t, "expected an integer, got '" + std::string(t.substr(0, 40)) + "'");
    return value;
  }
  // The rest of the current line (without the newline), advancing past it.
  std::string_view rest_of_line() {
    const std::size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    const std::string_view line = text_.substr(start, pos_ - start);
    if (pos_ < text_.size()) ++pos_;
    return line;
  }
  void skip_past(std::string_view marker) {
    const std::size_t found = text_.find(marker, pos_);
    if (found == std::string_view::npos)
      fail("missing '" + std::string(marker) + "'");
    pos_ = found + marker.size();
  }
  void expect(std::string_view word) {
    const std::string_view t = token();
    if (t != word) fail_at(t, "expected '" + std::string(word) + "', got '" + std::string(t.substr(0, 40)) + "'");
  }
  std::size_t position() const { return pos_; }
  // Moves to `offset` (binary data read elsewhere ends there).
  void seek(std::size_t offset) { pos_ = std::min(offset, text_.size()); }
  std::string_view text() const { return text_; }
  // A count read from the file, checked against what is left of it before anything is
  // reserved: each of its entries takes `values` tokens, each token at least 2 bytes.
  std::size_t count(std::string_view what, long long values_per_entry) {
    const std::string_view t = token();
    long long n = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), n);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || n < 0)
      fail_at(t, "expected a count for " + std::string(what) + ", got '" + std::string(t.substr(0, 40)) + "'");
    const std::size_t left = text_.size() - pos_;
    const auto per_entry = static_cast<std::size_t>(std::max(1LL, values_per_entry));
    if (static_cast<unsigned long long>(n) > left / (2 * per_entry))
      fail_at(t, std::string(what) + " count " + std::string(t) + " is more than the rest of the file holds");
    return static_cast<std::size_t>(n);
  }

  [[noreturn]] void fail(const std::string& problem) const { fail_offset(pos_, problem); }
  [[noreturn]] void fail_at(std::string_view token, const std::string& problem) const {
    fail_offset(static_cast<std::size_t>(token.data() - text_.data()), problem);
  }
  [[noreturn]] void fail_offset(std::size_t offset, const std::string& problem) const {
    const std::string_view all = whole_.data() ? whole_ : text_;
    const std::size_t absolute = std::min(base_ + offset, all.size());
    const std::size_t line = 1 + static_cast<std::size_t>(
                                     std::count(all.begin(), all.begin() + absolute, '\n'));
    throw InputError(path_, "line " + std::to_string(line), problem);
  }

 private:
  void skip_space() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (is_blank(c)) {
        ++pos_;
      } else if (hash_comments_ && c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }
  std::string_view text_;
  const std::string& path_;
  bool hash_comments_;
  std::size_t base_;
  std::string_view whole_;
  std::size_t pos_ = 0;
};

// Binary values in a file, little- or big-endian, each read checked against the end.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view bytes, std::size_t position, const std::string& path, std::string what,
               bool big_endian = false)
      : bytes_(bytes), pos_(position), path_(path), what_(std::move(what)), big_endian_(big_endian) {}

  template <class T>
  T read() {
    if (bytes_.size() - std::min(pos_, bytes_.size()) < sizeof(T))
      throw InputError(path_, what_, "binary data end before the file says they do");
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, bytes_.data() + pos_, sizeof(T));
    if (big_endian_) std::reverse(raw, raw + sizeof(T));
    pos_ += sizeof(T);
    T value;
    std::memcpy(&value, raw, sizeof(T));
    return value;
  }
  // A count of entries of `bytes_per_entry` bytes each, checked against what is left.
  std::size_t count(std::uint64_t n, std::size_t bytes_per_entry) const {
    const std::size_t left = bytes_.size() - std::min(pos_, bytes_.size());
    if (n > left / std::max<std::size_t>(bytes_per_entry, 1))
      throw InputError(path_, what_, "count " + std::to_string(n) + " is more than the rest of the file holds");
    return static_cast<std::size_t>(n);
  }
  std::size_t position() const { return pos_; }

 private:
  std::string_view bytes_;
  std::size_t pos_;
  const std::string& path_;
  std::string what_;
  bool big_endian_;
};

// Maps file node tags (any positive integers) to 0-based indices in ascending tag order.
class TagMap {
 public:
  void build(const std::vector<long long>& tags_in_file_order, const std::string& path,
             std::vector<std::size_t>& order) {
    const std::size_t n = tags_in_file_order.size();
    order.resize(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    if (!std::is_sorted(tags_in_file_order.begin(), tags_in_file_order.end()))
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return tags_in_file_order[a] < tags_in_file_order[b];
      });
    long long max_tag = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const long long tag = tags_in_file_order[order[k]];
      if (k > 0 && tag == tags_in_file_order[order[k - 1]])
        throw InputError(path, "", "node " + std::to_string(tag) + " is defined twice");
      max_tag = std::max(max_tag, tag);
    }
    dense_ = max_tag >= 0 && static_cast<std::size_t>(max_tag) <= 4 * n + 1024;
    if (dense_) {
      dense_index_.assign(static_cast<std::size_t>(max_tag) + 1, -1);
      for (std::size_t k = 0; k < n; ++k)
        if (tags_in_file_order[order[k]] >= 0)
          dense_index_[static_cast<std::size_t>(tags_in_file_order[order[k]])] =
              static_cast<std::int64_t>(k);
    } else {
      sparse_index_.reserve(n);
      for (std::size_t k = 0; k < n; ++k)
        sparse_index_.emplace(tags_in_file_order[order[k]], static_cast<std::int64_t>(k));
    }
  }
  // -1 when the tag is not a node.
  std::int64_t index(long long tag) const {
    if (dense_) {
      if (tag < 0 || static_cast<std::size_t>(tag) >= dense_index_.size()) return -1;
      return dense_index_[static_cast<std::size_t>(tag)];
    }
    const auto it = sparse_index_.find(tag);
    return it == sparse_index_.end() ? -1 : it->second;
  }

 private:
  bool dense_ = true;
  std::vector<std::int64_t> dense_index_;
  std::unordered_map<long long, std::int64_t> sparse_index_;
};

// Coordinates in file order → ascending tag order; returns the tag map.
inline TagMap sort_nodes_by_tag(RawMesh& raw, const std::vector<long long>& tags,
                         const std::string& path) {
  TagMap map;
  std::vector<std::size_t> order;
  map.build(tags, path, order);
  if (std::is_sorted(tags.begin(), tags.end())) return map;  // already in tag order
  std::vector<double> sorted(raw.coords.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    for (int d = 0; d < 3; ++d) sorted[3 * k + d] = raw.coords[3 * order[k] + d];
  raw.coords = std::move(sorted);
  return map;
}

// Cells collected with their file tags; the top dimension is kept, in ascending tag order.
struct TaggedCells {
  struct Cell {
    long long tag;
    std::int32_t phase;
    std::array<long long, 4> nodes;  // file node tags
  };
  std::vector<Cell> triangles, tetrahedra;
  // Cells the file marks cohesive (quads, prisms), nodes already in the internal order.
  struct CohesiveCell {
    long long tag;
    std::int32_t set;  // index into RawMesh::cohesive_sets, or LoadedMesh::kNoCohesiveSet
    bool several_sets;  // in other sets too (then written as LoadedMesh::kSeveralCohesiveSets)
    std::array<std::int32_t, 2> phases;  // as the file claims them; 0 = unsaid
    int corners;  // 4 or 6
    std::array<long long, 6> nodes;  // file node tags, internal order
  };
  std::vector<CohesiveCell> cohesive;

  std::vector<Cell>& kept() { return tetrahedra.empty() ? triangles : tetrahedra; }

  // The name of every phase id the kept cells use: `names`' entry, or "phase<id>" as
  // finish() names it.
  std::map<int, std::string> used_phase_names(const std::map<int, std::string>& names) {
    std::map<int, std::string> used;
    std::int32_t last = 0;
    for (const Cell& c : kept()) {
      if ((c.phase == last && !used.empty()) || used.count(c.phase)) continue;
      last = c.phase;
      const auto it = names.find(c.phase);
      used[c.phase] = it != names.end() && !it->second.empty() ? it->second : "phase" + std::to_string(c.phase);
    }
    return used;
  }

  // Ascending tag order; O(n) when the tags are a permutation of a range (as we write them).
  template <class C>
  static void sort_by_tag(std::vector<C>& cells) {
    if (cells.empty()) return;
    if (std::is_sorted(cells.begin(), cells.end(), [](const C& a, const C& b) { return a.tag < b.tag; }))
      return;
    long long lo = cells[0].tag, hi = cells[0].tag;
    for (const C& c : cells) lo = std::min(lo, c.tag), hi = std::max(hi, c.tag);
    // Unsigned: tags may span the whole long long range.
    const auto span = static_cast<unsigned long long>(hi) - static_cast<unsigned long long>(lo);
    if (span == cells.size() - 1) {
      std::vector<C> placed(cells.size());
      std::vector<bool> filled(cells.size(), false);
      bool permutation = true;
      for (const C& c : cells) {
        const auto at = static_cast<std::size_t>(static_cast<unsigned long long>(c.tag) -
                                                 static_cast<unsigned long long>(lo));
        if (filled[at]) { permutation = false; break; }
        filled[at] = true;
        placed[at] = c;
      }
      if (permutation) {
        cells = std::move(placed);
        return;
      }
    }
    std::stable_sort(cells.begin(), cells.end(), [](const C& a, const C& b) { return a.tag < b.tag; });
  }

  void finish(RawMesh& raw, const TagMap& nodes, const std::string& path) {
    std::vector<Cell>& kept = this->kept();
    raw.corners = kept.empty() ? 0 : (tetrahedra.empty() ? 3 : 4);
    sort_by_tag(kept);
    raw.cell_nodes.reserve(kept.size() * static_cast<std::size_t>(raw.corners));
    raw.cell_phase.reserve(kept.size());
    for (const Cell& c : kept) {
      for (int k = 0; k < raw.corners; ++k) {
        const std::int64_t i = nodes.index(c.nodes[static_cast<std::size_t>(k)]);
        if (i < 0)
          throw InputError(path, "", "element " + std::to_string(c.tag) + " uses node " +
                                         std::to_string(c.nodes[static_cast<std::size_t>(k)]) +
                                         ", which is not defined");
        raw.cell_nodes.push_back(static_cast<LocalId>(i));
      }
      raw.cell_phase.push_back(c.phase);
    }
    if (cohesive.empty()) return;
    sort_by_tag(cohesive);
    raw.cohesive_corners = cohesive.front().corners;
    raw.cohesive_nodes.reserve(cohesive.size() * static_cast<std::size_t>(raw.cohesive_corners));
    for (const CohesiveCell& c : cohesive) {
      if (c.corners != raw.cohesive_corners)
        throw InputError(path, "", "cohesive element " + std::to_string(c.tag) +
                                       " is not of the same kind as the others (quads and prisms mixed)");
      for (int k = 0; k < c.corners; ++k) {
        const std::int64_t i = nodes.index(c.nodes[static_cast<std::size_t>(k)]);
        if (i < 0)
          throw InputError(path, "", "cohesive element " + std::to_string(c.tag) + " uses node " +
                                         std::to_string(c.nodes[static_cast<std::size_t>(k)]) + ", which is not defined");
        raw.cohesive_nodes.push_back(static_cast<LocalId>(i));
      }
      raw.cohesive_phase.insert(raw.cohesive_phase.end(), c.phases.begin(), c.phases.end());
      raw.cohesive_set_of_cell.push_back(c.several_sets ? LoadedMesh::kSeveralCohesiveSets : c.set);
    }
  }
};


// The checks and defaults every reader ends with (mesh_read.cpp).
LoadedMesh finish(RawMesh raw, const std::string& path);

// The readers, one file each; read_mesh() picks one by the extension.
RawMesh read_vtu_raw(const std::string& path);  // one VTU piece, before finish()
LoadedMesh read_vtu(const std::string& path);
LoadedMesh read_pvtu(const std::string& path);
LoadedMesh read_legacy_vtk(const std::string& path);
LoadedMesh read_msh(const std::string& path);
LoadedMesh read_medit(const std::string& path);
LoadedMesh read_inp(const std::string& path);
LoadedMesh read_tetgen(const std::string& path);

}  // namespace cisamr::io::detail
