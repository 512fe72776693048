// The cisamr-report/1 document: one writer for sequential and distributed runs.
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <nlohmann/json.hpp>

#include "driver/driver.hpp"
#include "io/mesh_io.hpp"

namespace cisamr::driver {
namespace {

std::string hex(std::uint64_t sum) {
  char text[20];
  std::snprintf(text, sizeof text, "%016" PRIx64, sum);
  return text;
}

// The knobs and every counter of pipeline::Counters, by its report name.
template <int Dim>
nlohmann::json algorithm(const MeshRun<Dim>& run) {
  const pipeline::Options& options = run.options.pipeline;
  nlohmann::json j = {{"alpha", options.alpha}, {"extra_levels", options.extra_levels}};
  if constexpr (Dim == 3) {
    j["alpha_diagonal"] = options.alpha_diagonal3;
    j["guard_bound"] = options.bound3;
  }
  const pipeline::Counters<Dim>& counters = run.mesh.counters;
  pipeline::Counters<Dim>::for_each(
      [&](const char* name, auto member, pipeline::Reduction) { j[name] = counters.*member; });
  // Coarse cells of the partitions' boxes (ghosts are in "partitions").
  if (run.distributed) j["coarse_cells_meshed"] = counters.coarse_cells;
  return j;
}

std::string ghost_rule(int dim, const parallel::GhostRule& rule) {
  if (dim == 3) {
    std::string name = rule.margin3_cubes > 0
                           ? "forced-" + std::to_string(static_cast<int>(std::ceil(rule.margin3_cubes))) + "-cubes"
                           : "reach-3d";
    // The windows of r-adaptivity and face swapping (pipeline::Ghost), when not derived.
    const auto text = [](double cells) {
      std::ostringstream s;
      s << cells;
      return s.str();
    };
    const double swap = rule.swap_window3_cells();
    if (rule.radapt_window_cells3 < 0 && swap < 0)
      name += "-whole-ghost";
    else if (rule.radapt_window_cells3 != 0 || swap != 0)
      name += "-windows-" + text(rule.radapt_window_cells3) + "-" + text(swap);
    return name;
  }
  return rule.level_aware ? "level-aware" : "fixed-" + std::to_string(static_cast<int>(rule.fixed_cells)) + "-cells";
}

}  // namespace

template <int Dim>
std::string report(const MeshRun<Dim>& run, const std::string& scene_path, const Output& output) {
  const parallel::DistributedMesh<Dim>& m = run.mesh;
  nlohmann::json j;
  j["format"] = "cisamr-report/1";
  j["scene"] = scene_path;
  j["output"] = output.path;
  if (output.pieces) j["pieces"] = output.piece_paths;
  j["dimension"] = Dim;
  j["nodes"] = m.piece.global_nodes;
  j["elements"] = m.global_cells;
  nlohmann::json phases = nlohmann::json::array();  // measure: area in 2D, volume in 3D
  for (std::size_t k = 0; k < m.phases.size(); ++k) {
    const PhaseFigures f = k < run.phase_figures.size() ? run.phase_figures[k] : PhaseFigures{};
    phases.push_back({{"id", m.phases[k].id}, {"name", m.phases[k].name}, {"void", m.phases[k].is_void},
                      {"elements", f.elements}, {"measure", f.measure}});
  }
  j["phases"] = phases;
  const quality::AspectStats& a = run.aspect;  // angles: triangle angles in 2D, dihedral angles in 3D
  j["aspect_ratio"] = {{"max", a.max},
                       {"mean", a.mean},
                       {"bound", a.bound},
                       {"above_bound", a.above_bound},
                       {"bin_edges", a.bin_edges},
                       {"histogram", a.histogram},
                       {"min_angle_deg", a.min_angle_deg},
                       {"max_angle_deg", a.max_angle_deg}};
  j["algorithm"] = algorithm(run);
  nlohmann::json timings = nlohmann::json::object();  // seconds over ranks
  for (const parallel::PhaseSpread& s : run.timings) timings[s.name] = {{"min", s.min}, {"max", s.max}, {"mean", s.mean}};
  j["timings_s"] = timings;
  j["total_s"] = run.total_seconds;
  // Each process's maximum resident set size (VmHWM) at the end of the run, over ranks; per
  // element: all ranks' together over the mesh's elements.
  j["peak_rss_bytes"] = {{"min", run.peak_rss_bytes.min}, {"max", run.peak_rss_bytes.max},
                         {"total", run.peak_rss_bytes.total}};
  j["bytes_per_element"] =
      m.global_cells > 0 ? static_cast<double>(run.peak_rss_bytes.total) / static_cast<double>(m.global_cells) : 0.0;
  j["ranks"] = run.ranks;
  nlohmann::json parts = nlohmann::json::array();
  for (const parallel::PartitionSummary& p : m.partitions) {
    nlohmann::json part = {{"partition", p.id}, {"rank", p.rank}, {"elements", p.elements}};
    if (run.distributed) {
      part["lattice_min"] = std::vector<std::int64_t>(p.lattice_min.begin(), p.lattice_min.begin() + Dim);
      part["lattice_max"] = std::vector<std::int64_t>(p.lattice_max.begin(), p.lattice_max.begin() + Dim);
      part["load"] = p.load;
      part["cost"] = p.cost;
      part["nodes"] = p.nodes;
      part["ghost_cells"] = p.ghost;
      part["ghost_coarse_cells"] = p.ghost_cells;
      part["inclusions_loaded"] = p.inclusions;
      part["kernel_s"] = p.kernel_seconds;
      // The kernel's parts between exchanges (parallel::kKernelStages), where ranks wait.
      if (m.near_faces_exchanged)
        part["kernel_stages_s"] = std::vector<double>(p.stage_seconds.begin(), p.stage_seconds.end());
    }
    parts.push_back(part);
  }
  j["partitions"] = parts;
  if (run.distributed) {
    const parallel::Spread load = parallel::spread_of(m.partitions, &parallel::PartitionSummary::load);
    const parallel::Spread cost = parallel::spread_of(m.partitions, &parallel::PartitionSummary::cost);
    j["partition_method"] = m.partition_method;
    j["ghost_rule"] = ghost_rule(Dim, run.options.ghost);
    // 3D: whether the forest and the decisions near faces were exchanged or recomputed in a
    // wider ghost (lib/parallel/README.md), how many cubes and nodes took their owner's, and
    // how many cubes' own refinement differed.
    if constexpr (Dim == 3) {
      j["near_faces"] = m.near_faces_exchanged ? "exchanged" : "recomputed";
      j["exchanged_nodes"] = m.exchanged_nodes;
      j["exchanged_cubes"] = m.exchanged_cubes;
      j["replaced_cubes"] = m.replaced_cubes;
    }
    // The cuts balance the cost (the load plus, in 3D, the ghost's weighted load), so the
    // loads alone may differ more.
    j["load"] = {{"max", load.max},      {"mean", load.mean},      {"imbalance", load.imbalance()},
                 {"cost_max", cost.max}, {"cost_mean", cost.mean}, {"cost_imbalance", cost.imbalance()}};
    j["scene_inclusions"] = m.scene_inclusions;
    if constexpr (Dim == 3)  // each STL file read by one rank, then by the ranks whose partitions need it
      j["stl_files_read"] = {{"min", run.stl_files_read.min}, {"max", run.stl_files_read.max},
                             {"total", run.stl_files_read.total}};
  }
  if (run.any_periodic()) {
    // The torus: its axes and periods, the images the listed inclusions brought in, the slaves
    // the writers constrain, and (pieces of a parallel run) the exchange that found their masters.
    nlohmann::json periodic = {{"axes", std::vector<bool>(run.periodic.begin(), run.periodic.end())},
                               {"period", std::vector<double>(run.period.begin(), run.period.end())},
                               {"images", m.periodic_images},
                               {"slaves", run.periodic_slaves}};
    for (const parallel::PhaseSpread& s : run.timings)
      if (s.name == "periodic") periodic["master_exchange_s"] = s.max;
    j["periodic"] = periodic;
  }
  if (run.options.pipeline.cohesive) {
    // Zero-thickness cells on the interfaces: one set per phase pair, named as the .inp
    // ELSET and the .msh physical group.
    nlohmann::json sets = nlohmann::json::array();
    for (const auto& set : run.cohesive_sets)
      sets.push_back({{"name", io::cohesive_set_name(m.phases, set.lower, set.upper)},
                      {"phases", {set.lower, set.upper}},
                      {"elements", set.elements}});
    j["cohesive"] = {{"elements", run.cohesive_elements}, {"sets", sets}, {"type", Dim == 2 ? "COH2D4" : "COH3D6"}};
  }
  j["checksum"] = hex(run.checksum);
  return j.dump(2) + "\n";
}

template std::string report<2>(const MeshRun<2>&, const std::string&, const Output&);
template std::string report<3>(const MeshRun<3>&, const std::string&, const Output&);

}  // namespace cisamr::driver
