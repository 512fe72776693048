// Meshes other tools wrote (the fuzz seeds: Gmsh, meshio, VTK, TetGen conversions of two
// small cisamr meshes) read to the same mesh, with the phase names the files carry; and
// hand-written files for what the conversions do not cover.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include "core/error.hpp"
#include "io/mesh_io.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::read_text;
using testing::TempDir;

const std::string kCorpus = std::string(CISAMR_SOURCE_DIR) + "/tests/fuzz/corpus/";

struct Summary {
  int dimension = 0;
  std::size_t nodes = 0, cells = 0;
  std::map<int, std::size_t> cells_per_phase;
  std::map<int, std::string> names;  // from the file
  double coordinate_sum = 0;
};

Summary summarize(const LoadedMesh& l) {
  Summary s;
  s.dimension = l.dimension;
  const auto& phases = l.dimension == 2 ? l.mesh2.cell_phase : l.mesh3.cell_phase;
  const auto& coords = l.dimension == 2 ? l.mesh2.coords : l.mesh3.coords;
  s.nodes = coords.size() / static_cast<std::size_t>(l.dimension);
  s.cells = phases.size();
  for (const std::int32_t p : phases) ++s.cells_per_phase[p];
  for (const double c : coords) s.coordinate_sum += c;
  s.names = l.phase_names_in_file;
  return s;
}

// A corpus file holding several files (fuzz_target.hpp's separator) written out under `names`.
std::string unpack(const TempDir& dir, const std::string& corpus_file, const std::vector<std::string>& names) {
  const std::string text = read_text(kCorpus + corpus_file);
  const std::string separator = "\n@@next-file@@\n";
  std::size_t start = 0;
  for (const std::string& name : names) {
    EXPECT_LE(start, text.size()) << corpus_file << " holds fewer files than " << names.size();
    if (start > text.size()) break;
    const std::size_t end = std::min(text.find(separator, start), text.size());
    dir.write(name, text.substr(start, end - start));
    start = end + separator.size();
  }
  return dir.file(names.front());
}

void expect_same_mesh(const Summary& a, const Summary& b, const std::string& what) {
  EXPECT_EQ(a.dimension, b.dimension) << what;
  EXPECT_EQ(a.nodes, b.nodes) << what;
  EXPECT_EQ(a.cells, b.cells) << what;
  EXPECT_EQ(a.cells_per_phase, b.cells_per_phase) << what;
  EXPECT_NEAR(a.coordinate_sum, b.coordinate_sum, 1e-9 * (1 + std::abs(a.coordinate_sum))) << what;
}

TEST(ForeignMeshes, EveryConversionReadsToTheSameMeshWithItsNames) {
  for (const std::string scene : {"t2", "t3"}) {
    // Gmsh's ASCII MSH 2.2 is the reference: its physical names are the scene's.
    const Summary reference = summarize(read_mesh(kCorpus + "mesh_msh/gmsh22_" + scene + ".msh"));
    const std::map<int, std::string> names =
        scene == "t2" ? std::map<int, std::string>{{1, "matrix"}, {2, "fiber"}}
                      : std::map<int, std::string>{{1, "epoxy"}, {2, "silica"}};
    EXPECT_EQ(reference.names, names);
    EXPECT_EQ(reference.dimension, scene == "t2" ? 2 : 3);
    ASSERT_EQ(reference.cells_per_phase.size(), 2u);
    const std::vector<std::pair<std::string, bool>> files = {  // (file, carries names)
        {"mesh_msh/gmsh22_bin_" + scene + ".msh", true},
        {"mesh_msh/gmsh41_bin_" + scene + ".msh", true},
        {"mesh_vtu/meshio_zlib_" + scene + ".vtu", false},
        {"mesh_vtu/vtk_ascii_" + scene + ".vtu", true},
        {"mesh_vtu/vtk_default_zlib_" + scene + ".vtu", true},
        {"mesh_vtu/vtk_appended_raw_zlib_" + scene + ".vtu", true},
        {"mesh_vtu/vtk_inline_zlib_uint32_" + scene + ".vtu", true},
        {"mesh_vtk/ascii_" + scene + ".vtk", true},
        {"mesh_vtk/binary_" + scene + ".vtk", true},
        {"mesh_vtk/ascii42_" + scene + ".vtk", true},
        {"mesh_vtk/binary42_" + scene + ".vtk", true}};
    for (const auto& [file, named] : files) {
      const Summary s = summarize(read_mesh(kCorpus + file));
      expect_same_mesh(reference, s, file);
      const std::map<int, std::string> expected = named ? names : std::map<int, std::string>();
      EXPECT_EQ(s.names, expected) << file;
    }
  }
}

TEST(ForeignMeshes, TetgenNodeEleAnyBaseRegionAsPhase) {
  TempDir dir;
  const Summary one = summarize(read_mesh(unpack(dir, "mesh_tetgen/tetgen_r_1based.ele", {"a.ele", "a.node"})));
  const Summary zero = summarize(read_mesh(unpack(dir, "mesh_tetgen/tetgen_rz_0based.ele", {"b.ele", "b.node"})));
  const Summary ours = summarize(read_mesh(kCorpus + "mesh_vtu/vtk_ascii_t3.vtu"));
  expect_same_mesh(ours, one, "1-based");
  expect_same_mesh(ours, zero, "0-based");
  EXPECT_TRUE(one.names.empty());
  // Named by either file; a 2D Triangle-style pair with real-valued region attributes.
  expect_same_mesh(one, summarize(read_mesh(dir.file("a.node"))), "by .node");
  const LoadedMesh flat = read_mesh(unpack(dir, "mesh_tetgen/triangle_2d_comments.ele", {"c.ele", "c.node"}));
  ASSERT_EQ(flat.dimension, 2);
  EXPECT_EQ(flat.mesh2.cell_phase, (std::vector<std::int32_t>{7, 9}));
}

TEST(ForeignMeshes, PvtuMergesPiecesByGlobalIdOrCoordinates) {
  TempDir dir;
  const LoadedMesh three = read_mesh(unpack(dir, "mesh_pvtu/ours_two_pieces_3d.pvtu", {"m.pvtu", "piece0.vtu", "piece1.vtu"}));
  ASSERT_EQ(three.dimension, 3);
  const auto& m = three.mesh3;
  // Shared nodes merged: every node used, none twice.
  std::vector<int> used(m.coords.size() / 3, 0);
  for (const LocalId n : m.cell_nodes) used[static_cast<std::size_t>(n)] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
  std::map<std::array<double, 3>, int> seen;
  for (std::size_t n = 0; n < used.size(); ++n)
    EXPECT_EQ((++seen[{m.coords[3 * n], m.coords[3 * n + 1], m.coords[3 * n + 2]}]), 1) << "node " << n << " twice";
  std::set<std::int32_t> partitions(m.cell_partition.begin(), m.cell_partition.end());
  EXPECT_EQ(partitions, (std::set<std::int32_t>{0, 1}));
  // One piece rewritten by meshio without global ids: merged by coordinates.
  TempDir other;
  const LoadedMesh two = read_mesh(unpack(other, "mesh_pvtu/ours_and_ascii_piece_2d.pvtu", {"m.pvtu", "piece0.vtu", "piece1.vtu"}));
  ASSERT_EQ(two.dimension, 2);
  std::map<std::array<double, 2>, int> seen2;
  for (std::size_t n = 0; n < two.mesh2.coords.size() / 2; ++n)
    EXPECT_EQ((++seen2[{two.mesh2.coords[2 * n], two.mesh2.coords[2 * n + 1]}]), 1) << "node " << n << " twice";
  // A piece whose global_id array does not have one value per point (found by fuzzing: the
  // merge indexed past the array).
  TempDir third;
  const std::string piece = R"(<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="1">
<PointData><DataArray type="Int64" Name="global_id" format="ascii">0 1</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)";
  third.write("a.vtu", piece);
  const std::string bad = third.write("m.pvtu", R"(<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid>
<Piece Source="a.vtu"/></PUnstructuredGrid></VTKFile>)");
  try {
    read_mesh(bad);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.vtu: global_id: has 2 values for 3 points"), std::string::npos) << e.what();
  }
  // A missing piece is an error naming it.
  std::filesystem::remove(other.file("piece1.vtu"));
  try {
    read_mesh(other.file("m.pvtu"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("piece1.vtu"), std::string::npos) << e.what();
  }
}

TEST(ForeignMeshes, PhaseNamesFromVtuFieldDataMeditCommentsAndAbaqusSets) {
  TempDir dir;
  // The VTU field data our writer adds: names as bytes, each ended by 0, and their ids.
  const LoadedMesh vtu = read_mesh(dir.write("n.vtu", R"(<VTKFile type="UnstructuredGrid" byte_order="LittleEndian">
<UnstructuredGrid><FieldData>
<DataArray type="String" Name="phase_names" NumberOfTuples="2" format="ascii">109 97 116 0 103 108 97 115 115 32 102 0</DataArray>
<DataArray type="Int32" Name="phase_ids" NumberOfTuples="2" format="ascii">4 6</DataArray>
</FieldData><Piece NumberOfPoints="4" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 1 1 0</DataArray></Points>
<Cells><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 1 3 2</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3 6</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5 5</DataArray></Cells>
<CellData><DataArray type="Int32" Name="phase" format="ascii">4 6</DataArray></CellData>
</Piece></UnstructuredGrid></VTKFile>)"));
  EXPECT_EQ(vtu.phase_names_in_file, (std::map<int, std::string>{{4, "mat"}, {6, "glass f"}}));
  ASSERT_EQ(vtu.phases.size(), 2u);
  EXPECT_EQ(vtu.phases[1].name, "glass f");

  const LoadedMesh medit = read_mesh(kCorpus + "mesh_medit/phase_comments.mesh");
  EXPECT_EQ(medit.phase_names_in_file, (std::map<int, std::string>{{3, "matrix"}, {8, "fiber glass"}}));
  EXPECT_EQ(medit.mesh2.cell_phase, (std::vector<std::int32_t>{3, 8}));

  // Blocks without ELSET: the *ELSET blocks decide (ids, GENERATE); a later set naming
  // them, *NSET, *SURFACE and materials do not.
  const LoadedMesh inp = read_mesh(kCorpus + "mesh_inp/several_blocks_and_elsets.inp");
  EXPECT_EQ(inp.phase_names_in_file, (std::map<int, std::string>{{1, "matrix"}, {2, "fiber"}}));
  EXPECT_EQ(inp.mesh2.cell_phase, (std::vector<std::int32_t>{1, 1, 2, 2}));
}

// ---- what the conversions do not cover, and bad files ----

std::string read_error(const std::string& path) {
  try {
    read_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string base64(const std::string& bytes) {
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
  }
  return out;
}

template <class T>
std::string raw_bytes(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// A zlib block header (UInt64) and blocks of at most `block_size` bytes.
std::string compressed_block(const std::string& data, std::size_t block_size) {
  std::vector<std::uint64_t> header{0, block_size, data.size() % block_size};
  std::string blocks;
  for (std::size_t at = 0; at < data.size(); at += block_size) {
    const std::string part = data.substr(at, block_size);
    uLongf length = compressBound(part.size());
    std::string out(length, '\0');
    compress2(reinterpret_cast<Bytef*>(out.data()), &length, reinterpret_cast<const Bytef*>(part.data()), part.size(), 9);
    out.resize(length);
    header.push_back(length);
    blocks += out;
    ++header[0];
  }
  return raw_bytes(header) + blocks;
}

std::string compressed_vtu(const std::string& points_block) {
  const std::string cells = base64(compressed_block(raw_bytes(std::vector<std::int64_t>{0, 1, 2, 1, 3, 2}), 16));
  return R"(<VTKFile type="UnstructuredGrid" byte_order="LittleEndian" header_type="UInt64" compressor="vtkZLibDataCompressor">
<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="binary">)" + points_block + R"(</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="binary">)" + cells + R"(</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3 6</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5 5</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>)";
}

TEST(ForeignMeshes, CompressedBlocksOfAnySizeAndTheirLies) {
  TempDir dir;
  const std::vector<double> points{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  for (const std::size_t block : {8, 40, 96, 1000}) {  // several blocks, a short last one, one block
    const LoadedMesh l = read_mesh(dir.write("c.vtu", compressed_vtu(base64(compressed_block(raw_bytes(points), block)))));
    ASSERT_EQ(l.dimension, 2) << block;
    EXPECT_EQ(l.mesh2.coords, (std::vector<double>{0, 0, 1, 0, 0, 1, 1, 1})) << block;
    EXPECT_EQ(l.mesh2.cell_nodes, (std::vector<LocalId>{0, 1, 2, 1, 3, 2})) << block;
  }
  // A block claiming to inflate to 1 GB: refused before allocating.
  std::string lie = compressed_block(raw_bytes(points), 96);
  const std::uint64_t huge = 1ull << 30;
  std::memcpy(lie.data() + 8, &huge, 8);
  std::memcpy(lie.data() + 16, &huge, 8);
  EXPECT_NE(read_error(dir.write("l.vtu", compressed_vtu(base64(lie)))).find("more than zlib can"), std::string::npos);
  // A block count beyond the file, and data that are not zlib.
  std::string count = compressed_block(raw_bytes(points), 96);
  const std::uint64_t blocks = 1ull << 40;
  std::memcpy(count.data(), &blocks, 8);
  EXPECT_NE(read_error(dir.write("n.vtu", compressed_vtu(base64(count)))).find("blocks, more than the file holds"),
            std::string::npos);
  std::string garbage = compressed_block(raw_bytes(points), 96);
  garbage.back() ^= 0x55;
  garbage[garbage.size() - 5] ^= 0x55;
  EXPECT_NE(read_error(dir.write("g.vtu", compressed_vtu(base64(garbage)))).find("does not inflate"), std::string::npos);
  EXPECT_NE(read_error(dir.write("b.vtu", compressed_vtu("AAA*"))).find("not base64"), std::string::npos);
}

TEST(ForeignMeshes, BadFilesOfTheNewFormatsAreOneLineErrors) {
  TempDir dir;
  // MSH 2.2 binary: an element run of 0 elements would never end.
  std::string msh = "$MeshFormat\n2.2 1 8\n";
  const std::int32_t one = 1;
  msh.append(reinterpret_cast<const char*>(&one), 4);
  msh += "\n$EndMeshFormat\n$Nodes\n0\n$EndNodes\n$Elements\n1\n";
  const std::int32_t run[3] = {2, 0, 0};
  msh.append(reinterpret_cast<const char*>(run), 12);
  EXPECT_NE(read_error(dir.write("r.msh", msh)).find("bad element run header"), std::string::npos);
  // MSH 4.1 binary written big-endian.
  std::string big = "$MeshFormat\n4.1 1 8\n";
  big.append("\0\0\0\1", 4);
  EXPECT_NE(read_error(dir.write("e.msh", big + "\n$EndMeshFormat\n")).find("big-endian"), std::string::npos);
  // Legacy VTK: counts beyond the file, an unknown keyword, a binary string longer than the file.
  const std::string head = "# vtk DataFile Version 5.1\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  EXPECT_NE(read_error(dir.write("c.vtk", head + "POINTS 1000000000000 double\n0 0 0\n")).find("more than the rest of the file"),
            std::string::npos);
  EXPECT_NE(read_error(dir.write("k.vtk", head + "POLYGONS 1 4\n")).find("unsupported keyword 'POLYGONS'"), std::string::npos);
  std::string strings = "# vtk DataFile Version 5.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nFIELD FieldData 1\nphase_names 1 1 string\n";
  strings += "\x7f\xff\xff\xff";  // a 4-byte length: 2^30 - 1
  EXPECT_NE(read_error(dir.write("s.vtk", strings)).find("more than the rest of the file holds"), std::string::npos);
  EXPECT_NE(read_error(dir.write("t.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n")).find("POLYDATA"),
            std::string::npos);
  // TetGen: the .ele without its .node, a region attribute that is no id.
  dir.write("lone.ele", "1 4 0\n1 1 2 3 4\n");
  EXPECT_NE(read_error(dir.file("lone.ele")).find("lone.node: cannot read"), std::string::npos);
  dir.write("r.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  dir.write("r.ele", "1 4 1\n1 1 2 3 4 1.5\n");
  EXPECT_NE(read_error(dir.file("r.ele")).find("is not an integer phase id"), std::string::npos);
  dir.write("h.node", "1000000000000 3 0 0\n1 0 0 0\n");
  EXPECT_NE(read_error(dir.file("h.node")).find("more than"), std::string::npos);
  // Abaqus *INCLUDE is refused, not skipped.
  EXPECT_NE(read_error(dir.write("i.inp", "*NODE\n1, 0, 0\n*INCLUDE, INPUT=rest.inp\n")).find("*INCLUDE"), std::string::npos);
}

}  // namespace
}  // namespace cisamr::io
