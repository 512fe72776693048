// cisamr certify MESH [--scene SCENE] [--html R.html] [--json R.json] [--bound X] [--whole]
// Checks any mesh io::read_mesh can read: aspect ratio against the bound, conformity, and
// (with --scene) phase fidelity, 2D and 3D. A .pvtu with global ids is checked piece by
// piece (quality::PiecewiseCertifier), unless --whole or what it holds asks for the merged mesh. A mesh with cohesive cells is certified on its
// bulk welded by exact coordinates (quality::weld_view), and its cohesive cells and sets
// are checked too (quality::certify_cohesive). Exit status 3 when the mesh fails, 0 when it passes.
#include <cstdio>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/timer.hpp"
#include "geometry/periodic.hpp"
#include "geometry/scene.hpp"
#include "io/atomic_file.hpp"
#include "io/mesh_io.hpp"
#include "io/scene_io.hpp"
#include "quality/certificate.hpp"
#include "quality/phase_match.hpp"
#include "quality/pieces.hpp"

namespace cisamr::app {
namespace {

struct CertifyArgs {
  std::string mesh, scene, html, json, phase_map;
  double bound = 0;  // 0: the dimension's bound
  double fidelity_tolerance = -1;  // < 0: 1e-9 of the domain diagonal
  bool whole = false;              // a .pvtu merged and read whole, not piece by piece
  int threads = 0;                 // pieces checked at once; set from the hardware
};

void progress(const GlobalFlags& flags, const char* what) {
  if (show_progress(flags)) std::fprintf(stderr, "cisamr: %s\n", what);
}

// Without a scene (nullptr) the domain is the mesh's bounding box and fidelity is not checked.
template <int Dim>
quality::Certificate certify_mesh(const mesh::SimplexMesh<Dim>& mesh, const geometry::SceneDesc* scene,
                                  const quality::CertifyOptions& options, const GlobalFlags& flags,
                                  PhaseTimes& times) {
  if (mesh.cohesive.count() > 0) {  // the checks of a mesh without cohesive cells, on the welded bulk
    progress(flags, "welding the cohesive copies");
    const quality::WeldedMesh<Dim> welded = [&] {
      ScopedPhase timer(&times, "weld");
      return quality::weld_view<Dim>(mesh);
    }();
    quality::Certificate c = certify_mesh<Dim>(welded.mesh, scene, options, flags, times);
    c.notes.push_back("cohesive mesh: the checks above ran on the bulk cells with their " +
                      std::to_string(mesh.node_count()) + " nodes welded by exact coordinates into " +
                      std::to_string(welded.mesh.node_count()));
    return c;
  }
  if (!scene) {
    ScopedPhase timer(&times, "certify");
    progress(flags, "checking the mesh (domain = its bounding box)");
    // Without a scene a void cannot be told from a hole: open boundaries inside the box are
    // counted as inner boundary (still checked for hanging nodes), not failed.
    quality::CertifyOptions o = options;
    o.allow_inner_boundary = true;
    quality::Certificate c = quality::certify<Dim>(mesh, quality::bounding_box(mesh), o);
    c.notes.push_back("no scene: the domain is the mesh's bounding box, phase fidelity is not checked and "
                      "open boundaries inside it are taken for voids");
    return c;
  }
  progress(flags, "building the geometry oracle");
  const geometry::Oracle<Dim> oracle = [&] {
    ScopedPhase timer(&times, "oracle");
    return geometry::Oracle<Dim>(*scene);  // a periodic scene's geometry wraps: its images count
  }();
  ScopedPhase timer(&times, "certify");
  progress(flags, "checking the mesh against the scene");
  return quality::certify<Dim>(mesh, oracle, options);
}

std::vector<quality::MeshPhase> mesh_phases_of(const io::LoadedMesh& loaded) {
  std::vector<quality::MeshPhase> phases;
  for (const geometry::Phase& p : loaded.phases) {
    const auto named = loaded.phase_names_in_file.find(p.id);
    phases.push_back({p.id, named != loaded.phase_names_in_file.end() ? named->second : ""});
  }
  return phases;
}

std::vector<quality::PhaseMapEntry> phase_map_of(const CertifyArgs& args) {
  return args.phase_map.empty() ? std::vector<quality::PhaseMapEntry>{} : quality::parse_phase_map(args.phase_map);
}

std::string phase_match_note(const std::vector<quality::MeshPhase>& mesh_phases, const std::map<int, int>& scene_id) {
  std::string note = "mesh phases matched to the scene:";
  for (const quality::MeshPhase& m : mesh_phases)
    note += " " + (m.name.empty() ? std::to_string(m.id) : "'" + m.name + "'") + " -> " +
            std::to_string(scene_id.at(m.id)) + ",";
  note.pop_back();
  return note;
}

// The mesh's phase ids made the scene's: by --phase-map, by the names the file gives, by number.
std::string match_scene_phases(const CertifyArgs& args, io::LoadedMesh& loaded, const geometry::SceneDesc& scene) {
  const std::vector<quality::MeshPhase> mesh_phases = mesh_phases_of(loaded);
  const std::map<int, int> scene_id = quality::match_phases(mesh_phases, scene.phases, phase_map_of(args), args.mesh);
  if (loaded.dimension == 2) quality::relabel_phases<2>(loaded.mesh2, scene_id);
  else quality::relabel_phases<3>(loaded.mesh3, scene_id);
  return phase_match_note(mesh_phases, scene_id);
}

// The frame in which facets on the periodic planes are checked too: a periodic scene's faces
// where the mesher puts them, min and min + N·h (as certify's check_periodic takes them);
// without a scene, the axes the file's constraints tie and the mesh's bounding box (whose
// max faces are those same exact coordinates: every face of a whole mesh holds nodes).
template <int Dim>
std::optional<quality::CohesivePeriodicity<Dim>> periodic_frame(const io::LoadedMesh& loaded,
                                                                const mesh::SimplexMesh<Dim>& mesh,
                                                                const geometry::SceneDesc* scene) {
  std::optional<quality::CohesivePeriodicity<Dim>> frame;
  if (scene && scene->any_periodic()) {
    frame.emplace();
    const Vec3 period = geometry::periods(*scene);
    for (int d = 0; d < Dim; ++d) {
      const bool axis = scene->periodic[static_cast<std::size_t>(d)];
      frame->axes[static_cast<std::size_t>(d)] = axis;
      frame->faces.min[d] = scene->domain_min[d];
      frame->faces.max[d] = axis ? scene->domain_min[d] + period[d] : scene->domain_max[d];
    }
  } else if (!scene && loaded.any_periodic()) {
    frame.emplace();
    frame->faces = quality::bounding_box<Dim>(mesh);
    for (int d = 0; d < Dim; ++d) frame->axes[static_cast<std::size_t>(d)] = loaded.periodic_axes[static_cast<std::size_t>(d)];
  }
  return frame;
}

// The cohesive cells' checks, with the phase ids the file gives them (the bottom is on the
// lower id of the file's numbering, so these run before any relabelling to the scene's),
// across the periodic planes of a periodic mesh.
template <int Dim>
std::optional<quality::CohesiveSection> certify_cohesive_cells(const io::LoadedMesh& loaded,
                                                               const mesh::SimplexMesh<Dim>& mesh,
                                                               const geometry::SceneDesc* scene,
                                                               const GlobalFlags& flags, PhaseTimes& times) {
  if (mesh.cohesive.count() == 0) return std::nullopt;
  const std::optional<quality::CohesivePeriodicity<Dim>> periodic = periodic_frame<Dim>(loaded, mesh, scene);
  progress(flags, "checking the cohesive cells");
  ScopedPhase timer(&times, "cohesive");
  std::optional<quality::CohesiveSetsInFile> sets;
  if (!loaded.cohesive_set_of_cell.empty()) {
    sets.emplace();
    for (const io::LoadedMesh::CohesiveSet& set : loaded.cohesive_sets) sets->sets.push_back({set.name, set.named_pairs});
    sets->set_of_cell = loaded.cohesive_set_of_cell;
  }
  return quality::certify_cohesive<Dim>(mesh, sets ? &*sets : nullptr, periodic ? &*periodic : nullptr);
}

// The scene of --scene (none without), of the mesh's dimension.
std::optional<geometry::SceneDesc> read_scene_of(const CertifyArgs& args, int dimension, const GlobalFlags& flags,
                                                 PhaseTimes& times) {
  if (args.scene.empty()) {
    if (!args.phase_map.empty()) throw InputError("--phase-map", "", "needs --scene (the phases are mapped to the scene's)");
    return std::nullopt;
  }
  progress(flags, "reading the scene");
  ScopedPhase timer(&times, "read scene");
  geometry::SceneDesc scene = io::read_scene(args.scene);
  if (scene.dimension != dimension)
    throw InputError(args.scene, "dimension",
                     "the scene is " + std::to_string(scene.dimension) + "D but the mesh " + args.mesh + " is " +
                         std::to_string(dimension) + "D");
  return scene;
}

quality::Certificate certify_loaded(const CertifyArgs& args, io::LoadedMesh& loaded,
                                    const GlobalFlags& flags, PhaseTimes& times) {
  quality::CertifyOptions options;
  options.bound = args.bound;
  options.fidelity_tolerance = args.fidelity_tolerance;
  const std::optional<geometry::SceneDesc> scene = read_scene_of(args, loaded.dimension, flags, times);
  const geometry::SceneDesc* scene_or_none = scene ? &*scene : nullptr;
  const std::optional<quality::CohesiveSection> cohesive =
      loaded.dimension == 2 ? certify_cohesive_cells<2>(loaded, loaded.mesh2, scene_or_none, flags, times)
                            : certify_cohesive_cells<3>(loaded, loaded.mesh3, scene_or_none, flags, times);
  std::string match_note;
  if (scene) match_note = match_scene_phases(args, loaded, *scene);
  quality::Certificate c = loaded.dimension == 2 ? certify_mesh<2>(loaded.mesh2, scene_or_none, options, flags, times)
                                                 : certify_mesh<3>(loaded.mesh3, scene_or_none, options, flags, times);
  if (!match_note.empty()) c.notes.push_back(match_note);
  c.cohesive = cohesive;
  return c;
}

// The map entries that name a phase of `phases` (a piece need not hold every phase the map
// names; the whole map is checked against all pieces' phases at the end).
std::vector<quality::PhaseMapEntry> entries_naming(const std::vector<quality::PhaseMapEntry>& map,
                                                   const std::vector<quality::MeshPhase>& phases) {
  std::vector<quality::PhaseMapEntry> named;
  for (const quality::PhaseMapEntry& e : map)
    if (std::any_of(phases.begin(), phases.end(),
                    [&](const quality::MeshPhase& p) { return e.mesh == std::to_string(p.id) || e.mesh == p.name; }))
      named.push_back(e);
  return named;
}

// A .pvtu certified piece by piece (quality::PiecewiseCertifier): two passes, the first over
// the pieces' points and global ids only. nullopt when it must be read whole: a piece without
// global ids, with cohesive cells or periodic masters, ids too sparse, a periodic scene.
template <int Dim>
std::optional<quality::Certificate> certify_pieces(const CertifyArgs& args, const std::vector<std::string>& pieces,
                                                   io::VtuPoints first, const geometry::SceneDesc* scene,
                                                   std::vector<geometry::Phase>& phases, const GlobalFlags& flags,
                                                   PhaseTimes& times) {
  quality::CertifyOptions options;
  options.bound = args.bound;
  options.fidelity_tolerance = args.fidelity_tolerance;
  std::optional<geometry::Oracle<Dim>> oracle;
  if (scene) {
    progress(flags, "building the geometry oracle");
    ScopedPhase timer(&times, "oracle");
    oracle.emplace(*scene);
  }
  quality::PiecewiseCertifier<Dim> certifier(options, oracle ? &*oracle : nullptr);
  {
    progress(flags, "reading the pieces' global node ids");
    ScopedPhase timer(&times, "read ids");
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      io::VtuPoints points = k == 0 ? std::move(first) : io::read_vtu_points(pieces[k]);
      if (!points.has_global_id || points.has_cohesive || points.has_periodic_master) return std::nullopt;
      certifier.count_nodes(points.global_id, points.coords);
    }
    if (!certifier.ids_usable()) return std::nullopt;
  }
  const std::vector<quality::PhaseMapEntry> map = phase_map_of(args);
  certifier.end_first_pass();

  // Pieces read and checked on `threads` threads, added in piece order on this one (the
  // result, and the first bad piece reported, do not depend on the threads).
  struct Slot {
    std::optional<typename quality::PiecewiseCertifier<Dim>::CheckedPiece> checked;
    std::vector<quality::MeshPhase> mesh_phases;
    std::vector<geometry::Phase> phases;
    std::exception_ptr error;
    bool done = false;
  };
  std::vector<Slot> slots(pieces.size());
  std::mutex mutex;
  std::condition_variable ready;
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  const auto work = [&](PhaseTimes& worker_times) {
    for (std::size_t k; !stop && (k = next++) < pieces.size();) {
      Slot result;
      try {
        io::LoadedMesh loaded;
        {
          ScopedPhase timer(&worker_times, "read mesh");
          loaded = io::read_mesh(pieces[k]);
        }
        if (loaded.dimension != Dim)
          throw InputError(pieces[k], "", "is " + std::to_string(loaded.dimension) + "D, the first piece " +
                                              std::to_string(Dim) + "D");
        mesh::SimplexMesh<Dim>& piece = [&]() -> mesh::SimplexMesh<Dim>& {
          if constexpr (Dim == 2) return loaded.mesh2;
          else return loaded.mesh3;
        }();
        result.mesh_phases = mesh_phases_of(loaded);  // in the order of loaded.phases
        result.phases = loaded.phases;
        if (scene)
          quality::relabel_phases<Dim>(piece, quality::match_phases(result.mesh_phases, scene->phases,
                                                                    entries_naming(map, result.mesh_phases), pieces[k]));
        ScopedPhase timer(&worker_times, "certify");
        result.checked = certifier.check_piece(piece, pieces[k]);
      } catch (...) {
        result.error = std::current_exception();
      }
      const std::lock_guard<std::mutex> lock(mutex);
      result.done = true;
      slots[k] = std::move(result);
      ready.notify_all();
    }
  };
  const std::size_t thread_count = std::min<std::size_t>(static_cast<std::size_t>(args.threads), pieces.size());
  std::vector<PhaseTimes> worker_times(thread_count);
  std::vector<std::thread> workers;
  std::vector<quality::MeshPhase> all_phases;
  const auto wall = std::chrono::steady_clock::now();
  {
    // Joins the workers however this block ends (an error stops them after their piece).
    struct Join {
      std::vector<std::thread>& threads;
      std::atomic<bool>& stop;
      ~Join() {
        stop = true;
        for (std::thread& t : threads) t.join();
      }
    } join{workers, stop};
    for (std::size_t t = 0; t < thread_count; ++t) workers.emplace_back(work, std::ref(worker_times[t]));
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      if (show_progress(flags)) std::fprintf(stderr, "cisamr: checking piece %zu of %zu\n", k + 1, pieces.size());
      Slot slot;
      {
        std::unique_lock<std::mutex> lock(mutex);
        ready.wait(lock, [&] { return slots[k].done; });
        slot = std::move(slots[k]);
      }
      if (slot.error) std::rethrow_exception(slot.error);
      for (std::size_t i = 0; i < slot.mesh_phases.size(); ++i)
        if (std::none_of(all_phases.begin(), all_phases.end(), [&](const auto& q) { return q.id == slot.mesh_phases[i].id; })) {
          all_phases.push_back(slot.mesh_phases[i]);
          phases.push_back(slot.phases[i]);
        }
      ScopedPhase timer(&times, "add");
      certifier.add_checked(std::move(*slot.checked));
    }
  }
  times.add("pieces (wall)", std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count());
  for (const PhaseTimes& w : worker_times)
    for (const auto& [name, seconds] : w.phases()) times.add(name + " (threads)", seconds);
  std::sort(all_phases.begin(), all_phases.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  std::sort(phases.begin(), phases.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  ScopedPhase timer(&times, "certify");
  quality::Certificate c = certifier.finish();
  if (!scene) {
    c.notes.push_back("no scene: the domain is the mesh's bounding box, phase fidelity is not checked and "
                      "open boundaries inside it are taken for voids");
  } else {
    c.notes.push_back(phase_match_note(all_phases, quality::match_phases(all_phases, scene->phases, map, args.mesh)));
  }
  return c;
}

// A .pvtu with global ids, piece by piece; nullopt when it must be read whole.
std::optional<quality::Certificate> certify_pvtu_by_pieces(const CertifyArgs& args, std::vector<geometry::Phase>& phases,
                                                           const GlobalFlags& flags, PhaseTimes& times) {
  const std::vector<std::string> pieces = io::pvtu_piece_paths(args.mesh);
  io::VtuPoints first = io::read_vtu_points(pieces.front());
  // Tetrahedra have a z extent; triangles of a 2D mesh lie at z = 0 (io::read_mesh's rule).
  bool flat = true;
  for (std::size_t i = 2; i < first.coords.size() && flat; i += 3) flat = first.coords[i] == 0;
  const int dimension = flat ? 2 : 3;
  const std::optional<geometry::SceneDesc> scene = read_scene_of(args, dimension, flags, times);
  if (scene && scene->any_periodic()) return std::nullopt;
  const geometry::SceneDesc* scene_or_none = scene ? &*scene : nullptr;
  std::optional<quality::Certificate> c =
      dimension == 2 ? certify_pieces<2>(args, pieces, std::move(first), scene_or_none, phases, flags, times)
                     : certify_pieces<3>(args, pieces, std::move(first), scene_or_none, phases, flags, times);
  if (c && c->phase_names.empty())
    for (const geometry::Phase& p : phases) c->phase_names.emplace_back(p.id, p.name);
  return c;
}

}  // namespace

void add_certify_command(CLI::App& app, GlobalFlags& flags, int& exit_code) {
  auto args = std::make_shared<CertifyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "certify", "Check a mesh (aspect ratio, conformity, phase fidelity, cohesive cells) and write its certificate");
  cmd->add_option("mesh", args->mesh,
                  "Mesh file: .vtu (plain or zlib-compressed), .pvtu, .vtk (legacy), .msh (Gmsh 4.1/2.2, ASCII or "
                  "binary), .inp (Abaqus), .mesh (Medit), .node/.ele (TetGen)")
      ->required();
  cmd->add_option("--scene", args->scene,
                  "Scene the mesh was made from: domain box, expected measure and phase fidelity");
  cmd->add_option("--phase-map", args->phase_map,
                  "With --scene: mesh phases to scene phases, MESH=SCENE,... (ids or names; default: by the names "
                  "the file gives, else by id)");
  cmd->add_flag("--whole", args->whole,
               "Read a .pvtu whole, its pieces merged by global id (by default it is certified piece by piece, "
               "in memory bounded by the largest piece and the border between pieces)");
  args->threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 4u));
  cmd->add_option("--threads", args->threads,
                  "Pieces of a .pvtu checked at once, each on its own thread, each holding one piece in memory "
                  "(default: the cores, at most 4)")
      ->check(CLI::Range(1, 256));
  cmd->add_option("--html", args->html, "Write the certificate as a self-contained HTML page")->check(output_path());
  cmd->add_option("--json", args->json, "Write the certificate as JSON")->check(output_path());
  cmd->add_option("--bound", args->bound,
                  "Aspect-ratio bound, at least 1, the regular simplex's (default 3 in 2D, 5 in 3D)")
      ->check(number_in(1, 1e6));
  cmd->add_option("--fidelity-tolerance", args->fidelity_tolerance,
                  "Distance a node may lie from the phases it serves (default 1e-9 of the domain diagonal; "
                  "`cisamr mesh --report` gives the largest collapse deviation of sub-resolution features; "
                  "in 3D also the least distance a centroid may lie from its cell's phase)")
      ->check(number_in(1e-300, 1e300));
  cmd->callback([args, &flags, &exit_code] {
    for (const std::string* out : {&args->json, &args->html})  // before the mesh is read
      if (!out->empty()) io::check_writable(*out);
    PhaseTimes times;
    std::optional<quality::Certificate> by_pieces;
    std::vector<geometry::Phase> piece_phases;
    if (io::lowercase_extension(args->mesh) == ".pvtu" && !args->whole) by_pieces = certify_pvtu_by_pieces(*args, piece_phases, flags, times);
    quality::Certificate c;
    if (by_pieces) {
      c = std::move(*by_pieces);
    } else {
      progress(flags, "reading the mesh");
      io::LoadedMesh loaded;
      {
        ScopedPhase timer(&times, "read mesh");
        loaded = io::read_mesh(args->mesh);
      }
      c = certify_loaded(*args, loaded, flags, times);
      if (c.phase_names.empty())
        for (const geometry::Phase& p : loaded.phases) c.phase_names.emplace_back(p.id, p.name);
    }
    c.mesh_source = args->mesh;
    {
      ScopedPhase timer(&times, "write");
      io::OutputSet outputs;  // both certificates or neither
      if (!args->json.empty()) write_text_file(args->json, quality::certificate_json(c));
      if (!args->html.empty()) write_text_file(args->html, quality::certificate_html(c));
      outputs.commit();
    }
    // A certificate on standard output is the data there: the summary moves to stderr.
    FILE* summary = io::is_standard_output(args->json) || io::is_standard_output(args->html) ? stderr : stdout;
    if (!flags.quiet) std::fputs(quality::certificate_summary(c).c_str(), summary);
    if (flags.verbose)
      for (const auto& [name, seconds] : times.phases()) std::fprintf(summary, "  %-20s %8.3f s\n", name.c_str(), seconds);
    exit_code = c.passed() ? 0 : 3;
  });
}

}  // namespace cisamr::app
