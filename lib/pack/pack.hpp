#pragma once
// Virtual microstructures: hierarchical bounding-box packing (paper §3, note §9).
// A PackSpec (parsed from a cisamr-pack/1 JSON file, see README.md) describes a domain
// and particle populations; pack() places the particles and returns the scene plus a
// report. Pure: no printing, no files written; bad specs and unreachable targets throw
// InputError naming the field.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "geometry/scene.hpp"

namespace cisamr::pack {

enum class ShapeKind { circle, ellipse, polygon, nurbs, sphere, ellipsoid, fibre, stl };

// A random scalar: fixed, uniform(min,max), normal(mean,std), lognormal(mean,std of the
// value itself). normal/lognormal are truncated to [min, max] when given (and to > 0).
struct Law {
  enum class Kind { fixed, uniform, normal, lognormal };
  Kind kind = Kind::fixed;
  double value = 1, min = 0, max = 0, mean = 0, std = 0;
  bool has_min = false, has_max = false;
};

struct OrientationLaw {
  enum class Kind { random, fixed, normal };
  Kind kind = Kind::random;
  double angle = 0;  // 2D: fixed angle / normal mean (radians)
  double std = 0;    // normal: std of the angle (2D) or of the tilt angle (3D)
  geometry::Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // 3D fixed / normal mean
};

struct SpatialLaw {
  enum class Kind { uniform, clustered };
  Kind kind = Kind::uniform;
  int clusters = 0;
  double cluster_radius = 0;   // std of the Gaussian around each cluster centre
  double in_clusters = 0;      // fraction of placement trials drawn near a cluster centre
};

struct Population {
  std::string name;
  ShapeKind shape = ShapeKind::circle;
  int phase = 2;
  int levels = -1;  // -1: mesh.levels
  std::optional<std::int64_t> count;
  std::optional<double> volume_fraction;  // of the region (union for overlapping populations)
  double tolerance = 0.005;               // absolute, on the volume fraction
  Law size;                               // equivalent radius / radius / base radius / scale
  Law aspect;                             // ellipse, ellipsoid: a/b (≥ 1)
  std::optional<Law> aspect_c;            // ellipsoid: a/c (default: same draw as a/b)
  OrientationLaw orientation;
  SpatialLaw spatial;
  double min_gap = 0;
  bool overlap = false;                   // same-phase particles of this population may overlap
  std::optional<Box3> region;             // sub-box (default: the domain)
  int vertices = 8;                       // polygon vertices / NURBS control points
  double roughness = 0.25;                // polygon/NURBS radial perturbation (0..0.6)
  int axis = 0;                           // fibre axis (0 = x, 1 = y, 2 = z)
  std::string file;                       // stl: resolved path
  std::string field;                      // "populations[i]" for error messages
};

struct PackSpec {
  std::string source;  // spec file, for error messages
  int dimension = 2;
  std::uint64_t seed = 1;
  Box3 domain{};
  bool periodic = false;
  double h = 1;
  int levels = 0;
  std::vector<geometry::Phase> phases;
  int matrix_phase = 1;
  std::int64_t max_trials = 5000;    // random placement trials per particle
  std::int64_t max_failures = 200;   // particles that may fail before giving up
  // Particles the run may hold (not read from JSON; 0: what this machine's memory holds at
  // about 1 KB per particle). A request beyond it is refused before any particle is drawn.
  std::int64_t max_particles = 0;
  std::vector<Population> populations;
};

// Parses a cisamr-pack/1 document; `source` names it in errors, relative STL paths are
// resolved against its directory.
PackSpec parse_pack_spec(const std::string& json_text, const std::string& source);
PackSpec read_pack_spec(const std::string& path);

struct PopulationReport {
  std::string name;
  std::int64_t placed = 0;
  double achieved_fraction = 0;   // of the population's region
  bool fraction_is_estimate = false;  // overlapping populations: raster estimate of the union
  double size_min = 0, size_max = 0, size_mean = 0, size_std = 0;  // of the `size` values
  double size_scale = 1;          // count + volume_fraction: factor applied to the sampled sizes
  std::int64_t trials = 0, failures = 0;
};

struct PackReport {
  std::vector<PopulationReport> populations;
  double total_fraction = 0;      // Σ measures / domain measure (overlaps counted once when estimated)
  std::int64_t exact_checks = 0;        // GJK / analytic distance checks
  std::int64_t secondary_rejections = 0;  // pairs cleared by the secondary boxes alone
  double seconds = 0;
};

struct PackResult {
  geometry::SceneDesc scene;
  PackReport report;
};

PackResult pack(const PackSpec& spec);

}  // namespace cisamr::pack
