#pragma once
// Mesh files (DESIGN.md §7). Writers pick the format from the extension and write through
// AtomicFile; readers accept our own output and the common dialects of other tools.
//
//   .vtu   VTK XML UnstructuredGrid, raw appended binary (UInt64 headers, little endian):
//          cell data phase (Int32), partition (Int32), aspect_ratio (Float64);
//          point data global_id (Int64), boundary (UInt8, bit f: on box face f), and for a
//          periodic mesh periodic_master (Int64: the full master's global id, or -1); points
//          always with 3 components; field data phase_names (UInt8, ASCII: each name's bytes
//          then 0; meshio refuses VTK String arrays) and phase_ids (Int32), in phase-id order.
//          The global_id block is the file's last (VtuAwaitingIds writes it after the rest).
//   .msh   Gmsh 4.1 ASCII: one physical group and one entity per phase (tag = phase id);
//          per box face a curve (2D) or surface (3D) entity with its boundary lines or
//          triangles, in a physical group named XMIN ... ZMAX. Periodic: $Periodic after
//          $Elements, one link per periodic axis (max face entity → min face entity, the
//          4×4 affine map, every slave-face node with its single-axis master).
//   .inp   Abaqus: *NODE, one *ELEMENT block per phase, TYPE=CPS3|CPE3|C3D4, ELSET=name;
//          *NSET XMIN ... ZMAX and CORNER0; *SURFACE XMIN_FACES ... over face ELSETs.
//          Periodic: REF nodes n+1 ... (the last *NODE lines, at the max corner) in NSETs
//          REF_X, REF_Y, REF_Z, then *EQUATION per slave and dof, u_s − u_m − Σ u_REF_a = 0
//          over the axes along which s is shifted (node ids; ≤ 4 terms per line). Users
//          constrain CORNER0 and the REF nodes, never a slave.
// Periodic constraints (MeshWriteOptions::periodic) come from mesh/periodic_links.hpp:
// exact translates across the face box, a mesh that is not periodic is a MeshingError.
//   .mesh  Medit/INRIA, MeshVersionFormatted 2: element reference = phase id; boundary
//          edges (2D) or triangles (3D) with reference face + 1; "# phase ID NAME" comments.
// Box faces are numbered XMIN, XMAX, YMIN, YMAX, ZMIN, ZMAX = 0..5 (mesh/boundary.hpp).
//
// Numbers in ASCII formats are printed with the shortest text that reads back to the same
// double, so every format round-trips coordinates bit for bit.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "geometry/scene.hpp"
#include "io/atomic_file.hpp"
#include "mesh/simplex_mesh.hpp"

namespace cisamr::io {

enum class MeshFormat { vtu, msh, inp, medit };

// The format named by the file's extension. Throws InputError(path, "", "unknown mesh
// format '.xyz' (use .vtu, .msh, .inp or .mesh)"). Cheap: call it before meshing to fail early.
MeshFormat mesh_format_of(const std::string& path);

// 2D Abaqus elements: CPS3 (plane stress) or CPE3 (plane strain).
enum class PlaneKind { stress, strain };

struct MeshWriteOptions {
  // Per-cell aspect ratio for the VTU "aspect_ratio" array; computed when empty.
  std::vector<double> cell_aspect_ratio;
  // The format when the path's extension does not name it: "-" (standard output).
  std::optional<MeshFormat> format;
  // The box whose faces the boundary sets refer to (z unused in 2D): the exact coordinates
  // of the nodes on each face (driver::face_box). Unset: the mesh's bounding box, which is
  // the same whenever every face carries a node (always so for a whole mesh without voids).
  std::optional<Box3> face_box;
  PlaneKind plane = PlaneKind::stress;  // .inp in 2D
  // Periodic axes (scene domain.periodic; z unused in 2D). With any set, the mesh must be
  // periodic along them with respect to face_box (every node on a max face has its exact
  // translate on the min face, mesh/periodic_links.hpp): the writers add the constraints
  // (.inp REF nodes and *EQUATION, .msh $Periodic, .vtu periodic_master; .mesh nothing),
  // and a mesh that is not periodic is a MeshingError naming the node.
  std::array<bool, 3> periodic{};
  // The translation T_a from the min face to the max face along each periodic axis (the
  // lattice's N_a·h: face_box max = fl(min + T_a)); 0: face_box max − min. Only the .msh
  // affine transform uses it.
  std::array<double, 3> period{};
  // A piece of a parallel run holds slaves whose master is on another rank: there the
  // caller gives, per node, the full master's global id or -1 (parallel::periodic_masters),
  // and write_vtu writes it as periodic_master. Empty: the links are taken from the mesh.
  std::vector<GlobalId> periodic_master;
  // The scene has void phases: a node on a max face whose translate is absent (a void across
  // the period) is left unconstrained instead of refused (mesh::periodic_links).
  bool periodic_voids = false;
  bool any_periodic() const { return periodic[0] || periodic[1] || periodic[2]; }
};

// Writes `m` in the format of `path`'s extension (or options.format). `phases` gives the names (msh physical
// names, inp ELSET names, vtu phase_names, Medit comments); a phase id used by a cell but
// missing there is named "phase<id>". Empty cell_partition / node_global_id are written as 0 / the node index.
// Throws InputError for an unknown extension or an unwritable path; the destination is
// either the complete new file or untouched.
template <int Dim>
void write_mesh(const std::string& path, const mesh::SimplexMesh<Dim>& m,
                const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options = {});

// The VTU writer alone (one piece): what a parallel run writes per rank before the .pvtu.
// Its boundary bits refer to options.face_box: give the whole domain's for a piece.
template <int Dim>
void write_vtu(const std::string& path, const mesh::SimplexMesh<Dim>& m,
               const std::vector<geometry::Phase>& phases, const MeshWriteOptions& options = {});

// A .vtu written before its nodes' global ids are known (a streamed partition's piece, whose
// ids come after every partition is meshed): the constructor writes everything but the
// global_id block, the file's last, to the temporary; finish() appends the ids (one per
// node, in the mesh's order) and commits. Without finish() nothing appears. The same bytes
// as write_vtu of the mesh with those ids.
class VtuAwaitingIds {
 public:
  template <int Dim>
  VtuAwaitingIds(const std::string& path, const mesh::SimplexMesh<Dim>& m, const std::vector<geometry::Phase>& phases,
                 const MeshWriteOptions& options = {});
  VtuAwaitingIds(VtuAwaitingIds&&) noexcept;
  VtuAwaitingIds& operator=(VtuAwaitingIds&&) noexcept;
  ~VtuAwaitingIds();
  void finish(std::span<const GlobalId> ids);

 private:
  std::unique_ptr<AtomicFile> file_;
  std::size_t nodes_ = 0;
};

// The .pvtu text listing `pieces` (file names relative to the .pvtu), declaring the arrays
// write_vtu writes (`periodic`: the pieces have periodic_master, as write_vtu writes it for
// MeshWriteOptions::any_periodic()).
std::string pvtu_text(const std::vector<std::string>& pieces, bool periodic = false, bool cohesive = false);

// The element set (.inp ELSET, .msh physical group) of the cohesive cells between phases
// `lower` and `upper`: COH_<lower's name>_<upper's name> by Abaqus label rules.
std::string cohesive_set_name(const std::vector<geometry::Phase>& phases, std::int32_t lower, std::int32_t upper);

struct LoadedMesh {
  int dimension = 0;   // 2 or 3: which of mesh2 / mesh3 holds the mesh
  mesh::Mesh2 mesh2;
  mesh::Mesh3 mesh3;
  std::vector<geometry::Phase> phases;  // every phase id used by a cell, ascending
  // The names the file itself gives (physical names, ELSETs, VTU field data phase_names,
  // Medit "# phase ID NAME" comments, meshio's field data), by id: `phases` names the
  // others "phase<id>". certify matches phases to the scene's by these names.
  std::map<int, std::string> phase_names_in_file;
  // Periodic constraints the file carries (empty when none):
  // .msh: the $Periodic links (MSH 4.1), node pairs as 0-based node indices of this mesh.
  struct PeriodicLink {
    int entity_dimension = 0, entity = 0, master_entity = 0;
    std::vector<double> affine;  // as written: 16 values (row-major 4×4) or none
    std::vector<std::pair<LocalId, LocalId>> nodes;  // (slave, master)
  };
  std::vector<PeriodicLink> periodic_links;
  // .vtu / .pvtu: the point data periodic_master (per node, the full master's global id or -1).
  std::vector<GlobalId> periodic_master;
  // The axes along which the file's periodic constraints tie nodes: the translations of the
  // .msh $Periodic links, the axes along which a .vtu node and its periodic_master differ,
  // the REF_X, REF_Y, REF_Z node sets of our .inp. All false for a file without them.
  std::array<bool, 3> periodic_axes{};
  bool any_periodic() const { return periodic_axes[0] || periodic_axes[1] || periodic_axes[2]; }
  // Cohesive cells (docs/cohesive-design.md §6.1) are in mesh2/mesh3.cohesive, in the internal
  // node order, with the phases the file claims for them (0 where it says nothing), and
  // node_phase as the file gives it (.vtu) or else each node's first bulk cell's phase (for
  // a node of no bulk cell, the phase its first cohesive cell claims for that side).
  // Their element sets as the file names them (.msh physical groups COH_*, .inp ELSETs of
  // COH2D4/COH3D6 blocks and *ELSETs named COH_*); a .vtu names none.
  struct CohesiveSet {
    std::string name;
    // The phase pairs (lower id, upper id) the name denotes: COH_<A>_<B> with A, B the two
    // phases' names as the writers label them, or COH_<p>_<q> with their ids. Usually one.
    std::vector<std::array<std::int32_t, 2>> named_pairs;
  };
  std::vector<CohesiveSet> cohesive_sets;
  // Per cohesive cell: its index in cohesive_sets, or one of the two values below. Empty when
  // the format names no sets.
  std::vector<std::int32_t> cohesive_set_of_cell;
  static constexpr std::int32_t kNoCohesiveSet = -1;
  static constexpr std::int32_t kSeveralCohesiveSets = -2;
};

// Reads what cisamr and other tools write (lib/io/README.md, "Reading meshes"):
//   .vtu   ascii, inline base64, appended raw or base64; UInt32 or UInt64 headers; plain or
//          zlib-compressed (vtkZLibDataCompressor); one piece
//   .pvtu  its .vtu pieces, nodes merged by global_id (or else by exact coordinates)
//   .vtk   legacy, ASCII or BINARY, UNSTRUCTURED_GRID (versions 2 to 5.1)
//   .msh   Gmsh 4.1 and 2.2, ASCII and binary ($Periodic of 4.1 into periodic_links)
//   .mesh  Medit ASCII;  .inp  Abaqus (several element blocks, *ELSET);
//   .node/.ele  TetGen (or Triangle): the two files of the named stem
// Triangles or tetrahedra only: points and lines (and boundary triangles of a tetrahedral
// mesh) are skipped, any other element type is an InputError, except the cohesive cells a
// file marks as such: quads (2D) or wedges/prisms (3D) with cell data cohesive = 1 (.vtu,
// .pvtu, .vtk), in a physical group named COH_* (.msh), of type COH2D4/COH3D6 (.inp). A
// .pvtu with cohesive cells needs global_id (merging by coordinates would weld the copies). The mesh is 2D when its
// cells are triangles and every z is 0. Phases come from the phase array (or gmsh:physical,
// medit:ref) / physical tags / references / ELSETs / region attributes (1 when absent);
// absent global ids are the node index, absent partitions 0. Every problem is an
// InputError naming the file, never a crash; counts are checked against the file's size
// before anything is reserved.
LoadedMesh read_mesh(const std::string& path);

// The path's extension in lower case, dot included ("" when it has none): how the readers
// and writers recognise a format.
std::string lowercase_extension(const std::string& path);

// The .vtu pieces a .pvtu lists, in order, as paths (relative ones resolved against the
// .pvtu's folder).
std::vector<std::string> pvtu_piece_paths(const std::string& path);

// A .vtu piece's points and global ids, nothing else decoded (a mapped file's other arrays
// are not read from disk): the first pass of reading a partitioned mesh piece by piece.
struct VtuPoints {
  std::vector<double> coords;         // 3 per point
  std::vector<GlobalId> global_id;    // per point, when the piece has global_id
  bool has_global_id = false;
  bool has_cohesive = false;          // cell data `cohesive` (cohesive cells may be there)
  bool has_periodic_master = false;   // point data `periodic_master`
};
VtuPoints read_vtu_points(const std::string& path);

}  // namespace cisamr::io
