// cisamr mesh: parses the options, meshes through driver::mesh_scene (sequential, or the
// parallel mesher with --partitions N or under mpiexec), writes, prints (mesh_summary.cpp).
// Every rank runs all of this; only rank 0 prints and writes the report.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include <unistd.h>

#include "commands.hpp"
#include "mesh_summary.hpp"
#include "progress_line.hpp"
#include "driver/driver.hpp"
#include "io/atomic_file.hpp"
#include "parallel/collective.hpp"
#include "parallel/ghost.hpp"
#include "parallel/session.hpp"

namespace cisamr::app {
namespace {

struct MeshArgs {
  std::string scene, output, report, svg, format;
  std::string plane = "stress";  // 2D Abaqus elements: CPS3 (stress) or CPE3 (strain)
  std::string svg_axis = "z";
  std::optional<double> svg_at;
  bool gather = false;
  bool stream = false;  // write .pvtu pieces while meshing (parallel/stream.hpp)
  bool fixed_ghost = false;  // the fixed 3-cell inclusion margin instead of the level-aware one
  double ghost_cells = 0;    // --ghost-cubes: the box margin forced (comparisons), 0: derived
  std::optional<double> explode;  // --explode F: the regions of the written .vtu moved apart
  driver::Options options;
};

// --explode needs cohesive cells to show and one .vtu holding every region (the regions of
// pieces would span ranks). Checked before any work.
void check_explode(const MeshArgs& args, const driver::Output& output) {
  if (!args.explode) return;
  if (!(*args.explode > 1))
    throw InputError("--explode", "", "must be a number above 1 (1 would leave every region where it is)");
  if (!args.options.pipeline.cohesive)
    throw InputError("--explode", "", "needs --cohesive: it moves the phase regions apart to show the cohesive cells");
  if (output.pieces || (output.format ? *output.format : io::mesh_format_of(output.path)) != io::MeshFormat::vtu)
    throw InputError("--explode", "", "writes one .vtu file: give -o NAME.vtu (with --gather in a parallel run)");
}

// Whether --stream writes one Gmsh or Abaqus file (else .pvtu pieces).
bool streams_one_file(const MeshArgs& args) {
  const std::string format =
      args.format.empty() ? std::filesystem::path(args.output).extension().string() : "." + args.format;
  return format == ".msh" || format == ".inp";
}

// --stream writes .pvtu pieces, or one .msh from chunks, as partitions finish: no picture of
// the whole.
void check_stream(const MeshArgs& args) {
  if (args.gather) throw InputError("--stream", "", "writes the mesh as the partitions finish; drop --gather");
  if (!args.svg.empty())
    throw InputError("--stream", "", "--svg draws the whole mesh, which a streamed run never holds; drop one of them");
  const std::string extension = std::filesystem::path(args.output).extension().string();
  if (!streams_one_file(args) && (!args.format.empty() || extension != ".pvtu"))
    throw InputError(args.output, "",
                     "--stream writes .pvtu pieces or one .msh or .inp file: name the output NAME.pvtu, NAME.msh "
                     "or NAME.inp");
}

void run_mesh(MeshArgs& args, const GlobalFlags& flags, int& exit_code) {
  const Comm& comm = parallel::world();
  driver::Options& options = args.options;
  options.ghost.level_aware = !args.fixed_ghost;
  if (args.ghost_cells > 0) options.ghost.margin3_cubes = options.ghost.box_margin_cells = args.ghost_cells;
  options.figures = !args.report.empty();
  options.svg_slice = {.axis = args.svg_axis[0] - 'x', .at = args.svg_at};
  // Progress: drawn on rank 0, for the slowest rank (flags are alike on every rank, so every
  // rank creates the RankProgress, collectively, or none does).
  std::unique_ptr<ProgressLine> progress;
  std::unique_ptr<parallel::RankProgress> ranks;
  if (!flags.quiet) {
    if (comm.rank() == 0)
      progress = std::make_unique<ProgressLine>(
          isatty(STDERR_FILENO) ? ProgressLine::Mode::terminal : ProgressLine::Mode::log, ProgressLine::to_stderr(),
          flags.progress_interval);
    if (progress) progress->start_ticker();
    ranks = std::make_unique<parallel::RankProgress>(comm, progress.get());
  }
  options.progress = ranks.get();
  if (args.stream) {
    parallel::run_collectively(comm, [&] { check_stream(args); });
    // Unless told: the fewest partitions, at least 8 per rank, whose share fits in memory
    // (the driver chooses them from the scene).
    if (options.partitions == 0) {
      options.partitions = driver::kStreamedPartitionsPerRank * comm.size();
      options.stream_fewest_partitions = true;
    }
  }
  // Fail on a bad output name before any work.
  // A streamed .msh or .inp is one file, written on rank 0 from every partition's chunks (as --gather's).
  driver::Output output =
      driver::plan_output(comm, args.output, args.gather || (args.stream && streams_one_file(args)),
                          driver::is_distributed(comm, options), args.format,
                          args.plane == "strain" ? io::PlaneKind::strain : io::PlaneKind::stress);
  options.stream_format = output.format;
  options.stream_plane = output.plane;
  if (args.stream) options.stream = output.path;
  // Pieces, or one .msh or .inp of a parallel run (--gather): streamed when the mesh would not fit.
  else if ((output.pieces || (args.gather && streams_one_file(args) && driver::is_distributed(comm, options))) &&
           args.svg.empty())
    options.stream_if_needed = output.path;
  if (options.pipeline.cohesive)
    parallel::run_collectively(comm, [&] {
      if (!output.pieces && (output.format ? *output.format : io::mesh_format_of(output.path)) == io::MeshFormat::medit)
        throw InputError(output.path, "", "--cohesive: Medit .mesh cannot hold cohesive elements; write .vtu, .msh or .inp");
    });
  parallel::run_collectively(comm, [&] {
    check_explode(args, output);
    if (comm.rank() != 0) return;  // rank 0 writes the report and the picture
    if (!args.report.empty()) io::check_writable(args.report);
    if (!args.svg.empty()) io::check_writable(args.svg);
  });
  output.explode = args.explode.value_or(0);
  // The mesh (a streamed run writes its pieces while meshing), the picture and the report,
  // or none of them.
  io::OutputSet outputs;
  auto meshed = driver::mesh_scene(comm, args.scene, options);
  std::visit(
      [&](auto& run) {
        if (run.streamed && output.pieces) {  // one piece per partition (their number may have been chosen for memory)
          output.piece_paths.clear();
          for (std::size_t p = 0; p < run.mesh.partitions.size(); ++p)
            output.piece_paths.push_back(parallel::piece_path(output.path, static_cast<int>(p)));
        }
        if (comm.rank() == 0 && !run.note.empty() && !flags.quiet) std::fprintf(stderr, "cisamr: note: %s\n", run.note.c_str());
        driver::write_outputs(comm, run, output, args.svg);
        driver::finish(comm, run);
        if (!args.report.empty())
          parallel::run_collectively(comm, [&] {
            if (comm.rank() == 0) write_text_file(args.report, driver::report(run, args.scene, output));
          });
        parallel::run_collectively(comm, [&] { outputs.commit(); });
        // Data on standard output: the summary goes to stderr.
        const bool data_on_stdout = io::is_standard_output(args.report) || io::is_standard_output(output.path);
        if (progress) progress->finish();
        if (comm.rank() == 0) print_mesh_summary(data_on_stdout ? stderr : stdout, run, output, flags);
        exit_code = run.aspect.above_bound > 0 ? 3 : 0;
      },
      meshed);
}

}  // namespace

void add_mesh_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<MeshArgs>();
  pipeline::Options& knobs = args->options.pipeline;
  parallel::GhostRule& ghost = args->options.ghost;
  CLI::App* cmd = app.add_subcommand("mesh", "Mesh a scene (cisamr-scene/1 JSON) into a conforming simplex mesh");
  cmd->add_option("scene", args->scene, "Scene file")->required();
  cmd->add_option("-o,--output", args->output,
                  "Output mesh: .vtu, .msh (Gmsh 4.1), .inp (Abaqus) or .mesh (Medit); in parallel also .pvtu "
                  "(one .vtu piece per rank)")
      ->required()
      ->check(output_path());
  cmd->add_option("--format", args->format, "Mesh format when -o does not name one (-o - writes standard output)")
      ->check(CLI::IsMember({"vtu", "msh", "inp", "mesh"}));
  cmd->add_option("--plane", args->plane,
                  "2D .inp output: plane stress (CPS3 elements, the default) or plane strain (CPE3)")
      ->check(CLI::IsMember({"stress", "strain"}));
  cmd->add_option("--report", args->report, "Write a JSON report (counts, per-phase measure, aspect ratios, timings)")
      ->check(output_path());
  cmd->add_option("--svg", args->svg,
                  "Write a picture of the mesh coloured by phase (3D: the slice through the domain centre, "
                  "--svg-axis and --svg-at)")
      ->check(output_path());
  cmd->add_option("--svg-axis", args->svg_axis, "3D picture: the axis the slice plane is normal to")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->capture_default_str();
  cmd->add_option("--svg-at", args->svg_at,
                  "3D picture: the slice plane's coordinate along --svg-axis (default: the domain centre)")
      ->check(number_in(-1e30, 1e30));
  cmd->add_option("--alpha", knobs.alpha, "r-adaptivity snap threshold, fraction of the edge length")
      ->check(number_in(0.05, 0.5))
      ->capture_default_str();
  cmd->add_option("--extra-levels", knobs.extra_levels,
                  "Levels beyond the largest requested one that may separate close interfaces")
      ->check(number_in(0, 10, true))
      ->capture_default_str();
  cmd->add_option("--bound", args->options.bound, "Aspect-ratio bound for the exit status (default 3 in 2D, 5 in 3D)")
      ->check(number_in(1, 1e6));
  cmd->add_option("--partitions", args->options.partitions,
                  "Mesh N load-balanced partitions with the parallel mesher (N >= MPI ranks; default under "
                  "mpiexec: one per rank)")
      ->check(number_in(1, 1 << 20, true));
  cmd->add_option("--max-elements", args->options.max_elements,
                  "The most elements held in memory (default: what this machine's memory holds at 130 bytes "
                  "per element). A larger estimate is refused, or streamed when the output is .pvtu pieces; a "
                  "streamed run holds one partition and its ghost per rank at a time")
      ->check(number_in(1, 1e15));
  cmd->add_flag("--cohesive", args->options.pipeline.cohesive,
                "Zero-thickness cohesive elements on every interface between phases (COH2D4/COH3D6 in .inp, "
                "quads/prisms in .msh, quads/wedges in .vtu), interface nodes split per phase");
  cmd->add_option("--explode", args->explode,
                  "With --cohesive and a .vtu output: move each phase region away from the domain centre by (F-1) "
                  "times its centroid's offset, so that the cohesive cells show (for viewing only)")
      ->check(number_in(1, 1e6));
  cmd->add_flag("--stream", args->stream,
                "Write the mesh while meshing, partition by partition, holding one partition per rank at a time "
                "(default --partitions: 8 per rank, more if their share would not fit in memory): .pvtu (one "
                "piece per partition, global node ids) or one Gmsh .msh or Abaqus .inp (each partition's nodes "
                "and elements written as it is done, joined on rank 0)");
  cmd->add_flag("--gather", args->gather,
                "Parallel run: write one file on rank 0 (any format) instead of .pvtu pieces");
  cmd->add_flag("--fixed-ghost", args->fixed_ghost,
                "Parallel run (2D): a fixed 3-cell margin around every inclusion instead of the level-aware one");
  cmd->add_option("--ghost-closure-rounds", ghost.max_closure_rounds,
                  "Comparison: chain the ghost region through R rounds of nearby inclusions (0, the default, "
                  "is exact because inclusion levels are settled beforehand; -1: the full closure)")
      ->check(named("--ghost-closure-rounds", number_in(-1, 1e6, true)))
      ->group("");
  cmd->add_option("--ghost-cubes", args->ghost_cells,
                  "Comparison: a ghost of this many coarse cells (2D) or cubes (3D) instead of the one derived from "
                  "the kernel's reach (lib/parallel/README.md); too few break partition invariance")
      ->check(named("--ghost-cubes", number_in(0, 1e6)))
      ->group("");
  cmd->add_flag("--no-ghost-exchange{false}", args->options.exchange_near_faces,
                "Comparison (3D, in memory): every partition recomputes the forest and the decisions near its box's "
                "faces in a wider ghost instead of taking them from their owners (as a streamed run does)")
      ->group("");
  cmd->add_option("--ghost-windows", ghost.radapt_window_cells3,
                  "Comparison (3D): r-adaptivity's window around a partition box, in cells of the deciding level "
                  "(face swapping's: " + std::to_string(parallel::kRadaptWindow3 - parallel::kSwapWindow3) +
                      " fewer, at least half a cell), instead of the derived ones (" + std::to_string(parallel::kRadaptWindow3) +
                      " and " + std::to_string(parallel::kSwapWindow3) + "; 0: those); "
                  "-1: both on the whole ghost, as before the windows (lib/parallel/README.md); too small ones break partition "
                  "invariance")
      ->check(named("--ghost-windows", number_in(-1, 1e6)))
      ->group("");
  cmd->callback([args, &flags, &exit_code] { run_mesh(*args, flags, exit_code); });
}

}  // namespace cisamr::app
