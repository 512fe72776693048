// Cohesive cells through the writers and readers (docs/cohesive-design.md §2.4, §6.1): .vtu,
// .msh, .inp and .pvtu give back every cohesive cell (internal node order, through the
// inverse of mesh::CohesiveOrder) with the phases they were written with, node_phase, and
// the element sets; quads and prisms that a file does not mark cohesive are still refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "io/mesh_io.hpp"
#include "mesh/cohesive.hpp"
#include "mesh/metrics.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::read_text;
using testing::TempDir;

// Names with a blank and a dash: the set names are their Abaqus labels.
const std::vector<geometry::Phase> kPhases = {
    {1, "matrix", false}, {2, "glass fiber", false}, {7, "pore-filler", false}};

// The phase of a cell by its centroid: two boxes in a matrix, touching each other along x
// = 0.5 (so phases 2 and 7 meet too, and there are triple points or lines).
template <int Dim>
std::int32_t phase_at(const Vec<Dim>& c) {
  const bool in_band = c[1] > 0.3 && c[1] < 0.8 && (Dim == 2 || (c[Dim - 1] > 0.2 && c[Dim - 1] < 0.7));
  if (in_band && c[0] > 0.2 && c[0] < 0.5) return 2;
  if (in_band && c[0] >= 0.5 && c[0] < 0.8) return 7;
  return 1;
}

template <int Dim>
void set_phases(mesh::SimplexMesh<Dim>& m) {
  m.cell_phase.clear();
  for (std::size_t c = 0; c < m.cell_nodes.size() / (Dim + 1); ++c) {
    Vec<Dim> centroid{};
    for (int k = 0; k <= Dim; ++k)
      for (int d = 0; d < Dim; ++d) centroid[d] += m.point(m.cell_nodes[c * (Dim + 1) + k])[d] / (Dim + 1);
    m.cell_phase.push_back(phase_at<Dim>(centroid));
  }
  m.cell_partition.assign(m.cell_phase.size(), 0);
}

// A 10×10 square of triangles, split with cohesive cells; partitions that are not 0.
mesh::Mesh2 cohesive_mesh2() {
  mesh::Mesh2 m;
  const int n = 10;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.coords.insert(m.coords.end(), {i / double(n), j / double(n)});
  const auto node = [&](int i, int j) { return LocalId(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.cell_nodes.insert(m.cell_nodes.end(), {node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j), node(i + 1, j + 1),
                                               node(i, j + 1)});
  set_phases(m);
  mesh::insert_cohesive(m, 3);
  for (std::size_t c = 0; c < m.cohesive.count(); ++c) m.cohesive.partition[c] = static_cast<std::int32_t>(c % 4);
  return m;
}

// A 5×5×5 cube of cubes, 6 positive tetrahedra each, split with cohesive cells.
mesh::Mesh3 cohesive_mesh3() {
  mesh::Mesh3 m;
  const int n = 5;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.coords.insert(m.coords.end(), {i / double(n), j / double(n), k / double(n)});
  const auto node = [&](int i, int j, int k) { return LocalId((k * (n + 1) + j) * (n + 1) + i); };
  const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : permutations) {
          int at[3] = {i, j, k};
          std::array<LocalId, 4> t;
          t[0] = node(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[p[s]];
            t[s + 1] = node(at[0], at[1], at[2]);
          }
          if (mesh::signed_volume(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])) < 0) std::swap(t[2], t[3]);
          m.cell_nodes.insert(m.cell_nodes.end(), t.begin(), t.end());
        }
  set_phases(m);
  mesh::insert_cohesive(m, 0);
  return m;
}

template <int Dim>
const mesh::SimplexMesh<Dim>& loaded(const LoadedMesh& l) {
  if constexpr (Dim == 2) return l.mesh2;
  else return l.mesh3;
}

// A cohesive cell as (its nodes in internal order, bottom phase, top phase).
template <int Dim>
std::multiset<std::tuple<std::vector<LocalId>, std::int32_t, std::int32_t>> cohesive_cells(const mesh::SimplexMesh<Dim>& m) {
  std::multiset<std::tuple<std::vector<LocalId>, std::int32_t, std::int32_t>> cells;
  for (std::size_t c = 0; c < m.cohesive.count(); ++c)
    cells.emplace(std::vector<LocalId>(m.cohesive.cell(c), m.cohesive.cell(c) + 2 * Dim), m.cohesive.phase[2 * c],
                  m.cohesive.phase[2 * c + 1]);
  return cells;
}

template <int Dim>
void expect_same_bulk(const mesh::SimplexMesh<Dim>& r, const mesh::SimplexMesh<Dim>& m, const std::string& path) {
  ASSERT_EQ(r.coords.size(), m.coords.size()) << path;
  EXPECT_EQ(std::memcmp(r.coords.data(), m.coords.data(), m.coords.size() * sizeof(double)), 0) << path;
  EXPECT_EQ(r.cell_nodes, m.cell_nodes) << path;
  EXPECT_EQ(r.cell_phase, m.cell_phase) << path;
  EXPECT_EQ(r.node_phase, m.node_phase) << path;
}

template <int Dim>
void expect_vtu_round_trip(const mesh::SimplexMesh<Dim>& m, const TempDir& dir) {
  ASSERT_GT(m.cohesive.count(), 0u);
  const std::string path = dir.file("m.vtu");
  write_mesh(path, m, kPhases);
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, Dim);
  const mesh::SimplexMesh<Dim>& r = loaded<Dim>(l);
  expect_same_bulk(r, m, path);
  // VTU keeps the cells' order: everything comes back as it was.
  EXPECT_EQ(r.cohesive.nodes, m.cohesive.nodes);
  EXPECT_EQ(r.cohesive.phase, m.cohesive.phase);
  EXPECT_EQ(r.cohesive.partition, m.cohesive.partition);
  EXPECT_TRUE(l.cohesive_sets.empty());
  EXPECT_TRUE(l.cohesive_set_of_cell.empty());
}

// .msh and .inp group the cells by phase pair: the same cells, in another order, each in
// the one set named for its phases.
template <int Dim>
void expect_grouped_round_trip(const mesh::SimplexMesh<Dim>& m, const std::string& path) {
  write_mesh(path, m, kPhases);
  const LoadedMesh l = read_mesh(path);
  ASSERT_EQ(l.dimension, Dim) << path;
  const mesh::SimplexMesh<Dim>& r = loaded<Dim>(l);
  expect_same_bulk(r, m, path);
  EXPECT_EQ(cohesive_cells(r), cohesive_cells(m)) << path;
  std::set<std::string> names;
  for (const auto& set : l.cohesive_sets) names.insert(set.name);
  EXPECT_EQ(names, (std::set<std::string>{"COH_matrix_glass_fiber", "COH_matrix_pore-filler", "COH_glass_fiber_pore-filler"}))
      << path;
  ASSERT_EQ(l.cohesive_set_of_cell.size(), r.cohesive.count()) << path;
  for (std::size_t c = 0; c < r.cohesive.count(); ++c) {
    const std::int32_t set = l.cohesive_set_of_cell[c];
    ASSERT_GE(set, 0) << path;
    const auto& pairs = l.cohesive_sets[static_cast<std::size_t>(set)].named_pairs;
    ASSERT_EQ(pairs.size(), 1u) << path;
    EXPECT_EQ(pairs[0], (std::array<std::int32_t, 2>{r.cohesive.phase[2 * c], r.cohesive.phase[2 * c + 1]})) << path;
  }
}

TEST(CohesiveIo, VtuKeepsEveryCohesiveArray) {
  TempDir dir;
  expect_vtu_round_trip(cohesive_mesh2(), dir);
  expect_vtu_round_trip(cohesive_mesh3(), dir);
}

TEST(CohesiveIo, MshAndInpKeepTheCellsPhasesAndSets) {
  TempDir dir;
  const mesh::Mesh2 m2 = cohesive_mesh2();
  const mesh::Mesh3 m3 = cohesive_mesh3();
  // Every pair of the three phases meets.
  std::set<std::pair<int, int>> pairs;
  for (std::size_t c = 0; c < m3.cohesive.count(); ++c) pairs.emplace(m3.cohesive.phase[2 * c], m3.cohesive.phase[2 * c + 1]);
  EXPECT_EQ(pairs, (std::set<std::pair<int, int>>{{1, 2}, {1, 7}, {2, 7}}));
  expect_grouped_round_trip(m2, dir.file("m.msh"));
  expect_grouped_round_trip(m2, dir.file("m.inp"));
  expect_grouped_round_trip(m3, dir.file("m.msh"));
  expect_grouped_round_trip(m3, dir.file("m.inp"));
}

// Two .vtu pieces of one mesh under a .pvtu: the copies merge by global_id only, so every
// cohesive cell comes back with its nodes' global ids.
TEST(CohesiveIo, PvtuMergesPiecesByGlobalId) {
  TempDir dir;
  mesh::Mesh3 whole = cohesive_mesh3();
  whole.node_global_id.resize(whole.node_count());
  for (std::size_t n = 0; n < whole.node_count(); ++n) whole.node_global_id[n] = 100 + 2 * GlobalId(n);
  // Piece k: the bulk cells of one half of the list, the cohesive cells of one half, and
  // every node (unused nodes are harmless to the merge).
  for (int k = 0; k < 2; ++k) {
    mesh::Mesh3 piece = whole;
    const std::size_t cells = whole.cell_count(), cohesive = whole.cohesive.count();
    const std::size_t c0 = k * cells / 2, c1 = (k + 1) * cells / 2, h0 = k * cohesive / 2, h1 = (k + 1) * cohesive / 2;
    piece.cell_nodes.assign(whole.cell_nodes.begin() + 4 * c0, whole.cell_nodes.begin() + 4 * c1);
    piece.cell_phase.assign(whole.cell_phase.begin() + c0, whole.cell_phase.begin() + c1);
    piece.cell_partition.assign(c1 - c0, k);
    piece.cohesive.nodes.assign(whole.cohesive.nodes.begin() + 6 * h0, whole.cohesive.nodes.begin() + 6 * h1);
    piece.cohesive.phase.assign(whole.cohesive.phase.begin() + 2 * h0, whole.cohesive.phase.begin() + 2 * h1);
    piece.cohesive.partition.assign(h1 - h0, k);
    write_vtu(dir.file("p" + std::to_string(k) + ".vtu"), piece, kPhases);
  }
  const std::string pvtu = dir.write("m.pvtu", pvtu_text({"p0.vtu", "p1.vtu"}));
  const LoadedMesh l = read_mesh(pvtu);
  const mesh::Mesh3& r = l.mesh3;
  ASSERT_EQ(r.node_count(), whole.node_count());
  ASSERT_EQ(r.cohesive.count(), whole.cohesive.count());
  for (std::size_t c = 0; c < r.cohesive.count(); ++c)
    for (int k = 0; k < 6; ++k)
      EXPECT_EQ(r.node_global_id[r.cohesive.cell(c)[k]], whole.node_global_id[whole.cohesive.cell(c)[k]]);
  EXPECT_EQ(r.cohesive.phase, whole.cohesive.phase);
  for (std::size_t n = 0; n < r.node_count(); ++n)
    EXPECT_EQ(r.node_phase[n], whole.node_phase[static_cast<std::size_t>((r.node_global_id[n] - 100) / 2)]);

  // Without global_id the copies would be welded by their coordinates: refused.
  std::string piece = read_text(dir.file("p1.vtu"));
  piece = std::regex_replace(piece, std::regex("<DataArray type=\"Int64\" Name=\"global_id\"[^>]*/>"), "");
  dir.write("p1.vtu", piece);
  try {
    read_mesh(pvtu);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), pvtu);
    EXPECT_EQ(e.field(), "global_id");
    EXPECT_NE(e.problem().find("would weld the copies"), std::string::npos) << e.what();
  }
}

// An .inp of another origin: no "** cisamr" comments, the phases read from the set names.
TEST(CohesiveIo, InpPhasesComeFromTheCommentOrElseTheSetName) {
  TempDir dir;
  const std::string nodes = "*NODE\n1, 0, 0\n2, 1, 0\n3, 0, 1\n4, 1, 0\n5, 0, 1\n6, 1, 1\n";
  const std::string bulk = "*ELEMENT, TYPE=CPS3, ELSET=Soft\n1, 1, 2, 3\n*ELEMENT, TYPE=CPS3, ELSET=Hard\n2, 4, 6, 5\n";
  const LoadedMesh foreign = read_mesh(dir.write("f.inp", nodes + bulk + "*ELEMENT, TYPE=COH2D4, ELSET=COH_SOFT_HARD\n3, 3, 2, 4, 5\n"));
  ASSERT_EQ(foreign.mesh2.cohesive.count(), 1u);
  EXPECT_EQ(foreign.mesh2.cohesive.phase, (std::vector<std::int32_t>{1, 2}));
  // Abaqus order 1-2 bottom, 3-4 top with 4 over 1: internal b0 b1 t0 t1 = 3 2 5 4 (0-based 2 1 4 3).
  EXPECT_EQ(foreign.mesh2.cohesive.nodes, (std::vector<LocalId>{2, 1, 4, 3}));
  EXPECT_EQ(foreign.mesh2.node_phase, (std::vector<std::int32_t>{1, 1, 1, 2, 2, 2}));
  ASSERT_EQ(foreign.cohesive_sets.size(), 1u);
  EXPECT_EQ(foreign.cohesive_sets[0].named_pairs, (std::vector<std::array<std::int32_t, 2>>{{1, 2}}));

  // Our comment's claim is taken as it stands, even where the set's name denotes another pair.
  const LoadedMesh claimed = read_mesh(dir.write(
      "c.inp", nodes + bulk + "** cisamr cohesive 2 1 COH_SOFT_HARD\n*ELEMENT, TYPE=COH2D4, ELSET=COH_SOFT_HARD\n3, 3, 2, 4, 5\n"));
  EXPECT_EQ(claimed.mesh2.cohesive.phase, (std::vector<std::int32_t>{2, 1}));
  EXPECT_EQ(claimed.cohesive_sets[0].named_pairs, (std::vector<std::array<std::int32_t, 2>>{{1, 2}}));

  // A cell listed again by a COH_ *ELSET of another name is in two sets; one in none.
  const LoadedMesh several = read_mesh(dir.write(
      "s.inp", nodes + bulk + "*ELEMENT, TYPE=COH2D4, ELSET=COH_SOFT_HARD\n3, 3, 2, 4, 5\n*ELEMENT, TYPE=COH2D4\n4, 3, 2, 4, 5\n"
                              "*ELSET, ELSET=COH_OTHER\n3\n"));
  EXPECT_EQ(several.cohesive_set_of_cell,
            (std::vector<std::int32_t>{LoadedMesh::kSeveralCohesiveSets, LoadedMesh::kNoCohesiveSet}));
  ASSERT_EQ(several.cohesive_sets.size(), 2u);
  EXPECT_TRUE(several.cohesive_sets[1].named_pairs.empty());
}

// What certify's periodic frame needs without a scene: the axes the file's constraints
// tie, from each format's own constraints.
TEST(CohesiveIo, PeriodicAxesComeFromTheFilesConstraints) {
  TempDir dir;
  const mesh::Mesh2 m = cohesive_mesh2();  // a square grid: every face node has its translate
  for (const std::array<bool, 3>& axes : {std::array<bool, 3>{true, true, false}, std::array<bool, 3>{false, true, false},
                                          std::array<bool, 3>{false, false, false}})
    for (const char* name : {"p.vtu", "p.msh", "p.inp"}) {
      MeshWriteOptions options;
      options.periodic = axes;
      write_mesh(dir.file(name), m, kPhases, options);
      const LoadedMesh l = read_mesh(dir.file(name));
      EXPECT_EQ(l.periodic_axes, axes) << name;
      EXPECT_EQ(l.any_periodic(), axes[0] || axes[1]) << name;
      EXPECT_EQ(l.mesh2.cohesive.count(), m.cohesive.count()) << name;
    }
}

// A copy in no bulk cell (a periodic master only the join made) takes its phase from the
// side of the cohesive cell it is on, where the file has no node_phase.
TEST(CohesiveIo, NodePhaseOfACopyInNoBulkCellComesFromItsCohesiveCell) {
  TempDir dir;
  const LoadedMesh l = read_mesh(dir.write(
      "o.inp", "*NODE\n1, 0, 0\n2, 1, 0\n3, 0, 1\n4, 0, 0\n5, 0, 1\n*ELEMENT, TYPE=CPS3, ELSET=A\n1, 1, 2, 3\n"
               "** cisamr cohesive 1 4 COH_A_B\n*ELEMENT, TYPE=COH2D4, ELSET=COH_A_B\n2, 3, 1, 4, 5\n"));
  EXPECT_EQ(l.mesh2.cohesive.phase, (std::vector<std::int32_t>{1, 4}));
  EXPECT_EQ(l.mesh2.node_phase, (std::vector<std::int32_t>{1, 1, 1, 4, 4}));
}

void expect_read_error(const std::string& path, const std::string& problem) {
  try {
    read_mesh(path);
    FAIL() << "expected InputError for " << path;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  }
}

// A quad or prism the file does not mark cohesive is what it was before cohesive cells
// existed: an unsupported element.
TEST(CohesiveIo, UnmarkedQuadsAndPrismsAreStillRefused) {
  TempDir dir;
  const std::string grid = R"(<VTKFile type="UnstructuredGrid" byte_order="LittleEndian">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 1 1 0 0 1 0 2 0 0</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">1 4 2 0 1 2 3</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3 7</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5 9</DataArray></Cells>
CELLDATA</Piece></UnstructuredGrid></VTKFile>)";
  const auto vtu = [&](const std::string& name, const std::string& cell_data) {
    std::string text = grid;
    text.replace(text.find("CELLDATA"), 8, cell_data);
    return dir.write(name, text);
  };
  expect_read_error(vtu("plain.vtu", ""), "unsupported cell type 9 (quad)");
  expect_read_error(vtu("zero.vtu", R"(<CellData><DataArray type="UInt8" Name="cohesive" format="ascii">0 0</DataArray></CellData>)"),
                    "unsupported cell type 9 (quad)");
  expect_read_error(vtu("two.vtu", R"(<CellData><DataArray type="UInt8" Name="cohesive" format="ascii">0 2</DataArray></CellData>)"),
                    "is not 0 or 1");
  expect_read_error(vtu("tri.vtu", R"(<CellData><DataArray type="UInt8" Name="cohesive" format="ascii">1 1</DataArray></CellData>)"),
                    "cell 0 is marked cohesive but has type 5");
  // Marked: read as a cohesive cell, with phase 0 where the file names none.
  const LoadedMesh marked =
      read_mesh(vtu("marked.vtu", R"(<CellData><DataArray type="UInt8" Name="cohesive" format="ascii">0 1</DataArray></CellData>)"));
  EXPECT_EQ(marked.mesh2.cell_count(), 1u);
  EXPECT_EQ(marked.mesh2.cohesive.nodes, (std::vector<LocalId>{0, 1, 3, 2}));
  EXPECT_EQ(marked.mesh2.cohesive.phase, (std::vector<std::int32_t>{0, 0}));

  const std::string msh_head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 5 \"NAME\"\n$EndPhysicalNames\n"
                               "$Entities\n0 0 1 0\n1 0 0 0 1 1 0 1 5 0\n$EndEntities\n"
                               "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n"
                               "$Elements\n1 1 1 1\n2 1 3 1\n1 1 2 3 4\n$EndElements\n";
  std::string foreign = msh_head;
  foreign.replace(foreign.find("NAME"), 4, "INTERFACE");
  expect_read_error(dir.write("q.msh", foreign), "unsupported element type 3 (quadrangle)");
  // In a COH_ group: cohesive, but a mesh needs bulk cells.
  std::string cohesive = msh_head;
  cohesive.replace(cohesive.find("NAME"), 4, "COH_A_B");
  expect_read_error(dir.write("c.msh", cohesive), "no triangles or tetrahedra");

  expect_read_error(dir.write("p.inp", "*NODE\n1, 0, 0\n*ELEMENT, TYPE=C3D6, ELSET=a\n1, 1, 1, 1, 1, 1, 1\n"),
                    "unsupported element type 'C3D6'");
  // Cohesive prisms belong with tetrahedra.
  expect_read_error(dir.write("w.inp", "*NODE\n1, 0, 0\n2, 1, 0\n3, 0, 1\n*ELEMENT, TYPE=CPS3\n1, 1, 2, 3\n"
                                       "*ELEMENT, TYPE=COH3D6\n2, 1, 2, 3, 1, 2, 3\n"),
                    "cohesive prisms (wedges) in a triangle mesh");
}

}  // namespace
}  // namespace cisamr::io
