// cisamr pack SPEC -o SCENE [--seed S]
// Packs the particle populations of a cisamr-pack/1 spec (lib/pack/README.md) and writes the
// scene. Prints the achieved volume fractions and size statistics. Unreachable targets and
// bad spec fields are input errors (exit 2). With `-o -` the scene goes to standard output and
// the summary to standard error.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/timer.hpp"
#include "io/atomic_file.hpp"
#include "io/scene_io.hpp"
#include "pack/pack.hpp"

namespace cisamr::app {
namespace {

struct PackArgs {
  std::string spec, output;
  long long seed = -1;
};

}  // namespace

void add_pack_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<PackArgs>();
  CLI::App* cmd = app.add_subcommand("pack", "Pack a virtual microstructure (hierarchical bounding boxes) into a scene");
  cmd->add_option("spec", args->spec, "Packing spec (cisamr-pack/1 JSON)")->required();
  cmd->add_option("-o,--output", args->output, "Scene to write (cisamr-scene/1 JSON)")->required()->check(output_path());
  cmd->add_option("--seed", args->seed, "Override the spec's random seed")
      ->check(number_in(0, 9007199254740992.0, true));  // 2^53: every whole number up to it is exact
  cmd->callback([args, &flags, &exit_code] {
    PhaseTimes times;
    if (show_progress(flags)) std::fprintf(stderr, "cisamr: packing %s\n", args->spec.c_str());
    pack::PackSpec spec;
    {
      ScopedPhase timer(&times, "read spec");
      spec = pack::read_pack_spec(args->spec);
    }
    if (args->seed >= 0) spec.seed = static_cast<std::uint64_t>(args->seed);
    pack::PackResult result;
    {
      ScopedPhase timer(&times, "pack");
      result = pack::pack(spec);
    }
    {
      ScopedPhase timer(&times, "write");
      io::write_scene(args->output, result.scene);
    }
    const pack::PackReport& r = result.report;
    FILE* summary = io::is_standard_output(args->output) ? stderr : stdout;
    if (!flags.quiet) {
      std::fprintf(summary, "packed %zu inclusions (%dD, seed %llu) in %.2f s -> %s\n", result.scene.inclusions.size(),
                   spec.dimension, static_cast<unsigned long long>(spec.seed), r.seconds, args->output.c_str());
      std::fprintf(summary, "  %-16s %9s %9s %9s %10s %10s %10s %10s %10s %8s\n", "population", "placed", "target", "fraction",
                   "size min", "size mean", "size max", "size std", "trials", "failed");
      for (std::size_t i = 0; i < r.populations.size(); ++i) {
        const auto& p = r.populations[i];
        const auto& s = spec.populations[i];
        char target[32] = "-";
        if (s.volume_fraction) std::snprintf(target, sizeof target, "%.4f", *s.volume_fraction);
        std::fprintf(summary, "  %-16s %9lld %9s %8.4f%s %10.4g %10.4g %10.4g %10.4g %10lld %8lld\n", p.name.c_str(),
                     static_cast<long long>(p.placed), target, p.achieved_fraction, p.fraction_is_estimate ? "~" : " ",
                     p.size_min, p.size_mean, p.size_max, p.size_std, static_cast<long long>(p.trials),
                     static_cast<long long>(p.failures));
        if (p.size_scale != 1) std::fprintf(summary, "  %-16s sizes scaled by %.6g to meet both count and volume fraction\n", "", p.size_scale);
      }
      std::fprintf(summary, "  total volume fraction %.4f%s; %lld exact checks, %lld pairs cleared by secondary boxes\n",
                   r.total_fraction, "", static_cast<long long>(r.exact_checks),
                   static_cast<long long>(r.secondary_rejections));
      bool estimate = false;
      for (const auto& p : r.populations) estimate = estimate || p.fraction_is_estimate;
      if (estimate) std::fprintf(summary, "  ~ union of overlapping particles, estimated on a raster\n");
    }
    if (flags.verbose)
      for (const auto& [name, seconds] : times.phases()) std::fprintf(summary, "  %-10s %8.3f s\n", name.c_str(), seconds);
    exit_code = 0;
  });
}

}  // namespace cisamr::app
