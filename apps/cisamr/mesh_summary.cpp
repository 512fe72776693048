// What `cisamr mesh` prints after a run (rank 0 only): the summary line, the collapse note,
// with -v the phase timings and the partitions, and the warning about unresolved cells.
#include "mesh_summary.hpp"

#include <algorithm>

namespace cisamr::app {

template <int Dim>
void print_mesh_summary(std::FILE* out, const driver::MeshRun<Dim>& run, const driver::Output& output,
                        const GlobalFlags& flags) {
  const pipeline::Counters<Dim>& counters = run.mesh.counters;
  if (!flags.quiet) {
    std::fprintf(out, "%s: %lld nodes, %lld %s, max aspect ratio %.3f (bound %.1f, %zu above), %.3f s", output.path.c_str(),
                static_cast<long long>(run.mesh.piece.global_nodes), static_cast<long long>(run.mesh.global_cells),
                Dim == 2 ? "triangles" : "tetrahedra", run.aspect.max, run.bound, run.aspect.above_bound,
                run.total_seconds);
    if (run.distributed) std::fprintf(out, ", %d rank(s), %zu partitions", run.ranks, run.mesh.partitions.size());
    std::fprintf(out, "\n");
    if (run.options.pipeline.cohesive)
      std::fprintf(out, "%lld cohesive elements (%s) on the interfaces between phases, in %zu set(s)\n",
                   static_cast<long long>(run.cohesive_elements), Dim == 2 ? "COH2D4" : "COH3D6",
                   run.cohesive_sets.size());
    if constexpr (Dim == 2) {
      if (counters.collapsed > 0)
        std::fprintf(out, "%lld quads held a feature below the local resolution (a tangency, a thin gap or a wedge "
                    "sharper than the bound allows); collapsed with nodes at most %.3g from the phases they serve\n",
                    static_cast<long long>(counters.collapsed), counters.max_collapse_deviation);
    } else if (counters.collapsed_nodes + counters.collapsed_cut_points > 0) {
      std::fprintf(out, "%lld nodes could neither stay nor snap without a tetrahedron above the bound (a tangency, a "
                  "thin gap or a wedge at the domain boundary); collapsed onto the interface, at most %.3g from "
                  "the phases they serve\n",
                  static_cast<long long>(counters.collapsed_nodes), counters.max_collapse_deviation);
    }
  }
  if (flags.verbose) {
    if (run.distributed)
      std::fprintf(out, "  %-10s %9s %9s %9s   (seconds over %d rank(s))\n", "phase", "min", "max", "mean", run.ranks);
    for (const auto& s : run.timings)
      if (run.distributed)
        std::fprintf(out, "  %-10s %9.3f %9.3f %9.3f\n", s.name.c_str(), s.min, s.max, s.mean);
      else
        std::fprintf(out, "  %-10s %8.3f s\n", s.name.c_str(), s.max);
    const double per_element = run.mesh.global_cells > 0 ? static_cast<double>(run.peak_rss_bytes.total) /
                                                               static_cast<double>(run.mesh.global_cells)
                                                         : 0.0;
    std::fprintf(out, "  peak memory %.1f MiB (the largest rank's), %.0f bytes per %s (all ranks)\n",
                 static_cast<double>(run.peak_rss_bytes.max) / (1024.0 * 1024.0), per_element,
                 Dim == 2 ? "triangle" : "tetrahedron");
    if (run.distributed) {
      const parallel::Spread load = parallel::spread_of(run.mesh.partitions, &parallel::PartitionSummary::load);
      const parallel::Spread cost = parallel::spread_of(run.mesh.partitions, &parallel::PartitionSummary::cost);
      std::fprintf(out, "  partition loads: max %.4g, mean %.4g, imbalance %.3f (%s)\n", load.max, load.mean,
                  load.imbalance(), run.mesh.partition_method.c_str());
      if (cost.max != load.max || cost.mean != load.mean)  // 3D: the cuts balanced load plus ghost
        std::fprintf(out, "  partition costs (load and ghost): max %.4g, mean %.4g, imbalance %.3f\n", cost.max, cost.mean,
                    cost.imbalance());
      for (const auto& p : run.mesh.partitions) {
        std::fprintf(out, "  part %3d rank %2d cells ", p.id, p.rank);
        for (int d = 0; d < Dim; ++d)
          std::fprintf(out, "%s[%lld,%lld)", d ? "x" : "", static_cast<long long>(p.lattice_min[d]),
                      static_cast<long long>(p.lattice_max[d]));
        std::fprintf(out, " load %10.4g elements %9lld ghost %3d inclusions %6lld kernel %.3f s\n", p.load,
                    static_cast<long long>(p.elements), p.ghost, static_cast<long long>(p.inclusions), p.kernel_seconds);
      }
    }
  }
  if (counters.unresolved > 0)
    std::fprintf(stderr, "cisamr: warning: %lld %s below the finest level's resolution\n",
                 static_cast<long long>(counters.unresolved), Dim == 2 ? "quads" : "leaves");
}

template void print_mesh_summary<2>(std::FILE*, const driver::MeshRun<2>&, const driver::Output&, const GlobalFlags&);
template void print_mesh_summary<3>(std::FILE*, const driver::MeshRun<3>&, const driver::Output&, const GlobalFlags&);

}  // namespace cisamr::app
