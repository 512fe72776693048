#pragma once
// Certifying a mesh given as pieces that share nodes by global id (the .pvtu of a parallel or
// streamed run) one piece at a time: memory bounded by the largest piece and the border
// between pieces (the nodes they share, the facets of those), never by the whole mesh, and
// the same checks and counts as certify() of the merged mesh (README.md, "Partitioned
// meshes", says what differs: examples name pieces, near-duplicates across pieces are
// sought among border nodes).
#include <memory>
#include <span>
#include <string>

#include "core/types.hpp"
#include "geometry/oracle.hpp"
#include "mesh/simplex_mesh.hpp"
#include "quality/certificate.hpp"

namespace cisamr::quality {

// Two passes over the pieces, in the same order: count_nodes for every piece (which nodes
// more than one piece holds, and without a scene the domain box), then add_piece for every
// piece, then finish(). A periodic scene is not certified piece by piece (its faces are
// matched across the whole mesh): read the mesh whole.
template <int Dim>
class PiecewiseCertifier {
 public:
  // oracle: the scene's (its domain, expected measure and phase fidelity), or null: the
  // domain is the pieces' bounding box and fidelity is not checked.
  PiecewiseCertifier(const CertifyOptions& options, const geometry::Oracle<Dim>* oracle);
  ~PiecewiseCertifier();
  PiecewiseCertifier(const PiecewiseCertifier&) = delete;
  PiecewiseCertifier& operator=(const PiecewiseCertifier&) = delete;

  // First pass: a piece's global node ids and coordinates (3 per node, z = 0 in 2D).
  void count_nodes(std::span<const GlobalId> ids, std::span<const double> coords3);
  // After the first pass: whether the global ids seen are non-negative, below 2^31 and dense
  // enough (the largest below 4 × the nodes listed + 2^20) to be marked in bitmaps; if not,
  // read the mesh whole.
  bool ids_usable() const;
  // Second pass: a piece with node_global_id set (its phase ids the scene's); `name` prefixes
  // the examples it gives. Throws InputError naming `name` when a node's coordinates differ
  // from those another piece gives the same global id.
  void add_piece(const mesh::SimplexMesh<Dim>& piece, const std::string& name);

  // add_piece in two steps, so that pieces are checked on several threads: after
  // end_first_pass(), check_piece (const: any number of threads at once, each on its own
  // piece) does the work that needs no other piece; add_checked, called in piece order on
  // one thread, adds its result (and throws what add_piece throws).
  struct Checked;
  struct CheckedDeleter {
    void operator()(Checked* c) const;
  };
  using CheckedPiece = std::unique_ptr<Checked, CheckedDeleter>;
  void end_first_pass();
  CheckedPiece check_piece(const mesh::SimplexMesh<Dim>& piece, const std::string& name) const;
  void add_checked(CheckedPiece piece);
  // The certificate of the whole mesh.
  Certificate finish();

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace cisamr::quality
