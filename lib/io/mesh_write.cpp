// Mesh writers: VTU (raw appended binary), Gmsh MSH 4.1, Abaqus INP, Medit MESH.
// Binary arrays are written straight from the mesh's vectors (or in fixed-size chunks when
// they must be converted); ASCII goes through TextWriter, which formats with std::to_chars
// into one large buffer. No iostreams.
#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string_view>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "io/inp_stream.hpp"
#include "io/msh_stream.hpp"
#include "mesh/boundary.hpp"
#include "mesh/cohesive.hpp"
#include "mesh/metrics.hpp"
#include "mesh/periodic_links.hpp"

namespace cisamr::io {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the VTU writer stores arrays in host order and declares LittleEndian");

// ASCII output: numbers are formatted into a large buffer that goes to the file in one write.
class TextWriter {
 public:
  explicit TextWriter(AtomicFile& file) : file_(file), buffer_(kCapacity) {}
  ~TextWriter() = default;

  TextWriter& operator<<(std::string_view text) {
    if (text.size() > kSlack) {
      flush();
      file_.write(text);
      return *this;
    }
    make_room();
    std::memcpy(buffer_.data() + used_, text.data(), text.size());
    used_ += text.size();
    return *this;
  }
  TextWriter& operator<<(char c) {
    make_room();
    buffer_[used_++] = c;
    return *this;
  }
  TextWriter& integer(long long value) {
    make_room();
    used_ = static_cast<std::size_t>(
        std::to_chars(buffer_.data() + used_, buffer_.data() + buffer_.size(), value).ptr -
        buffer_.data());
    return *this;
  }
  // Shortest text that reads back to the same double.
  TextWriter& real(double value) {
    make_room();
    used_ = static_cast<std::size_t>(
        std::to_chars(buffer_.data() + used_, buffer_.data() + buffer_.size(), value).ptr -
        buffer_.data());
    return *this;
  }
  // The shortest round-trip text when it has at most `width` characters, else scientific
  // notation with as many digits as fit (Abaqus and CalculiX read numbers of at most 20
  // characters; only magnitudes below about 1e-4 or above 1e16 need the second form).
  TextWriter& real_within(double value, int width) {
    make_room();
    char* at = buffer_.data() + used_;
    char* end = std::to_chars(at, buffer_.data() + buffer_.size(), value).ptr;
    for (int digits = 16; end - at > width && digits >= 0; --digits)
      end = std::to_chars(at, buffer_.data() + buffer_.size(), value, std::chars_format::scientific, digits).ptr;
    used_ = static_cast<std::size_t>(end - buffer_.data());
    return *this;
  }
  void flush() {
    file_.write(buffer_.data(), used_);
    used_ = 0;
  }

 private:
  static constexpr std::size_t kCapacity = std::size_t{1} << 22;
  static constexpr std::size_t kSlack = 256;  // room guaranteed for one item
  void make_room() {
    if (used_ + kSlack > buffer_.size()) flush();
  }
  AtomicFile& file_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
};

template <int Dim>
void check_mesh(const mesh::SimplexMesh<Dim>& m) {
  const std::size_t cells = m.cell_count();
  if (m.coords.size() % Dim != 0 || m.cell_nodes.size() != cells * (Dim + 1) ||
      (!m.cell_partition.empty() && m.cell_partition.size() != cells) ||
      (!m.node_global_id.empty() && m.node_global_id.size() != m.node_count()) ||
      m.cohesive.nodes.size() != m.cohesive.count() * 2 * Dim || m.cohesive.phase.size() != 2 * m.cohesive.count() ||
      (m.cohesive.count() > 0 && m.node_phase.size() != m.node_count()))
    throw std::invalid_argument("write_mesh: inconsistent array sizes in the mesh");
  if (m.node_count() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw std::invalid_argument("write_mesh: too many nodes for LocalId");
}

std::string phase_name(const std::vector<geometry::Phase>& phases, int id) {
  for (const auto& p : phases)
    if (p.id == id) return p.name;
  return "phase" + std::to_string(id);
}

// The distinct values of cell_phase, ascending, by a scan (a mesh has a handful of phases):
// a sorted copy of every cell's phase cost 4 bytes per cell at the writers' peak and a sort
// of the whole mesh (1.3 % of a 3D run's instructions).
std::vector<int> distinct_phase_ids(const std::vector<std::int32_t>& cell_phase) {
  std::vector<int> ids;
  for (std::size_t c = 0; c < cell_phase.size(); ++c) {
    const int id = cell_phase[c];
    if ((c > 0 && id == cell_phase[c - 1]) || std::find(ids.begin(), ids.end(), id) != ids.end()) continue;
    ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

// Cells grouped by phase (ascending id), original order kept inside a group.
struct PhaseGroups {
  std::vector<int> ids;                 // distinct phase ids, ascending
  std::vector<std::size_t> begin;       // group g = order[begin[g] .. begin[g+1])
  std::vector<std::size_t> order;       // cell indices
};

PhaseGroups group_by_phase(const std::vector<std::int32_t>& cell_phase) {
  PhaseGroups groups;
  groups.ids = distinct_phase_ids(cell_phase);
  std::vector<std::size_t> group_of(cell_phase.size());
  groups.begin.assign(groups.ids.size() + 1, 0);
  for (std::size_t c = 0; c < cell_phase.size(); ++c) {
    const auto g = static_cast<std::size_t>(
        std::lower_bound(groups.ids.begin(), groups.ids.end(), cell_phase[c]) - groups.ids.begin());
    group_of[c] = g;
    ++groups.begin[g + 1];
  }
  for (std::size_t g = 0; g < groups.ids.size(); ++g) groups.begin[g + 1] += groups.begin[g];
  groups.order.resize(cell_phase.size());
  std::vector<std::size_t> next(groups.begin.begin(), groups.begin.end() - 1);
  for (std::size_t c = 0; c < cell_phase.size(); ++c) groups.order[next[group_of[c]]++] = c;
  return groups;
}

// Every phase named in `phases` and every id a cell uses, ascending, with its name.
std::vector<geometry::Phase> phases_in_id_order(const std::vector<geometry::Phase>& phases,
                                                const std::vector<std::int32_t>& cell_phase) {
  std::vector<int> ids = distinct_phase_ids(cell_phase);
  for (const auto& p : phases) ids.push_back(p.id);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<geometry::Phase> out;
  for (int id : ids) out.push_back({id, phase_name(phases, id), false});
  return out;
}

// The boundary sets the writers emit, against options.face_box or the bounding box.
template <int Dim>
mesh::BoundarySets<Dim> boundary_sets_for(const mesh::SimplexMesh<Dim>& m, const MeshWriteOptions& options) {
  Box<Dim> box = mesh::bounding_box(m);
  if (options.face_box)
    for (int d = 0; d < Dim; ++d) box.min[d] = options.face_box->min[d], box.max[d] = options.face_box->max[d];
  return mesh::boundary_sets(m, box);
}

// The periodic links the writers emit (options.periodic against the face box), or none.
template <int Dim>
struct PeriodicOutput {
  bool any = false;
  Box<Dim> faces{};
  std::array<bool, Dim> axes{};
  std::array<double, Dim> period{};  // T_a
  mesh::PeriodicLinks<Dim> links;
};

template <int Dim>
PeriodicOutput<Dim> periodic_output(const mesh::SimplexMesh<Dim>& m, const MeshWriteOptions& options) {
  PeriodicOutput<Dim> out;
  for (int a = 0; a < Dim; ++a) out.axes[static_cast<std::size_t>(a)] = options.periodic[static_cast<std::size_t>(a)];
  for (bool a : out.axes) out.any = out.any || a;
  if (!out.any) return out;
  out.faces = mesh::bounding_box(m);
  if (options.face_box)
    for (int d = 0; d < Dim; ++d) out.faces.min[d] = options.face_box->min[d], out.faces.max[d] = options.face_box->max[d];
  for (int a = 0; a < Dim; ++a) {
    const double t = options.period[static_cast<std::size_t>(a)];
    out.period[static_cast<std::size_t>(a)] = t != 0 ? t : out.faces.max[a] - out.faces.min[a];
  }
  out.links = mesh::periodic_links<Dim>(m, out.faces, out.axes, options.periodic_voids);
  return out;
}

// The nodes of a cell facet, in their outward order (mesh::FacetVertices).
template <int Dim>
std::array<LocalId, Dim> facet_nodes(const mesh::SimplexMesh<Dim>& m, const mesh::CellFacet& f) {
  std::array<LocalId, Dim> nodes;
  const LocalId* corners = m.cell(static_cast<std::size_t>(f.cell));
  for (int k = 0; k < Dim; ++k) nodes[k] = corners[mesh::FacetVertices<Dim>::local[f.opposite][k]];
  return nodes;
}

// ------------------------------------------------------------------------------ VTU

// One appended array: an 8-byte size header then the bytes, produced in chunks.
template <class T, class Fill>
void write_array_chunked(AtomicFile& file, std::size_t count, Fill fill) {
  const std::uint64_t bytes = count * sizeof(T);
  file.write(&bytes, sizeof bytes);
  constexpr std::size_t kChunk = 1 << 16;
  std::vector<T> chunk(std::min(count, kChunk));
  for (std::size_t first = 0; first < count; first += kChunk) {
    const std::size_t n = std::min(kChunk, count - first);
    for (std::size_t i = 0; i < n; ++i) chunk[i] = fill(first + i);
    file.write(chunk.data(), n * sizeof(T));
  }
}
template <class T>
void write_array_raw(AtomicFile& file, std::span<const T> values) {
  const std::uint64_t bytes = values.size() * sizeof(T);
  file.write(&bytes, sizeof bytes);
  file.write(values.data(), bytes);
}
template <class T>
void write_array_raw(AtomicFile& file, const std::vector<T>& values) {
  write_array_raw(file, std::span<const T>(values));
}

// The VTK ASCII encoding of a string array: each string's bytes as decimal integers, then 0.
// The phase names as one byte array, each name followed by a 0 byte. A UInt8 array rather
// than VTK's String type because meshio (5.x, 7.x) refuses every file holding a String array.
std::string phase_name_bytes(const std::vector<geometry::Phase>& phases, std::size_t& count) {
  std::string text;
  count = 0;
  for (const auto& p : phases) {
    for (unsigned char c : p.name) text += std::to_string(static_cast<unsigned>(c)) + ' ';
    text += "0 ";
    count += p.name.size() + 1;
  }
  if (!text.empty()) text.pop_back();
  return text;
}

// A .vtu but for its last block, the global ids, and the closing tags (write_vtu_ids).
template <int Dim>
void write_vtu_without_ids(AtomicFile& file, const mesh::SimplexMesh<Dim>& m,
                           const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  constexpr int kCorners = Dim + 1;
  constexpr int kCohesiveCorners = 2 * Dim;
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  // Cohesive cells follow the bulk cells (VTK quads / wedges, cell data cohesive = 1).
  const std::size_t cohesive = m.cohesive.count(), all_cells = cells + cohesive;
  // Every piece of a cohesive run declares the arrays, also one without cohesive cells.
  const bool cohesive_arrays = cohesive > 0 || !m.node_phase.empty();
  const std::size_t connectivity = cells * kCorners + cohesive * kCohesiveCorners;
  if (!options.cell_aspect_ratio.empty() && options.cell_aspect_ratio.size() != cells)
    throw std::invalid_argument("write_mesh: cell_aspect_ratio has the wrong size");
  const bool wide_offsets = connectivity > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  const std::size_t offset_size = wide_offsets ? 8 : 4;

  struct Array {
    const char* where;  // PointData, CellData, Points, Cells
    const char* type;
    const char* name;
    int components;
    std::size_t bytes;
  };
  // periodic_master (Int64): the full master's global id, or -1, only for periodic meshes.
  std::vector<GlobalId> periodic_master;
  if (options.any_periodic()) {
    if (!options.periodic_master.empty()) {
      if (options.periodic_master.size() != nodes)
        throw std::invalid_argument("write_mesh: periodic_master has the wrong size");
      periodic_master = options.periodic_master;
    } else {
      periodic_master.assign(nodes, -1);
      const auto gid = [&](LocalId n) {
        return m.node_global_id.empty() ? GlobalId(n) : m.node_global_id[static_cast<std::size_t>(n)];
      };
      for (const mesh::PeriodicSlave<Dim>& s : periodic_output(m, options).links.slaves)
        periodic_master[static_cast<std::size_t>(s.node)] = gid(s.master);
    }
  }
  const bool periodic = options.any_periodic();
  std::vector<Array> arrays = {
      {"PointData", "Int64", "global_id", 1, nodes * 8},
      {"PointData", "UInt8", "boundary", 1, nodes},
      {"CellData", "Int32", "phase", 1, all_cells * 4},
      {"CellData", "Int32", "partition", 1, all_cells * 4},
      {"CellData", "Float64", "aspect_ratio", 1, all_cells * 8},
      {"Points", "Float64", "Points", 3, nodes * 3 * 8},
      {"Cells", "Int32", "connectivity", 1, connectivity * 4},
      {"Cells", wide_offsets ? "Int64" : "Int32", "offsets", 1, all_cells * offset_size},
      {"Cells", "UInt8", "types", 1, all_cells},
  };
  if (periodic) arrays.insert(arrays.begin() + 2, {"PointData", "Int64", "periodic_master", 1, nodes * 8});
  // Cohesive meshes: each node's phase (the copy it is), and per cell whether it is cohesive
  // and its top phase (a bulk cell's own phase), after phase / partition / aspect_ratio.
  if (cohesive_arrays) {
    const auto cell_data = std::find_if(arrays.begin(), arrays.end(), [](const Array& a) { return a.name == std::string_view("aspect_ratio"); });
    arrays.insert(cell_data + 1, {{"CellData", "UInt8", "cohesive", 1, all_cells}, {"CellData", "Int32", "phase_top", 1, all_cells * 4}});
    const auto point_data = std::find_if(arrays.begin(), arrays.end(), [](const Array& a) { return a.name == std::string_view("boundary"); });
    arrays.insert(point_data + 1, {"PointData", "Int32", "node_phase", 1, nodes * 4});
  }

  std::string xml;
  xml += "<?xml version=\"1.0\"?>\n";
  xml += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n";
  xml += "  <UnstructuredGrid>\n";
  // Phase names (bytes, each name ended by 0) and their ids, in id order.
  const std::vector<geometry::Phase> named = phases_in_id_order(phases, m.cell_phase);
  std::size_t name_bytes = 0;
  const std::string name_values = phase_name_bytes(named, name_bytes);
  const std::string tuples = " NumberOfTuples=\"" + std::to_string(named.size()) + "\" format=\"ascii\">\n";
  xml += "    <FieldData>\n";
  xml += "      <DataArray type=\"UInt8\" Name=\"phase_names\" NumberOfTuples=\"" + std::to_string(name_bytes) +
         "\" format=\"ascii\">\n";
  xml += "        " + name_values + "\n      </DataArray>\n";
  xml += "      <DataArray type=\"Int32\" Name=\"phase_ids\"" + tuples + "        ";
  for (std::size_t i = 0; i < named.size(); ++i) {
    if (i > 0) xml += ' ';
    xml += std::to_string(named[i].id);
  }
  xml += "\n      </DataArray>\n    </FieldData>\n";
  xml += "    <Piece NumberOfPoints=\"" + std::to_string(nodes) + "\" NumberOfCells=\"" +
         std::to_string(all_cells) + "\">\n";
  // The appended blocks are laid out in the reverse of the declaration order. VTK does not
  // care; meshio (5.x) rewrites offsets one by one while looking tags up by offset, and
  // mixes up two arrays when a rewritten offset equals a later raw one: with the reverse
  // layout the tag it must find always comes first in the document.
  const std::size_t kArrays = arrays.size();
  std::vector<std::uint64_t> offsets_of(kArrays);
  std::uint64_t offset = 0;
  for (std::size_t k = kArrays; k-- > 0;) {
    offsets_of[k] = offset;
    offset += 8 + arrays[k].bytes;
  }
  std::string_view open_section;
  for (std::size_t k = 0; k < kArrays; ++k) {
    const Array& a = arrays[k];
    if (open_section != a.where) {
      if (!open_section.empty()) xml += "      </" + std::string(open_section) + ">\n";
      open_section = a.where;
      xml += "      <" + std::string(open_section) +
             (open_section == "CellData" ? " Scalars=\"phase\"" : "") + ">\n";
    }
    xml += "        <DataArray type=\"" + std::string(a.type) + "\" Name=\"" + a.name + "\"";
    if (a.components != 1)
      xml += " NumberOfComponents=\"" + std::to_string(a.components) + "\"";
    xml += " format=\"appended\" offset=\"" + std::to_string(offsets_of[k]) + "\"/>\n";
  }
  xml += "      </" + std::string(open_section) + ">\n";
  xml += "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
  file.write(xml);

  // Blocks in reverse declaration order (see above).
  using Order = mesh::CohesiveOrder<Dim>;
  const std::uint8_t cell_type = Dim == 2 ? 5 : 10;  // VTK_TRIANGLE, VTK_TETRA
  write_array_chunked<std::uint8_t>(file, all_cells, [&](std::size_t c) {
    return c < cells ? cell_type : static_cast<std::uint8_t>(Order::vtk_type);
  });
  const auto end_of = [&](std::size_t c) {
    return c < cells ? (c + 1) * kCorners : cells * kCorners + (c + 1 - cells) * kCohesiveCorners;
  };
  if (wide_offsets)
    write_array_chunked<std::int64_t>(file, all_cells, [&](std::size_t c) { return std::int64_t(end_of(c)); });
  else
    write_array_chunked<std::int32_t>(file, all_cells, [&](std::size_t c) { return std::int32_t(end_of(c)); });
  if (cohesive == 0) {
    write_array_raw(file, m.cell_nodes);
  } else {
    write_array_chunked<std::int32_t>(file, connectivity, [&](std::size_t i) {
      if (i < cells * kCorners) return m.cell_nodes[i];
      const std::size_t j = i - cells * kCorners, c = j / kCohesiveCorners, k = j % kCohesiveCorners;
      return m.cohesive.nodes[c * kCohesiveCorners + static_cast<std::size_t>(Order::vtk[k])];
    });
  }
  if constexpr (Dim == 3) {
    write_array_raw(file, m.coords);
  } else {
    write_array_chunked<double>(file, nodes * 3, [&](std::size_t i) {
      const std::size_t node = i / 3, axis = i % 3;
      return axis < 2 ? m.coords[node * 2 + axis] : 0.0;
    });
  }
  if (cohesive_arrays) {  // phase_top, cohesive (reverse order)
    write_array_chunked<std::int32_t>(file, all_cells, [&](std::size_t c) {
      return c < cells ? m.cell_phase[c] : m.cohesive.phase[2 * (c - cells) + 1];
    });
    write_array_chunked<std::uint8_t>(file, all_cells, [&](std::size_t c) { return std::uint8_t(c >= cells); });
  }
  // A cohesive cell has no aspect ratio: 0.
  if (options.cell_aspect_ratio.empty())
    write_array_chunked<double>(file, all_cells,
                                [&](std::size_t c) { return c < cells ? mesh::cell_aspect_ratio(m, c) : 0.0; });
  else if (cohesive == 0)
    write_array_raw(file, options.cell_aspect_ratio);
  else
    write_array_chunked<double>(file, all_cells,
                                [&](std::size_t c) { return c < cells ? options.cell_aspect_ratio[c] : 0.0; });
  write_array_chunked<std::int32_t>(file, all_cells, [&](std::size_t c) {
    if (c >= cells) return m.cohesive.partition[c - cells];
    return m.cell_partition.empty() ? 0 : m.cell_partition[c];
  });
  write_array_chunked<std::int32_t>(file, all_cells, [&](std::size_t c) {
    return c < cells ? m.cell_phase[c] : m.cohesive.phase[2 * (c - cells)];
  });
  if (periodic) write_array_raw(file, periodic_master);
  if (cohesive_arrays) write_array_raw(file, m.node_phase);
  write_array_raw(file, boundary_sets_for(m, options).node_faces);
}

constexpr std::string_view kVtuEnd = "\n  </AppendedData>\n</VTKFile>\n";

// The global_id block (the last one, see above) and the closing tags.
void write_vtu_ids(AtomicFile& file, std::span<const GlobalId> ids) {
  write_array_raw(file, ids);
  file.write(kVtuEnd);
}

template <int Dim>
void write_vtu_file(AtomicFile& file, const mesh::SimplexMesh<Dim>& m,
                    const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  write_vtu_without_ids(file, m, phases, options);
  if (!m.node_global_id.empty()) {
    write_vtu_ids(file, m.node_global_id);
    return;
  }
  write_array_chunked<std::int64_t>(file, m.node_count(), [](std::size_t i) { return std::int64_t(i); });
  file.write(kVtuEnd);
}

std::string abaqus_label(const std::string& name);

// Cohesive cells grouped by phase pair (ascending), each group's set name
// COH_<lower phase name>_<other> (Abaqus label rules, also the Gmsh physical name).
struct CohesiveGroups {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  std::vector<std::string> names;
  std::vector<std::size_t> order, begin;  // cells of group g: order[begin[g] .. begin[g+1])
};
template <int Dim>
CohesiveGroups group_cohesive(const mesh::SimplexMesh<Dim>& m, const std::vector<geometry::Phase>& phases) {
  CohesiveGroups groups;
  const std::size_t count = m.cohesive.count();
  const auto pair_of = [&](std::size_t c) { return std::pair(m.cohesive.phase[2 * c], m.cohesive.phase[2 * c + 1]); };
  groups.order.resize(count);
  std::iota(groups.order.begin(), groups.order.end(), std::size_t{0});
  std::stable_sort(groups.order.begin(), groups.order.end(), [&](std::size_t a, std::size_t b) { return pair_of(a) < pair_of(b); });
  for (std::size_t i = 0; i < count; ++i) {
    const auto pair = pair_of(groups.order[i]);
    if (!groups.pairs.empty() && groups.pairs.back() == pair) continue;
    groups.pairs.push_back(pair);
    groups.begin.push_back(i);
    groups.names.push_back(cohesive_set_name(phases, pair.first, pair.second));
  }
  groups.begin.push_back(count);
  return groups;
}

// ------------------------------------------------------------------------------ MSH 4.1

// What the head of a .msh names: the phases' cell groups (ascending id), the box faces that
// carry facets, the cohesive pairs' groups (with their set names).
struct MshHeadGroups {
  std::vector<MshGroup> phases, faces, cohesive;
  std::vector<std::string> cohesive_names;
  bool placeholder_entity = false;  // nodes but no cells: entity 1 holds them
};

// $MeshFormat, $PhysicalNames, $Entities. Box faces: entity tag face + 1 (dimension Dim-1),
// physical tag past every phase id, so that no reader that ignores the dimension of a
// physical name confuses a face with a phase. Cohesive cells: one Dim-dimensional entity
// and physical group per phase pair, tagged past the faces' physical tags. One surface (2D)
// or volume (3D) entity per phase, tagged with the phase id.
template <int Dim>
void write_msh_head_sections(TextWriter& out, const MshHeadGroups& g, const std::vector<geometry::Phase>& phases) {
  constexpr int kFaces = mesh::box_face_count(Dim);
  const int face_physical_base = (g.phases.empty() ? 0 : g.phases.back().id) + 1;
  const int cohesive_base = face_physical_base + kFaces;
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  out << "$PhysicalNames\n";
  out.integer(static_cast<long long>(g.phases.size() + g.faces.size() + g.cohesive.size())) << '\n';
  for (const MshGroup& phase : g.phases) {
    std::string name = phase_name(phases, phase.id);
    std::replace(name.begin(), name.end(), '"', '\'');
    out.integer(Dim) << ' ';
    out.integer(phase.id) << " \"" << name << "\"\n";
  }
  for (const MshGroup& face : g.faces) {
    out.integer(Dim - 1) << ' ';
    out.integer(face_physical_base + face.id) << " \"" << mesh::kBoxFaceNames[static_cast<std::size_t>(face.id)] << "\"\n";
  }
  for (std::size_t k = 0; k < g.cohesive.size(); ++k) {
    out.integer(Dim) << ' ';
    out.integer(cohesive_base + static_cast<int>(k)) << " \"" << g.cohesive_names[k] << "\"\n";
  }
  out << "$EndPhysicalNames\n";

  const auto write_box = [&](const MshBox& box) {
    for (double x : box.lo) out << ' ', out.real(x);
    for (double x : box.hi) out << ' ', out.real(x);
  };
  const std::size_t volumes = g.phases.size() + (g.placeholder_entity ? 1 : 0) + g.cohesive.size();
  out << "$Entities\n";
  if constexpr (Dim == 2) {
    out << "0 ";
    out.integer(static_cast<long long>(g.faces.size())) << ' ';
    out.integer(static_cast<long long>(volumes)) << " 0\n";
  } else {
    out << "0 0 ";
    out.integer(static_cast<long long>(g.faces.size())) << ' ';
    out.integer(static_cast<long long>(volumes)) << '\n';
  }
  for (const MshGroup& face : g.faces) {
    out.integer(face.id + 1);
    write_box(face.box);
    out << " 1 ";
    out.integer(face_physical_base + face.id) << " 0\n";
  }
  for (const MshGroup& phase : g.phases) {
    out.integer(phase.id);
    write_box(phase.box);
    out << " 1 ", out.integer(phase.id) << " 0\n";
  }
  if (g.placeholder_entity) out << '1', write_box(MshBox{}), out << " 0 0\n";
  for (std::size_t k = 0; k < g.cohesive.size(); ++k) {
    out.integer(cohesive_base + static_cast<int>(k));
    write_box(g.cohesive[k].box);
    out << " 1 ", out.integer(cohesive_base + static_cast<int>(k)) << " 0\n";
  }
  out << "$EndEntities\n";
}

// The cells of `m` by phase, each group's count and box.
template <int Dim>
std::vector<MshGroup> phase_groups(const mesh::SimplexMesh<Dim>& m, const PhaseGroups& groups) {
  std::vector<MshGroup> out;
  for (std::size_t g = 0; g < groups.ids.size(); ++g) {
    MshGroup group{groups.ids[g], groups.begin[g + 1] - groups.begin[g], {}};
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i) {
      const LocalId* corners = m.cell(groups.order[i]);
      for (int k = 0; k <= Dim; ++k) group.box.add(&m.coords[static_cast<std::size_t>(corners[k]) * Dim], Dim);
    }
    out.push_back(group);
  }
  return out;
}

// The box faces of `sets` that carry facets, each one's count and box.
template <int Dim>
std::vector<MshGroup> face_groups(const mesh::SimplexMesh<Dim>& m, const mesh::BoundarySets<Dim>& sets) {
  std::vector<MshGroup> out;
  for (int f = 0; f < mesh::box_face_count(Dim); ++f) {
    const auto& facets = sets.facets[static_cast<std::size_t>(f)];
    if (facets.empty()) continue;
    MshGroup group{f, facets.size(), {}};
    for (const mesh::CellFacet& facet : facets)
      for (LocalId n : facet_nodes(m, facet)) group.box.add(&m.coords[static_cast<std::size_t>(n) * Dim], Dim);
    out.push_back(group);
  }
  return out;
}

// A $Nodes / $Elements line of counts: blocks, entries, the first and last tag (1 and entries).
void write_section_counts(TextWriter& out, std::uint64_t blocks, std::uint64_t entries) {
  out.integer(static_cast<long long>(blocks)) << ' ';
  out.integer(static_cast<long long>(entries)) << ' ';
  out.integer(entries > 0 ? 1 : 0) << ' ';
  out.integer(static_cast<long long>(entries)) << '\n';
}

template <int Dim>
std::array<LocalId, Dim + 1> cell_nodes(const mesh::SimplexMesh<Dim>& m, std::size_t c) {
  std::array<LocalId, Dim + 1> nodes;
  std::copy(m.cell(c), m.cell(c) + Dim + 1, nodes.begin());
  return nodes;
}

// One element line: tag, then the nodes' numbers (global id + 1 when ids are given).
template <std::size_t N>
void write_element(TextWriter& out, std::uint64_t tag, const std::array<LocalId, N>& nodes, const GlobalId* ids) {
  out.integer(static_cast<long long>(tag));
  for (LocalId n : nodes) out << ' ', out.integer((ids ? ids[n] : static_cast<GlobalId>(n)) + 1LL);
  out << '\n';
}

template <int Dim>
void write_msh_file(AtomicFile& file, const mesh::SimplexMesh<Dim>& m,
                    const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  const PhaseGroups groups = group_by_phase(m.cell_phase);
  const mesh::BoundarySets<Dim> sets = boundary_sets_for(m, options);
  using Order = mesh::CohesiveOrder<Dim>;
  const CohesiveGroups cohesive = group_cohesive(m, phases);
  MshHeadGroups head;
  head.phases = phase_groups(m, groups);
  head.faces = face_groups(m, sets);
  head.placeholder_entity = groups.ids.empty() && nodes > 0;
  for (std::size_t g = 0; g < cohesive.pairs.size(); ++g) {
    MshGroup group{static_cast<std::int32_t>(g), cohesive.begin[g + 1] - cohesive.begin[g], {}};
    for (std::size_t i = cohesive.begin[g]; i < cohesive.begin[g + 1]; ++i)
      for (int k = 0; k < 2 * Dim; ++k)
        group.box.add(&m.coords[static_cast<std::size_t>(m.cohesive.cell(cohesive.order[i])[k]) * Dim], Dim);
    head.cohesive.push_back(group);
  }
  head.cohesive_names = cohesive.names;
  std::vector<int> faces;
  for (const MshGroup& face : head.faces) faces.push_back(face.id);
  std::size_t facet_total = 0;
  for (const MshGroup& face : head.faces) facet_total += face.count;
  const int face_physical_base = (groups.ids.empty() ? 0 : groups.ids.back()) + 1;
  const int cohesive_base = face_physical_base + mesh::box_face_count(Dim);
  const int node_entity = groups.ids.empty() ? 1 : groups.ids.front();

  TextWriter out(file);
  write_msh_head_sections<Dim>(out, head, phases);

  // All nodes in one block on the first entity (a node shared by phases has one home).
  out << "$Nodes\n";
  if (nodes == 0) {
    out << "0 0 0 0\n";
  } else {
    write_section_counts(out, 1, nodes);
    out.integer(Dim) << ' ';
    out.integer(node_entity) << " 0 ";
    out.integer(static_cast<long long>(nodes)) << '\n';
    for (std::size_t n = 0; n < nodes; ++n) out.integer(static_cast<long long>(n + 1)) << '\n';
    for (std::size_t n = 0; n < nodes; ++n) {
      for (int d = 0; d < Dim; ++d) {
        if (d > 0) out << ' ';
        out.real(m.coords[n * Dim + d]);
      }
      out << (Dim == 2 ? " 0\n" : "\n");
    }
  }
  out << "$EndNodes\n";

  // Element tag = cell index + 1, so that reading restores the original order; the
  // boundary lines / triangles follow, face by face.
  const std::size_t elements = cells + facet_total + m.cohesive.count();
  out << "$Elements\n";
  write_section_counts(out, groups.ids.size() + faces.size() + cohesive.pairs.size(), elements);
  for (std::size_t g = 0; g < groups.ids.size(); ++g) {
    out.integer(Dim) << ' ';
    out.integer(groups.ids[g]) << (Dim == 2 ? " 2 " : " 4 ");
    out.integer(static_cast<long long>(groups.begin[g + 1] - groups.begin[g])) << '\n';
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i) write_element(out, groups.order[i] + 1, cell_nodes<Dim>(m, groups.order[i]), nullptr);
  }
  std::size_t tag = cells;
  for (int f : faces) {
    const auto& facets = sets.facets[static_cast<std::size_t>(f)];
    out.integer(Dim - 1) << ' ';
    out.integer(f + 1) << (Dim == 2 ? " 1 " : " 2 ");
    out.integer(static_cast<long long>(facets.size())) << '\n';
    for (const mesh::CellFacet& facet : facets) write_element(out, ++tag, facet_nodes(m, facet), nullptr);
  }
  for (std::size_t g = 0; g < cohesive.pairs.size(); ++g) {
    out.integer(Dim) << ' ';
    out.integer(cohesive_base + static_cast<int>(g)) << ' ';
    out.integer(Order::gmsh_type) << ' ';
    out.integer(static_cast<long long>(cohesive.begin[g + 1] - cohesive.begin[g])) << '\n';
    for (std::size_t i = cohesive.begin[g]; i < cohesive.begin[g + 1]; ++i) {
      out.integer(static_cast<long long>(++tag));
      const LocalId* nodes = m.cohesive.cell(cohesive.order[i]);
      for (int k : Order::gmsh) out << ' ', out.integer(nodes[k] + 1LL);
      out << '\n';
    }
  }
  out << "$EndElements\n";

  // Periodic meshes: one link per periodic axis a, from the a-max face entity (slave) to
  // the a-min face entity (master), with the affine map master → slave (identity plus T_a
  // in row a, column 4) and every node of the slave face with its single-axis master.
  // Gmsh skips a link whose entities it cannot find, so both faces must carry facets.
  const PeriodicOutput<Dim> periodic = periodic_output(m, options);
  if (periodic.any) {
    const auto has_entity = [&](int f) { return std::find(faces.begin(), faces.end(), f) != faces.end(); };
    std::vector<int> axes;
    for (int a = 0; a < Dim; ++a)
      if (periodic.axes[static_cast<std::size_t>(a)] && has_entity(2 * a) && has_entity(2 * a + 1)) axes.push_back(a);
    out << "$Periodic\n";
    out.integer(static_cast<long long>(axes.size())) << '\n';
    for (int a : axes) {
      out.integer(Dim - 1) << ' ';
      out.integer(2 * a + 2) << ' ';
      out.integer(2 * a + 1) << "\n16";
      for (int i = 0; i < 16; ++i) {
        const int row = i / 4, column = i % 4;
        const double value = column == 3 && row == a ? periodic.period[static_cast<std::size_t>(a)] : row == column ? 1 : 0;
        out << ' ', out.real(value);
      }
      out << '\n';
      std::size_t pairs = 0;
      const auto paired = [a](const mesh::PeriodicSlave<Dim>& s) {
        return ((s.shift >> a) & 1) && s.axis_master[static_cast<std::size_t>(a)] >= 0;
      };
      for (const mesh::PeriodicSlave<Dim>& s : periodic.links.slaves) pairs += paired(s);
      out.integer(static_cast<long long>(pairs)) << '\n';
      for (const mesh::PeriodicSlave<Dim>& s : periodic.links.slaves)
        if (paired(s)) {
          out.integer(s.node + 1LL) << ' ';
          out.integer(s.axis_master[static_cast<std::size_t>(a)] + 1LL) << '\n';
        }
    }
    out << "$EndPeriodic\n";
  }
  out.flush();
}

// ---- streamed (msh_stream.hpp) ----

template <int Dim>
void write_node_coordinates(TextWriter& out, const double* p) {
  for (int d = 0; d < Dim; ++d) {
    if (d > 0) out << ' ';
    out.real(p[d]);
  }
  out << (Dim == 2 ? " 0\n" : "\n");
}

}  // namespace

void MshBox::add(const double* p, int dim) {
  for (int d = 0; d < dim; ++d) {
    lo[d] = empty ? p[d] : std::min(lo[d], p[d]);
    hi[d] = empty ? p[d] : std::max(hi[d], p[d]);
  }
  empty = false;
}

void MshBox::add(const MshBox& other) {
  if (other.empty) return;
  for (int d = 0; d < 3; ++d) {
    lo[d] = empty ? other.lo[d] : std::min(lo[d], other.lo[d]);
    hi[d] = empty ? other.hi[d] : std::max(hi[d], other.hi[d]);
  }
  empty = false;
}

template <int Dim>
MshPartSummary msh_part_summary(const mesh::SimplexMesh<Dim>& m, const MeshWriteOptions& options) {
  if (!options.face_box) throw std::invalid_argument("msh_part_summary: the domain's face box is needed");
  MshPartSummary s;
  s.cells = m.cell_count();
  s.phases = phase_groups(m, group_by_phase(m.cell_phase));
  for (const MshGroup& face : face_groups(m, boundary_sets_for(m, options))) s.faces[static_cast<std::size_t>(face.id)] = face;
  return s;
}

int msh_node_entity(const std::vector<MshPartSummary>& parts) {
  int entity = 0;
  bool any = false;
  for (const MshPartSummary& p : parts)
    for (const MshGroup& g : p.phases) entity = any ? std::min(entity, g.id) : g.id, any = true;
  return any ? entity : 1;
}

template <int Dim>
void write_msh_head(AtomicFile& file, const std::vector<MshPartSummary>& parts, const std::vector<geometry::Phase>& phases) {
  MshHeadGroups head;
  std::uint64_t nodes = 0;
  std::array<MshGroup, 6> faces{};
  for (const MshPartSummary& p : parts) {
    nodes += p.owned_nodes;
    for (const MshGroup& g : p.phases) {
      auto at = std::lower_bound(head.phases.begin(), head.phases.end(), g.id,
                                 [](const MshGroup& a, std::int32_t id) { return a.id < id; });
      if (at == head.phases.end() || at->id != g.id) at = head.phases.insert(at, MshGroup{g.id, 0, {}});
      at->count += g.count;
      at->box.add(g.box);
    }
    for (int f = 0; f < mesh::box_face_count(Dim); ++f) {
      MshGroup& face = faces[static_cast<std::size_t>(f)];
      face.id = f;
      face.count += p.faces[static_cast<std::size_t>(f)].count;
      face.box.add(p.faces[static_cast<std::size_t>(f)].box);
    }
  }
  for (int f = 0; f < mesh::box_face_count(Dim); ++f)
    if (faces[static_cast<std::size_t>(f)].count > 0) head.faces.push_back(faces[static_cast<std::size_t>(f)]);
  head.placeholder_entity = head.phases.empty() && nodes > 0;
  TextWriter out(file);
  write_msh_head_sections<Dim>(out, head, phases);
  std::size_t blocks = 0;
  for (const MshPartSummary& p : parts) blocks += p.owned_nodes > 0 ? 1 : 0;
  out << "$Nodes\n";
  write_section_counts(out, blocks, nodes);
  out.flush();
}

void write_msh_elements_head(AtomicFile& file, const std::vector<MshPartSummary>& parts) {
  std::uint64_t blocks = 0, elements = 0;
  for (const MshPartSummary& p : parts) {
    blocks += p.phases.size();
    elements += p.cells;
    for (const MshGroup& face : p.faces) blocks += face.count > 0 ? 1 : 0, elements += face.count;
  }
  TextWriter out(file);
  out << "$EndNodes\n$Elements\n";
  write_section_counts(out, blocks, elements);
  out.flush();
}

void write_msh_tail(AtomicFile& file) { file.write("$EndElements\n"); }

template <int Dim>
void write_msh_node_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& m, GlobalId first_owned, std::uint64_t owned,
                          int node_entity) {
  if (owned == 0) return;
  TextWriter out(file);
  out.integer(Dim) << ' ';
  out.integer(node_entity) << " 0 ";
  out.integer(static_cast<long long>(owned)) << '\n';
  for (std::uint64_t k = 0; k < owned; ++k) out.integer(first_owned + static_cast<long long>(k) + 1) << '\n';
  // The owned nodes in local order are the ids first_owned, first_owned + 1, … (owned-first numbering).
  const GlobalId end = first_owned + static_cast<GlobalId>(owned);
  std::uint64_t written = 0;
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const GlobalId id = m.node_global_id[n];
    if (id < first_owned || id >= end) continue;
    if (id != first_owned + static_cast<GlobalId>(written))
      throw std::logic_error("write_msh_node_chunk: the owned ids are not one ascending run");
    write_node_coordinates<Dim>(out, &m.coords[n * Dim]);
    ++written;
  }
  if (written != owned) throw std::logic_error("write_msh_node_chunk: owned nodes missing");
  out.flush();
}

template <int Dim>
void write_msh_cell_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& m, std::uint64_t first_cell_tag) {
  const PhaseGroups groups = group_by_phase(m.cell_phase);
  TextWriter out(file);
  for (std::size_t g = 0; g < groups.ids.size(); ++g) {
    out.integer(Dim) << ' ';
    out.integer(groups.ids[g]) << (Dim == 2 ? " 2 " : " 4 ");
    out.integer(static_cast<long long>(groups.begin[g + 1] - groups.begin[g])) << '\n';
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i)
      write_element(out, first_cell_tag + groups.order[i] + 1, cell_nodes<Dim>(m, groups.order[i]), m.node_global_id.data());
  }
  out.flush();
}

template <int Dim>
void write_msh_face_chunks(const std::array<AtomicFile*, 6>& faces, const mesh::SimplexMesh<Dim>& m,
                           const MeshWriteOptions& options, const std::array<std::uint64_t, 6>& first_facet_tag) {
  const mesh::BoundarySets<Dim> sets = boundary_sets_for(m, options);
  for (int f = 0; f < mesh::box_face_count(Dim); ++f) {
    const auto& facets = sets.facets[static_cast<std::size_t>(f)];
    if (facets.empty()) continue;
    TextWriter out(*faces[static_cast<std::size_t>(f)]);
    out.integer(Dim - 1) << ' ';
    out.integer(f + 1) << (Dim == 2 ? " 1 " : " 2 ");
    out.integer(static_cast<long long>(facets.size())) << '\n';
    std::uint64_t tag = first_facet_tag[static_cast<std::size_t>(f)];
    for (const mesh::CellFacet& facet : facets) write_element(out, ++tag, facet_nodes(m, facet), m.node_global_id.data());
    out.flush();
  }
}

#define CISAMR_MSH_STREAM(D)                                                                                        \
  template MshPartSummary msh_part_summary<D>(const mesh::SimplexMesh<D>&, const MeshWriteOptions&);                \
  template void write_msh_head<D>(AtomicFile&, const std::vector<MshPartSummary>&,                                  \
                                  const std::vector<geometry::Phase>&);                                             \
  template void write_msh_node_chunk<D>(AtomicFile&, const mesh::SimplexMesh<D>&, GlobalId, std::uint64_t, int);    \
  template void write_msh_cell_chunk<D>(AtomicFile&, const mesh::SimplexMesh<D>&, std::uint64_t);                   \
  template void write_msh_face_chunks<D>(const std::array<AtomicFile*, 6>&, const mesh::SimplexMesh<D>&,            \
                                         const MeshWriteOptions&, const std::array<std::uint64_t, 6>&);
CISAMR_MSH_STREAM(2)
CISAMR_MSH_STREAM(3)
#undef CISAMR_MSH_STREAM

namespace {

// ------------------------------------------------------------------------------ INP

// Abaqus labels: a letter first, then letters, digits and underscores.
std::string abaqus_label(const std::string& name) {
  std::string label;
  for (char c : name) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    label += ok ? c : '_';
  }
  if (label.empty() || !((label[0] >= 'A' && label[0] <= 'Z') || (label[0] >= 'a' && label[0] <= 'z')))
    label = "P_" + label;
  return label.substr(0, 80);
}

// Abaqus face ids of the facet opposite local vertex v (mesh::FacetVertices): C3D4
// S1 = (1,2,3), S2 = (1,4,2), S3 = (2,4,3), S4 = (3,4,1); CPS3/CPE3 S1 = (1,2), S2 = (2,3),
// S3 = (3,1) (1-based element nodes).
template <int Dim>
struct AbaqusFaceOf;
template <>
struct AbaqusFaceOf<2> {
  static constexpr int id[3] = {2, 3, 1};
};
template <>
struct AbaqusFaceOf<3> {
  static constexpr int id[4] = {3, 4, 2, 1};
};

// Abaqus input rules: at most 16 entries per data line, numbers of at most 20 characters.
constexpr int kAbaqusNumberWidth = 20;

std::string inp_heading(std::uint64_t nodes, std::uint64_t cells, int dim) {
  return "*HEADING\ncisamr mesh: " + std::to_string(nodes) + " nodes, " + std::to_string(cells) +
         (dim == 2 ? " triangles\n" : " tetrahedra\n");
}

// A phase's element block head; our reader takes the phase id and full name from the
// comment, Abaqus ignores it.
std::string inp_element_header(const std::vector<geometry::Phase>& phases, int id, const char* element_type) {
  std::string name = phase_name(phases, id);
  std::replace(name.begin(), name.end(), '\n', ' ');
  return "** cisamr phase " + std::to_string(id) + " " + name + "\n*ELEMENT, TYPE=" + element_type +
         ", ELSET=" + abaqus_label(name) + "\n";
}

std::string inp_nset_header(int face) {
  return "*NSET, NSET=" + std::string(mesh::kBoxFaceNames[static_cast<std::size_t>(face)]) + "\n";
}
std::string inp_elset_header(int face, int side) {
  return "*ELSET, ELSET=" + std::string(mesh::kBoxFaceNames[static_cast<std::size_t>(face)]) + "_S" +
         std::to_string(side) + "\n";
}
// Per face, *SURFACE <FACE>_FACES listing its ELSETs <FACE>_S<k> (the Abaqus face ids used).
std::string inp_surface(int face, const std::vector<int>& sides) {
  const std::string name(mesh::kBoxFaceNames[static_cast<std::size_t>(face)]);
  std::string text = "*SURFACE, TYPE=ELEMENT, NAME=" + name + "_FACES\n";
  for (int k : sides) text += name + "_S" + std::to_string(k) + ", S" + std::to_string(k) + "\n";
  return text;
}

// One element line: tag, then its nodes' numbers (global id + 1 when ids are given).
void write_inp_element(TextWriter& out, std::uint64_t tag, const LocalId* corners, int count, const GlobalId* ids) {
  out.integer(static_cast<long long>(tag));
  for (int k = 0; k < count; ++k) out << ", ", out.integer((ids ? ids[corners[k]] : static_cast<GlobalId>(corners[k])) + 1LL);
  out << '\n';
}

// Abaqus data lines hold at most 16 entries.
void write_id_lines(TextWriter& out, const std::vector<long long>& ids) {
  for (std::size_t i = 0; i < ids.size(); ++i) {
    out.integer(ids[i]);
    out << ((i % 16 == 15 || i + 1 == ids.size()) ? "\n" : ", ");
  }
}

// Periodic constraints (docs/periodic-design.md §5). One REF node per periodic axis, ids
// n+1 ... in axis order, at the max corner of the face box: their lines close the mesh's
// *NODE block (a second *NODE block makes meshio drop the first), announced by a comment
// before it that our reader takes to skip them (they belong to no element).
template <int Dim>
std::array<long long, Dim> reference_nodes(const mesh::SimplexMesh<Dim>& m, const PeriodicOutput<Dim>& periodic) {
  std::array<long long, Dim> ref{};
  long long next = static_cast<long long>(m.node_count());
  for (int a = 0; a < Dim; ++a) ref[static_cast<std::size_t>(a)] = periodic.axes[static_cast<std::size_t>(a)] ? ++next : -1;
  return ref;
}

// After the mesh: each REF node alone in NSET REF_X / REF_Y / REF_Z, then one equation per
// slave and dof, slaves in node order: s - m - the REF nodes of the axes s is shifted along.
// Node ids, not sets (CalculiX); at most 4 terms per data line (Abaqus).
template <int Dim>
void write_inp_constraints(TextWriter& out, const mesh::SimplexMesh<Dim>& m, const PeriodicOutput<Dim>& periodic) {
  const std::array<long long, Dim> ref = reference_nodes(m, periodic);
  out << "** cisamr periodic constraints. Each node s on a periodic max face is tied to its master m\n"
         "** (s moved to the min face of every axis it lies on the max face of; CORNER0 for the far\n"
         "** corner) by one equation per dof d: u(s,d) - u(m,d) - sum of u(REF_a,d) over those axes a = 0.\n"
         "** The displacement of REF_a is the jump of u across the cell along a: for a macroscopic\n"
         "** strain E, u(REF_a) = E . (T_a e_a), T_a the period. Constrain CORNER0 (rigid motion)\n"
         "** and the REF nodes, never a slave (each slave dof is eliminated by its equation).\n";
  for (int a = 0; a < Dim; ++a) {
    if (ref[static_cast<std::size_t>(a)] < 0) continue;
    out << "*NSET, NSET=REF_" << "XYZ"[a] << '\n';
    out.integer(ref[static_cast<std::size_t>(a)]) << '\n';
  }
  if (periodic.links.slaves.empty()) return;
  out << "*EQUATION\n";
  for (const mesh::PeriodicSlave<Dim>& s : periodic.links.slaves)
    for (int d = 1; d <= Dim; ++d) {
      const int terms = 2 + std::popcount(static_cast<unsigned>(s.shift));
      out.integer(terms) << '\n';
      int written = 0;
      const auto term = [&](long long node, const char* coefficient) {
        if (written > 0) out << (written % 4 == 0 ? "\n" : ", ");
        out.integer(node) << ", ";
        out.integer(d) << ", " << coefficient;
        ++written;
      };
      term(s.node + 1LL, "1.0");
      term(s.master + 1LL, "-1.0");
      for (int a = 0; a < Dim; ++a)
        if ((s.shift >> a) & 1) term(ref[static_cast<std::size_t>(a)], "-1.0");
      out << '\n';
    }
}

// Cohesive cells after the bulk ones (ids continue theirs), one ELSET per phase pair,
// COH_<lower phase name>_<other>, in the node order of Abaqus COH2D4 / COH3D6 (mesh/cohesive.hpp):
// the default STACK DIRECTION of a *COHESIVE SECTION points from the bottom (lower phase id)
// to the top.
template <int Dim>
void write_inp_cohesive(TextWriter& out, const mesh::SimplexMesh<Dim>& m, const std::vector<geometry::Phase>& phases) {
  using Order = mesh::CohesiveOrder<Dim>;
  const CohesiveGroups groups = group_cohesive(m, phases);
  for (std::size_t g = 0; g < groups.pairs.size(); ++g) {
    // Our reader takes the two phase ids from this comment; Abaqus ignores it.
    out << "** cisamr cohesive ";
    out.integer(groups.pairs[g].first) << ' ';
    out.integer(groups.pairs[g].second) << ' ' << groups.names[g] << '\n';
    out << "*ELEMENT, TYPE=" << Order::abaqus_type << ", ELSET=" << groups.names[g] << '\n';
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i) {
      const std::size_t c = groups.order[i];
      out.integer(static_cast<long long>(m.cell_count() + c + 1));
      const LocalId* nodes = m.cohesive.cell(c);
      for (int k : Order::abaqus) out << ", ", out.integer(nodes[k] + 1LL);
      out << '\n';
    }
  }
}

template <int Dim>
void write_inp_file(AtomicFile& file, const mesh::SimplexMesh<Dim>& m,
                    const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  constexpr int kCorners = Dim + 1;
  constexpr int kFaces = mesh::box_face_count(Dim);
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  const PhaseGroups groups = group_by_phase(m.cell_phase);
  const char* element_type = Dim == 3 ? "C3D4" : options.plane == PlaneKind::strain ? "CPE3" : "CPS3";
  const PeriodicOutput<Dim> periodic = periodic_output(m, options);  // throws before any output
  const std::array<long long, Dim> ref = reference_nodes(m, periodic);
  TextWriter out(file);
  out << inp_heading(nodes, cells, Dim);
  if (periodic.any) {
    out << "** cisamr periodic reference nodes";
    for (long long id : ref)
      if (id >= 0) out << ' ', out.integer(id);
    out << '\n';
  }
  out << "*NODE\n";
  for (std::size_t n = 0; n < nodes; ++n) {
    out.integer(static_cast<long long>(n + 1));
    for (int d = 0; d < Dim; ++d) out << ", ", out.real_within(m.coords[n * Dim + d], kAbaqusNumberWidth);
    out << '\n';
  }
  for (long long id : ref) {
    if (id < 0) continue;
    out.integer(id);
    for (int d = 0; d < Dim; ++d) out << ", ", out.real_within(periodic.faces.max[d], kAbaqusNumberWidth);
    out << '\n';
  }
  for (std::size_t g = 0; g < groups.ids.size(); ++g) {
    out << inp_element_header(phases, groups.ids[g], element_type);
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i)
      write_inp_element(out, groups.order[i] + 1, m.cell(groups.order[i]), kCorners, nullptr);
  }
  write_inp_cohesive(out, m, phases);

  // Boundary sets (DESIGN.md §7); a face no node lies on (a void covers it) has none.
  const mesh::BoundarySets<Dim> sets = boundary_sets_for(m, options);
  std::vector<long long> ids;
  for (int f = 0; f < kFaces; ++f) {
    ids.clear();
    for (std::size_t n = 0; n < nodes; ++n)
      if ((sets.node_faces[n] >> f) & 1) ids.push_back(static_cast<long long>(n + 1));
    if (ids.empty()) continue;
    out << inp_nset_header(f);
    write_id_lines(out, ids);
  }
  if (sets.corner0 >= 0) {
    out << "*NSET, NSET=CORNER0\n";
    out.integer(sets.corner0 + 1LL) << '\n';
  }
  // Element-face surfaces: per face, one ELSET per Abaqus face id that occurs
  // (<FACE>_S<k>), then *SURFACE <FACE>_FACES listing them.
  for (int f = 0; f < kFaces; ++f) {
    const auto& facets = sets.facets[static_cast<std::size_t>(f)];
    if (facets.empty()) continue;
    const std::string face(mesh::kBoxFaceNames[static_cast<std::size_t>(f)]);
    std::vector<int> used;
    for (int k = 1; k <= kCorners; ++k) {
      ids.clear();
      for (const mesh::CellFacet& facet : facets)
        if (AbaqusFaceOf<Dim>::id[facet.opposite] == k) ids.push_back(facet.cell + 1);
      if (ids.empty()) continue;
      used.push_back(k);
      out << inp_elset_header(f, k);
      write_id_lines(out, ids);
    }
    out << inp_surface(f, used);
  }
  if (periodic.any) write_inp_constraints(out, m, periodic);
  out.flush();
}

// ---- streamed (inp_stream.hpp) ----

}  // namespace

std::string inp_stream_head(std::uint64_t nodes, std::uint64_t cells, int dim) {
  return inp_heading(nodes, cells, dim) + "*NODE\n";
}

std::string inp_stream_element_header(const std::vector<geometry::Phase>& phases, int id, int dim, PlaneKind plane) {
  return inp_element_header(phases, id, dim == 3 ? "C3D4" : plane == PlaneKind::strain ? "CPE3" : "CPS3");
}
std::string inp_stream_nset_header(int face) { return inp_nset_header(face); }
std::string inp_stream_elset_header(int face, int side) { return inp_elset_header(face, side); }
std::string inp_stream_surface(int face, const std::vector<int>& sides) { return inp_surface(face, sides); }

template <int Dim>
void write_inp_node_chunk(AtomicFile& file, const mesh::SimplexMesh<Dim>& m, GlobalId first_owned, std::uint64_t owned) {
  TextWriter out(file);
  const GlobalId end = first_owned + static_cast<GlobalId>(owned);
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const GlobalId id = m.node_global_id[n];
    if (id < first_owned || id >= end) continue;
    out.integer(id + 1LL);
    for (int d = 0; d < Dim; ++d) out << ", ", out.real_within(m.coords[n * Dim + d], kAbaqusNumberWidth);
    out << '\n';
  }
  out.flush();
}

template <int Dim>
void write_inp_cell_chunks(const std::vector<AtomicFile*>& per_phase, const std::vector<int>& phase_ids,
                           const mesh::SimplexMesh<Dim>& m, std::uint64_t first_cell_tag) {
  const PhaseGroups groups = group_by_phase(m.cell_phase);
  for (std::size_t g = 0; g < groups.ids.size(); ++g) {
    const auto at = std::find(phase_ids.begin(), phase_ids.end(), groups.ids[g]);
    if (at == phase_ids.end()) throw std::logic_error("write_inp_cell_chunks: a phase missing from the list");
    TextWriter out(*per_phase[static_cast<std::size_t>(at - phase_ids.begin())]);
    for (std::size_t i = groups.begin[g]; i < groups.begin[g + 1]; ++i)
      write_inp_element(out, first_cell_tag + groups.order[i] + 1, m.cell(groups.order[i]), Dim + 1, m.node_global_id.data());
    out.flush();
  }
}

template <int Dim>
GlobalId write_inp_set_chunks(const std::array<AtomicFile*, 6>& nsets,
                              const std::array<std::array<AtomicFile*, 4>, 6>& elsets, const mesh::SimplexMesh<Dim>& m,
                              const MeshWriteOptions& options, GlobalId first_owned, std::uint64_t owned,
                              std::uint64_t first_cell_tag) {
  const mesh::BoundarySets<Dim> sets = boundary_sets_for(m, options);
  const GlobalId end = first_owned + static_cast<GlobalId>(owned);
  const auto is_owned = [&](std::size_t n) { return m.node_global_id[n] >= first_owned && m.node_global_id[n] < end; };
  std::vector<long long> ids;
  for (int f = 0; f < mesh::box_face_count(Dim); ++f) {
    ids.clear();
    for (std::size_t n = 0; n < m.node_count(); ++n)
      if (((sets.node_faces[n] >> f) & 1) && is_owned(n)) ids.push_back(m.node_global_id[n] + 1LL);
    TextWriter out(*nsets[static_cast<std::size_t>(f)]);
    write_id_lines(out, ids);
    out.flush();
    for (int k = 1; k <= Dim + 1; ++k) {
      ids.clear();
      for (const mesh::CellFacet& facet : sets.facets[static_cast<std::size_t>(f)])
        if (AbaqusFaceOf<Dim>::id[facet.opposite] == k) ids.push_back(static_cast<long long>(first_cell_tag) + facet.cell + 1);
      TextWriter side(*elsets[static_cast<std::size_t>(f)][static_cast<std::size_t>(k - 1)]);
      write_id_lines(side, ids);
      side.flush();
    }
  }
  return sets.corner0 >= 0 && is_owned(static_cast<std::size_t>(sets.corner0))
             ? m.node_global_id[static_cast<std::size_t>(sets.corner0)]
             : -1;
}

#define CISAMR_INP_STREAM(D)                                                                                        \
  template void write_inp_node_chunk<D>(AtomicFile&, const mesh::SimplexMesh<D>&, GlobalId, std::uint64_t);         \
  template void write_inp_cell_chunks<D>(const std::vector<AtomicFile*>&, const std::vector<int>&,                  \
                                         const mesh::SimplexMesh<D>&, std::uint64_t);                               \
  template GlobalId write_inp_set_chunks<D>(const std::array<AtomicFile*, 6>&,                                      \
                                            const std::array<std::array<AtomicFile*, 4>, 6>&,                       \
                                            const mesh::SimplexMesh<D>&, const MeshWriteOptions&, GlobalId,         \
                                            std::uint64_t, std::uint64_t);
CISAMR_INP_STREAM(2)
CISAMR_INP_STREAM(3)
#undef CISAMR_INP_STREAM

namespace {

// ------------------------------------------------------------------------------ Medit

template <int Dim>
void write_medit_file(AtomicFile& file, const mesh::SimplexMesh<Dim>& m,
                      const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  constexpr int kCorners = Dim + 1;
  constexpr int kFaces = mesh::box_face_count(Dim);
  const std::size_t nodes = m.node_count(), cells = m.cell_count();
  TextWriter out(file);
  out << "MeshVersionFormatted 2\n\nDimension ";
  out.integer(Dim) << '\n';
  for (const geometry::Phase& p : phases_in_id_order(phases, m.cell_phase)) {
    std::string name = p.name;
    std::replace(name.begin(), name.end(), '\n', ' ');
    out << "# phase ";
    out.integer(p.id) << ' ' << name << '\n';
  }
  out << "\nVertices\n";
  out.integer(static_cast<long long>(nodes)) << '\n';
  for (std::size_t n = 0; n < nodes; ++n) {
    for (int d = 0; d < Dim; ++d) out.real(m.coords[n * Dim + d]) << ' ';
    out << "0\n";
  }
  out << (Dim == 2 ? "\nTriangles\n" : "\nTetrahedra\n");
  out.integer(static_cast<long long>(cells)) << '\n';
  for (std::size_t c = 0; c < cells; ++c) {
    const LocalId* corners = m.cell(c);
    for (int k = 0; k < kCorners; ++k) out.integer(corners[k] + 1LL) << ' ';
    out.integer(m.cell_phase[c]) << '\n';
  }
  // Boundary edges (2D) or triangles (3D) on the box faces, reference face + 1.
  const mesh::BoundarySets<Dim> sets = boundary_sets_for(m, options);
  std::size_t facet_total = 0;
  for (const auto& facets : sets.facets) facet_total += facets.size();
  if (facet_total > 0) {
    out << (Dim == 2 ? "\nEdges\n" : "\nTriangles\n");
    out.integer(static_cast<long long>(facet_total)) << '\n';
    for (int f = 0; f < kFaces; ++f)
      for (const mesh::CellFacet& facet : sets.facets[static_cast<std::size_t>(f)]) {
        for (LocalId n : facet_nodes(m, facet)) out.integer(n + 1LL) << ' ';
        out.integer(f + 1) << '\n';
      }
  }
  out << "\nEnd\n";
  out.flush();
}

}  // namespace

std::string lowercase_extension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

MeshFormat mesh_format_of(const std::string& path) {
  if (path.empty()) throw InputError("\"\"", "", "cannot write: the output path is empty");
  if (path == "-") throw InputError(path, "", "standard output has no file extension: name the mesh format");
  const std::string extension = std::filesystem::path(path).extension().string();
  const std::string lower = lowercase_extension(path);
  if (lower == ".vtu") return MeshFormat::vtu;
  if (lower == ".msh") return MeshFormat::msh;
  if (lower == ".inp") return MeshFormat::inp;
  if (lower == ".mesh") return MeshFormat::medit;
  throw InputError(path, "",
                   (extension.empty() ? std::string("no file extension")
                                      : "unknown mesh format '" + extension + "'") +
                       " (use .vtu, .msh, .inp or .mesh)");
}

template <int Dim>
void write_vtu(const std::string& path, const mesh::SimplexMesh<Dim>& m,
               const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  check_mesh(m);
  AtomicFile file(path);
  write_vtu_file(file, m, phases, options);
  file.commit();
}

template <int Dim>
VtuAwaitingIds::VtuAwaitingIds(const std::string& path, const mesh::SimplexMesh<Dim>& m,
                               const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options)
    : nodes_(m.node_count()) {
  check_mesh(m);
  file_ = std::make_unique<AtomicFile>(path);
  write_vtu_without_ids(*file_, m, phases, options);
  file_->flush();
}
VtuAwaitingIds::VtuAwaitingIds(VtuAwaitingIds&&) noexcept = default;
VtuAwaitingIds& VtuAwaitingIds::operator=(VtuAwaitingIds&&) noexcept = default;
VtuAwaitingIds::~VtuAwaitingIds() = default;

void VtuAwaitingIds::finish(std::span<const GlobalId> ids) {
  if (file_ == nullptr) throw std::logic_error("VtuAwaitingIds::finish: already finished");
  if (ids.size() != nodes_) throw std::invalid_argument("VtuAwaitingIds::finish: one global id per node");
  write_vtu_ids(*file_, ids);
  file_->commit();
  file_.reset();
}

template VtuAwaitingIds::VtuAwaitingIds(const std::string&, const mesh::Mesh2&, const std::vector<geometry::Phase>&,
                                        const MeshWriteOptions&);
template VtuAwaitingIds::VtuAwaitingIds(const std::string&, const mesh::Mesh3&, const std::vector<geometry::Phase>&,
                                        const MeshWriteOptions&);

template <int Dim>
void write_mesh(const std::string& path, const mesh::SimplexMesh<Dim>& m,
                const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options) {
  const MeshFormat format = options.format ? *options.format : mesh_format_of(path);
  check_mesh(m);
  AtomicFile file(path);
  switch (format) {
    case MeshFormat::vtu: write_vtu_file(file, m, phases, options); break;
    case MeshFormat::msh: write_msh_file(file, m, phases, options); break;
    case MeshFormat::inp: write_inp_file(file, m, phases, options); break;
    case MeshFormat::medit: write_medit_file(file, m, phases, options); break;
  }
  file.commit();
}

template void write_mesh<2>(const std::string&, const mesh::Mesh2&,
                            const std::vector<geometry::Phase>&, const MeshWriteOptions&);
template void write_mesh<3>(const std::string&, const mesh::Mesh3&,
                            const std::vector<geometry::Phase>&, const MeshWriteOptions&);
template void write_vtu<2>(const std::string&, const mesh::Mesh2&, const std::vector<geometry::Phase>&,
                           const MeshWriteOptions&);
template void write_vtu<3>(const std::string&, const mesh::Mesh3&, const std::vector<geometry::Phase>&,
                           const MeshWriteOptions&);

std::string cohesive_set_name(const std::vector<geometry::Phase>& phases, std::int32_t lower, std::int32_t upper) {
  return abaqus_label("COH_" + phase_name(phases, lower) + "_" + phase_name(phases, upper));
}

std::string pvtu_text(const std::vector<std::string>& pieces, bool periodic, bool cohesive) {
  // The arrays write_vtu_file declares (field data is read from the pieces).
  std::string xml;
  xml += "<?xml version=\"1.0\"?>\n";
  xml += "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  xml += "  <PUnstructuredGrid GhostLevel=\"0\">\n";
  xml += "    <PPointData>\n";
  xml += "      <PDataArray type=\"Int64\" Name=\"global_id\"/>\n";
  xml += "      <PDataArray type=\"UInt8\" Name=\"boundary\"/>\n";
  if (periodic) xml += "      <PDataArray type=\"Int64\" Name=\"periodic_master\"/>\n";
  if (cohesive) xml += "      <PDataArray type=\"Int32\" Name=\"node_phase\"/>\n";
  xml += "    </PPointData>\n";
  xml += "    <PCellData Scalars=\"phase\">\n";
  xml += "      <PDataArray type=\"Int32\" Name=\"phase\"/>\n";
  xml += "      <PDataArray type=\"Int32\" Name=\"partition\"/>\n";
  xml += "      <PDataArray type=\"Float64\" Name=\"aspect_ratio\"/>\n";
  if (cohesive) {
    xml += "      <PDataArray type=\"UInt8\" Name=\"cohesive\"/>\n";
    xml += "      <PDataArray type=\"Int32\" Name=\"phase_top\"/>\n";
  }
  xml += "    </PCellData>\n";
  xml += "    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n";
  for (const std::string& piece : pieces) xml += "    <Piece Source=\"" + piece + "\"/>\n";
  xml += "  </PUnstructuredGrid>\n</VTKFile>\n";
  return xml;
}

}  // namespace cisamr::io
