// Mesh readers: VTU, Gmsh MSH (4.1 and 2.2 ASCII), Medit MESH (ASCII), Abaqus INP.
// Each reader fills a RawMesh (3 coordinates per node, 0-based cells of the top dimension
// found in the file); finish() decides the dimension, checks indices and applies defaults.
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

namespace cisamr::io {
namespace {

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

std::string upper(std::string_view s) {
  std::string u(s);
  for (char& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

std::string_view trim(std::string_view s) {
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
};

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
TagMap sort_nodes_by_tag(RawMesh& raw, const std::vector<long long>& tags,
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

  // Ascending tag order; O(n) when the tags are a permutation of a range (as we write them).
  static void sort_by_tag(std::vector<Cell>& cells) {
    if (cells.empty()) return;
    if (std::is_sorted(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) { return a.tag < b.tag; }))
      return;
    long long lo = cells[0].tag, hi = cells[0].tag;
    for (const Cell& c : cells) lo = std::min(lo, c.tag), hi = std::max(hi, c.tag);
    // Unsigned: tags may span the whole long long range.
    const auto span = static_cast<unsigned long long>(hi) - static_cast<unsigned long long>(lo);
    if (span == cells.size() - 1) {
      std::vector<Cell> placed(cells.size());
      std::vector<bool> filled(cells.size(), false);
      bool permutation = true;
      for (const Cell& c : cells) {
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
    std::stable_sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) { return a.tag < b.tag; });
  }

  void finish(RawMesh& raw, const TagMap& nodes, const std::string& path) {
    std::vector<Cell>& kept = tetrahedra.empty() ? triangles : tetrahedra;
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
  }
};

template <int Dim>
void fill_mesh(RawMesh& raw, mesh::SimplexMesh<Dim>& m) {
  const std::size_t nodes = raw.coords.size() / 3;
  m.coords.resize(nodes * Dim);
  for (std::size_t n = 0; n < nodes; ++n)
    for (int d = 0; d < Dim; ++d) m.coords[n * Dim + d] = raw.coords[3 * n + d];
  m.cell_nodes = std::move(raw.cell_nodes);
  m.cell_phase = std::move(raw.cell_phase);
  m.cell_partition = std::move(raw.cell_partition);
  if (m.cell_partition.empty()) m.cell_partition.assign(m.cell_phase.size(), 0);
  m.node_global_id = std::move(raw.node_global_id);
  if (m.node_global_id.empty()) {
    m.node_global_id.resize(nodes);
    for (std::size_t n = 0; n < nodes; ++n) m.node_global_id[n] = static_cast<GlobalId>(n);
  }
}

LoadedMesh finish(RawMesh raw, const std::string& path) {
  const std::size_t nodes = raw.coords.size() / 3;
  if (nodes > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw InputError(path, "", "too many nodes (" + std::to_string(nodes) + ")");
  for (std::size_t i = 0; i < raw.cell_nodes.size(); ++i)
    if (raw.cell_nodes[i] < 0 || static_cast<std::size_t>(raw.cell_nodes[i]) >= nodes)
      throw InputError(path, "", "cell " + std::to_string(i / std::max(raw.corners, 1)) +
                                     " refers to node " + std::to_string(raw.cell_nodes[i]) +
                                     " of " + std::to_string(nodes));
  const std::size_t cells = raw.corners ? raw.cell_nodes.size() / static_cast<std::size_t>(raw.corners) : 0;
  if (cells == 0) throw InputError(path, "", "no triangles or tetrahedra: not a mesh");
  if (raw.cell_phase.empty()) raw.cell_phase.assign(cells, 1);
  if (raw.cell_phase.size() != cells || (!raw.cell_partition.empty() && raw.cell_partition.size() != cells))
    throw InputError(path, "", "cell data do not match the number of cells");
  if (!raw.node_global_id.empty() && raw.node_global_id.size() != nodes)
    throw InputError(path, "", "point data do not match the number of points");

  LoadedMesh result;
  bool flat = true;
  for (std::size_t n = 0; n < nodes; ++n)
    if (raw.coords[3 * n + 2] != 0) {
      flat = false;
      break;
    }
  if (raw.corners == 3 && !flat)
    throw InputError(path, "", "triangles outside the plane z = 0: a surface mesh, not a 2D "
                               "or volume mesh (only 2D triangle and 3D tetrahedron meshes are read)");
  result.dimension = raw.corners == 4 || (raw.corners == 0 && !flat) ? 3 : 2;

  std::vector<std::int32_t> ids;  // distinct phase ids: few, so a linear search is cheap
  std::int32_t last = 0;
  for (const std::int32_t id : raw.cell_phase) {
    if ((id == last && !ids.empty()) || std::find(ids.begin(), ids.end(), id) != ids.end()) continue;
    ids.push_back(id);
    last = id;
  }
  std::sort(ids.begin(), ids.end());
  for (const std::int32_t id : ids) {
    const auto it = raw.phase_names.find(id);
    result.phases.push_back(geometry::Phase{
        id, it != raw.phase_names.end() ? it->second : "phase" + std::to_string(id), false});
  }
  if (result.dimension == 2)
    fill_mesh(raw, result.mesh2);
  else
    fill_mesh(raw, result.mesh3);
  return result;
}

// ------------------------------------------------------------------------------ VTU

struct XmlTag {
  std::string name;            // "DataArray", "/DataArray", ...
  std::map<std::string, std::string> attributes;
  bool self_closing = false;
  std::size_t end = 0;         // offset just after '>'
};

// Reads the tag starting at text[start] == '<'. Comments and declarations are returned with
// an empty name.
XmlTag read_tag(std::string_view text, std::size_t start, const std::string& path) {
  XmlTag tag;
  if (text.compare(start, 4, "<!--") == 0) {
    const std::size_t close = text.find("-->", start);
    if (close == std::string_view::npos) throw InputError(path, "", "unterminated XML comment");
    tag.end = close + 3;
    return tag;
  }
  const std::size_t close = text.find('>', start);
  if (close == std::string_view::npos) throw InputError(path, "", "unterminated XML tag");
  tag.end = close + 1;
  if (text[start + 1] == '?' || text[start + 1] == '!') return tag;
  std::string_view inside = text.substr(start + 1, close - start - 1);
  if (!inside.empty() && inside.back() == '/') {
    tag.self_closing = true;
    inside.remove_suffix(1);
  }
  std::size_t i = 0;
  while (i < inside.size() && !std::isspace(static_cast<unsigned char>(inside[i]))) ++i;
  tag.name = std::string(inside.substr(0, i));
  while (i < inside.size()) {
    while (i < inside.size() && std::isspace(static_cast<unsigned char>(inside[i]))) ++i;
    if (i >= inside.size()) break;
    const std::size_t key_start = i;
    while (i < inside.size() && inside[i] != '=' && !std::isspace(static_cast<unsigned char>(inside[i]))) ++i;
    const std::string key(inside.substr(key_start, i - key_start));
    while (i < inside.size() && std::isspace(static_cast<unsigned char>(inside[i]))) ++i;
    if (i >= inside.size() || inside[i] != '=')
      throw InputError(path, "", "malformed XML attribute '" + key + "' in <" + tag.name + ">");
    ++i;
    while (i < inside.size() && std::isspace(static_cast<unsigned char>(inside[i]))) ++i;
    if (i >= inside.size() || (inside[i] != '"' && inside[i] != '\''))
      throw InputError(path, "", "malformed XML attribute '" + key + "' in <" + tag.name + ">");
    const char quote = inside[i++];
    const std::size_t value_start = i;
    while (i < inside.size() && inside[i] != quote) ++i;
    tag.attributes[key] = std::string(inside.substr(value_start, i - value_start));
    ++i;
  }
  return tag;
}

std::string attribute(const XmlTag& tag, const std::string& key, const std::string& fallback = "") {
  const auto it = tag.attributes.find(key);
  return it == tag.attributes.end() ? fallback : it->second;
}

// A size attribute (NumberOfPoints, offset): decimal digits only, at most `limit` (the
// file's size: nothing in it can count or point beyond it).
std::size_t size_attribute(const XmlTag& tag, const std::string& key, std::size_t limit,
                           const std::string& path) {
  const std::string text = attribute(tag, key, "0");
  std::size_t value = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || text[0] == '-' || r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw InputError(path, "", "<" + tag.name + "> " + key + "=\"" + text.substr(0, 40) +
                                   "\" is not a non-negative integer");
  if (value > limit)
    throw InputError(path, "", "<" + tag.name + "> " + key + "=\"" + text +
                                   "\" is more than the file (" + std::to_string(limit) + " bytes) can hold");
  return value;
}

struct VtkType {
  const char* name;
  int bytes;
  bool is_real;
  bool is_signed;
};
constexpr VtkType kVtkTypes[] = {
    {"Int8", 1, false, true},    {"UInt8", 1, false, false},  {"Int16", 2, false, true},
    {"UInt16", 2, false, false}, {"Int32", 4, false, true},   {"UInt32", 4, false, false},
    {"Int64", 8, false, true},   {"UInt64", 8, false, false}, {"Float32", 4, true, true},
    {"Float64", 8, true, true},
};

template <class T>
T load(const unsigned char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

// A DataArray's values, read on demand: binary values stay where they are (in the mapped
// file or the decoded base64 buffer), ascii values are parsed into vectors.
struct DataValues {
  const VtkType* type = nullptr;
  const unsigned char* bytes = nullptr;  // binary: `count` little-endian values
  std::size_t count = 0;
  std::vector<unsigned char> owned;      // decoded base64
  std::vector<double> reals;             // ascii, real types
  std::vector<std::int64_t> ints;        // ascii, integer types
  bool ascii = false;

  bool is_real() const { return type->is_real; }
  std::size_t size() const { return ascii ? (type->is_real ? reals.size() : ints.size()) : count; }
  double real(std::size_t i) const {
    if (ascii) return type->is_real ? reals[i] : static_cast<double>(ints[i]);
    if (type->is_real) return type->bytes == 8 ? load<double>(bytes + 8 * i) : load<float>(bytes + 4 * i);
    return static_cast<double>(integer(i));
  }
  std::int64_t integer(std::size_t i) const {
    if (ascii) return type->is_real ? static_cast<std::int64_t>(reals[i]) : ints[i];
    const unsigned char* p = bytes + i * static_cast<std::size_t>(type->bytes);
    if (type->is_real) return static_cast<std::int64_t>(real(i));
    switch (type->bytes) {
      case 1: return type->is_signed ? load<std::int8_t>(p) : load<std::uint8_t>(p);
      case 2: return type->is_signed ? load<std::int16_t>(p) : load<std::uint16_t>(p);
      case 4: return type->is_signed ? load<std::int32_t>(p) : load<std::uint32_t>(p);
      default: return static_cast<std::int64_t>(load<std::uint64_t>(p));
    }
  }
};

void set_binary(const unsigned char* bytes, std::size_t size, const VtkType& type, DataValues& out) {
  out.type = &type;
  out.bytes = bytes;
  out.count = size / static_cast<std::size_t>(type.bytes);
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// Decodes base64 characters (whitespace ignored) until `end` or the first padding run.
// Returns the position after the consumed characters (padding included).
std::size_t base64_decode(std::string_view text, std::size_t begin, std::size_t end,
                          std::size_t max_groups, std::vector<unsigned char>& out) {
  std::uint32_t accumulator = 0;
  int bits = 0, in_group = 0;
  std::size_t groups = 0, i = begin;
  for (; i < end && groups < max_groups; ++i) {
    const char c = text[i];
    if (is_blank(c)) continue;
    if (c == '=') {  // padding ends this base64 run
      while (i < end && (text[i] == '=' || is_blank(text[i]))) {
        if (text[i] == '=') ++in_group;
        ++i;
        if (in_group == 4) break;
      }
      return i;
    }
    const int v = base64_value(c);
    if (v < 0) break;
    accumulator = (accumulator << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((accumulator >> bits) & 0xFF));
    }
    if (++in_group == 4) in_group = 0, ++groups;
  }
  return i;
}

// VTK base64 blocks: a header (byte count) then the data, encoded either as one run or as
// two runs (VTK's own writer pads the header run). Both are accepted.
void decode_base64_block(std::string_view text, std::size_t begin, std::size_t end,
                         int header_bytes, const VtkType& type, DataValues& out,
                         const std::string& path, const std::string& name) {
  std::vector<unsigned char> bytes;
  const std::size_t header_groups = (static_cast<std::size_t>(header_bytes) + 2) / 3;
  const std::size_t after_header = base64_decode(text, begin, end, header_groups, bytes);
  if (bytes.size() < static_cast<std::size_t>(header_bytes))
    throw InputError(path, "", "DataArray '" + name + "': truncated base64 header");
  const std::uint64_t size = header_bytes == 8 ? load<std::uint64_t>(bytes.data())
                                               : load<std::uint32_t>(bytes.data());
  if (size > end - begin)  // base64 takes 4 characters for 3 bytes: checked before reserving
    throw InputError(path, "", "DataArray '" + name + "': its header claims " + std::to_string(size) +
                                   " bytes, more than its base64 text holds");
  // Decode only this array's groups: appended base64 runs straight into the next array.
  // A padded run that held exactly the header means two runs (VTK's writer); otherwise the
  // header and data share one run, which may already have ended inside the header groups.
  const bool run_ended = after_header > begin && text[after_header - 1] == '=';
  const bool separate_runs = run_ended && bytes.size() == static_cast<std::size_t>(header_bytes);
  bytes.erase(bytes.begin(), bytes.begin() + header_bytes);
  std::size_t data_groups = 0;
  if (separate_runs)
    data_groups = (static_cast<std::size_t>(size) + 2) / 3;
  else if (!run_ended)
    data_groups = (static_cast<std::size_t>(size) + static_cast<std::size_t>(header_bytes) + 2) / 3 -
                  header_groups;
  bytes.reserve(bytes.size() + 3 * data_groups);
  base64_decode(text, after_header, end, data_groups, bytes);
  if (bytes.size() < size)
    throw InputError(path, "", "DataArray '" + name + "': base64 data shorter than its header says");
  out.owned = std::move(bytes);
  set_binary(out.owned.data(), static_cast<std::size_t>(size), type, out);
}

LoadedMesh read_vtu(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  const std::size_t appended_tag = text.find("<AppendedData");
  const std::string_view xml(text.data(), appended_tag == std::string::npos ? text.size() : appended_tag);
  std::size_t appended_start = std::string::npos;  // first byte after '_'
  bool appended_base64 = false;
  if (appended_tag != std::string::npos) {
    const XmlTag tag = read_tag(text, appended_tag, path);
    appended_base64 = attribute(tag, "encoding", "raw") == "base64";
    appended_start = text.find('_', tag.end);
    if (appended_start == std::string::npos) throw InputError(path, "", "AppendedData without '_'");
    ++appended_start;
  }

  int header_bytes = 4;
  bool seen_vtkfile = false, seen_piece = false;
  std::vector<std::string> open;  // element stack
  RawMesh raw;
  std::optional<DataValues> points, connectivity, offsets, types, phase, partition, global_id;
  std::size_t number_of_points = 0, number_of_cells = 0;

  std::size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string_view::npos) {
    const XmlTag tag = read_tag(xml, pos, path);
    pos = tag.end;
    if (tag.name.empty()) continue;
    if (tag.name[0] == '/') {
      if (!open.empty()) open.pop_back();
      continue;
    }
    if (tag.name == "VTKFile") {
      seen_vtkfile = true;
      if (attribute(tag, "type") != "UnstructuredGrid")
        throw InputError(path, "", "VTK file of type '" + attribute(tag, "type") +
                                       "', expected UnstructuredGrid");
      if (attribute(tag, "byte_order", "LittleEndian") != "LittleEndian")
        throw InputError(path, "", "big-endian VTU files are not supported");
      const std::string header = attribute(tag, "header_type", "UInt32");
      if (header != "UInt32" && header != "UInt64")
        throw InputError(path, "", "unsupported header_type '" + header + "'");
      header_bytes = header == "UInt64" ? 8 : 4;
      if (!attribute(tag, "compressor").empty())
        throw InputError(path, "", "compressed VTU (" + attribute(tag, "compressor") +
                                       ") is not supported: write it uncompressed");
    } else if (tag.name == "Piece") {
      if (seen_piece) throw InputError(path, "", "VTU files with several pieces are not supported");
      seen_piece = true;
      number_of_points = size_attribute(tag, "NumberOfPoints", text.size(), path);
      number_of_cells = size_attribute(tag, "NumberOfCells", text.size(), path);
    } else if (tag.name == "DataArray") {
      const std::string name = attribute(tag, "Name");
      const std::string type_name = attribute(tag, "type");
      const VtkType* type = nullptr;
      for (const VtkType& t : kVtkTypes)
        if (type_name == t.name) type = &t;
      if (!type) throw InputError(path, "", "DataArray '" + name + "' has unsupported type '" + type_name + "'");
      const std::string format = attribute(tag, "format", "ascii");
      std::size_t content_end = pos;
      if (!tag.self_closing) {
        content_end = xml.find("</DataArray", pos);
        if (content_end == std::string_view::npos)
          throw InputError(path, "", "DataArray '" + name + "' is not closed");
      }
      DataValues values;
      if (format == "appended") {
        if (appended_start == std::string::npos)
          throw InputError(path, "", "DataArray '" + name + "' is appended but there is no AppendedData");
        const std::size_t at = appended_start + size_attribute(tag, "offset", text.size() - appended_start, path);
        if (appended_base64) {
          const std::size_t end = text.find('<', at);
          decode_base64_block(text, at, end == std::string::npos ? text.size() : end, header_bytes,
                              *type, values, path, name);
        } else {
          if (at + static_cast<std::size_t>(header_bytes) > text.size())
            throw InputError(path, "", "DataArray '" + name + "': offset beyond the end of the file");
          const auto* p = reinterpret_cast<const unsigned char*>(text.data() + at);
          const std::uint64_t size = header_bytes == 8 ? load<std::uint64_t>(p) : load<std::uint32_t>(p);
          // Subtracted, not added: a size near 2^64 would wrap the sum around.
          if (size > text.size() - at - static_cast<std::size_t>(header_bytes))
            throw InputError(path, "", "DataArray '" + name + "': data beyond the end of the file");
          set_binary(p + header_bytes, static_cast<std::size_t>(size), *type, values);
        }
      } else if (format == "binary") {
        decode_base64_block(text, pos, content_end, header_bytes, *type, values, path, name);
      } else if (format == "ascii") {
        Scanner scanner(text.substr(pos, content_end - pos), path, false, pos, text);
        values.type = type;
        values.ascii = true;
        while (!scanner.at_end()) {
          if (type->is_real)
            values.reals.push_back(scanner.real());
          else
            values.ints.push_back(scanner.integer());
        }
      } else {
        throw InputError(path, "", "DataArray '" + name + "' has unknown format '" + format + "'");
      }
      const std::string section = open.empty() ? "" : open.back();
      if (section == "Points") points = std::move(values);
      else if (section == "Cells" && name == "connectivity") connectivity = std::move(values);
      else if (section == "Cells" && name == "offsets") offsets = std::move(values);
      else if (section == "Cells" && name == "types") types = std::move(values);
      else if (section == "CellData" && (name == "phase" || (!phase && (name == "gmsh:physical" || name == "medit:ref"))))
        phase = std::move(values);
      else if (section == "CellData" && name == "partition") partition = std::move(values);
      else if (section == "PointData" && name == "global_id") global_id = std::move(values);
      if (!tag.self_closing) {
        pos = content_end;  // the closing tag pops the stack
        open.push_back(tag.name);
      }
      continue;
    }
    if (!tag.self_closing) open.push_back(tag.name);
  }
  if (!seen_vtkfile) throw InputError(path, "", "not a VTK XML file (no <VTKFile>)");
  if (!points) throw InputError(path, "", "no Points array");
  if (!connectivity || !offsets || !types)
    throw InputError(path, "", "missing Cells array (connectivity, offsets and types are required)");
  if (points->size() != 3 * number_of_points)
    throw InputError(path, "", "Points has " + std::to_string(points->size()) + " values, expected 3 × " +
                                   std::to_string(number_of_points));
  // Real values read as integers could be anything (NaN, 1e300): integer arrays only.
  if (types->is_real() || connectivity->is_real() || offsets->is_real() || (phase && phase->is_real()) ||
      (partition && partition->is_real()))
    throw InputError(path, "", "connectivity, offsets, types, phase and partition must be integer arrays");
  if (types->size() != number_of_cells || offsets->size() != number_of_cells)
    throw InputError(path, "", "offsets/types do not have NumberOfCells entries");

  raw.coords.resize(points->size());
  if (!points->ascii && points->type->is_real && points->type->bytes == 8 && points->size() > 0)
    std::memcpy(raw.coords.data(), points->bytes, 8 * points->size());
  else
    for (std::size_t i = 0; i < points->size(); ++i) raw.coords[i] = points->real(i);

  // Keep the cells of the top dimension; points and lines (and triangles next to tets) go.
  bool has_tets = false;
  for (std::size_t c = 0; c < number_of_cells; ++c) {
    const std::int64_t t = types->integer(c);
    if (t == 10) has_tets = true;
    else if (t != 5 && t != 1 && t != 2 && t != 3 && t != 4) {
      static const std::map<std::int64_t, const char*> kNames = {
          {7, "polygon"}, {8, "pixel"}, {9, "quad"}, {11, "voxel"}, {12, "hexahedron"},
          {13, "wedge"}, {14, "pyramid"}, {21, "quadratic edge"}, {22, "quadratic triangle"},
          {24, "quadratic tetra"}};
      const auto it = kNames.find(t);
      throw InputError(path, "", "unsupported cell type " + std::to_string(t) +
                                     (it != kNames.end() ? std::string(" (") + it->second + ")" : "") +
                                     ": only triangles and tetrahedra are read");
    }
  }
  raw.corners = has_tets ? 4 : 3;
  const std::int64_t wanted = has_tets ? 10 : 5;
  if (phase && phase->size() != number_of_cells) throw InputError(path, "", "phase array has the wrong size");
  if (partition && partition->size() != number_of_cells)
    throw InputError(path, "", "partition array has the wrong size");
  raw.cell_nodes.reserve(number_of_cells * static_cast<std::size_t>(raw.corners));
  if (phase) raw.cell_phase.reserve(number_of_cells);
  if (partition) raw.cell_partition.reserve(number_of_cells);
  std::int64_t previous_end = 0;
  std::size_t kept = 0;
  for (std::size_t c = 0; c < number_of_cells; ++c) {
    const std::int64_t end = offsets->integer(c);
    const std::int64_t start = previous_end;
    previous_end = end;
    if (end < start || static_cast<std::size_t>(end) > connectivity->size())
      throw InputError(path, "", "bad offsets for cell " + std::to_string(c));
    if (types->integer(c) != wanted) continue;
    if (end - start != raw.corners)
      throw InputError(path, "", "cell " + std::to_string(c) + " has " + std::to_string(end - start) +
                                     " nodes, expected " + std::to_string(raw.corners));
    for (std::int64_t k = start; k < end; ++k) {
      const std::int64_t node = connectivity->integer(static_cast<std::size_t>(k));
      if (node < 0 || static_cast<std::size_t>(node) >= number_of_points)
        throw InputError(path, "", "cell " + std::to_string(c) + " refers to node " + std::to_string(node) +
                                       " of " + std::to_string(number_of_points));
      raw.cell_nodes.push_back(static_cast<LocalId>(node));
    }
    if (phase) raw.cell_phase.push_back(static_cast<std::int32_t>(phase->integer(c)));
    if (partition) raw.cell_partition.push_back(static_cast<std::int32_t>(partition->integer(c)));
    ++kept;
  }
  if (kept == 0) raw.corners = 0;
  if (global_id) {
    if (global_id->is_real()) throw InputError(path, "", "global_id must be an integer array");
    raw.node_global_id.resize(global_id->size());
    for (std::size_t i = 0; i < global_id->size(); ++i) raw.node_global_id[i] = global_id->integer(i);
  }
  return finish(std::move(raw), path);
}

// ------------------------------------------------------------------------------ MSH

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

void read_physical_names(Scanner& s, RawMesh& raw) {
  const long long count = s.integer();
  for (long long i = 0; i < count; ++i) {
    s.integer();  // dimension
    const long long tag = s.integer();
    std::string_view name = trim(s.rest_of_line());
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    raw.phase_names[static_cast<int>(tag)] = std::string(name);
  }
  s.expect("$EndPhysicalNames");
}

LoadedMesh read_msh(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  Scanner s(text, path);
  if (s.at_end() || s.token() != "$MeshFormat")
    throw InputError(path, "", "not a Gmsh file (it must start with $MeshFormat)");
  const std::string_view version = s.token();
  const long long file_type = s.integer();
  s.integer();  // data size
  if (file_type != 0) s.fail("binary MSH files are not supported: save as ASCII");
  const bool v4 = version.substr(0, 2) == "4.";
  if (!v4 && version.substr(0, 2) != "2.")
    s.fail("unsupported MSH version " + std::string(version) + " (4.1 and 2.2 are read)");
  if (v4 && version != "4.1") s.fail("unsupported MSH version " + std::string(version) + " (4.1 and 2.2 are read)");
  s.skip_past("$EndMeshFormat");

  RawMesh raw;
  TaggedCells cells;
  std::vector<long long> node_tags;
  // (dimension, entity tag) → first physical tag, 0 when none.
  std::map<std::pair<int, long long>, int> entity_physical;
  bool seen_nodes = false, seen_elements = false;

  while (!s.at_end()) {
    const std::string_view section = s.token();
    if (section == "$PhysicalNames") {
      read_physical_names(s, raw);
    } else if (section == "$Entities" && v4) {
      long long counts[4];
      for (auto& c : counts) c = s.integer();
      for (int dim = 0; dim < 4; ++dim)
        for (long long e = 0; e < counts[dim]; ++e) {
          const long long tag = s.integer();
          for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) s.real();
          const long long physical_count = s.integer();
          int physical = 0;
          for (long long k = 0; k < physical_count; ++k) {
            const long long p = s.integer();
            if (k == 0) physical = static_cast<int>(p);
          }
          if (dim > 0) {
            const long long bounding = s.integer();
            for (long long k = 0; k < bounding; ++k) s.integer();
          }
          entity_physical[{dim, tag}] = physical;
        }
      s.expect("$EndEntities");
    } else if (section == "$Nodes") {
      seen_nodes = true;
      if (v4) {
        const long long blocks = s.integer();
        const auto total = static_cast<long long>(s.count("$Nodes", 4));  // a tag and 3 coordinates each
        s.integer(), s.integer();
        node_tags.reserve(static_cast<std::size_t>(total));
        raw.coords.reserve(3 * static_cast<std::size_t>(total));
        for (long long b = 0; b < blocks; ++b) {
          const long long entity_dim = s.integer();
          s.integer();  // entity tag
          const long long parametric = s.integer();
          const long long count = s.integer();
          for (long long i = 0; i < count; ++i) node_tags.push_back(s.integer());
          for (long long i = 0; i < count; ++i) {
            for (int d = 0; d < 3; ++d) raw.coords.push_back(s.real());
            if (parametric) for (long long k = 0; k < std::min(entity_dim, 2LL); ++k) s.real();
          }
        }
      } else {
        const long long count = s.integer();
        for (long long i = 0; i < count; ++i) {
          node_tags.push_back(s.integer());
          for (int d = 0; d < 3; ++d) raw.coords.push_back(s.real());
        }
      }
      s.expect("$EndNodes");
    } else if (section == "$Elements") {
      seen_elements = true;
      if (v4) {
        const long long blocks = s.integer();
        s.integer(), s.integer(), s.integer();
        for (long long b = 0; b < blocks; ++b) {
          const int entity_dim = static_cast<int>(s.integer());
          const long long entity_tag = s.integer();
          const long long type = s.integer();
          const long long count = s.integer();
          const int n = gmsh_node_count(type);
          if (n == 0) unsupported_gmsh_type(s, type);
          const auto it = entity_physical.find({entity_dim, entity_tag});
          const std::int32_t phase = it != entity_physical.end() && it->second != 0 ? it->second : 1;
          for (long long i = 0; i < count; ++i) {
            const long long tag = s.integer();
            std::array<long long, 4> nodes{};
            for (int k = 0; k < n; ++k) {
              const long long node = s.integer();
              if (k < 4) nodes[static_cast<std::size_t>(k)] = node;
            }
            add_gmsh_cell(cells, s, type, tag, phase, nodes);
          }
        }
      } else {
        const long long count = s.integer();
        for (long long i = 0; i < count; ++i) {
          const long long tag = s.integer();
          const long long type = s.integer();
          const long long tag_count = s.integer();
          std::int32_t phase = 1;
          for (long long k = 0; k < tag_count; ++k) {
            const long long t = s.integer();
            if (k == 0 && t != 0) phase = static_cast<std::int32_t>(t);
          }
          const int n = gmsh_node_count(type);
          if (n == 0) unsupported_gmsh_type(s, type);
          std::array<long long, 4> nodes{};
          for (int k = 0; k < n; ++k) {
            const long long node = s.integer();
            if (k < 4) nodes[static_cast<std::size_t>(k)] = node;
          }
          add_gmsh_cell(cells, s, type, tag, phase, nodes);
        }
      }
      s.expect("$EndElements");
    } else if (!section.empty() && section[0] == '$') {
      s.skip_past("$End" + std::string(section.substr(1)));  // $NodeData, $Periodic, ...
    } else {
      s.fail("expected a section such as $Nodes, got '" + std::string(section.substr(0, 40)) + "'");
    }
  }
  if (!seen_nodes || !seen_elements) throw InputError(path, "", "missing $Nodes or $Elements");
  const TagMap map = sort_nodes_by_tag(raw, node_tags, path);
  cells.finish(raw, map, path);
  return finish(std::move(raw), path);
}

// ------------------------------------------------------------------------------ Medit

LoadedMesh read_medit(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  Scanner s(text, path, /*hash_comments=*/true);
  RawMesh raw;
  TaggedCells cells;
  int dimension = 0;
  bool seen_version = false;
  while (!s.at_end()) {
    const std::string_view keyword = s.token();
    const std::string word = upper(keyword);
    if (word == "END") break;
    if (word == "MESHVERSIONFORMATTED") {
      seen_version = true;
      const long long version = s.integer();
      if (version < 1 || version > 4) s.fail("unsupported MeshVersionFormatted " + std::to_string(version));
      continue;
    }
    if (!seen_version)
      s.fail_at(keyword, "not a Medit mesh (it must start with MeshVersionFormatted)");
    if (word == "DIMENSION") {
      dimension = static_cast<int>(s.integer());
      if (dimension != 2 && dimension != 3) s.fail("Dimension must be 2 or 3");
      continue;
    }
    // Sections we skip, with the number of values per entry (-1: the dimension).
    static const std::map<std::string, int> kSkipped = {
        {"EDGES", 3},          {"CORNERS", 1},           {"REQUIREDVERTICES", 1},
        {"RIDGES", 1},         {"REQUIREDEDGES", 1},     {"REQUIREDTRIANGLES", 1},
        {"NORMALATVERTICES", 2}, {"TANGENTATVERTICES", 2}, {"NORMALATTRIANGLEVERTICES", 3},
        {"NORMALS", -1},       {"TANGENTS", -1}};
    static const std::map<std::string, int> kRejected = {
        {"QUADRILATERALS", 5}, {"HEXAHEDRA", 9}, {"PRISMS", 7}, {"PYRAMIDS", 6}};
    const auto skipped = kSkipped.find(word);
    const auto rejected = kRejected.find(word);
    if (word != "VERTICES" && word != "TRIANGLES" && word != "TETRAHEDRA" && skipped == kSkipped.end() &&
        rejected == kRejected.end())
      s.fail_at(keyword, "unknown Medit keyword '" + std::string(keyword.substr(0, 40)) + "'");
    const int values_per_entry = word == "VERTICES"     ? dimension + 1
                                 : word == "TRIANGLES"  ? 4
                                 : word == "TETRAHEDRA" ? 5
                                 : rejected != kRejected.end() ? rejected->second
                                 : skipped->second < 0  ? dimension
                                                        : skipped->second;
    const long long count = static_cast<long long>(s.count(keyword.substr(0, 40), values_per_entry));
    if (word == "VERTICES") {
      if (dimension == 0) s.fail("Vertices before Dimension");
      raw.coords.reserve(3 * static_cast<std::size_t>(count));
      for (long long i = 0; i < count; ++i) {
        for (int d = 0; d < dimension; ++d) raw.coords.push_back(s.real());
        if (dimension == 2) raw.coords.push_back(0.0);
        s.integer();  // vertex reference
      }
    } else if (word == "TRIANGLES" || word == "TETRAHEDRA") {
      const int n = word == "TRIANGLES" ? 3 : 4;
      auto& list = n == 3 ? cells.triangles : cells.tetrahedra;
      for (long long i = 0; i < count; ++i) {
        std::array<long long, 4> nodes{};
        for (int k = 0; k < n; ++k) nodes[static_cast<std::size_t>(k)] = s.integer();
        list.push_back({i, static_cast<std::int32_t>(s.integer()), nodes});
      }
    } else if (skipped != kSkipped.end()) {
      for (long long i = 0; i < count * values_per_entry; ++i) s.token();
    } else if (count > 0) {
      s.fail_at(keyword, "unsupported element type '" + std::string(keyword) +
                             "': only triangles and tetrahedra are read");
    }
  }
  if (!seen_version) throw InputError(path, "", "not a Medit mesh (it must start with MeshVersionFormatted)");
  // Medit nodes are numbered 1..n in file order.
  std::vector<long long> tags(raw.coords.size() / 3);
  for (std::size_t i = 0; i < tags.size(); ++i) tags[i] = static_cast<long long>(i + 1);
  const TagMap map = sort_nodes_by_tag(raw, tags, path);
  cells.finish(raw, map, path);
  return finish(std::move(raw), path);
}

// ------------------------------------------------------------------------------ Abaqus

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

LoadedMesh read_inp(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  RawMesh raw;
  TaggedCells cells;
  std::vector<long long> node_tags;
  std::map<std::string, int> elset_phase;  // ELSET name → phase id, when no comment gives it
  std::optional<std::pair<int, std::string>> announced;  // from "** cisamr phase ID NAME"
  enum class Block { none, nodes, triangles, tetrahedra } block = Block::none;
  std::int32_t block_phase = 1;
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

  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view line = trim(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    if (line.empty()) continue;
    if (line.substr(0, 2) == "**") {
      constexpr std::string_view kMarker = "** cisamr phase ";
      if (line.substr(0, kMarker.size()) == kMarker) {
        std::string_view rest = line.substr(kMarker.size());
        const std::size_t space = rest.find(' ');
        const long long id = parse_int(rest.substr(0, space));
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
      if (keyword == "NODE") {
        block = Block::nodes;
      } else if (keyword == "ELEMENT") {
        const std::string type = upper(params["TYPE"]);
        if (std::find(std::begin(kTriangleTypes), std::end(kTriangleTypes), type) != std::end(kTriangleTypes))
          block = Block::triangles;
        else if (std::find(std::begin(kTetTypes), std::end(kTetTypes), type) != std::end(kTetTypes))
          block = Block::tetrahedra;
        else
          fail("unsupported element type '" + params["TYPE"] + "': only triangles and tetrahedra are read");
        const std::string elset = params["ELSET"];
        if (announced) {
          block_phase = announced->first;
          raw.phase_names[announced->first] = announced->second;
          announced.reset();
        } else if (!elset.empty()) {
          const auto [it, inserted] = elset_phase.emplace(elset, static_cast<int>(elset_phase.size()) + 1);
          block_phase = it->second;
          if (inserted) raw.phase_names[it->second] = elset;
        } else {
          block_phase = 1;
        }
      }
      continue;
    }
    if (block == Block::none) continue;  // data of a keyword we do not read
    split_commas(line, fields);
    if (block == Block::nodes) {
      if (fields.size() != 3 && fields.size() != 4) fail("a node line needs an id and 2 or 3 coordinates");
      node_tags.push_back(parse_int(fields[0]));
      for (std::size_t d = 1; d < 4; ++d) raw.coords.push_back(d < fields.size() ? parse_real(fields[d]) : 0.0);
    } else {
      const std::size_t n = block == Block::triangles ? 3 : 4;
      if (fields.size() != n + 1)
        fail("an element line needs an id and " + std::to_string(n) + " nodes");
      std::array<long long, 4> nodes{};
      for (std::size_t k = 0; k < n; ++k) nodes[k] = parse_int(fields[k + 1]);
      (block == Block::triangles ? cells.triangles : cells.tetrahedra)
          .push_back({parse_int(fields[0]), block_phase, nodes});
    }
  }
  const TagMap map = sort_nodes_by_tag(raw, node_tags, path);
  cells.finish(raw, map, path);
  return finish(std::move(raw), path);
}

}  // namespace

LoadedMesh read_mesh(const std::string& path) {
  switch (mesh_format_of(path)) {
    case MeshFormat::vtu: return read_vtu(path);
    case MeshFormat::msh: return read_msh(path);
    case MeshFormat::inp: return read_inp(path);
    case MeshFormat::medit: return read_medit(path);
  }
  throw InputError(path, "", "unknown mesh format");
}

}  // namespace cisamr::io
