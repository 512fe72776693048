// cisamr partition SCENE -n N -o PARTS.json [--svg PARTS.svg] [--compare-uniform]
// Algorithm 1: load-balanced boxes on the background lattice (lib/partition/README.md).
// Both outputs appear together or not at all (io::OutputSet). `-` for either writes it to
// standard output, and the summary then goes to standard error.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/timer.hpp"
#include "io/atomic_file.hpp"
#include "io/scene_io.hpp"
#include "parallel/ghost.hpp"
#include "partition/partition.hpp"

namespace cisamr::app {
namespace {

struct PartitionArgs {
  std::string scene, output, svg;
  int n = 0;
  bool compare_uniform = false;
  bool no_rebalance = false;
  int oversubscription = 8;
  std::string method = "best";
};

void write_text(const std::string& path, const std::string& text) {
  io::AtomicFile file(path);
  file.write(text);
  file.commit();
}

void print_row(FILE* out, const char* name, const partition::Partition& p, double seconds) {
  std::fprintf(out, "  %-14s %6zu %12.6g %12.6g %9.4f %14.6g %9.3f\n", name, p.parts.size(), p.max_load(), p.mean_load(),
               p.imbalance(), p.shared_face_measure(), seconds);
}

}  // namespace

void add_partition_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<PartitionArgs>();
  CLI::App* cmd = app.add_subcommand("partition", "Split the domain into load-balanced boxes (Algorithm 1)");
  cmd->add_option("scene", args->scene, "Scene (cisamr-scene/1 JSON)")->required();
  cmd->add_option("-n,--parts", args->n, "Number of partitions")->required()->check(number_in(1, 1 << 20, true));
  cmd->add_option("-o,--output", args->output, "Partition file to write (cisamr-partition/1 JSON)")
      ->required()
      ->check(output_path());
  cmd->add_option("--svg", args->svg, "Also draw the boxes over the inclusions (3D: three z-slices)")
      ->check(output_path());
  cmd->add_flag("--compare-uniform", args->compare_uniform,
                "Also compute a uniform grid of the same number of boxes and print both");
  cmd->add_flag("--no-rebalance", args->no_rebalance, "No face sliding after merging/bisection");
  cmd->add_option("--method", args->method, "best, merge (Algorithm 1 only) or bisection")
      ->check(CLI::IsMember({"best", "merge", "bisection"}))
      ->capture_default_str();
  cmd->add_option("--oversubscription", args->oversubscription, "Leaves per partition in the over-decomposition (≥)")
      ->check(number_in(1, 1 << 20, true))
      ->capture_default_str();
  cmd->callback([args, &flags, &exit_code] {
    PhaseTimes times;
    if (show_progress(flags)) std::fprintf(stderr, "cisamr: partitioning %s into %d boxes\n", args->scene.c_str(), args->n);
    geometry::SceneDesc scene;
    {
      ScopedPhase timer(&times, "read scene");
      scene = io::read_scene(args->scene);
    }
    partition::PartitionOptions options;
    options.rebalance = !args->no_rebalance;
    options.oversubscription = args->oversubscription;
    using Method = partition::PartitionOptions::Method;
    options.method = args->method == "merge" ? Method::merge : args->method == "bisection" ? Method::bisection : Method::best;
    options = parallel::ghost_aware(options, scene.dimension);  // the boxes `cisamr mesh` meshes
    partition::Partition p;
    const auto t0 = std::chrono::steady_clock::now();
    {
      ScopedPhase timer(&times, "partition");
      p = partition::partition_domain(scene, args->n, options);
    }
    const double ours_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    {
      ScopedPhase timer(&times, "write");
      io::OutputSet outputs;
      write_text(args->output, partition::to_json(p, args->scene));
      if (!args->svg.empty()) write_text(args->svg, partition::to_svg(p, scene));
      outputs.commit();
    }
    FILE* summary = io::is_standard_output(args->output) || io::is_standard_output(args->svg) ? stderr : stdout;
    if (!flags.quiet) {
      std::fprintf(summary, "partitioned %s into %zu boxes -> %s\n", args->scene.c_str(), p.parts.size(), args->output.c_str());
      std::fprintf(summary, "  %-14s %6s %12s %12s %9s %14s %9s\n", "method", "parts", "max load", "mean load", "max/mean",
                   "shared faces", "time [s]");
      print_row(summary, p.method.c_str(), p, ours_s);
      if (p.ghost_weight > 0)  // 3D: what the cuts balanced
        std::fprintf(summary, "  cost (load and %.2f x the load of a %lld-cell ghost): max %.6g, mean %.6g, max/mean %.4f\n",
                     p.ghost_weight, static_cast<long long>(p.ghost_cells), p.max_cost(), p.mean_cost(),
                     p.cost_imbalance());
      if (args->compare_uniform) {
        const auto t1 = std::chrono::steady_clock::now();
        const partition::Partition u = partition::uniform_grid_partition(scene, args->n, options);
        print_row(summary, "uniform grid", u, std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
      }
    }
    if (flags.verbose)
      for (const auto& [name, seconds] : times.phases()) std::fprintf(summary, "  %-10s %8.3f s\n", name.c_str(), seconds);
    exit_code = 0;
  });
}

}  // namespace cisamr::app
