#pragma once
// Cohesive cells on a partitioned or periodic mesh (docs/cohesive-design.md §1, §4): the
// pure halves that one partition applies to its own result. pipeline::mesh applies them to
// the whole domain as one partition; parallel::join_cohesive applies them to every
// partition, moving the claims between ranks. Both therefore make the same cells.
//
// A copy is named (node identity, phase): the merge of partitions matches copies by that
// pair, so a copy on a partition face is one node of the global mesh like any other.
//
// 1. split_and_claim: each partition splits its interface nodes per phase and inserts the
//    cells of the facets whose two bulk cells it holds (mesh::insert_cohesive). A facet on
//    an inner partition face or a periodic plane has one cell in the partition: it becomes
//    a claim, keyed by its nodes' identities moved to their canonical image.
// 2. pair_facet_claims: two claims of one key with different phases make one cell, emitted
//    by the claimant on its box's lo plane (on a periodic plane, the min face's side).
// 3. apply_facet_joins: the emitter builds the cell from its own bulk cell's vertex order,
//    adding the other phase's copies of the facet's nodes when it has none.
// 4. copy_claims / missing_copies / apply_copy_needs (periodic only): a copy of phase r on a
//    periodic max face needs an r-copy at each image of its node nearer the min faces (its
//    masters); one is added where no r-cell made it (a master in no bulk cell).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "grid/lattice.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr::pipeline {

template <int Dim>
struct FacetClaim {
  std::array<NodeIdentity<Dim>, Dim> key{};  // its nodes' canonical identities, sorted
  std::int32_t phase = 0;                   // its bulk cell's
  std::int32_t partition = 0;
  std::int32_t rank = 0;                    // where the claimant lives (set by the exchange)
  std::int64_t cell = 0;                    // in the partition's mesh
  std::int32_t opposite = 0;                // the cell's vertex opposite the facet
  std::int32_t lo_side = 0;                 // 1: the facet lies on its box's lo plane
};

// What the claimant on the lo side of a different-phase facet emits.
struct FacetJoin {
  std::int32_t partition = 0;
  std::int32_t rank = 0;
  std::int64_t cell = 0;
  std::int32_t opposite = 0;
  std::int32_t other_phase = 0;
  auto operator<=>(const FacetJoin&) const = default;
};

// A copy on a periodic plane: its node's canonical identity, which image it is (bit d: on
// the max face of axis d), its phase.
template <int Dim>
struct CopyClaim {
  NodeIdentity<Dim> canonical{};
  std::uint8_t image = 0;
  std::int32_t phase = 0;
  std::int32_t partition = 0;
  std::int32_t rank = 0;
};

// A copy a partition must add: phase `phase` at image `image` of `canonical`.
template <int Dim>
struct CopyNeed {
  std::int32_t partition = 0;
  std::int32_t rank = 0;
  NodeIdentity<Dim> canonical{};
  std::uint8_t image = 0;
  std::int32_t phase = 0;
  auto operator<=>(const CopyNeed&) const = default;
};

// Step 1 on the result of partition `partition` (coarse cells `box`): splits, inserts the
// local cells, extends node_identity to the copies, returns the open facets' claims.
template <int Dim>
std::vector<FacetClaim<Dim>> split_and_claim(Result<Dim>& result, const grid::Lattice<Dim>& lattice,
                                             const grid::CellRange<Dim>& box, std::int32_t partition);

// Step 2 over every claim of some keys (all claims of a key together). Returns the joins in
// (partition, cell, opposite) order. Throws std::logic_error for more than two claims of a
// key, or two of different phases neither or both on a lo plane.
template <int Dim>
std::vector<FacetJoin> pair_facet_claims(std::vector<FacetClaim<Dim>> claims);

// Step 3: the joins of this partition (in the order pair_facet_claims gives them).
template <int Dim>
void apply_facet_joins(Result<Dim>& result, std::span<const FacetJoin> joins);

// Step 4. copy_claims: every copy of this partition on a periodic plane. missing_copies:
// over every claim of some canonical identities, the copies to add, one per partition
// holding the image (sorted). apply_copy_needs: adds them (coordinates from a node at the
// same identity in the partition, bit for bit).
template <int Dim>
std::vector<CopyClaim<Dim>> copy_claims(const Result<Dim>& result, const grid::Lattice<Dim>& lattice,
                                        std::int32_t partition);
template <int Dim>
std::vector<CopyNeed<Dim>> missing_copies(std::vector<CopyClaim<Dim>> claims);
template <int Dim>
void apply_copy_needs(Result<Dim>& result, const grid::Lattice<Dim>& lattice, std::span<const CopyNeed<Dim>> needs);

// All four steps on a whole-domain result (one partition, box = the domain).
template <int Dim>
void insert_cohesive_whole(Result<Dim>& result, const grid::Lattice<Dim>& lattice);

// Hash of a node identity (the exchanges' rendezvous).
template <int Dim>
std::uint64_t identity_hash(const NodeIdentity<Dim>& id);

}  // namespace cisamr::pipeline
