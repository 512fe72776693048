// Periodic constraints written with the mesh (issue 12, item 4; docs/periodic-design.md §5):
//  - mesh::periodic_links on hand-made periodic meshes (2D grid, 3D tet lattices of 5 and 6
//    tets per cube, one or every axis periodic, an origin off zero), and its failure on a
//    mesh that is not periodic;
//  - the rules on every written .inp (periodic_rules.hpp, parsed here, not by lib/io), the
//    .msh $Periodic and the .vtu periodic_master read back, on real 2D periodic meshes
//    (tests/support periodic_scene) and the 3D lattices;
//  - the exact .inp text of a tiny case; non-periodic output carries none of it.
#include "mesh/periodic_links.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "core/error.hpp"
#include "driver/driver.hpp"
#include "geometry/oracle.hpp"
#include "io/mesh_io.hpp"
#include "mesh/metrics.hpp"
#include "parallel/output.hpp"
#include "periodic_rules.hpp"
#include "pipeline/pipeline.hpp"
#include "support/random_scenes.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::TempDir;
using testing::read_text;

// A structured mesh of n^Dim cells of size h from `origin`, coordinates as the lattice
// makes them (origin + i·h, so the max face is fl(origin + n·h) = fl(min + T)). 2D: two
// triangles per square; 3D: 6 tetrahedra around the main diagonal (Kuhn), or 5 with the
// parity alternating (needs even n to be periodic).
template <int Dim>
mesh::SimplexMesh<Dim> lattice_mesh(int n, double origin, double h, bool five = false) {
  mesh::SimplexMesh<Dim> m;
  const int v = n + 1;
  const auto id = [&](std::array<int, Dim> i) {
    int k = 0;
    for (int d = Dim - 1; d >= 0; --d) k = k * v + i[d];
    return static_cast<LocalId>(k);
  };
  const int total = static_cast<int>(std::pow(v, Dim));
  for (int k = 0; k < total; ++k) {
    int r = k;
    for (int d = 0; d < Dim; ++d, r /= v) m.coords.push_back(origin + static_cast<double>(r % v) * h);
  }
  const auto add = [&](std::array<std::array<int, Dim>, Dim + 1> c) {
    std::array<Vec<Dim>, Dim + 1> p;
    for (int k = 0; k <= Dim; ++k) p[k] = m.point(id(c[k]));
    double vol;
    if constexpr (Dim == 2) vol = mesh::signed_area(p[0], p[1], p[2]);
    else vol = mesh::signed_volume(p[0], p[1], p[2], p[3]);
    if (vol < 0) std::swap(c[0], c[1]);
    for (const auto& i : c) m.cell_nodes.push_back(id(i));
    m.cell_phase.push_back(1);
  };
  const int cells = static_cast<int>(std::pow(n, Dim));
  for (int k = 0; k < cells; ++k) {
    std::array<int, Dim> o;
    int r = k;
    for (int d = 0; d < Dim; ++d, r /= n) o[d] = r % n;
    const auto at = [&](std::array<int, Dim> local) {
      for (int d = 0; d < Dim; ++d) local[d] += o[d];
      return local;
    };
    if constexpr (Dim == 2) {
      add({at({0, 0}), at({1, 0}), at({1, 1})});
      add({at({0, 0}), at({1, 1}), at({0, 1})});
    } else if (!five) {
      const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
      for (const auto& p : perms) {
        std::array<int, 3> a{0, 0, 0}, b = a, c = a;
        b[p[0]] = 1;
        c = b, c[p[1]] = 1;
        add({at({0, 0, 0}), at(b), at(c), at({1, 1, 1})});
      }
    } else {
      const int parity = (o[0] + o[1] + o[2]) & 1;
      std::array<std::array<int, 3>, 4> centre;
      int k2 = 0;
      for (int c = 0; c < 8; ++c) {
        const std::array<int, 3> x{c & 1, (c >> 1) & 1, (c >> 2) & 1};
        if (((x[0] + x[1] + x[2] + parity) & 1) == 0) {
          centre[static_cast<std::size_t>(k2++)] = at(x);
        } else {
          std::array<std::array<int, 3>, 4> t{at(x), at(x), at(x), at(x)};
          for (int d = 0; d < 3; ++d) t[static_cast<std::size_t>(d + 1)][d] += x[d] ? -1 : 1;
          add(t);
        }
      }
      add(centre);
    }
  }
  return m;
}

template <int Dim>
Box<Dim> lattice_box(int n, double origin, double h) {
  Box<Dim> b;
  for (int d = 0; d < Dim; ++d) b.min[d] = origin, b.max[d] = origin + static_cast<double>(n) * h;
  return b;
}

template <int Dim>
MeshWriteOptions periodic_options(const Box<Dim>& faces, const std::array<bool, Dim>& axes,
                                  const std::array<double, Dim>& period) {
  MeshWriteOptions o;
  o.face_box = Box3{};
  for (int d = 0; d < Dim; ++d) {
    o.face_box->min[d] = faces.min[d], o.face_box->max[d] = faces.max[d];
    o.periodic[static_cast<std::size_t>(d)] = axes[static_cast<std::size_t>(d)];
    o.period[static_cast<std::size_t>(d)] = period[static_cast<std::size_t>(d)];
  }
  return o;
}

// ---- mesh::periodic_links

TEST(PeriodicLinks, SquareGridBothAxes) {
  const mesh::Mesh2 m = lattice_mesh<2>(2, 0.0, 1.0);  // nodes k = x + 3y
  const auto links = mesh::periodic_links<2>(m, lattice_box<2>(2, 0, 1), {true, true});
  ASSERT_EQ(links.slaves.size(), 5u);  // (2,0) (2,1) (0,2) (1,2) (2,2)
  const LocalId expect_node[] = {2, 5, 6, 7, 8}, expect_master[] = {0, 3, 0, 1, 0};
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(links.slaves[k].node, expect_node[k]);
    EXPECT_EQ(links.slaves[k].master, expect_master[k]);
  }
  // The far corner: x-master (0,2), y-master (2,0), full master CORNER0.
  EXPECT_EQ(links.slaves[4].shift, 3);
  EXPECT_EQ(links.slaves[4].axis_master[0], 6);
  EXPECT_EQ(links.slaves[4].axis_master[1], 2);
  EXPECT_EQ(links.slaves[0].axis_master[1], -1);
}

TEST(PeriodicLinks, OneAxisOnlyAndNoneAtAll) {
  const mesh::Mesh2 m = lattice_mesh<2>(3, 0.1, 0.3);
  const auto x = mesh::periodic_links<2>(m, lattice_box<2>(3, 0.1, 0.3), {true, false});
  EXPECT_EQ(x.slaves.size(), 4u);
  for (const auto& s : x.slaves) EXPECT_EQ(s.shift, 1);
  EXPECT_TRUE(mesh::periodic_links<2>(m, lattice_box<2>(3, 0.1, 0.3), {false, false}).slaves.empty());
}

TEST(PeriodicLinks, TetLatticesFiveAndSixPerCube) {
  for (bool five : {false, true}) {
    SCOPED_TRACE(five ? "5 tets per cube" : "6 tets per cube");
    const mesh::Mesh3 m = lattice_mesh<3>(2, 0.1, 0.3, five);
    EXPECT_EQ(m.cell_count(), five ? 40u : 48u);
    const Box3 faces = lattice_box<3>(2, 0.1, 0.3);
    const auto links = mesh::periodic_links<3>(m, faces, {true, true, true});
    EXPECT_EQ(links.slaves.size(), 27u - 8u);
    const auto& corner = links.slaves.back();
    EXPECT_EQ(corner.node, 26);
    EXPECT_EQ(corner.shift, 7);
    EXPECT_EQ(corner.master, 0);  // CORNER0
    EXPECT_EQ(corner.axis_master[0], 24);  // (0, 2, 2)
    const auto z = mesh::periodic_links<3>(m, faces, {false, false, true});
    EXPECT_EQ(z.slaves.size(), 9u);
  }
}

TEST(PeriodicLinks, AMeshThatIsNotPeriodicIsRefusedNamingTheNode) {
  mesh::Mesh2 m = lattice_mesh<2>(2, 0.0, 1.0);
  m.coords[2 * 5 + 1] = std::nextafter(1.0, 2.0);  // node (2, 1) off its translate by one ulp
  try {
    mesh::periodic_links<2>(m, lattice_box<2>(2, 0, 1), {true, true});
    FAIL() << "no error";
  } catch (const MeshingError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("node 5"), std::string::npos) << what;
    EXPECT_NE(what.find("1.0000000000000002"), std::string::npos) << what;
    EXPECT_NE(what.find("not periodic"), std::string::npos) << what;
  }
  // In a scene with voids a node without translate is a free surface across the period
  // (a void fills the other side): not a slave, no constraint.
  const auto lenient = mesh::periodic_links<2>(m, lattice_box<2>(2, 0, 1), {true, true}, true);
  ASSERT_EQ(lenient.unpaired.size(), 1u);
  EXPECT_EQ(lenient.unpaired[0], 5);
  EXPECT_EQ(lenient.slaves.size(), 4u);
  // The writers say the same.
  TempDir dir;
  EXPECT_THROW(write_mesh<2>(dir.file("m.inp"), m, {}, periodic_options<2>(lattice_box<2>(2, 0, 1), {true, true}, {2, 2})),
               MeshingError);
  EXPECT_TRUE(dir.entries().empty());
}

// ---- the written files on hand-made meshes

TEST(PeriodicOutput, TinyInpText) {
  TempDir dir;
  const mesh::Mesh2 m = lattice_mesh<2>(2, 0.0, 1.0);
  write_mesh<2>(dir.file("m.inp"), m, {}, periodic_options<2>(lattice_box<2>(2, 0, 1), {true, true}, {2, 2}));
  const std::string text = read_text(dir.file("m.inp"));
  // The REF nodes close the *NODE block (meshio reads only one), announced for our reader.
  EXPECT_EQ(text.find("*HEADING\ncisamr mesh: 9 nodes, 8 triangles\n** cisamr periodic reference nodes 10 11\n*NODE\n"), 0u);
  EXPECT_NE(text.find("\n9, 2, 2\n10, 2, 2\n11, 2, 2\n** cisamr phase 1"), std::string::npos);
  const std::string tail = text.substr(text.find("*NSET, NSET=REF_X"));
  EXPECT_EQ(tail,
            "*NSET, NSET=REF_X\n10\n*NSET, NSET=REF_Y\n11\n"
            "*EQUATION\n"
            "3\n3, 1, 1.0, 1, 1, -1.0, 10, 1, -1.0\n3\n3, 2, 1.0, 1, 2, -1.0, 10, 2, -1.0\n"
            "3\n6, 1, 1.0, 4, 1, -1.0, 10, 1, -1.0\n3\n6, 2, 1.0, 4, 2, -1.0, 10, 2, -1.0\n"
            "3\n7, 1, 1.0, 1, 1, -1.0, 11, 1, -1.0\n3\n7, 2, 1.0, 1, 2, -1.0, 11, 2, -1.0\n"
            "3\n8, 1, 1.0, 2, 1, -1.0, 11, 1, -1.0\n3\n8, 2, 1.0, 2, 2, -1.0, 11, 2, -1.0\n"
            "4\n9, 1, 1.0, 1, 1, -1.0, 10, 1, -1.0, 11, 1, -1.0\n4\n9, 2, 1.0, 1, 2, -1.0, 10, 2, -1.0, 11, 2, -1.0\n");
  // Our reader skips the REF nodes and the equations.
  const LoadedMesh back = read_mesh(dir.file("m.inp"));
  EXPECT_EQ(back.mesh2.node_count(), 9u);
}

TEST(PeriodicOutput, TetLatticeFilesFollowTheRules) {
  for (bool five : {false, true})
    for (const std::array<bool, 3> axes : {std::array<bool, 3>{true, true, true}, std::array<bool, 3>{true, false, false},
                                           std::array<bool, 3>{false, true, true}}) {
      SCOPED_TRACE(std::string(five ? "5" : "6") + " tets per cube, axes " + std::to_string(axes[0]) +
                   std::to_string(axes[1]) + std::to_string(axes[2]));
      TempDir dir;
      const double origin = 0.1, h = 0.3;
      mesh::Mesh3 m = lattice_mesh<3>(2, origin, h, five);
      const Box3 faces = lattice_box<3>(2, origin, h);
      const std::array<double, 3> period{2 * h, 2 * h, 2 * h};
      const MeshWriteOptions o = periodic_options<3>(faces, axes, period);
      write_mesh<3>(dir.file("m.inp"), m, {}, o);
      write_mesh<3>(dir.file("m.msh"), m, {}, o);
      write_mesh<3>(dir.file("m.vtu"), m, {}, o);
      const testing::InpSummary s = testing::check_inp_rules<3>(read_text(dir.file("m.inp")), m.node_count(), faces, axes, period);
      EXPECT_EQ(s.equations, 3 * s.slaves);
      if (axes[0] && axes[1] && axes[2]) {
        EXPECT_EQ(s.slaves, 19u);
        EXPECT_NE(read_text(dir.file("m.inp")).find("5\n27, 1, 1.0, 1, 1, -1.0, 28, 1, -1.0, 29, 1, -1.0\n30, 1, -1.0\n"),
                  std::string::npos)
            << "the far corner's equation of 5 terms on 2 lines";
      }
      testing::check_msh_links<3>(read_mesh(dir.file("m.msh")), faces, axes, period);
      testing::check_vtu_masters<3>(read_mesh(dir.file("m.vtu")), faces, axes, period);
      // The section follows $EndElements.
      const std::string msh = read_text(dir.file("m.msh"));
      EXPECT_EQ(msh.find("$EndElements\n$Periodic\n"), msh.find("$EndElements"));
    }
}

TEST(PeriodicOutput, NonPeriodicFilesCarryNoneOfIt) {
  TempDir dir;
  const mesh::Mesh2 m = lattice_mesh<2>(2, 0.0, 1.0);
  MeshWriteOptions o = periodic_options<2>(lattice_box<2>(2, 0, 1), {false, false}, {2, 2});
  for (const char* name : {"m.inp", "m.msh", "m.vtu"}) {
    write_mesh<2>(dir.file(name), m, {}, o);
    const std::string text = read_text(dir.file(name));
    EXPECT_EQ(text.find("EQUATION"), std::string::npos);
    EXPECT_EQ(text.find("REF_"), std::string::npos);
    EXPECT_EQ(text.find("Periodic"), std::string::npos);
    EXPECT_EQ(text.find("periodic_master"), std::string::npos);
  }
  EXPECT_EQ(pvtu_text({"a.vtu"}).find("periodic_master"), std::string::npos);
  EXPECT_NE(pvtu_text({"a.vtu"}, true).find("<PDataArray type=\"Int64\" Name=\"periodic_master\"/>"), std::string::npos);
}

// CalculiX through the 3D constraints (corner equations of 5 terms on 2 lines): the six unit
// strains of validation/fe/homogenise.py on a periodic tet lattice of one material come out
// uniform, and the effective stiffness is the material's (ccx prints 7 digits).
TEST(PeriodicOutput, CalculixHomogenisesA3dLatticeOfOneMaterial) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0) GTEST_SKIP() << "ccx (CalculiX) not found";
  TempDir dir;
  const double h = 0.25;
  mesh::Mesh3 m = lattice_mesh<3>(4, 0.0, h, true);
  for (std::size_t c = 0; c < m.cell_count(); ++c) m.cell_phase[c] = c % 3 == 0 ? 2 : 1;  // two ELSETs, one material
  const Box3 faces = lattice_box<3>(4, 0.0, h);
  write_mesh<3>(dir.file("m.inp"), m, {{1, "matrix", false}, {2, "other", false}},
                periodic_options<3>(faces, {true, true, true}, {4 * h, 4 * h, 4 * h}));
  const std::string command = "/usr/bin/python3 " CISAMR_SOURCE_DIR "/validation/fe/homogenise.py " + dir.file("m.inp") +
                              " --material matrix=1000,0.25 --material other=1000,0.25 --json " + dir.file("r.json") +
                              " > " + dir.file("log.txt") + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(dir.file("log.txt"));
  std::printf("%s", read_text(dir.file("log.txt")).c_str());
  const std::string json = read_text(dir.file("r.json"));
  const auto number = [&](const std::string& key) {
    const std::size_t at = json.find("\"" + key + "\": ");
    return at == std::string::npos ? -1.0 : std::strtod(json.c_str() + at + key.size() + 4, nullptr);
  };
  EXPECT_LE(number("max_strain_deviation"), 1e-6) << json;
  EXPECT_EQ(number("slaves"), 125 - 64);
  // E 1000, nu 0.25: lambda = mu = 400; C11 = 1200, C12 = 400, C44 = 400.
  const std::size_t at = json.find("\"stiffness\": [");
  ASSERT_NE(at, std::string::npos);
  std::vector<double> c;
  const char* p = json.c_str() + at + 14;
  for (int k = 0; k < 36; ++k) {
    while (*p && !(std::isdigit(static_cast<unsigned char>(*p)) || *p == '-')) ++p;
    char* end;
    c.push_back(std::strtod(p, &end));
    p = end;
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      const double want = i < 3 && j < 3 ? (i == j ? 1200 : 400) : i == j ? 400 : 0;
      EXPECT_NEAR(c[static_cast<std::size_t>(6 * i + j)], want, 1e-6 * 1200) << "C" << i + 1 << j + 1;
    }
}

// ---- real 2D periodic meshes

struct Meshed {
  geometry::SceneDesc scene;
  mesh::Mesh2 mesh;
  Box2 faces;
  std::array<bool, 2> axes{};
  std::array<double, 2> period{};
};

Meshed mesh_periodic(unsigned seed) {
  Meshed r;
  r.scene = cisamr::testing::periodic_scene(seed);
  const geometry::Oracle2 oracle(r.scene);
  r.mesh = pipeline::mesh(oracle).mesh;
  r.faces = driver::face_box<2>(r.scene, {});
  const grid::Lattice2 lattice = pipeline::make_lattice<2>(r.scene, {});
  for (int a = 0; a < 2; ++a) r.axes[a] = r.scene.periodic[a], r.period[a] = lattice.period(a);
  return r;
}

TEST(PeriodicOutput, RealMeshesFollowTheRules) {
  std::size_t slaves = 0, equations = 0, corners = 0, pairs = 0, x_only = 0, y_only = 0;
  for (unsigned seed = 1; seed <= 15; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Meshed r = mesh_periodic(seed);
    x_only += r.axes[0] && !r.axes[1];
    y_only += !r.axes[0] && r.axes[1];
    TempDir dir;
    MeshWriteOptions o = periodic_options<2>(r.faces, r.axes, r.period);
    o.plane = PlaneKind::strain;
    for (const char* name : {"m.inp", "m.msh", "m.vtu"}) write_mesh<2>(dir.file(name), r.mesh, r.scene.phases, o);
    const auto s = testing::check_inp_rules<2>(read_text(dir.file("m.inp")), r.mesh.node_count(), r.faces, r.axes, r.period);
    EXPECT_GT(s.slaves, 0u);
    slaves += s.slaves, equations += s.equations, corners += s.corner_equations;
    pairs += testing::check_msh_links<2>(read_mesh(dir.file("m.msh")), r.faces, r.axes, r.period);
    EXPECT_EQ(testing::check_vtu_masters<2>(read_mesh(dir.file("m.vtu")), r.faces, r.axes, r.period), s.slaves);
    // The .inp still reads as the mesh (REF nodes skipped).
    EXPECT_EQ(read_mesh(dir.file("m.inp")).mesh2.node_count(), r.mesh.node_count());
  }
  EXPECT_GT(x_only, 0u);  // per-axis periodicity is covered
  EXPECT_GT(y_only, 0u);
  EXPECT_GT(corners, 0u);
  std::printf("15 periodic scenes: %zu slaves, %zu equations (%zu with two REF terms), %zu $Periodic node pairs\n", slaves,
              equations, corners, pairs);
}

// A piece writer on one rank: the pieces path gives the same periodic_master.
TEST(PeriodicOutput, PvtuOnOneRankMatchesTheVtu) {
  const Meshed r = mesh_periodic(7);
  TempDir dir;
  const MeshWriteOptions o = periodic_options<2>(r.faces, r.axes, r.period);
  const SerialComm comm;
  parallel::write_pvtu<2>(comm, dir.file("p.pvtu"), r.mesh, r.scene.phases, o);
  write_mesh<2>(dir.file("m.vtu"), r.mesh, r.scene.phases, o);
  const LoadedMesh pieces = read_mesh(dir.file("p.pvtu")), whole = read_mesh(dir.file("m.vtu"));
  EXPECT_EQ(pieces.periodic_master, whole.periodic_master);
  EXPECT_GT(testing::check_vtu_masters<2>(pieces, r.faces, r.axes, r.period), 0u);
  EXPECT_NE(read_text(dir.file("p.pvtu")).find("periodic_master"), std::string::npos);
}

}  // namespace
}  // namespace cisamr::io
