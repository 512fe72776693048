#pragma once
// The certification result of a mesh (aspect-ratio statistics + conformity + optional phase
// fidelity) and its renderings: JSON, a self-contained HTML page, a short text summary.
// Pure functions returning strings; the caller writes them (io::AtomicFile).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "quality/periodic.hpp"
#include "core/types.hpp"
#include "mesh/simplex_mesh.hpp"
#include "quality/cohesive.hpp"
#include "quality/quality.hpp"

namespace cisamr::quality {

// DESIGN.md §2.2: 3 in 2D, 5 in 3D.
inline double default_bound(int dimension) { return dimension == 2 ? 3.0 : 5.0; }

// With voids the meshed measure differs from domain minus the exact void measure by the
// polygonal approximation of the void boundaries, so only gross errors are caught by the
// measure; holes are then caught by the fidelity check (open facets must lie on a void).
inline constexpr double kVoidMeasureTolerance = 0.05;

struct CertifyOptions {
  double bound = 0;           // <= 0: default_bound(dimension)
  int worst_count = 20;       // rows of the worst-elements table
  double expected_measure = -1;  // < 0: not checked (used only without a scene)
  bool allow_inner_boundary = false;  // used only without a scene
  double measure_tolerance = kDefaultMeasureTolerance;
  double fidelity_tolerance = -1;  // < 0: default_fidelity_tolerance(scene)
};

// The element sets a file puts its cohesive cells in (.msh physical groups, .inp ELSETs;
// io::LoadedMesh::cohesive_sets): what the set rules check. A format without set names
// (.vtu) gives none, and the set rules are not checked.
struct CohesiveSetsInFile {
  struct Set {
    std::string name;
    std::vector<std::array<std::int32_t, 2>> named_pairs;  // the phase pairs (lower, upper) its name denotes
  };
  std::vector<Set> sets;
  std::vector<std::int32_t> set_of_cell;  // per cohesive cell: index into sets, kNoSet or kSeveralSets
  static constexpr std::int32_t kNoSet = -1, kSeveralSets = -2;
};

// The cohesive part of a certificate (docs/cohesive-design.md §6.2): check_cohesive's counts
// and, where the file names sets, the set rules: every cohesive cell in exactly one set,
// whose name denotes the pair of phases the cell claims (check_cohesive holds the claim to
// the bulk cells on its facet), and no set empty.
struct CohesiveSection {
  std::size_t cells = 0;             // cohesive cells
  std::size_t interface_facets = 0;  // welded facets between bulk cells of two phases
  std::size_t nodes = 0;             // in the file (certify's other checks see the welded mesh)
  struct Count {
    std::string key, label;
    std::size_t value = 0;
  };
  std::vector<Count> checks;  // every rule, each count an error when above 0
  bool sets_named = false;    // the file names sets (else `sets` lists the phase pairs claimed)
  struct SetRow {
    std::string name;  // empty when the file names no sets
    std::int32_t lower = 0, upper = 0;  // the pair its name denotes (or the claimed pair); 0: none
    std::size_t cells = 0;
  };
  std::vector<SetRow> sets;
  std::vector<std::string> examples;  // the first few failures, with ids and positions
  bool ok() const;
};

// Checks the cohesive cells of `m` (check_cohesive, with the file's phase ids; across the
// periodic planes of `periodic` when given) and, given the file's sets, the set rules.
template <int Dim>
CohesiveSection certify_cohesive(const mesh::SimplexMesh<Dim>& m, const CohesiveSetsInFile* sets,
                                 const CohesivePeriodicity<Dim>* periodic = nullptr);

struct Certificate {
  std::string mesh_source;   // file names for the report ("" if none)
  std::string scene_source;
  int dimension = 0;
  std::size_t node_count = 0, cell_count = 0;
  std::vector<std::pair<int, std::size_t>> cells_per_phase;  // (phase id, cells), by id
  std::vector<std::pair<int, std::string>> phase_names;      // from the scene, if any
  Box3 domain;  // z unused in 2D
  bool domain_from_scene = false;  // else the mesh's bounding box
  AspectStats aspect;
  ConformityReport conformity;
  std::optional<FidelityReport> fidelity;
  std::optional<PeriodicReport> periodic;  // a periodic scene: its faces match (check_periodic)
  // A mesh with cohesive cells: the checks above ran on its welded bulk (weld_view), these
  // on the cohesive cells.
  std::optional<CohesiveSection> cohesive;
  std::vector<std::string> notes;  // what was not checked and why

  bool quality_ok() const { return aspect.above_bound == 0; }
  bool passed() const {
    return quality_ok() && conformity.ok && (!fidelity || fidelity->ok) && (!periodic || periodic->ok) &&
           (!cohesive || cohesive->ok());
  }
};

// Without a scene: the given domain box (for boundary facets) and options.
template <int Dim>
Certificate certify(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& domain, const CertifyOptions& options);

// Against a scene: domain from the scene, expected measure = domain − voids (the oracle's
// exact void measures), inner boundary allowed iff the scene has a void phase (the total
// measure then checked to kVoidMeasureTolerance only), plus the phase-fidelity check
// (check_fidelity: nodes, in 3D centroids, per-phase measures).
// options.expected_measure/allow_inner_boundary are ignored.
template <int Dim>
Certificate certify(const mesh::SimplexMesh<Dim>& m, const geometry::Oracle<Dim>& oracle, const CertifyOptions& options);

std::string certificate_json(const Certificate& c);     // format "cisamr-certificate/1"
std::string certificate_html(const Certificate& c);     // one page, inline SVG and CSS
std::string certificate_summary(const Certificate& c);  // a few lines for the terminal

}  // namespace cisamr::quality
