// VTK readers: XML UnstructuredGrid (.vtu: ascii, inline base64, appended raw or base64,
// zlib-compressed or not), parallel .pvtu (its pieces merged), legacy .vtk (ASCII and
// BINARY, UNSTRUCTURED_GRID). XML is parsed by pugixml; the appended raw block, which is not
// XML, is cut off first and read in place.
#include <zlib.h>

#include <filesystem>
#include <tuple>

#include <pugixml.hpp>

#include "core/error.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io::detail {
namespace {

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
    {"String", 1, false, false},  // bytes, each string ended by 0: phase_names only
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
  std::vector<unsigned char> owned;      // decoded base64, decompressed or byte-swapped
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

const VtkType* vtk_type(std::string_view name) {
  for (const VtkType& t : kVtkTypes)
    if (name == t.name) return &t;
  return nullptr;
}

// ----------------------------------------------------------------------- shared assembly

// What an unstructured grid needs, from either VTK dialect.
struct GridArrays {
  std::size_t number_of_points = 0, number_of_cells = 0;
  std::optional<DataValues> points, connectivity, offsets, types, phase, partition, global_id, periodic_master;
  std::optional<DataValues> cohesive, phase_top, node_phase;  // cohesive meshes (mesh_write.cpp)
  std::map<int, std::string> phase_names;  // from field data
  // meshio's convention for Gmsh physical names: an integer field array NAME = [tag, dim].
  std::vector<std::tuple<std::string, std::int64_t, std::int64_t>> tag_dimension_names;
};

bool is_phase_array(std::string_view name) { return name == "phase" || name == "gmsh:physical" || name == "medit:ref"; }

bool is_cell_array(std::string_view name) {
  return is_phase_array(name) || name == "partition" || name == "cohesive" || name == "phase_top";
}

// Keeps "phase" over the other tools' names for it.
void take_cell_array(GridArrays& g, std::string_view name, DataValues&& values) {
  if (name == "phase" || (!g.phase && is_phase_array(name))) g.phase = std::move(values);
  else if (name == "partition") g.partition = std::move(values);
  else if (name == "cohesive") g.cohesive = std::move(values);
  else if (name == "phase_top") g.phase_top = std::move(values);
}

// Field data: phase_names (bytes, each name ended by 0: our UInt8 array or VTK's String
// array) with phase_ids, or meshio's NAME = [tag, dimension].
void take_field_arrays(GridArrays& g, const std::vector<std::pair<std::string, DataValues>>& arrays,
                       const std::string& path) {
  const DataValues* names = nullptr;
  const DataValues* ids = nullptr;
  for (const auto& [name, values] : arrays) {
    if (name == "phase_names" && !values.is_real()) names = &values;
    else if (name == "phase_ids" && !values.is_real()) ids = &values;
    else if (!values.is_real() && values.size() == 2)
      g.tag_dimension_names.emplace_back(name, values.integer(0), values.integer(1));
  }
  if (!names && !ids) return;
  if (!names || !ids) throw InputError(path, "FieldData", "phase_names and phase_ids come together");
  std::vector<std::string> split;
  std::string current;
  for (std::size_t i = 0; i < names->size(); ++i) {
    const std::int64_t byte = names->integer(i);
    if (byte < 0 || byte > 255) throw InputError(path, "FieldData phase_names", "a value is not a byte");
    if (byte == 0) split.push_back(std::move(current)), current.clear();
    else current.push_back(static_cast<char>(byte));
  }
  if (!current.empty()) split.push_back(std::move(current));
  if (split.size() != ids->size())
    throw InputError(path, "FieldData", std::to_string(split.size()) + " phase_names but " +
                                            std::to_string(ids->size()) + " phase_ids");
  for (std::size_t k = 0; k < split.size(); ++k) {
    const std::int64_t id = ids->integer(k);
    if (id < std::numeric_limits<std::int32_t>::min() || id > std::numeric_limits<std::int32_t>::max())
      throw InputError(path, "FieldData phase_ids", "id " + std::to_string(id) + " is out of range");
    g.phase_names[static_cast<int>(id)] = split[k];
  }
}

std::int32_t int32_value(std::int64_t v, const char* what, const std::string& path) {
  if (v < std::numeric_limits<std::int32_t>::min() || v > std::numeric_limits<std::int32_t>::max())
    throw InputError(path, what, "value " + std::to_string(v) + " is out of range");
  return static_cast<std::int32_t>(v);
}

// Cell c of the grid, marked cohesive: its nodes from VTK's order to the internal one, its
// phases from phase (the bottom's) and phase_top (0 where an array is missing).
void add_cohesive_cell(RawMesh& raw, const GridArrays& g, std::size_t c, std::int64_t start, std::int64_t end,
                       const std::string& path) {
  const int corners = raw.cohesive_corners;
  if (end - start != corners)
    throw InputError(path, "", "cohesive cell " + std::to_string(c) + " has " + std::to_string(end - start) +
                                   " nodes, expected " + std::to_string(corners));
  std::array<LocalId, 6> file{}, internal{};
  for (int k = 0; k < corners; ++k) {
    const std::int64_t node = g.connectivity->integer(static_cast<std::size_t>(start + k));
    if (node < 0 || static_cast<std::uint64_t>(node) >= g.number_of_points)
      throw InputError(path, "", "cell " + std::to_string(c) + " refers to node " + std::to_string(node) + " of " +
                                     std::to_string(g.number_of_points));
    file[static_cast<std::size_t>(k)] = static_cast<LocalId>(node);
  }
  cohesive_to_internal(corners, CohesiveFileOrder::vtk, file.data(), internal.data());
  raw.cohesive_nodes.insert(raw.cohesive_nodes.end(), internal.begin(), internal.begin() + corners);
  raw.cohesive_phase.push_back(g.phase ? int32_value(g.phase->integer(c), "phase", path) : 0);
  raw.cohesive_phase.push_back(g.phase_top ? int32_value(g.phase_top->integer(c), "phase_top", path) : 0);
  if (g.partition) raw.cohesive_partition.push_back(int32_value(g.partition->integer(c), "partition", path));
}

RawMesh assemble(GridArrays& g, const std::string& path) {
  RawMesh raw;
  if (!g.points) throw InputError(path, "Points", "no Points array");
  if (!g.connectivity || !g.offsets || !g.types)
    throw InputError(path, "Cells", "missing cell arrays (connectivity, offsets and types are required)");
  const DataValues& points = *g.points;
  const DataValues& connectivity = *g.connectivity;
  const DataValues& offsets = *g.offsets;
  const DataValues& types = *g.types;
  const std::size_t number_of_points = g.number_of_points, number_of_cells = g.number_of_cells;
  if (points.size() != 3 * number_of_points)
    throw InputError(path, "Points", "has " + std::to_string(points.size()) + " values, NumberOfPoints " +
                                         std::to_string(number_of_points) + " needs 3 × as many");
  // Real values read as integers could be anything (NaN, 1e300): integer arrays only.
  if (types.is_real() || connectivity.is_real() || offsets.is_real() || (g.phase && g.phase->is_real()) ||
      (g.partition && g.partition->is_real()) || (g.cohesive && g.cohesive->is_real()) ||
      (g.phase_top && g.phase_top->is_real()))
    throw InputError(path, "", "connectivity, offsets, types, phase, partition, cohesive and phase_top must be integer arrays");
  if (types.size() != number_of_cells || offsets.size() != number_of_cells)
    throw InputError(path, "Cells", "offsets/types do not have one entry per cell");
  if (g.cohesive && g.cohesive->size() != number_of_cells) throw InputError(path, "cohesive", "array has the wrong size");
  if (g.phase_top && g.phase_top->size() != number_of_cells) throw InputError(path, "phase_top", "array has the wrong size");
  // A quad (2D) or wedge (3D) is read only where cell data cohesive = 1 mark it.
  const auto marked_cohesive = [&](std::size_t c) {
    if (!g.cohesive) return false;
    const std::int64_t flag = g.cohesive->integer(c);
    if (flag != 0 && flag != 1)
      throw InputError(path, "cohesive", "value " + std::to_string(flag) + " of cell " + std::to_string(c) + " is not 0 or 1");
    return flag == 1;
  };

  raw.coords.resize(points.size());
  if (!points.ascii && points.type->is_real && points.type->bytes == 8 && points.size() > 0)
    std::memcpy(raw.coords.data(), points.bytes, 8 * points.size());
  else
    for (std::size_t i = 0; i < points.size(); ++i) raw.coords[i] = points.real(i);

  // Keep the cells of the top dimension; points and lines (and triangles next to tets) go.
  bool has_tets = false;
  std::int64_t cohesive_type = 0;  // 9 or 13 once a cohesive cell is seen
  for (std::size_t c = 0; c < number_of_cells; ++c) {
    const std::int64_t t = types.integer(c);
    const bool cohesive = marked_cohesive(c);
    if (cohesive && t != 9 && t != 13)
      throw InputError(path, "cohesive", "cell " + std::to_string(c) + " is marked cohesive but has type " +
                                             std::to_string(t) + " (a cohesive cell is a quad, 9, or a wedge, 13)");
    if (cohesive) {
      if (cohesive_type != 0 && t != cohesive_type)
        throw InputError(path, "cohesive", "quads and wedges are both marked cohesive");
      cohesive_type = t;
    } else if (t == 10) has_tets = true;
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
  raw.cohesive_corners = cohesive_type == 9 ? 4 : cohesive_type == 13 ? 6 : 0;
  if (g.phase && g.phase->size() != number_of_cells) throw InputError(path, "phase", "array has the wrong size");
  if (g.partition && g.partition->size() != number_of_cells)
    throw InputError(path, "partition", "array has the wrong size");
  raw.cell_nodes.reserve(number_of_cells * static_cast<std::size_t>(raw.corners));
  if (g.phase) raw.cell_phase.reserve(number_of_cells);
  if (g.partition) raw.cell_partition.reserve(number_of_cells);
  auto int32 = [&](std::int64_t v, const char* what) { return int32_value(v, what, path); };
  std::int64_t previous_end = 0;
  std::size_t kept = 0;
  for (std::size_t c = 0; c < number_of_cells; ++c) {
    const std::int64_t end = offsets.integer(c);
    const std::int64_t start = previous_end;
    previous_end = end;
    if (end < start || static_cast<std::uint64_t>(end) > connectivity.size())
      throw InputError(path, "offsets", "bad offsets for cell " + std::to_string(c));
    if (raw.cohesive_corners != 0 && marked_cohesive(c)) {
      add_cohesive_cell(raw, g, c, start, end, path);
      continue;
    }
    if (types.integer(c) != wanted) continue;
    if (end - start != raw.corners)
      throw InputError(path, "", "cell " + std::to_string(c) + " has " + std::to_string(end - start) +
                                     " nodes, expected " + std::to_string(raw.corners));
    for (std::int64_t k = start; k < end; ++k) {
      const std::int64_t node = connectivity.integer(static_cast<std::size_t>(k));
      if (node < 0 || static_cast<std::uint64_t>(node) >= number_of_points)
        throw InputError(path, "", "cell " + std::to_string(c) + " refers to node " + std::to_string(node) +
                                       " of " + std::to_string(number_of_points));
      raw.cell_nodes.push_back(static_cast<LocalId>(node));
    }
    if (g.phase) raw.cell_phase.push_back(int32(g.phase->integer(c), "phase"));
    if (g.partition) raw.cell_partition.push_back(int32(g.partition->integer(c), "partition"));
    ++kept;
  }
  if (kept == 0) raw.corners = 0;
  if (g.global_id) {
    if (g.global_id->is_real()) throw InputError(path, "global_id", "must be an integer array");
    raw.node_global_id.resize(g.global_id->size());
    for (std::size_t i = 0; i < g.global_id->size(); ++i) raw.node_global_id[i] = g.global_id->integer(i);
  }
  if (g.periodic_master) {
    if (g.periodic_master->is_real()) throw InputError(path, "periodic_master", "must be an integer array");
    raw.periodic_master.resize(g.periodic_master->size());
    for (std::size_t i = 0; i < g.periodic_master->size(); ++i) raw.periodic_master[i] = g.periodic_master->integer(i);
  }
  if (g.node_phase && raw.cohesive_corners != 0) {  // the copies' phases: only meaningful with cohesive cells
    if (g.node_phase->is_real()) throw InputError(path, "node_phase", "must be an integer array");
    raw.node_phase.resize(g.node_phase->size());
    for (std::size_t i = 0; i < g.node_phase->size(); ++i) raw.node_phase[i] = int32_value(g.node_phase->integer(i), "node_phase", path);
  }
  raw.phase_names = g.phase_names;
  if (raw.phase_names.empty())
    for (const auto& [name, tag, dimension] : g.tag_dimension_names)
      if (dimension == raw.corners - 1 && tag >= std::numeric_limits<int>::min() &&
          tag <= std::numeric_limits<int>::max())
        raw.phase_names[static_cast<int>(tag)] = name;
  return raw;
}

// ----------------------------------------------------------------------- VTU blocks

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// Decodes base64 text quad by quad, blanks ignored. A quad may end in padding, so runs
// encoded one after the other (VTK encodes the header and the data separately) decode to
// their bytes one after the other.
std::vector<unsigned char> base64_decode(std::string_view text, const std::string& path, const std::string& what) {
  std::vector<unsigned char> out;
  out.reserve(text.size() / 4 * 3);
  int quad[4];
  int have = 0, padding = 0;
  for (const char c : text) {
    if (is_blank(c)) continue;
    if (c == '=') {
      if (have < 2) throw InputError(path, what, "misplaced base64 padding");
      quad[have++] = 0;
      ++padding;
    } else {
      const int v = base64_value(c);
      if (v < 0 || padding > 0) throw InputError(path, what, "not base64 text");
      quad[have++] = v;
    }
    if (have == 4) {
      const std::uint32_t bits = (static_cast<std::uint32_t>(quad[0]) << 18) | (static_cast<std::uint32_t>(quad[1]) << 12) |
                                 (static_cast<std::uint32_t>(quad[2]) << 6) | static_cast<std::uint32_t>(quad[3]);
      out.push_back(static_cast<unsigned char>(bits >> 16));
      if (padding < 2) out.push_back(static_cast<unsigned char>(bits >> 8));
      if (padding < 1) out.push_back(static_cast<unsigned char>(bits));
      have = padding = 0;
    }
  }
  if (have != 0) throw InputError(path, what, "base64 text ends inside a group of 4 characters");
  return out;
}

// A VTU binary block: a header (UInt32 or UInt64 values) and its data, plain or zlib blocks.
struct BlockFormat {
  int header_bytes = 4;
  bool compressed = false;
};

// The data of the block starting at bytes[0], and the block's total length. Plain data stay
// in place; compressed data are inflated into `owned`.
std::pair<std::string_view, std::size_t> unpack_block(std::string_view bytes, const BlockFormat& format,
                                                      std::vector<unsigned char>& owned, const std::string& path,
                                                      const std::string& what) {
  const auto hb = static_cast<std::size_t>(format.header_bytes);
  std::size_t at = 0;
  auto header_value = [&]() -> std::uint64_t {
    if (bytes.size() - at < hb) throw InputError(path, what, "block header beyond the end of its data");
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + at);
    at += hb;
    return hb == 8 ? load<std::uint64_t>(p) : load<std::uint32_t>(p);
  };
  if (!format.compressed) {
    const std::uint64_t size = header_value();
    // Compared with what is left, not added: a size near 2^64 would wrap a sum around.
    if (size > bytes.size() - at)
      throw InputError(path, what, "its header claims " + std::to_string(size) + " bytes, more than the file holds");
    return {bytes.substr(at, static_cast<std::size_t>(size)), at + static_cast<std::size_t>(size)};
  }
  const std::uint64_t blocks = header_value();
  const std::uint64_t block_size = header_value();
  const std::uint64_t last_size = header_value();
  if (blocks > (bytes.size() - at) / hb)
    throw InputError(path, what, "compression header claims " + std::to_string(blocks) + " blocks, more than the file holds");
  std::vector<std::uint64_t> compressed(static_cast<std::size_t>(blocks));
  std::uint64_t compressed_total = 0;
  for (auto& size : compressed) {
    size = header_value();
    if (size > bytes.size()) throw InputError(path, what, "compressed block larger than the file");
    compressed_total += size;
  }
  if (compressed_total > bytes.size() - at)
    throw InputError(path, what, "compressed blocks run beyond the end of the file");
  // zlib inflates at most about 1032:1; anything beyond that is a lie, refused before allocating.
  auto inflated_size = [&](std::size_t k) { return k + 1 == compressed.size() && last_size != 0 ? last_size : block_size; };
  std::uint64_t total = 0;
  for (std::size_t k = 0; k < compressed.size(); ++k) {
    if (inflated_size(k) > 1100 * compressed[k] + 64)
      throw InputError(path, what, "compressed block " + std::to_string(k) + " claims to inflate to " +
                                       std::to_string(inflated_size(k)) + " bytes, more than zlib can");
    total += inflated_size(k);
  }
  owned.resize(static_cast<std::size_t>(total));
  std::size_t out = 0;
  for (std::size_t k = 0; k < compressed.size(); ++k) {
    uLongf length = static_cast<uLongf>(inflated_size(k));
    const int status = ::uncompress(owned.data() + out, &length,
                                    reinterpret_cast<const Bytef*>(bytes.data() + at), static_cast<uLong>(compressed[k]));
    if (status != Z_OK || length != inflated_size(k))
      throw InputError(path, what, "compressed block " + std::to_string(k) + " does not inflate to " +
                                       std::to_string(inflated_size(k)) + " bytes (zlib: " +
                                       (status == Z_OK ? "short" : std::to_string(status)) + ")");
    at += static_cast<std::size_t>(compressed[k]);
    out += static_cast<std::size_t>(length);
  }
  return {std::string_view(reinterpret_cast<const char*>(owned.data()), owned.size()), at};
}

// A size attribute (NumberOfPoints, offset): decimal digits only, at most `limit`.
std::size_t size_attribute(const pugi::xml_node& node, const char* key, std::size_t limit, const std::string& path) {
  const std::string text = node.attribute(key) ? node.attribute(key).value() : "0";
  std::size_t value = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  const std::string where = std::string("<") + node.name() + "> " + key;
  if (text.empty() || text[0] == '-' || r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw InputError(path, where, "\"" + text.substr(0, 40) + "\" is not a non-negative integer");
  if (value > limit)
    throw InputError(path, where, "\"" + text.substr(0, 40) + "\" is more than the file can hold");
  return value;
}

// Where the appended data of a VTU file lie: its bytes after '_', and their encoding.
struct Appended {
  std::string_view data;
  bool base64 = false;
  bool present = false;
  std::vector<std::size_t> offsets;  // of every appended array, sorted: a base64 array ends at the next
};

// Parses the blank-separated numbers of an ascii DataArray.
void parse_ascii(std::string_view text, const VtkType& type, DataValues& out, const std::string& path,
                 const std::string& what) {
  out.type = &type;
  out.ascii = true;
  std::size_t pos = 0;
  while (true) {
    while (pos < text.size() && is_blank(text[pos])) ++pos;
    if (pos >= text.size()) break;
    std::size_t end = pos;
    while (end < text.size() && !is_blank(text[end])) ++end;
    const char* begin = text.data() + pos + (text[pos] == '+' ? 1 : 0);
    const char* stop = text.data() + end;
    bool ok;
    if (type.is_real) {
      double v = 0;
      const auto r = std::from_chars(begin, stop, v);
      ok = r.ec == std::errc() && r.ptr == stop;
      out.reals.push_back(v);
    } else {
      std::int64_t v = 0;
      const auto r = std::from_chars(begin, stop, v);
      ok = r.ec == std::errc() && r.ptr == stop;
      out.ints.push_back(v);
    }
    if (!ok)
      throw InputError(path, what, "expected " + std::string(type.is_real ? "a number" : "an integer") + ", got '" +
                                       std::string(text.substr(pos, std::min<std::size_t>(end - pos, 40))) + "'");
    pos = end;
  }
}

// VTK writes string arrays in FieldData as <Array>.
bool is_array(const pugi::xml_node& node) {
  return std::string_view(node.name()) == "DataArray" || std::string_view(node.name()) == "Array";
}

class VtuReader {
 public:
  VtuReader(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  RawMesh read() {
    pugi::xml_document doc;
    std::string xml;
    const pugi::xml_node piece = open(doc, xml);
    const pugi::xml_node grid = piece.parent();
    GridArrays g;
    // Counts are checked against the arrays, never used to reserve: any size passes here.
    const std::size_t no_limit = std::numeric_limits<std::size_t>::max() / 64;
    g.number_of_points = size_attribute(piece, "NumberOfPoints", no_limit, path_);
    g.number_of_cells = size_attribute(piece, "NumberOfCells", no_limit, path_);
    if (const pugi::xml_node points = piece.child("Points").child("DataArray")) g.points = decode(points);
    for (const pugi::xml_node a : piece.child("Cells").children("DataArray")) {
      const std::string name = a.attribute("Name").value();
      if (name == "connectivity") g.connectivity = decode(a);
      else if (name == "offsets") g.offsets = decode(a);
      else if (name == "types") g.types = decode(a);
    }
    for (const pugi::xml_node a : piece.child("CellData").children("DataArray")) {
      const std::string name = a.attribute("Name").value();
      if (is_cell_array(name)) take_cell_array(g, name, decode(a));
    }
    for (const pugi::xml_node a : piece.child("PointData").children("DataArray")) {
      const std::string_view name = a.attribute("Name").value();
      if (name == "global_id") g.global_id = decode(a);
      else if (name == "periodic_master") g.periodic_master = decode(a);
      else if (name == "node_phase") g.node_phase = decode(a);
    }
    std::vector<std::pair<std::string, DataValues>> field;
    for (const pugi::xml_node holder : {grid.child("FieldData"), piece.child("FieldData")})
      for (const pugi::xml_node a : holder.children()) {
        if (!is_array(a)) continue;
        const VtkType* t = vtk_type(a.attribute("type").value());
        if (t && !t->is_real) field.emplace_back(a.attribute("Name").value(), decode(a));
      }
    take_field_arrays(g, field, path_);
    return assemble(g, path_);
  }

  // The points and global ids only (a mapped file's other arrays are not even touched).
  VtuPoints read_points() {
    pugi::xml_document doc;
    std::string xml;
    const pugi::xml_node piece = open(doc, xml);
    VtuPoints result;
    const std::size_t no_limit = std::numeric_limits<std::size_t>::max() / 64;
    const std::size_t points = size_attribute(piece, "NumberOfPoints", no_limit, path_);
    const pugi::xml_node array = piece.child("Points").child("DataArray");
    if (!array) throw InputError(path_, "Points", "no Points array");
    const DataValues values = decode(array);
    if (values.size() != 3 * points)
      throw InputError(path_, "Points", "has " + std::to_string(values.size()) + " values, NumberOfPoints " +
                                            std::to_string(points) + " needs 3 × as many");
    result.coords.resize(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) result.coords[i] = values.real(i);
    for (const pugi::xml_node a : piece.child("PointData").children("DataArray")) {
      const std::string_view name = a.attribute("Name").value();
      if (name == "periodic_master") result.has_periodic_master = true;
      if (name != "global_id") continue;
      const DataValues ids = decode(a);
      if (ids.is_real()) throw InputError(path_, "global_id", "must be an integer array");
      if (ids.size() != points)
        throw InputError(path_, "global_id", "has " + std::to_string(ids.size()) + " values for " +
                                                 std::to_string(points) + " points");
      result.has_global_id = true;
      result.global_id.resize(points);
      for (std::size_t i = 0; i < points; ++i) result.global_id[i] = ids.integer(i);
    }
    for (const pugi::xml_node a : piece.child("CellData").children("DataArray"))
      if (std::string_view(a.attribute("Name").value()) == "cohesive") result.has_cohesive = true;
    return result;
  }

 private:
  // Parses the XML before the appended block into `doc` (over `xml`) and returns the piece.
  pugi::xml_node open(pugi::xml_document& doc, std::string& xml) {
    // The appended block is not XML: the XML is what comes before it, closed.
    const std::size_t appended_tag = text_.find("<AppendedData");
    xml.assign(text_.substr(0, appended_tag));
    if (appended_tag != std::string_view::npos) {
      const std::size_t close = text_.find('>', appended_tag);
      if (close == std::string_view::npos) throw InputError(path_, "AppendedData", "unterminated tag");
      const std::string_view opening = text_.substr(appended_tag, close - appended_tag);
      appended_.base64 = opening.find("\"base64\"") != std::string_view::npos;
      if (!appended_.base64 && opening.find("\"raw\"") == std::string_view::npos)
        throw InputError(path_, "AppendedData", "encoding must be \"raw\" or \"base64\"");
      const std::size_t underscore = text_.find('_', close);
      if (underscore == std::string_view::npos) throw InputError(path_, "AppendedData", "no '_' before the data");
      appended_.present = true;
      appended_.data = text_.substr(underscore + 1);
      if (appended_.base64) appended_.data = appended_.data.substr(0, appended_.data.find('<'));
      xml += "</VTKFile>";
    }
    const pugi::xml_parse_result parsed = doc.load_buffer_inplace(xml.data(), xml.size(), pugi::parse_default);
    if (!parsed) {
      const auto offset = std::min(static_cast<std::size_t>(std::max<std::ptrdiff_t>(parsed.offset, 0)), xml.size());
      const auto line = 1 + std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(offset), '\n');
      throw InputError(path_, "line " + std::to_string(line), std::string("not well-formed XML: ") + parsed.description());
    }
    const pugi::xml_node root = doc.child("VTKFile");
    if (!root) throw InputError(path_, "", "not a VTK XML file (no <VTKFile>)");
    const std::string type = root.attribute("type").value();
    if (type != "UnstructuredGrid")
      throw InputError(path_, "VTKFile type", "'" + type.substr(0, 40) + "', expected UnstructuredGrid");
    if (std::string(root.attribute("byte_order").as_string("LittleEndian")) != "LittleEndian")
      throw InputError(path_, "VTKFile byte_order", "big-endian VTU files are not supported");
    const std::string header = root.attribute("header_type").as_string("UInt32");
    if (header != "UInt32" && header != "UInt64")
      throw InputError(path_, "VTKFile header_type", "unsupported '" + header.substr(0, 40) + "'");
    format_.header_bytes = header == "UInt64" ? 8 : 4;
    const std::string compressor = root.attribute("compressor").value();
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
      throw InputError(path_, "VTKFile compressor", "'" + compressor.substr(0, 40) +
                                                        "' is not supported (vtkZLibDataCompressor is)");
    format_.compressed = !compressor.empty();

    const pugi::xml_node grid = root.child("UnstructuredGrid");
    if (!grid) throw InputError(path_, "UnstructuredGrid", "missing");
    const pugi::xml_node piece = grid.child("Piece");
    if (!piece) throw InputError(path_, "Piece", "missing");
    if (piece.next_sibling("Piece"))
      throw InputError(path_, "Piece", "VTU files with several pieces are not supported");
    collect_appended_offsets(grid, piece);
    return piece;
  }

  // The offsets of the appended arrays of the sections read (not a walk of the whole tree:
  // a file may nest elements deeper than any stack).
  void collect_appended_offsets(const pugi::xml_node& grid, const pugi::xml_node& piece) {
    std::vector<pugi::xml_node> holders = {grid.child("FieldData")};
    for (const pugi::xml_node section : piece.children()) holders.push_back(section);
    for (const pugi::xml_node holder : holders)
      for (const pugi::xml_node a : holder.children())
        if (is_array(a) && std::string_view(a.attribute("format").value()) == "appended")
          appended_.offsets.push_back(size_attribute(a, "offset", appended_.data.size(), path_));
    std::sort(appended_.offsets.begin(), appended_.offsets.end());
  }

  DataValues decode(const pugi::xml_node& node) {
    const std::string name = node.attribute("Name").value();
    const std::string what = "DataArray " + name.substr(0, 40);
    const std::string type_name = node.attribute("type").value();
    const VtkType* type = vtk_type(type_name);
    if (!type) throw InputError(path_, what, "unsupported type '" + type_name.substr(0, 40) + "'");
    const std::string format = node.attribute("format").as_string("ascii");
    DataValues values;
    if (format == "ascii") {
      parse_ascii(node.child_value(), *type, values, path_, what);
      return values;
    }
    std::vector<unsigned char> decoded;
    std::string_view block;
    if (format == "binary") {
      decoded = base64_decode(node.child_value(), path_, what);
      block = std::string_view(reinterpret_cast<const char*>(decoded.data()), decoded.size());
    } else if (format == "appended") {
      if (!appended_.present) throw InputError(path_, what, "appended, but there is no AppendedData");
      const std::size_t offset = size_attribute(node, "offset", appended_.data.size(), path_);
      if (appended_.base64) {
        // A base64 array runs to the next array's offset.
        const auto next = std::upper_bound(appended_.offsets.begin(), appended_.offsets.end(), offset);
        const std::size_t end = next == appended_.offsets.end() ? appended_.data.size() : *next;
        decoded = base64_decode(appended_.data.substr(offset, end - offset), path_, what);
        block = std::string_view(reinterpret_cast<const char*>(decoded.data()), decoded.size());
      } else {
        block = appended_.data.substr(offset);
      }
    } else {
      throw InputError(path_, what, "unknown format '" + format.substr(0, 40) + "'");
    }
    std::vector<unsigned char> inflated;
    const std::string_view data = unpack_block(block, format_, inflated, path_, what).first;
    const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
    if (format_.compressed) {
      values.owned = std::move(inflated);
      bytes = values.owned.data();
    } else if (!decoded.empty()) {
      const auto at = static_cast<std::size_t>(bytes - decoded.data());
      values.owned = std::move(decoded);
      bytes = values.owned.data() + at;
    }
    set_binary(bytes, data.size(), *type, values);
    return values;
  }

  std::string_view text_;
  const std::string& path_;
  Appended appended_;
  BlockFormat format_;
};

// ----------------------------------------------------------------------- legacy .vtk

// The legacy format: keywords and counts as text, values as text (ASCII) or big-endian
// binary (BINARY), each binary run starting after the newline of its header line.
class LegacyReader {
 public:
  LegacyReader(std::string_view text, const std::string& path) : text_(text), path_(path), s_(text, path) {}

  RawMesh read() {
    const std::string_view first = s_.rest_of_line();
    if (first.substr(0, 22) != "# vtk DataFile Version")
      throw InputError(path_, "line 1", "not a legacy VTK file (it must start with '# vtk DataFile Version')");
    const std::string_view version = trim(first.substr(22));
    new_cells_ = !version.empty() && version[0] >= '5';
    s_.rest_of_line();  // title
    const std::string mode = upper(trim(s_.rest_of_line()));
    if (mode != "ASCII" && mode != "BINARY") s_.fail("expected ASCII or BINARY, got '" + mode.substr(0, 40) + "'");
    binary_ = mode == "BINARY";
    s_.expect("DATASET");
    const std::string dataset = upper(s_.token());
    if (dataset != "UNSTRUCTURED_GRID")
      s_.fail("dataset " + dataset.substr(0, 40) + " is not supported (UNSTRUCTURED_GRID is)");

    GridArrays g;
    std::vector<std::pair<std::string, DataValues>> dataset_field;
    Where where = Where::dataset;
    std::optional<DataValues> cell_list;  // legacy CELLS: count, then the ids, per cell
    bool has_cells = false;
    while (!s_.at_end()) {
      const std::string keyword = upper(s_.token());
      if (keyword == "POINTS") {
        g.number_of_points = count("POINTS", 3);
        g.points = values(3 * g.number_of_points, s_.token(), "POINTS");
      } else if (keyword == "CELLS") {
        has_cells = true;
        if (new_cells_) {
          const std::size_t offsets = count("CELLS", 1);
          const std::size_t connectivity = count("CELLS", 1);
          s_.expect("OFFSETS");
          DataValues o = values(offsets, s_.token(), "OFFSETS");
          s_.expect("CONNECTIVITY");
          g.connectivity = values(connectivity, s_.token(), "CONNECTIVITY");
          if (o.size() == 0 || o.is_real()) throw InputError(path_, "OFFSETS", "needs integer values, the first 0");
          // VTK's offsets start with 0 and have one more entry than cells: drop the 0.
          DataValues ends;
          ends.type = vtk_type("Int64");
          ends.ascii = true;
          for (std::size_t i = 1; i < o.size(); ++i) ends.ints.push_back(o.integer(i));
          if (o.integer(0) != 0) throw InputError(path_, "OFFSETS", "the first offset must be 0");
          g.offsets = std::move(ends);
        } else {
          const std::size_t cells = count("CELLS", 2);
          const std::size_t size = count("CELLS", 1);
          cell_list = values(size, "int", "CELLS");
          // Split "n id id id" runs into connectivity and offsets.
          DataValues connectivity, offsets;
          connectivity.type = offsets.type = vtk_type("Int64");
          connectivity.ascii = offsets.ascii = true;
          std::size_t at = 0;
          for (std::size_t c = 0; c < cells; ++c) {
            if (at >= cell_list->size()) throw InputError(path_, "CELLS", "fewer values than its cells need");
            const std::int64_t n = cell_list->integer(at++);
            if (n < 0 || static_cast<std::uint64_t>(n) > cell_list->size() - at)
              throw InputError(path_, "CELLS", "cell " + std::to_string(c) + " has a bad node count");
            for (std::int64_t k = 0; k < n; ++k) connectivity.ints.push_back(cell_list->integer(at++));
            offsets.ints.push_back(static_cast<std::int64_t>(connectivity.ints.size()));
          }
          if (at != cell_list->size()) throw InputError(path_, "CELLS", "more values than its cells need");
          g.connectivity = std::move(connectivity);
          g.offsets = std::move(offsets);
        }
      } else if (keyword == "CELL_TYPES") {
        g.number_of_cells = count("CELL_TYPES", 1);
        g.types = values(g.number_of_cells, "int", "CELL_TYPES");
      } else if (keyword == "CELL_DATA" || keyword == "POINT_DATA") {
        where = keyword == "CELL_DATA" ? Where::cells : Where::points;
        tuples_ = count(keyword.c_str(), 1);
      } else if (keyword == "SCALARS") {
        const std::string name(s_.token());
        const std::string type(s_.token());
        const std::size_t line_end = text_.find('\n', s_.position());
        long long components = 1;
        if (trim(text_.substr(s_.position(), line_end - s_.position())).size() > 0) components = s_.integer();
        if (components < 1 || components > 4) s_.fail("SCALARS " + name.substr(0, 40) + ": 1 to 4 components");
        s_.expect("LOOKUP_TABLE");
        s_.token();
        take(g, where, name, values(tuples_ * static_cast<std::size_t>(components), type, name));
      } else if (keyword == "FIELD") {
        s_.token();  // its name
        const long long arrays = static_cast<long long>(count("FIELD", 4));
        for (long long k = 0; k < arrays; ++k) {
          const std::string name(s_.token());
          if (upper(name) == "METADATA") {
            skip_metadata();
            --k;
            continue;
          }
          const std::size_t components = count(name.c_str(), 1);
          const std::size_t tuples = count(name.c_str(), 1);
          if (components != 0 && tuples > std::numeric_limits<std::size_t>::max() / components)
            s_.fail(name.substr(0, 40) + ": too many values");
          DataValues v = values(components * tuples, s_.token(), name);
          if (where == Where::dataset) dataset_field.emplace_back(name, std::move(v));
          else take(g, where, name, std::move(v));
        }
      } else if (keyword == "VECTORS" || keyword == "NORMALS" || keyword == "TENSORS" ||
                 keyword == "GLOBAL_IDS" || keyword == "PEDIGREE_IDS") {
        const std::string name(s_.token());
        const std::size_t per = keyword == "TENSORS" ? 9 : keyword == "VECTORS" || keyword == "NORMALS" ? 3 : 1;
        DataValues v = values(tuples_ * per, s_.token(), name);
        if (keyword == "GLOBAL_IDS") take(g, where, "global_id", std::move(v));
      } else if (keyword == "METADATA") {
        skip_metadata();
      } else if (keyword == "LOOKUP_TABLE") {
        s_.token();
        values(4 * count("LOOKUP_TABLE", 4), "float", "LOOKUP_TABLE");
      } else {
        s_.fail("unsupported keyword '" + keyword.substr(0, 40) + "'");
      }
    }
    if (!has_cells) throw InputError(path_, "CELLS", "missing");
    take_field_arrays(g, dataset_field, path_);
    return assemble(g, path_);
  }

 private:
  std::size_t count(const char* what, long long values_per_entry) {
    return binary_ ? checked_binary_count(what, values_per_entry) : s_.count(what, values_per_entry);
  }
  // In a binary file each value takes at least 1 byte.
  std::size_t checked_binary_count(const char* what, long long values_per_entry) {
    const long long n = s_.integer();
    const std::size_t left = text_.size() - s_.position();
    if (n < 0 || static_cast<unsigned long long>(n) > left / static_cast<std::size_t>(std::max(1LL, values_per_entry)))
      s_.fail(std::string(what) + " count " + std::to_string(n) + " is more than the rest of the file holds");
    return static_cast<std::size_t>(n);
  }

  // VTK 9 writes METADATA blocks (INFORMATION, COMPONENT_NAMES) ended by a blank line.
  void skip_metadata() {
    s_.rest_of_line();
    while (s_.position() < text_.size()) {
      if (trim(s_.rest_of_line()).empty()) return;
    }
  }

  enum class Where { dataset, cells, points };
  void take(GridArrays& g, Where where, const std::string& name, DataValues&& v) {
    if (where == Where::cells && is_cell_array(name)) take_cell_array(g, name, std::move(v));
    else if (where == Where::points && name == "global_id") g.global_id = std::move(v);
    else if (where == Where::points && name == "node_phase") g.node_phase = std::move(v);
  }

  DataValues values(std::size_t n, std::string_view type_name, const std::string& what) {
    static const std::map<std::string, std::string, std::less<>> kTypes = {
        {"bit", "UInt8"},          {"unsigned_char", "UInt8"},   {"char", "Int8"},
        {"unsigned_short", "UInt16"}, {"short", "Int16"},        {"unsigned_int", "UInt32"},
        {"int", "Int32"},          {"unsigned_long", "UInt64"},  {"long", "Int64"},
        {"float", "Float32"},      {"double", "Float64"},        {"vtkidtype", "Int64"},
        {"vtktypeint64", "Int64"}, {"vtktypeuint64", "UInt64"},  {"vtktypeint32", "Int32"},
        {"vtktypeuint32", "UInt32"}, {"string", "String"},       {"utf8_string", "String"}};
    std::string lower(type_name);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const auto it = kTypes.find(lower);
    if (it == kTypes.end() || lower == "bit")
      s_.fail(what.substr(0, 40) + ": unsupported type '" + std::string(type_name.substr(0, 40)) + "'");
    const VtkType& type = *vtk_type(it->second);
    DataValues out;
    if (type.name == std::string_view("String")) return strings(n, type, what);
    if (!binary_) {
      out.type = &type;
      out.ascii = true;
      if (n > (text_.size() - s_.position()) / 2) s_.fail(what.substr(0, 40) + ": more values than the file holds");
      for (std::size_t i = 0; i < n; ++i) {
        if (type.is_real) out.reals.push_back(s_.real());
        else out.ints.push_back(s_.integer());
      }
      return out;
    }
    s_.rest_of_line();
    BinaryCursor cursor(text_, s_.position(), path_, what, /*big_endian=*/true);
    const auto size = static_cast<std::size_t>(type.bytes);
    cursor.count(n, size);
    out.owned.resize(n * size);
    for (std::size_t i = 0; i < n; ++i) {
      unsigned char* p = out.owned.data() + i * size;
      switch (size) {
        case 1: { const auto v = cursor.read<std::uint8_t>(); std::memcpy(p, &v, 1); break; }
        case 2: { const auto v = cursor.read<std::uint16_t>(); std::memcpy(p, &v, 2); break; }
        case 4: { const auto v = cursor.read<std::uint32_t>(); std::memcpy(p, &v, 4); break; }
        default: { const auto v = cursor.read<std::uint64_t>(); std::memcpy(p, &v, 8); break; }
      }
    }
    s_.seek(cursor.position());
    set_binary(out.owned.data(), out.owned.size(), type, out);
    return out;
  }

  // String arrays, kept as the bytes of each string followed by 0 (as the XML format stores
  // them). ASCII: one string per line, %XX escapes. BINARY: each string led by its length in
  // 1, 2, 4 or 8 big-endian bytes, the top two bits of the first byte saying which (3, 2, 1, 0).
  DataValues strings(std::size_t n, const VtkType& type, const std::string& what) {
    DataValues out;
    out.type = &type;
    out.ascii = true;
    s_.rest_of_line();
    if (binary_) {
      BinaryCursor cursor(text_, s_.position(), path_, what, /*big_endian=*/true);
      cursor.count(n, 1);
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t first = cursor.read<std::uint8_t>();
        const int extra_bytes = first >> 6 == 3 ? 0 : first >> 6 == 2 ? 1 : first >> 6 == 1 ? 3 : 7;
        std::uint64_t length = first >> 6 == 0 ? first : first & 0x3F;
        for (int k = 0; k < extra_bytes; ++k) length = (length << 8) | cursor.read<std::uint8_t>();
        cursor.count(length, 1);
        for (std::uint64_t k = 0; k < length; ++k) out.ints.push_back(cursor.read<std::uint8_t>());
        out.ints.push_back(0);
      }
      s_.seek(cursor.position());
      return out;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (s_.position() >= text_.size()) throw InputError(path_, what, "fewer strings than it says");
      const std::string_view line = s_.rest_of_line();
      for (std::size_t k = 0; k < line.size(); ++k) {
        unsigned char c = static_cast<unsigned char>(line[k]);
        if (c == '\r' && k + 1 == line.size()) break;
        if (c == '%' && k + 2 < line.size()) {
          int value = 0;
          const auto r = std::from_chars(line.data() + k + 1, line.data() + k + 3, value, 16);
          if (r.ec == std::errc() && r.ptr == line.data() + k + 3) c = static_cast<unsigned char>(value), k += 2;
        }
        out.ints.push_back(c);
      }
      out.ints.push_back(0);
    }
    return out;
  }

  std::string_view text_;
  const std::string& path_;
  Scanner s_;
  bool binary_ = false;
  bool new_cells_ = false;  // version 5: OFFSETS and CONNECTIVITY
  std::size_t tuples_ = 0;  // of the current CELL_DATA or POINT_DATA
};

// ----------------------------------------------------------------------- pvtu

// Pieces are merged: nodes with the same global_id (when every piece has one), otherwise
// with exactly the same coordinates, become one node.
RawMesh merge_pieces(std::vector<RawMesh>& pieces, const std::vector<std::string>& piece_paths) {
  RawMesh merged;
  for (std::size_t k = 0; k < pieces.size(); ++k)  // what finish() checks of the merged mesh, per piece
    if (!pieces[k].node_global_id.empty() && pieces[k].node_global_id.size() != pieces[k].coords.size() / 3)
      throw InputError(piece_paths[k], "global_id", "has " + std::to_string(pieces[k].node_global_id.size()) +
                                                        " values for " + std::to_string(pieces[k].coords.size() / 3) +
                                                        " points");
  const bool by_global_id = std::all_of(pieces.begin(), pieces.end(), [](const RawMesh& p) { return !p.node_global_id.empty(); });
  std::unordered_map<GlobalId, LocalId> by_id;
  // Coordinates compared by their bits (0 and -0 as one): NaN must not break the ordering.
  std::map<std::array<std::uint64_t, 3>, LocalId> by_position;
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x == 0 ? 0.0 : x); };
  bool any_partition = false;
  for (const RawMesh& p : pieces) any_partition = any_partition || !p.cell_partition.empty();
  // periodic_master when every piece has it; a node's copies must agree.
  const bool masters = by_global_id && !pieces.empty() &&
                       std::all_of(pieces.begin(), pieces.end(), [](const RawMesh& p) { return !p.periodic_master.empty(); });
  for (std::size_t k = 0; k < pieces.size() && masters; ++k)
    if (pieces[k].periodic_master.size() != pieces[k].coords.size() / 3)
      throw InputError(piece_paths[k], "periodic_master", "has " + std::to_string(pieces[k].periodic_master.size()) +
                                                              " values for " + std::to_string(pieces[k].coords.size() / 3) +
                                                              " points");
  // node_phase when every piece has it (a piece's cohesive cells are its own, its copies too).
  const bool any_cohesive = std::any_of(pieces.begin(), pieces.end(), [](const RawMesh& p) { return p.cohesive_corners != 0; });
  const bool node_phases = any_cohesive &&
                           std::all_of(pieces.begin(), pieces.end(), [](const RawMesh& p) { return !p.node_phase.empty(); });
  for (std::size_t k = 0; k < pieces.size() && node_phases; ++k)
    if (pieces[k].node_phase.size() != pieces[k].coords.size() / 3)
      throw InputError(piece_paths[k], "node_phase", "has " + std::to_string(pieces[k].node_phase.size()) + " values for " +
                                                         std::to_string(pieces[k].coords.size() / 3) + " points");
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    RawMesh& p = pieces[k];
    if (p.corners == 0) continue;
    if (merged.corners != 0 && p.corners != merged.corners)
      throw InputError(piece_paths[k], "", "its cells are not of the same kind as the other pieces'");
    if (p.cohesive_corners != 0 && merged.cohesive_corners != 0 && p.cohesive_corners != merged.cohesive_corners)
      throw InputError(piece_paths[k], "cohesive", "its cohesive cells are not of the same kind as the other pieces'");
    merged.corners = p.corners;
    const std::size_t nodes = p.coords.size() / 3;
    std::vector<LocalId> local(nodes);
    for (std::size_t n = 0; n < nodes; ++n) {
      const auto next = static_cast<LocalId>(merged.coords.size() / 3);
      LocalId id;
      if (by_global_id) {
        id = by_id.emplace(p.node_global_id[n], next).first->second;
      } else {
        id = by_position
                 .emplace(std::array<std::uint64_t, 3>{bits(p.coords[3 * n]), bits(p.coords[3 * n + 1]),
                                                       bits(p.coords[3 * n + 2])},
                          next)
                 .first->second;
      }
      if (id == next) {
        merged.coords.insert(merged.coords.end(), p.coords.begin() + static_cast<std::ptrdiff_t>(3 * n),
                             p.coords.begin() + static_cast<std::ptrdiff_t>(3 * n + 3));
        if (by_global_id) merged.node_global_id.push_back(p.node_global_id[n]);
        if (masters) merged.periodic_master.push_back(p.periodic_master[n]);
        if (node_phases) merged.node_phase.push_back(p.node_phase[n]);
      } else if (masters && merged.periodic_master[static_cast<std::size_t>(id)] != p.periodic_master[n]) {
        throw InputError(piece_paths[k], "periodic_master",
                         "node with global id " + std::to_string(p.node_global_id[n]) + " has master " +
                             std::to_string(p.periodic_master[n]) + " here and " +
                             std::to_string(merged.periodic_master[static_cast<std::size_t>(id)]) + " in an earlier piece");
      } else if (node_phases && merged.node_phase[static_cast<std::size_t>(id)] != p.node_phase[n]) {
        throw InputError(piece_paths[k], "node_phase",
                         "node with global id " + std::to_string(p.node_global_id[n]) + " has phase " +
                             std::to_string(p.node_phase[n]) + " here and " +
                             std::to_string(merged.node_phase[static_cast<std::size_t>(id)]) + " in an earlier piece");
      }
      local[n] = id;
    }
    if (p.cohesive_corners != 0) {
      merged.cohesive_corners = p.cohesive_corners;
      for (const LocalId node : p.cohesive_nodes) merged.cohesive_nodes.push_back(local[static_cast<std::size_t>(node)]);
      merged.cohesive_phase.insert(merged.cohesive_phase.end(), p.cohesive_phase.begin(), p.cohesive_phase.end());
      if (any_partition && p.cohesive_partition.empty())
        p.cohesive_partition.assign(p.cohesive_phase.size() / 2, static_cast<std::int32_t>(k));
      merged.cohesive_partition.insert(merged.cohesive_partition.end(), p.cohesive_partition.begin(), p.cohesive_partition.end());
    }
    for (const LocalId node : p.cell_nodes) merged.cell_nodes.push_back(local[static_cast<std::size_t>(node)]);
    const std::size_t cells = p.cell_nodes.size() / static_cast<std::size_t>(p.corners);
    if (p.cell_phase.empty()) p.cell_phase.assign(cells, 1);
    merged.cell_phase.insert(merged.cell_phase.end(), p.cell_phase.begin(), p.cell_phase.end());
    if (any_partition) {
      if (p.cell_partition.empty()) p.cell_partition.assign(cells, static_cast<std::int32_t>(k));
      merged.cell_partition.insert(merged.cell_partition.end(), p.cell_partition.begin(), p.cell_partition.end());
    }
    merged.phase_names.insert(p.phase_names.begin(), p.phase_names.end());
  }
  return merged;
}

}  // namespace

RawMesh read_vtu_raw(const std::string& path) {
  const MappedFile file(path);
  return VtuReader(file.view(), path).read();
}

LoadedMesh read_vtu(const std::string& path) { return finish(read_vtu_raw(path), path); }

LoadedMesh read_legacy_vtk(const std::string& path) {
  const MappedFile file(path);
  return finish(LegacyReader(file.view(), path).read(), path);
}

}  // namespace cisamr::io::detail

namespace cisamr::io {

std::vector<std::string> pvtu_piece_paths(const std::string& path) {
  const detail::MappedFile file(path);
  const std::string_view text = file.view();
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(text.data(), text.size(), pugi::parse_default);
  if (!parsed) throw InputError(path, "", std::string("not well-formed XML: ") + parsed.description());
  const pugi::xml_node grid = doc.child("VTKFile").child("PUnstructuredGrid");
  if (!grid) throw InputError(path, "", "not a parallel VTU file (no <VTKFile><PUnstructuredGrid>)");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  std::vector<std::string> piece_paths;
  for (const pugi::xml_node piece : grid.children("Piece")) {
    const std::string source = piece.attribute("Source").value();
    if (source.empty()) throw InputError(path, "Piece " + std::to_string(piece_paths.size()), "no Source");
    const std::filesystem::path piece_path = std::filesystem::path(source).is_absolute() ? std::filesystem::path(source) : folder / source;
    if (piece_path.extension() != ".vtu")
      throw InputError(path, "Piece " + std::to_string(piece_paths.size()), "Source '" + source.substr(0, 80) + "' is not a .vtu file");
    piece_paths.push_back(piece_path.string());
  }
  if (piece_paths.empty()) throw InputError(path, "Piece", "no pieces");
  return piece_paths;
}

VtuPoints read_vtu_points(const std::string& path) {
  const detail::MappedFile file(path);
  return detail::VtuReader(file.view(), path).read_points();
}

namespace detail {

LoadedMesh read_pvtu(const std::string& path) {
  const std::vector<std::string> piece_paths = pvtu_piece_paths(path);
  std::vector<RawMesh> pieces;
  for (const std::string& piece_path : piece_paths) pieces.push_back(read_vtu_raw(piece_path));
  for (std::size_t k = 0; k < pieces.size(); ++k)
    if (pieces[k].node_global_id.empty() &&
        std::any_of(pieces.begin(), pieces.end(), [](const RawMesh& p) { return p.cohesive_corners != 0; }))
      throw InputError(path, "global_id",
                       "piece " + piece_paths[k] + " has none, but the pieces hold cohesive cells: merging them by "
                       "coordinates would weld the copies");
  return finish(merge_pieces(pieces, piece_paths), path);
}

}  // namespace detail
}  // namespace cisamr::io
