#pragma once
// Side by side: one 3D scene meshed by our mesher (pipeline::mesh) and by TetGen
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
#include "compare/tetgen_mesh.hpp"

namespace cisamr::compare {

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
  // Every timed run of this mesher (CompareOptions::repeats); seconds/cpu_seconds above
  // are those of the run with the median wall time.
  std::vector<double> run_seconds, run_cpu_seconds;
  bool runs_differ = false;  // repeated runs gave different tetrahedron counts (non-determinism)
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
  // Choosing TetGen's -a to match our tetrahedron count N. TetGen's count is not N0 + C/a
  // (the quality bound refines around the surfaces whatever a is, and -a interacts with
  // -q: on data/bench/spheres300.json it falls like a^-1.5 to a^-2), so -a is found by measured
  // runs: a_1 = volume_factor · V / N (V the meshed volume), a_2 from a_1 assuming
  // count ∝ a^-initial_slope, then the secant through the last two runs in log-log space;
  // once runs lie on both sides of N, log-log interpolation between the closest run above
  // and the closest below (the count jumps with a: keep the bracket). Until a count is
  // within match_tolerance of N or match_runs runs were made. Every run
  // is a full measured run in its own child; the one closest to N is reported, the others'
  // time is reported separately (not counted in TetGen's time).
  int match_runs = 4;
  double match_tolerance = 0.05;
  double volume_factor = 3.0;   // count · a / V of TetGen -pq1.4 near 10^6 tets (measured)
  double initial_slope = 1.25;
  // Timed runs of each mesher (each in a fresh child): the run with the median wall time is
  // reported (its phases, memory, CPU time), with every run's wall and CPU time listed.
  int repeats = 1;
  bool run_tetgen = true;
  bool isolate = true;          // each mesher in a forked child (clean memory figures)
  bool check_conformity = true;
  std::function<void(const std::string&)> progress;  // optional; called in the parent
};

// One TetGen run made while matching -a to our count.
struct MatchingRun {
  double max_volume = 0;
  std::int64_t tets = 0;
  double seconds = 0;
};

struct Comparison {
  std::string scene_source;
  std::int64_t inclusions = 0;
  double h = 0;
  int levels = 0;
  MesherReport ours, tetgen;
  bool has_tetgen = false;
  std::vector<MatchingRun> tetgen_matching;  // in order; empty when -a was given
  double tetgen_matching_seconds = 0;        // wall time of the matching runs not reported
  double time_ratio = 0;                     // TetGen seconds / ours (wall, median runs)
  double cpu_time_ratio = 0;                 // the same with CPU time
};

Comparison compare3(const geometry::SceneDesc& scene, const CompareOptions& options);

// The measurements of one mesh, the same for both meshers (tets go to inclusions by their
// centroid). Timing and memory fields are left for the caller.
MesherReport measure_mesh(const mesh::Mesh3& m, const geometry::SceneDesc& scene, bool check_conformity);

std::string comparison_table(const Comparison& c);  // plain text, fixed-width columns
std::string comparison_json(const Comparison& c);   // "cisamr-compare/1"
std::string comparison_html(const Comparison& c);   // one self-contained page

}  // namespace cisamr::compare
