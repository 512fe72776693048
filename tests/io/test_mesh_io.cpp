#include "io/mesh_io.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <numeric>

#include "core/error.hpp"
#include "mesh/metrics.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::read_text;
using testing::TempDir;

const std::vector<geometry::Phase> kPhases = {
    {1, "matrix", false}, {2, "glass fiber", false}, {5, "pore", true}, {9, "unused", false}};

// A structured grid of triangles with awkward coordinates (0.1 steps, thirds, a -0.0),
// interleaved phases (so writers that group by phase must restore the order), partitions
// and global ids that are not the node index.
mesh::Mesh2 grid_mesh2(int nx, int ny) {
  mesh::Mesh2 m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      m.coords.push_back(i == 0 ? -0.0 : i * 0.1);
      m.coords.push_back(1.0 / 3.0 + j / 7.0);
    }
  const auto node = [&](int i, int j) { return LocalId(j * (nx + 1) + i); };
  const int phases[] = {1, 2, 5};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const LocalId a = node(i, j), b = node(i + 1, j), c = node(i + 1, j + 1), d = node(i, j + 1);
      for (const auto& t : {std::array<LocalId, 3>{a, b, c}, std::array<LocalId, 3>{a, c, d}}) {
        m.cell_nodes.insert(m.cell_nodes.end(), t.begin(), t.end());
        const std::size_t cell = m.cell_phase.size();
        m.cell_phase.push_back(phases[(cell * 7 / 3) % 3]);
        m.cell_partition.push_back(static_cast<std::int32_t>(cell % 4));
      }
    }
  for (std::size_t n = 0; n < m.node_count(); ++n) m.node_global_id.push_back(1000 + 3 * GlobalId(n));
  return m;
}

// Cubes split into 6 tetrahedra around the main diagonal, positively oriented.
mesh::Mesh3 grid_mesh3(int nx, int ny, int nz) {
  mesh::Mesh3 m;
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        m.coords.push_back(i * 0.1);
        m.coords.push_back(j / 3.0);
        m.coords.push_back(1e-3 + k * 0.7);
      }
  const auto node = [&](int i, int j, int k) { return LocalId((k * (ny + 1) + j) * (nx + 1) + i); };
  const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : permutations) {
          int at[3] = {i, j, k};
          std::array<LocalId, 4> t;
          t[0] = node(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[p[s]];
            t[s + 1] = node(at[0], at[1], at[2]);
          }
          if (mesh::signed_volume(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])) < 0)
            std::swap(t[2], t[3]);
          m.cell_nodes.insert(m.cell_nodes.end(), t.begin(), t.end());
          const std::size_t cell = m.cell_phase.size();
          m.cell_phase.push_back(cell % 5 == 0 ? 2 : 1);
          m.cell_partition.push_back(static_cast<std::int32_t>(cell / 7));
        }
  for (std::size_t n = 0; n < m.node_count(); ++n) m.node_global_id.push_back(GlobalId(n) * 2);
  return m;
}

template <int Dim>
const mesh::SimplexMesh<Dim>& loaded(const LoadedMesh& l) {
  if constexpr (Dim == 2) return l.mesh2;
  else return l.mesh3;
}

template <int Dim>
void expect_round_trip(const mesh::SimplexMesh<Dim>& m, const std::string& path, bool keeps_names,
                       bool keeps_ids) {
  write_mesh(path, m, kPhases);
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, Dim) << path;
  const mesh::SimplexMesh<Dim>& r = loaded<Dim>(l);
  ASSERT_EQ(r.coords.size(), m.coords.size()) << path;
  EXPECT_EQ(std::memcmp(r.coords.data(), m.coords.data(), m.coords.size() * sizeof(double)), 0)
      << path << ": coordinates differ in some bit";
  EXPECT_EQ(r.cell_nodes, m.cell_nodes) << path;
  EXPECT_EQ(r.cell_phase, m.cell_phase) << path;
  if (keeps_ids) {
    EXPECT_EQ(r.cell_partition, m.cell_partition) << path;
    EXPECT_EQ(r.node_global_id, m.node_global_id) << path;
  } else {
    EXPECT_EQ(r.cell_partition, std::vector<std::int32_t>(m.cell_count(), 0)) << path;
    std::vector<GlobalId> index(m.node_count());
    std::iota(index.begin(), index.end(), 0);
    EXPECT_EQ(r.node_global_id, index) << path;
  }
  std::vector<int> used(m.cell_phase.begin(), m.cell_phase.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  ASSERT_EQ(l.phases.size(), used.size()) << path;
  for (std::size_t i = 0; i < used.size(); ++i) {
    EXPECT_EQ(l.phases[i].id, used[i]) << path;
    std::string expected = "phase" + std::to_string(used[i]);
    if (keeps_names)
      for (const auto& p : kPhases)
        if (p.id == used[i]) expected = p.name;
    EXPECT_EQ(l.phases[i].name, expected) << path;
  }
}

TEST(MeshIo, RoundTrip2dEveryFormat) {
  TempDir dir;
  const mesh::Mesh2 m = grid_mesh2(5, 4);
  expect_round_trip(m, dir.file("m.vtu"), true, true);
  expect_round_trip(m, dir.file("m.msh"), true, false);
  expect_round_trip(m, dir.file("m.inp"), true, false);
  expect_round_trip(m, dir.file("m.mesh"), true, false);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"m.inp", "m.mesh", "m.msh", "m.vtu"}));
}

TEST(MeshIo, RoundTrip3dEveryFormat) {
  TempDir dir;
  const mesh::Mesh3 m = grid_mesh3(3, 2, 2);
  expect_round_trip(m, dir.file("m.vtu"), true, true);
  expect_round_trip(m, dir.file("m.msh"), true, false);
  expect_round_trip(m, dir.file("m.inp"), true, false);
  expect_round_trip(m, dir.file("m.mesh"), true, false);
}

TEST(MeshIo, ExtensionIsCaseInsensitiveAndUnknownIsInputError) {
  TempDir dir;
  const mesh::Mesh2 m = grid_mesh2(1, 1);
  write_mesh(dir.file("UPPER.VTU"), m, kPhases);
  EXPECT_EQ(read_mesh(dir.file("UPPER.VTU")).mesh2.cell_count(), 2u);
  try {
    write_mesh(dir.file("m.xyz"), m, kPhases);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "");
    EXPECT_EQ(e.problem(), "unknown mesh format '.xyz' (use .vtu, .msh, .inp or .mesh)");
  }
  EXPECT_THROW(read_mesh(dir.file("m.stl")), InputError);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"UPPER.VTU"});
}

TEST(MeshIo, MissingCellDataGetDefaults) {
  TempDir dir;
  mesh::Mesh2 m = grid_mesh2(2, 1);
  m.cell_partition.clear();
  m.node_global_id.clear();
  write_mesh(dir.file("m.vtu"), m, {});
  const LoadedMesh l = read_mesh(dir.file("m.vtu"));
  EXPECT_EQ(l.mesh2.cell_partition, std::vector<std::int32_t>(m.cell_count(), 0));
  EXPECT_EQ(l.mesh2.node_global_id.back(), GlobalId(m.node_count() - 1));
  EXPECT_EQ(l.mesh2.cell_phase, m.cell_phase);
}

// Reads the appended "aspect_ratio" array straight from the bytes of our VTU.
std::vector<double> vtu_aspect_ratios(const std::string& path) {
  const std::string text = read_text(path);
  const std::size_t name = text.find("Name=\"aspect_ratio\"");
  const std::size_t offset_at = text.find("offset=\"", name) + 8;
  const std::size_t offset = std::stoull(text.substr(offset_at));
  const std::size_t base = text.find('_', text.find("<AppendedData encoding=\"raw\">")) + 1;
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, text.data() + base + offset, 8);
  std::vector<double> values(bytes / 8);
  std::memcpy(values.data(), text.data() + base + offset + 8, bytes);
  return values;
}

TEST(MeshIo, VtuAspectRatioIsComputedOrTaken) {
  TempDir dir;
  const mesh::Mesh3 m = grid_mesh3(2, 1, 1);
  write_mesh(dir.file("a.vtu"), m, kPhases);
  const std::vector<double> computed = vtu_aspect_ratios(dir.file("a.vtu"));
  ASSERT_EQ(computed.size(), m.cell_count());
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    EXPECT_EQ(computed[c], mesh::cell_aspect_ratio(m, c));
    EXPECT_GT(computed[c], 1.0);
  }
  MeshWriteOptions options;
  for (std::size_t c = 0; c < m.cell_count(); ++c) options.cell_aspect_ratio.push_back(c + 0.5);
  write_mesh(dir.file("b.vtu"), m, kPhases, options);
  EXPECT_EQ(vtu_aspect_ratios(dir.file("b.vtu")), options.cell_aspect_ratio);
  options.cell_aspect_ratio.pop_back();
  EXPECT_THROW(write_mesh(dir.file("c.vtu"), m, kPhases, options), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.vtu")));
}

// A streamed piece: written before its global ids, finished with them, the bytes write_vtu
// writes for the mesh with those ids; never finished, nothing is left.
TEST(MeshIo, VtuAwaitingIdsWritesWhatWriteVtuWrites) {
  TempDir dir;
  mesh::Mesh3 m = grid_mesh3(2, 2, 1);
  std::vector<GlobalId> ids(m.node_count());
  for (std::size_t n = 0; n < ids.size(); ++n) ids[n] = static_cast<GlobalId>(1000 + 7 * n);
  MeshWriteOptions options;
  for (std::size_t c = 0; c < m.cell_count(); ++c) options.cell_aspect_ratio.push_back(1.0 + 0.25 * c);
  m.cell_partition.assign(m.cell_count(), 3);
  {
    VtuAwaitingIds piece(dir.file("late.vtu"), m, kPhases, options);
    EXPECT_FALSE(std::filesystem::exists(dir.file("late.vtu")));
    EXPECT_THROW(piece.finish(std::span<const GlobalId>(ids).first(ids.size() - 1)), std::invalid_argument);
    piece.finish(ids);
    EXPECT_THROW(piece.finish(ids), std::logic_error);
  }
  m.node_global_id = ids;
  write_vtu(dir.file("whole.vtu"), m, kPhases, options);
  EXPECT_EQ(read_text(dir.file("late.vtu")), read_text(dir.file("whole.vtu")));
  { VtuAwaitingIds abandoned(dir.file("abandoned.vtu"), m, kPhases, options); }
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"late.vtu", "whole.vtu"}));  // no temporary left
}

TEST(MeshIo, FormatOptionOverridesTheExtension) {
  TempDir dir;
  MeshWriteOptions options;
  options.format = MeshFormat::msh;  // what "-" (standard output) needs: it has no extension
  write_mesh(dir.file("m.vtu"), grid_mesh2(1, 1), kPhases, options);
  EXPECT_EQ(read_text(dir.file("m.vtu")).rfind("$MeshFormat\n", 0), 0u);
  EXPECT_THROW(write_mesh(dir.file("m.txt"), grid_mesh2(1, 1), kPhases), InputError);
}

TEST(MeshIo, MshDeclaresOnePhysicalGroupPerPhase) {
  TempDir dir;
  write_mesh(dir.file("m.msh"), grid_mesh2(3, 3), kPhases);
  const std::string text = read_text(dir.file("m.msh"));
  EXPECT_EQ(text.rfind("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n", 0), 0u);
  // The phases, then the box faces (dimension 1, tags past the largest phase id).
  EXPECT_NE(text.find("$PhysicalNames\n7\n2 1 \"matrix\"\n2 2 \"glass fiber\"\n2 5 \"pore\"\n"
                      "1 6 \"XMIN\"\n1 7 \"XMAX\"\n1 8 \"YMIN\"\n1 9 \"YMAX\"\n"),
            std::string::npos);
  EXPECT_EQ(text.find("unused"), std::string::npos);
}

TEST(MeshIo, InpHasOneElsetPerPhase) {
  TempDir dir;
  write_mesh(dir.file("m.inp"), grid_mesh3(1, 1, 1), kPhases);
  const std::string text = read_text(dir.file("m.inp"));
  EXPECT_NE(text.find("*ELEMENT, TYPE=C3D4, ELSET=matrix\n"), std::string::npos);
  EXPECT_NE(text.find("*ELEMENT, TYPE=C3D4, ELSET=glass_fiber\n"), std::string::npos);
}

// ---- files written by other tools ----

TEST(MeshIo, ReadsMsh22WithLinesAndPoints) {
  TempDir dir;
  const std::string path = dir.write("a.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
1 10 "boundary"
2 7 "rubber"
$EndPhysicalNames
$Nodes
4
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
$EndNodes
$Elements
4
1 15 2 0 1 1
2 1 2 10 1 1 2
3 2 2 7 1 1 2 3
4 2 2 0 2 1 3 4
$EndElements
)");
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, 2);
  EXPECT_EQ(l.mesh2.cell_nodes, (std::vector<LocalId>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(l.mesh2.cell_phase, (std::vector<std::int32_t>{7, 1}));
  ASSERT_EQ(l.phases.size(), 2u);
  EXPECT_EQ(l.phases[0].name, "phase1");
  EXPECT_EQ(l.phases[1].name, "rubber");
}

TEST(MeshIo, ReadsMsh41WithEntitiesSkippingBoundaryTriangles) {
  TempDir dir;
  const std::string path = dir.write("b.msh", R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
1
3 4 "steel"
$EndPhysicalNames
$Entities
1 0 1 1
1 0 0 0 0
1 0 0 0 1 1 0 0 0
1 0 0 0 1 1 1 1 4 0
$EndEntities
$Nodes
2 5 1 5
0 1 0 1
1
0 0 0
3 1 0 4
5
3
2
4
0 0 1
0 1 0
1 0 0
1 1 1
$EndNodes
$Elements
2 3 1 7
2 1 2 1
1 1 2 3
3 1 4 2
7 1 2 3 5
3 2 3 5 4
$EndElements
$NodeData
1
"temperature"
$EndNodeData
)");
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, 3);
  EXPECT_EQ(l.mesh3.cell_nodes, (std::vector<LocalId>{1, 2, 4, 3, 0, 1, 2, 4}));
  EXPECT_EQ(l.mesh3.cell_phase, (std::vector<std::int32_t>{4, 4}));
  EXPECT_EQ(l.mesh3.point(4), (Vec3{0, 0, 1}));
  EXPECT_EQ(l.mesh3.point(1), (Vec3{1, 0, 0}));
  ASSERT_EQ(l.phases.size(), 1u);
  EXPECT_EQ(l.phases[0].name, "steel");
}

TEST(MeshIo, ReadsAsciiVtuAsWrittenByMeshio) {
  TempDir dir;
  const std::string path = dir.write("c.vtu", R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
<!-- This file was created by meshio -->
<UnstructuredGrid>
<Piece NumberOfPoints="4" NumberOfCells="3">
<Points>
<DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">
0.0 0.0 0.0
1.0 0.0 0.0
1.0 1.0 0.0
0.0 1.0 0.0
</DataArray>
</Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">
0 1 0 1 2 0 2 3
</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">
2 5 8
</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">
3 5 5
</DataArray>
</Cells>
<CellData>
<DataArray type="Int32" Name="gmsh:physical" format="ascii">
9 3 4
</DataArray>
</CellData>
</Piece>
</UnstructuredGrid>
</VTKFile>
)");
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, 2);
  EXPECT_EQ(l.mesh2.cell_nodes, (std::vector<LocalId>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(l.mesh2.cell_phase, (std::vector<std::int32_t>{3, 4}));
  EXPECT_EQ(l.mesh2.coords, (std::vector<double>{0, 0, 1, 0, 1, 1, 0, 1}));
}

std::string base64(const void* data, std::size_t size) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = static_cast<const unsigned char*>(data);
  std::string out;
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t v = (std::uint32_t(b[i]) << 16) | (i + 1 < size ? std::uint32_t(b[i + 1]) << 8 : 0) |
                            (i + 2 < size ? std::uint32_t(b[i + 2]) : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < size ? kAlphabet[v & 63] : '=';
  }
  return out;
}

// VTK writes the header and the data as two base64 runs; other writers as one.
template <class T>
std::string binary_array(const std::vector<T>& values, bool joint) {
  const std::uint32_t bytes = static_cast<std::uint32_t>(values.size() * sizeof(T));
  if (!joint) return base64(&bytes, 4) + base64(values.data(), bytes);
  std::string all(reinterpret_cast<const char*>(&bytes), 4);
  all.append(reinterpret_cast<const char*>(values.data()), bytes);
  return base64(all.data(), all.size());
}

TEST(MeshIo, ReadsInlineBase64VtuWithUInt32Headers) {
  for (const bool joint : {false, true}) {
    TempDir dir;
    const std::vector<float> points = {0, 0, 0, 2, 0, 0, 0, 0.5f, 0, 0, 0, 3};
    const std::string path = dir.write("d.vtu",
        std::string(R"(<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32">
<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="binary">)") +
            binary_array(points, joint) + R"(</DataArray></Points>
<Cells>
<DataArray type="Int32" Name="connectivity" format="binary">)" +
            binary_array(std::vector<std::int32_t>{0, 1, 2, 3}, joint) + R"(</DataArray>
<DataArray type="Int32" Name="offsets" format="binary">)" +
            binary_array(std::vector<std::int32_t>{4}, joint) + R"(</DataArray>
<DataArray type="UInt8" Name="types" format="binary">)" +
            binary_array(std::vector<std::uint8_t>{10}, joint) + R"(</DataArray>
</Cells>
<CellData><DataArray type="Int64" Name="phase" format="binary">)" +
            binary_array(std::vector<std::int64_t>{6}, joint) + R"(</DataArray></CellData>
</Piece></UnstructuredGrid></VTKFile>
)");
    const LoadedMesh l = read_mesh(path);
    ASSERT_EQ(l.dimension, 3) << joint;
    EXPECT_EQ(l.mesh3.cell_nodes, (std::vector<LocalId>{0, 1, 2, 3})) << joint;
    EXPECT_EQ(l.mesh3.cell_phase, (std::vector<std::int32_t>{6})) << joint;
    EXPECT_EQ(l.mesh3.point(2), (Vec3{0, 0.5, 0})) << joint;
    EXPECT_EQ(l.mesh3.point(3), (Vec3{0, 0, 3})) << joint;
  }
}

TEST(MeshIo, ReadsMeditWithCommentsAndSkippedSections) {
  TempDir dir;
  const std::string flat = dir.write("e.mesh", R"(# written by hand
MeshVersionFormatted 1
Dimension 2
Vertices
3
0 0 1
1 0 1
0 1 1
Edges
1
1 2 5
Corners 1 1
Triangles
1
1 2 3 8
End
)");
  const LoadedMesh a = read_mesh(flat);
  ASSERT_EQ(a.dimension, 2);
  EXPECT_EQ(a.mesh2.cell_phase, (std::vector<std::int32_t>{8}));
  EXPECT_EQ(a.mesh2.coords, (std::vector<double>{0, 0, 1, 0, 0, 1}));

  const std::string solid = dir.write("f.mesh", R"(MeshVersionFormatted 2
Dimension 3
Vertices
4
0 0 0 0
1 0 0 0
0 1 0 0
0 0 1 0
Triangles
1
1 3 2 1
Tetrahedra
1
1 2 3 4 3
End
)");
  const LoadedMesh b = read_mesh(solid);
  ASSERT_EQ(b.dimension, 3);
  EXPECT_EQ(b.mesh3.cell_nodes, (std::vector<LocalId>{0, 1, 2, 3}));
  EXPECT_EQ(b.mesh3.cell_phase, (std::vector<std::int32_t>{3}));
}

TEST(MeshIo, ReadsAbaqusWithoutOurComments) {
  TempDir dir;
  const std::string path = dir.write("g.inp", R"(*Heading
** generated elsewhere
*Node
1, 0., 0.
2, 1., 0.
3, 0., 1.
4, 1., 1.
*Element, type=CPS3, elset=Alpha
1, 1, 2, 3
*Element, type=CPS3, elset=Beta
2, 2, 4, 3
*Elset, elset=All
1, 2
)");
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, 2);
  EXPECT_EQ(l.mesh2.cell_nodes, (std::vector<LocalId>{0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(l.mesh2.cell_phase, (std::vector<std::int32_t>{1, 2}));
  ASSERT_EQ(l.phases.size(), 2u);
  EXPECT_EQ(l.phases[0].name, "Alpha");
  EXPECT_EQ(l.phases[1].name, "Beta");
}

// ---- unreadable meshes ----

void expect_read_error(const std::string& path, const std::string& problem) {
  try {
    read_mesh(path);
    ADD_FAILURE() << path << ": no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  }
}

TEST(MeshIo, UnsupportedContentIsInputError) {
  TempDir dir;
  expect_read_error(dir.file("missing.vtu"), "cannot read");
  expect_read_error(dir.write("q.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n"
                                       "0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 3 1\n1 1 2 3 4\n$EndElements\n"),
                    "unsupported element type 3 (quadrangle)");
  expect_read_error(dir.write("b.msh", "$MeshFormat\n4.1 1 8\n"), "binary data end before the file says they do");
  expect_read_error(dir.write("u.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n"
                                       "$Elements\n1\n1 2 0 1 2 3\n$EndElements\n"),
                    "uses node 2, which is not defined");
  expect_read_error(dir.write("h.inp", "*NODE\n1, 0, 0\n*ELEMENT, TYPE=CPS4, ELSET=a\n1, 1, 1, 1, 1\n"),
                    "unsupported element type 'CPS4'");
  expect_read_error(dir.write("q.mesh", "MeshVersionFormatted 2\nDimension 2\nVertices\n1\n0 0 0\n"
                                        "Quadrilaterals\n1\n1 1 1 1 0\nEnd\n"),
                    "unsupported element type 'Quadrilaterals'");
  expect_read_error(dir.write("x.mesh", "MeshVersionFormatted 2\nDimension 3\nFoo 1\nEnd\n"),
                    "line 3: unknown Medit keyword 'Foo'");
  const std::string cube = R"(<VTKFile type="UnstructuredGrid" byte_order="LittleEndian">
<UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="1">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 1</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">TYPE</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)";
  std::string surface = cube;
  surface.replace(surface.find("TYPE"), 4, "5");
  expect_read_error(dir.write("s.vtu", surface), "triangles outside the plane z = 0");
  std::string hexahedron = cube;
  hexahedron.replace(hexahedron.find("TYPE"), 4, "12");
  expect_read_error(dir.write("hex.vtu", hexahedron), "unsupported cell type 12 (hexahedron)");
  expect_read_error(dir.write("z.vtu", R"(<VTKFile type="UnstructuredGrid" compressor="vtkLZ4DataCompressor"/>)"),
                    "'vtkLZ4DataCompressor' is not supported");
  expect_read_error(dir.write("bad.vtu", R"(<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="1" NumberOfCells="0">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 zero 0</DataArray></Points>
</Piece></UnstructuredGrid></VTKFile>)"),
                    "expected a number, got 'zero'");
}

// ---- input that must be refused, not followed (found by fuzzing) ----

std::string read_error(const std::string& path) {
  try {
    read_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// Our own 2D VTU (raw appended, UInt64 headers) of two triangles.
std::string small_vtu(const TempDir& dir) {
  mesh::Mesh2 m;
  m.coords = {0, 0, 1, 0, 0, 1, 1, 1};
  m.cell_nodes = {0, 1, 2, 1, 3, 2};
  m.cell_phase = {1, 1};
  const std::string path = dir.file("small.vtu");
  write_mesh(path, m, {{1, "matrix", false}});
  return read_text(path);
}

TEST(MeshIo, AppendedSizeNear2To64IsRefusedNotFollowed) {
  TempDir dir;
  // The connectivity block's UInt64 size 2^64 - 8 wrapped the bounds check around; the
  // offsets then sent the reader 4 GB past the mapped file (SIGSEGV).
  std::string text = R"(<VTKFile type="UnstructuredGrid" byte_order="LittleEndian" header_type="UInt64">
<UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="appended" offset="0"/>
<DataArray type="Int64" Name="offsets" format="ascii">999999997 1000000000</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">1 5</DataArray></Cells>
</Piece></UnstructuredGrid>
<AppendedData encoding="raw">_)";
  const std::uint64_t huge = ~std::uint64_t{0} - 7;
  const std::int32_t nodes[3] = {0, 1, 2};
  text.append(reinterpret_cast<const char*>(&huge), 8);
  text.append(reinterpret_cast<const char*>(nodes), 12);
  text += "\n</AppendedData></VTKFile>\n";
  EXPECT_NE(read_error(dir.write("wrap.vtu", text)).find("more than the file holds"), std::string::npos);
}

TEST(MeshIo, VtuSizeAttributesAreCheckedNumbers) {
  TempDir dir;
  const std::string text = small_vtu(dir);
  for (const std::string& bad : {"x", "", "-1", "99999999999999999999", "18446744073709551615", "1000000"}) {
    std::string points = text, offset = text;
    points.replace(points.find("NumberOfPoints=\"4\""), 18, "NumberOfPoints=\"" + bad + "\"");
    const std::string first = read_error(dir.write("p.vtu", points));
    EXPECT_NE(first.find("NumberOfPoints"), std::string::npos) << bad << ": " << first;
    const std::size_t at = offset.find("offset=\"0\"");
    ASSERT_NE(at, std::string::npos);
    offset.replace(at, 10, "offset=\"" + bad + "\"");
    const std::string second = read_error(dir.write("o.vtu", offset));
    EXPECT_NE(second.find("offset"), std::string::npos) << bad << ": " << second;
  }
}

TEST(MeshIo, CountsBeyondTheFileAreRefusedBeforeAllocating) {
  TempDir dir;
  EXPECT_NE(read_error(dir.write("v.mesh", "MeshVersionFormatted 2\nDimension 3\nVertices\n1000000000000000000\n0 0 0 0\n"))
                .find("Vertices count 1000000000000000000 is more than the rest of the file holds"),
            std::string::npos);
  EXPECT_NE(read_error(dir.write("n.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1000000000000000000 1 1\n"))
                .find("$Nodes count"),
            std::string::npos);
}

TEST(MeshIo, FilesWithoutCellsAreNotMeshes) {
  TempDir dir;
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"empty.inp", ""},
           {"text.inp", "just some text\n"},
           {"dim.mesh", "MeshVersionFormatted 2\nDimension 3\nEnd\n"},
           {"none.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n0\n$EndElements\n"}}) {
    EXPECT_NE(read_error(dir.write(name, text)).find("no triangles or tetrahedra"), std::string::npos) << name;
  }
}

TEST(MeshIo, ExtremeElementTagsSortWithoutOverflow) {
  TempDir dir;
  const LoadedMesh l = read_mesh(dir.write("tags.inp", R"(*NODE
1, 0, 0
2, 1, 0
3, 0, 1
4, 1, 1
*ELEMENT, TYPE=CPS3
9223372036854775807, 2, 4, 3
-9223372036854775808, 1, 2, 3
)"));
  EXPECT_EQ(l.mesh2.cell_nodes, (std::vector<LocalId>{0, 1, 2, 1, 3, 2}));
}

TEST(MeshIo, RealConnectivityIsRefused) {
  TempDir dir;
  const std::string what = read_error(dir.write("r.vtu", R"(<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="1">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Cells><DataArray type="Float64" Name="connectivity" format="ascii">0 1 1e300</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)"));
  EXPECT_NE(what.find("must be integer arrays"), std::string::npos) << what;
}

}  // namespace
}  // namespace cisamr::io
