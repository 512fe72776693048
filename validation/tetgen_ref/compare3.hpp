#pragma once
// Side by side: one 3D scene meshed by our mesher (pipeline::mesh3_with_stats) and by TetGen
// (tetgen_mesh.hpp), with the same measurements for both: tetrahedra, wall time, peak
// memory, per-phase and per-inclusion volume error, aspect-ratio distribution (DESIGN.md §2
// definition), dihedral angles, conformity. Used by validation/bench/bench_mesh3 and by
// `cisamr compare`; nothing here prints (progress goes through a callback).
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "geometry/scene.hpp"
#include "pipeline/pipeline.hpp"
#include "tetgen_ref/tetgen_mesh.hpp"

namespace cisamr::tetgen_ref {

// Aspect-ratio bins of the report: [1,1.5) [1.5,2) [2,3) [3,4) [4,5) [5,10) [10,inf].
inline constexpr std::array<double, 7> kAspectBinLower{1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 10.0};

struct PhaseVolume {
  int id = 0;
  std::string name;
  double exact = 0, meshed = 0, relative_error = 0;  // (meshed - exact) / exact
};

struct MesherReport {
  std::string name;      // "cisamr" / "TetGen 1.5"
  std::string settings;  // "h = 0.02, levels 1" / "-pq1.4a...AQ"
  std::int64_t tets = 0, nodes = 0;
  double seconds = 0;    // wall time of the whole mesher call (geometry set-up included)
  double cpu_seconds = 0;  // user + system CPU time of the same call (less sensitive to load)
  std::vector<std::pair<std::string, double>> phase_seconds;
  double tets_per_second = 0;
  // Memory: peak resident set during the mesher call minus the resident set just before it
  // (Linux VmHWM after resetting it through /proc/self/clear_refs), in a child process
  // when `isolated`. memory_method says exactly what was measured.
  double peak_rss_delta_bytes = 0, bytes_per_tet = 0;
  bool isolated = false;
  std::string memory_method;
  std::vector<PhaseVolume> phases;  // non-void phases of the scene
  // Per inclusion (tets assigned by centroid): relative volume error against the exact one.
  std::int64_t inclusions_measured = 0;
  double inclusion_error_worst = 0; // the error of largest magnitude (signed)
  double inclusion_error_mean = 0;  // mean signed error
  std::int64_t inclusion_worst = -1;
  std::int64_t tets_outside_inclusions = 0;  // inclusion-phase tets whose centroid is in none
  // Aspect ratio (mesh/metrics.hpp) and dihedral angles.
  double aspect_max = 0, aspect_mean = 0;
  std::array<std::int64_t, kAspectBinLower.size()> aspect_bins{};
  std::int64_t above_5 = 0;
  double min_dihedral_deg = 0, max_dihedral_deg = 0;
  bool conformity_checked = false, conforming = false;
  std::string conformity_problems;  // counts of what failed, "" when conforming
  std::vector<std::pair<std::string, double>> extra;  // mesher-specific numbers (e.g. PLC size)
};

struct CompareOptions {
  pipeline::Options cisamr;     // our mesher's knobs
  TetgenOptions tetgen;         // max_volume <= 0: chosen to match our tetrahedron count
  // Choosing TetGen's -a to match our tetrahedron count N: TetGen's count behaves like
  // N0 + C / a, where N0 (the tets the quality bound puts around the inclusion surfaces)
  // dominates scenes of many small inclusions. pilots = 2: one run without -a gives N0, one
  // at a guess (a quarter of the volume tets) gives C; 1: N0 only, C = V / volume_factor;
  // 0: no pilot, N0 = 0. Pilot runs are not counted in TetGen's time.
  int pilots = 2;
  double volume_factor = 2.0;   // first guess: mean volume of a volume-bound TetGen tet ≈ a / 2
  bool run_tetgen = true;
  bool isolate = true;          // each mesher in a forked child (clean memory figures)
  bool check_conformity = true;
  std::function<void(const std::string&)> progress;  // optional; called in the parent
};

struct Comparison {
  std::string scene_source;
  std::int64_t inclusions = 0;
  double h = 0;
  int levels = 0;
  MesherReport ours, tetgen;
  bool has_tetgen = false;
  double tetgen_pilot_seconds = 0;   // not included in TetGen's time
  std::int64_t tetgen_pilot_tets = 0;  // N0: TetGen's count without -a (0: no pilot)
  double tetgen_pilot_volume = 0;      // a of the second pilot (0: none)
  std::int64_t tetgen_pilot2_tets = 0; // its count
  double time_ratio = 0;             // TetGen seconds / ours
};

Comparison compare3(const geometry::SceneDesc& scene, const CompareOptions& options);

// The measurements of one mesh, the same for both meshers (tets go to inclusions by their
// centroid). Timing and memory fields are left for the caller.
MesherReport measure_mesh(const mesh::Mesh3& m, const geometry::SceneDesc& scene, bool check_conformity);

std::string comparison_table(const Comparison& c);  // plain text, fixed-width columns
std::string comparison_json(const Comparison& c);   // "cisamr-compare/1"
std::string comparison_html(const Comparison& c);   // one self-contained page

}  // namespace cisamr::tetgen_ref
