// Our 3D mesher and TetGen on one scene, measured alike. See compare3.hpp.
#include "compare/compare3.hpp"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "geometry/oracle.hpp"
#include "mesh/metrics.hpp"
#include "pipeline/pipeline.hpp"
#include "quality/quality.hpp"

namespace cisamr::compare {
namespace {

using Json = nlohmann::json;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double cpu_seconds_now() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// ---- memory: Linux /proc/self, VmHWM reset through clear_refs ----

long proc_status_kb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(field);
  while (std::getline(in, line))
    if (line.compare(0, n, field) == 0 && line.size() > n && line[n] == ':') return std::stol(line.substr(n + 1));
  return -1;
}

struct MemoryProbe {
  bool reset = false;  // VmHWM was reset to the current RSS
  long baseline_kb = 0;
  long peak_kb = 0;

  void start() {
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
    clear.flush();
    reset = static_cast<bool>(clear);
    baseline_kb = proc_status_kb("VmRSS");
  }
  void stop() {
    peak_kb = reset ? proc_status_kb("VmHWM") : [] {
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      return ru.ru_maxrss;
    }();
  }
  double delta_bytes() const { return std::max(0L, peak_kb - baseline_kb) * 1024.0; }
  std::string method(bool isolated) const {
    std::string m = reset ? "peak RSS (VmHWM, reset via /proc/self/clear_refs) minus RSS before the call"
                          : "getrusage max RSS minus RSS before the call (VmHWM reset unavailable: upper bound)";
    return m + (isolated ? ", in a forked child process" : ", in this process (earlier runs' freed memory may be reused)");
  }
};

// ---- per-inclusion containment (tets go to inclusions by centroid) ----

bool contains(const geometry::Shape& shape, const Vec3& p, double slack) {
  if (const auto* s = std::get_if<geometry::Sphere>(&shape)) {
    const double d = mesh::distance<3>(p, s->center);
    return d <= s->radius * (1 + slack);
  }
  if (const auto* e = std::get_if<geometry::Ellipsoid>(&shape)) {
    double q = 0;
    for (int c = 0; c < 3; ++c) {  // body coordinate c = column c of the rotation · (p − centre)
      double local = 0;
      for (int r = 0; r < 3; ++r) local += e->rotation[r][c] * (p[r] - e->center[r]);
      q += (local / e->semi_axes[c]) * (local / e->semi_axes[c]);
    }
    return q <= (1 + slack) * (1 + slack);
  }
  return false;
}

double exact_volume(const geometry::Shape& shape) {
  if (const auto* s = std::get_if<geometry::Sphere>(&shape)) return 4.0 / 3.0 * M_PI * std::pow(s->radius, 3);
  if (const auto* e = std::get_if<geometry::Ellipsoid>(&shape))
    return 4.0 / 3.0 * M_PI * e->semi_axes[0] * e->semi_axes[1] * e->semi_axes[2];
  return 0;
}

// ---- JSON (also the pipe format between the child and the parent) ----

Json to_json(const MesherReport& r) {
  Json phases = Json::array();
  for (const PhaseVolume& p : r.phases)
    phases.push_back({{"id", p.id}, {"name", p.name}, {"exact", p.exact}, {"meshed", p.meshed},
                      {"relative_error", p.relative_error}});
  Json bins = Json::array();
  for (std::size_t b = 0; b < r.aspect_bins.size(); ++b)
    bins.push_back({{"from", kAspectBinLower[b]},
                    {"to", b + 1 < kAspectBinLower.size() ? Json(kAspectBinLower[b + 1]) : Json("inf")},
                    {"tets", r.aspect_bins[b]}});
  Json phase_seconds = Json::array(), extra = Json::array();
  for (const auto& [name, s] : r.phase_seconds) phase_seconds.push_back({name, s});
  for (const auto& [name, v] : r.extra) extra.push_back({name, v});
  return {{"name", r.name},
          {"settings", r.settings},
          {"tets", r.tets},
          {"nodes", r.nodes},
          {"seconds", r.seconds},
          {"cpu_seconds", r.cpu_seconds},
          {"phase_seconds", phase_seconds},
          {"tets_per_second", r.tets_per_second},
          {"run_seconds", r.run_seconds},
          {"run_cpu_seconds", r.run_cpu_seconds},
          {"runs_differ", r.runs_differ},
          {"peak_rss_delta_bytes", r.peak_rss_delta_bytes},
          {"bytes_per_tet", r.bytes_per_tet},
          {"isolated", r.isolated},
          {"memory_method", r.memory_method},
          {"phase_volumes", phases},
          {"inclusions_measured", r.inclusions_measured},
          {"inclusion_volume_error_worst", r.inclusion_error_worst},
          {"inclusion_volume_error_mean", r.inclusion_error_mean},
          {"inclusion_worst", r.inclusion_worst},
          {"tets_outside_inclusions", r.tets_outside_inclusions},
          {"aspect_ratio", {{"max", r.aspect_max}, {"mean", r.aspect_mean}, {"above_5", r.above_5}, {"bins", bins}}},
          {"dihedral_deg", {{"min", r.min_dihedral_deg}, {"max", r.max_dihedral_deg}}},
          {"conformity", {{"checked", r.conformity_checked}, {"ok", r.conforming}, {"problems", r.conformity_problems}}},
          {"extra", extra}};
}

MesherReport from_json(const Json& j) {
  MesherReport r;
  r.name = j.at("name");
  r.settings = j.at("settings");
  r.tets = j.at("tets");
  r.nodes = j.at("nodes");
  r.seconds = j.at("seconds");
  r.cpu_seconds = j.at("cpu_seconds");
  for (const Json& p : j.at("phase_seconds")) r.phase_seconds.emplace_back(p[0], p[1]);
  r.tets_per_second = j.at("tets_per_second");
  r.run_seconds = j.at("run_seconds").get<std::vector<double>>();
  r.run_cpu_seconds = j.at("run_cpu_seconds").get<std::vector<double>>();
  r.runs_differ = j.at("runs_differ");
  r.peak_rss_delta_bytes = j.at("peak_rss_delta_bytes");
  r.bytes_per_tet = j.at("bytes_per_tet");
  r.isolated = j.at("isolated");
  r.memory_method = j.at("memory_method");
  for (const Json& p : j.at("phase_volumes"))
    r.phases.push_back({p.at("id"), p.at("name"), p.at("exact"), p.at("meshed"), p.at("relative_error")});
  r.inclusions_measured = j.at("inclusions_measured");
  r.inclusion_error_worst = j.at("inclusion_volume_error_worst");
  r.inclusion_error_mean = j.at("inclusion_volume_error_mean");
  r.inclusion_worst = j.at("inclusion_worst");
  r.tets_outside_inclusions = j.at("tets_outside_inclusions");
  const Json& a = j.at("aspect_ratio");
  r.aspect_max = a.at("max").is_number() ? a.at("max").get<double>() : INFINITY;
  r.aspect_mean = a.at("mean");
  r.above_5 = a.at("above_5");
  for (std::size_t b = 0; b < r.aspect_bins.size(); ++b) r.aspect_bins[b] = a.at("bins").at(b).at("tets");
  r.min_dihedral_deg = j.at("dihedral_deg").at("min");
  r.max_dihedral_deg = j.at("dihedral_deg").at("max");
  r.conformity_checked = j.at("conformity").at("checked");
  r.conforming = j.at("conformity").at("ok");
  r.conformity_problems = j.at("conformity").at("problems");
  for (const Json& e : j.at("extra")) r.extra.emplace_back(e[0], e[1]);
  return r;
}

// Runs `work` in a forked child when `isolate` (its memory figures then start from a clean
// high-water mark and nothing it allocates stays in this process); the report comes back
// as JSON through a pipe. Errors come back too: InputError keeps its file/field/problem.
template <class Work>
MesherReport run_maybe_isolated(bool isolate, Work&& work) {
  if (!isolate) {
    MesherReport r = work();
    r.isolated = false;
    return r;
  }
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    close(fd[0]);
    Json answer;
    int code = 0;
    try {
      MesherReport r = work();
      r.isolated = true;
      answer = {{"report", to_json(r)}};
    } catch (const InputError& e) {
      answer = {{"input_error", {e.file(), e.field(), e.problem()}}};
      code = 1;
    } catch (const std::exception& e) {
      answer = {{"error", e.what()}};
      code = 1;
    }
    const std::string text = answer.dump();
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = write(fd[1], text.data() + written, text.size() - written);
      if (n <= 0) break;
      written += static_cast<std::size_t>(n);
    }
    close(fd[1]);
    _exit(code);
  }
  close(fd[1]);
  std::string text;
  char buffer[65536];
  for (;;) {
    const ssize_t n = read(fd[0], buffer, sizeof buffer);
    if (n > 0) text.append(buffer, static_cast<std::size_t>(n));
    else if (n == 0 || errno != EINTR) break;
  }
  close(fd[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status))
    throw std::runtime_error("the measuring child process died of signal " + std::to_string(WTERMSIG(status)) +
                             (WTERMSIG(status) == SIGKILL ? " (out of memory?)" : ""));
  const Json answer = Json::parse(text, nullptr, false);
  if (answer.is_discarded()) throw std::runtime_error("the measuring child process returned no report");
  if (answer.contains("input_error")) {
    const Json& e = answer["input_error"];
    throw InputError(e[0], e[1], e[2]);
  }
  if (answer.contains("error")) throw std::runtime_error(answer["error"].get<std::string>());
  return from_json(answer.at("report"));
}

double total_volume(const geometry::SceneDesc& scene) {
  double v = 1;
  for (int d = 0; d < 3; ++d) v *= scene.domain_max[d] - scene.domain_min[d];
  return v;
}

int finest_levels(const geometry::SceneDesc& scene) {
  int levels = scene.levels;
  for (const auto& inc : scene.inclusions) levels = std::max(levels, inc.levels);
  return levels;
}

void say(const CompareOptions& options, const std::string& what) {
  if (options.progress) options.progress(what);
}

std::string fixed(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

std::string grouped(std::int64_t n) {  // 1234567 → "1,234,567"
  std::string digits = std::to_string(n < 0 ? -n : n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

std::string percent(double relative) {
  char text[32];
  std::snprintf(text, sizeof text, "%+.2f %%", 100 * relative);
  return text;
}

double extra_value(const MesherReport& r, const std::string& name) {
  for (const auto& [n, v] : r.extra)
    if (n == name) return v;
  return 0;
}

std::string bin_label(std::size_t b) {
  char text[32];
  if (b + 1 < kAspectBinLower.size())
    std::snprintf(text, sizeof text, "[%g, %g)", kAspectBinLower[b], kAspectBinLower[b + 1]);
  else
    std::snprintf(text, sizeof text, ">= %g", kAspectBinLower[b]);
  return text;
}

}  // namespace

MesherReport measure_mesh(const mesh::Mesh3& m, const geometry::SceneDesc& scene, bool check_conformity) {
  MesherReport r;
  r.tets = static_cast<std::int64_t>(m.cell_count());
  r.nodes = static_cast<std::int64_t>(m.node_count());
  const geometry::Oracle3 oracle(scene);
  const std::vector<double> exact_phase = oracle.phase_measures();

  // Volumes per phase and per inclusion (centroid in the shape, slack 1e-9 of its size).
  std::vector<double> phase_volume(scene.phases.size(), 0.0), inclusion_volume(scene.inclusions.size(), 0.0);
  std::vector<std::int32_t> candidates;
  std::vector<double> aspect(m.cell_count());
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const LocalId* n = m.cell(c);
    const Vec3 a = m.point(n[0]), b = m.point(n[1]), cc = m.point(n[2]), d = m.point(n[3]);
    const double v = std::abs(mesh::signed_volume(a, b, cc, d));
    const int phase = scene.phase_index(m.cell_phase[c]);
    if (phase >= 0) phase_volume[static_cast<std::size_t>(phase)] += v;
    aspect[c] = mesh::aspect_ratio(a, b, cc, d);
    if (m.cell_phase[c] == scene.matrix_phase) continue;
    const Vec3 centroid{(a[0] + b[0] + cc[0] + d[0]) / 4, (a[1] + b[1] + cc[1] + d[1]) / 4,
                        (a[2] + b[2] + cc[2] + d[2]) / 4};
    oracle.candidates(Box3{centroid, centroid}, candidates);
    bool found = false;
    for (std::int32_t i : candidates)
      if (scene.inclusions[static_cast<std::size_t>(i)].phase == m.cell_phase[c] &&
          contains(scene.inclusions[static_cast<std::size_t>(i)].shape, centroid, 1e-9)) {
        inclusion_volume[static_cast<std::size_t>(i)] += v;
        found = true;
        break;
      }
    if (!found) ++r.tets_outside_inclusions;
  }
  for (std::size_t p = 0; p < scene.phases.size(); ++p) {
    if (scene.phases[p].is_void) continue;
    const double exact = exact_phase[p];
    r.phases.push_back({scene.phases[p].id, scene.phases[p].name, exact, phase_volume[p],
                        exact > 0 ? (phase_volume[p] - exact) / exact : 0.0});
  }
  double sum = 0;
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    const int phase = scene.phase_index(scene.inclusions[i].phase);
    if (phase < 0 || scene.phases[static_cast<std::size_t>(phase)].is_void) continue;
    const double exact = exact_volume(scene.inclusions[i].shape);
    if (!(exact > 0)) continue;
    const double error = (inclusion_volume[i] - exact) / exact;
    ++r.inclusions_measured;
    sum += error;
    if (std::abs(error) > std::abs(r.inclusion_error_worst) || r.inclusion_worst < 0) {
      r.inclusion_error_worst = error;
      r.inclusion_worst = static_cast<std::int64_t>(i);
    }
  }
  if (r.inclusions_measured > 0) r.inclusion_error_mean = sum / static_cast<double>(r.inclusions_measured);

  // Aspect ratio bins, maximum, mean; dihedral angles from quality::aspect_statistics.
  double finite_sum = 0;
  std::int64_t finite = 0;
  for (double ar : aspect) {
    std::size_t b = 0;
    while (b + 1 < kAspectBinLower.size() && !(ar < kAspectBinLower[b + 1])) ++b;
    ++r.aspect_bins[b];
    if (!(ar <= 5.0)) ++r.above_5;
    r.aspect_max = std::max(r.aspect_max, ar);
    if (std::isfinite(ar)) finite_sum += ar, ++finite;
  }
  r.aspect_mean = finite > 0 ? finite_sum / static_cast<double>(finite) : 0;
  const quality::AspectStats stats = quality::aspect_statistics(m, 5.0, 1);
  r.min_dihedral_deg = stats.min_angle_deg;
  r.max_dihedral_deg = stats.max_angle_deg;

  if (check_conformity) {
    bool has_void = false;
    double void_volume = 0;
    for (std::size_t p = 0; p < scene.phases.size(); ++p)
      if (scene.phases[p].is_void) has_void = true, void_volume += exact_phase[p];
    Box<3> box;
    for (int d = 0; d < 3; ++d) box.min[d] = scene.domain_min[d], box.max[d] = scene.domain_max[d];
    // With voids the meshed volume is only close to the exact one (inscribed surfaces).
    const quality::ConformityReport cr = quality::check_conformity<3>(
        m, box, total_volume(scene) - void_volume, has_void, has_void ? 0.05 : quality::kDefaultMeasureTolerance);
    r.conformity_checked = true;
    r.conforming = cr.ok;
    if (!cr.ok) {
      const std::pair<const char*, std::size_t> problems[] = {
          {"duplicate nodes", cr.duplicate_nodes},       {"degenerate", cr.degenerate_cells},
          {"inverted", cr.inverted_cells},               {"non-manifold facets", cr.non_manifold_facets},
          {"open inner facets", cr.open_facets_inside},  {"hanging nodes", cr.hanging_nodes},
          {"mismatched orientation", cr.mismatched_orientation_facets}};
      for (const auto& [what, count] : problems)
        if (count > 0) r.conformity_problems += (r.conformity_problems.empty() ? "" : ", ") + std::to_string(count) + " " + what;
      if (cr.measure_error > cr.measure_tolerance)
        r.conformity_problems += (r.conformity_problems.empty() ? "" : ", ") + std::string("volume off by ") +
                                 percent(cr.measure_error);
    }
  }
  return r;
}

namespace {

// Runs `measured` (one timed run in its own child when isolated) `repeats` times and keeps
// the run with the median wall time, listing every run's wall and CPU time.
template <class Measured>
MesherReport median_run(const CompareOptions& options, int repeats, std::vector<MesherReport> done, Measured&& measured) {
  while (static_cast<int>(done.size()) < std::max(1, repeats)) done.push_back(run_maybe_isolated(options.isolate, measured));
  std::vector<std::size_t> order(done.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return done[a].seconds < done[b].seconds; });
  MesherReport r = done[order[(order.size() - 1) / 2]];
  r.run_seconds.clear();
  r.run_cpu_seconds.clear();
  for (const MesherReport& run : done) {
    r.run_seconds.push_back(run.seconds);
    r.run_cpu_seconds.push_back(run.cpu_seconds);
    if (run.tets != r.tets || run.nodes != r.nodes) r.runs_differ = true;
  }
  return r;
}

}  // namespace

Comparison compare3(const geometry::SceneDesc& scene, const CompareOptions& options) {
  check_tetgen_scene(scene);  // fail on bad input before any meshing
  Comparison c;
  c.scene_source = scene.source;
  c.inclusions = static_cast<std::int64_t>(scene.inclusions.size());
  c.h = scene.h;
  c.levels = finest_levels(scene);

  const auto ours_once = [&] {
    MemoryProbe memory;
    memory.start();
    const double cpu_start = cpu_seconds_now();
    const auto start = std::chrono::steady_clock::now();
    const auto oracle_start = start;
    const geometry::Oracle3 oracle(scene);
    const double oracle_seconds = seconds_since(oracle_start);
    pipeline::Result<3> result = pipeline::mesh(oracle, options.cisamr);
    const double seconds = seconds_since(start);
    const double cpu = cpu_seconds_now() - cpu_start;
    memory.stop();
    MesherReport r = measure_mesh(result.mesh, scene, options.check_conformity);
    r.cpu_seconds = cpu;
    r.name = "cisamr";
    r.settings = "h = " + fixed(scene.h, 6) + ", levels " + std::to_string(c.levels);
    r.seconds = seconds;
    r.tets_per_second = seconds > 0 ? static_cast<double>(r.tets) / seconds : 0;
    r.phase_seconds.emplace_back("oracle", oracle_seconds);
    for (const auto& phase : result.times.phases()) r.phase_seconds.push_back(phase);
    r.peak_rss_delta_bytes = memory.delta_bytes();
    r.bytes_per_tet = r.tets > 0 ? r.peak_rss_delta_bytes / static_cast<double>(r.tets) : 0;
    r.memory_method = memory.method(options.isolate);
    const pipeline::Counters<3>& s = result.counters;
    r.extra = {{"leaves", double(s.leaves)},          {"cut_tets", double(s.cut_tets)},
               {"snapped_nodes", double(s.snapped_nodes)}, {"face_swaps", double(s.face_swaps)},
               {"collapsed_nodes", double(s.collapsed_nodes)}, {"refused_nodes", double(s.refused_nodes)},
               {"inverted", double(s.inverted)},      {"unresolved", double(s.unresolved)},
               {"worst_kept", s.worst_kept},          {"worst_split", s.worst_split},
               {"worst_closure", s.worst_closure},    {"max_level", double(s.max_level)}};
    return r;
  };
  say(options, "meshing with cisamr" + std::string(options.repeats > 1 ? " (" + std::to_string(options.repeats) + " runs)" : ""));
  c.ours = median_run(options, options.repeats, {}, ours_once);
  if (!options.run_tetgen) return c;
  c.has_tetgen = true;

  const auto tetgen_once = [&](double max_volume) {
    return [&options, &scene, max_volume] {
      MemoryProbe memory;
      memory.start();
      TetgenOptions run = options.tetgen;
      run.max_volume = max_volume;
      run.on_tetrahedralized = [&memory] { memory.stop(); };
      const double cpu_start = cpu_seconds_now();
      const auto start = std::chrono::steady_clock::now();
      TetgenMesh t = mesh_scene_with_tetgen(scene, run);
      const double seconds = seconds_since(start);
      const double cpu = cpu_seconds_now() - cpu_start;
      MesherReport r = measure_mesh(t.mesh, scene, options.check_conformity);
      r.cpu_seconds = cpu;
      r.name = "TetGen 1.5";
      r.settings = "-" + t.switches;
      r.seconds = seconds;
      r.tets_per_second = seconds > 0 ? static_cast<double>(r.tets) / seconds : 0;
      r.phase_seconds = {{"plc", t.plc_seconds}, {"tetrahedralize", t.tetgen_seconds}, {"copy", t.copy_seconds}};
      r.peak_rss_delta_bytes = memory.delta_bytes();
      r.bytes_per_tet = r.tets > 0 ? r.peak_rss_delta_bytes / static_cast<double>(r.tets) : 0;
      r.memory_method = memory.method(options.isolate) + "; read when tetrahedralize returns (before the copy)";
      r.extra = {{"surface_points", double(t.surface_points)},
                 {"surface_triangles", double(t.surface_triangles)},
                 {"max_volume", run.max_volume}};
      return r;
    };
  };

  if (options.tetgen.max_volume > 0) {
    say(options, "meshing with TetGen");
    c.tetgen = median_run(options, options.repeats, {}, tetgen_once(options.tetgen.max_volume));
  } else {
    // -a matched to our count by measured runs (compare3.hpp): volume model, then the
    // secant in log-log space; the run closest to our count is reported.
    double meshed_volume = total_volume(scene);
    for (std::size_t p = 0; p < scene.phases.size(); ++p)
      if (scene.phases[p].is_void)
        for (const auto& inc : scene.inclusions)
          if (inc.phase == scene.phases[p].id) meshed_volume -= exact_volume(inc.shape);
    const double target = std::max<double>(1, static_cast<double>(c.ours.tets));
    const auto miss = [&](std::int64_t tets) { return std::abs(std::log(std::max<double>(1, double(tets)) / target)); };
    std::vector<MesherReport> runs;
    double a = options.volume_factor * meshed_volume / target;
    for (int k = 0; k < std::max(1, options.match_runs); ++k) {
      say(options, "meshing with TetGen, -a" + fixed(a, 12) + (k == 0 ? " (matching our count)" : ""));
      runs.push_back(run_maybe_isolated(options.isolate, tetgen_once(a)));
      c.tetgen_matching.push_back({a, runs.back().tets, runs.back().seconds});
      if (miss(runs.back().tets) <= std::log1p(options.match_tolerance)) break;
      // Next a. Once runs lie on both sides of N: interpolate in log-log space between the
      // closest run above and the closest below (TetGen's count jumps with a, so keep the
      // bracket rather than the last two runs). Before: count ∝ a^-slope, the slope from
      // the last two runs (clamped), else the prior.
      const MatchingRun* above = nullptr;
      const MatchingRun* below = nullptr;
      for (const MatchingRun& m : c.tetgen_matching) {
        if (double(m.tets) > target && (above == nullptr || m.tets < above->tets)) above = &m;
        if (double(m.tets) < target && (below == nullptr || m.tets > below->tets)) below = &m;
      }
      if (above != nullptr && below != nullptr) {
        const double la = std::log(above->max_volume), lb = std::log(below->max_volume);
        const double na = std::log(double(above->tets)), nb = std::log(double(std::max<std::int64_t>(1, below->tets)));
        double t = (na - std::log(target)) / (na - nb);
        t = std::isfinite(t) ? std::clamp(t, 0.1, 0.9) : 0.5;  // keep inside the bracket
        a = std::exp(la + t * (lb - la));
        continue;
      }
      double slope = options.initial_slope;
      if (runs.size() >= 2) {
        const MatchingRun& p = c.tetgen_matching[c.tetgen_matching.size() - 2];
        const MatchingRun& q = c.tetgen_matching.back();
        const double measured = -std::log(double(std::max<std::int64_t>(1, q.tets)) / double(std::max<std::int64_t>(1, p.tets))) /
                                std::log(q.max_volume / p.max_volume);
        if (std::isfinite(measured)) slope = std::clamp(measured, 0.5, 3.0);
      }
      a *= std::pow(double(std::max<std::int64_t>(1, runs.back().tets)) / target, 1.0 / slope);
    }
    std::size_t best = 0;
    for (std::size_t k = 1; k < runs.size(); ++k)
      if (miss(runs[k].tets) < miss(runs[best].tets)) best = k;
    for (std::size_t k = 0; k < runs.size(); ++k)
      if (k != best) c.tetgen_matching_seconds += runs[k].seconds;
    if (options.repeats > 1) say(options, "TetGen, -a" + fixed(c.tetgen_matching[best].max_volume, 12) + ": " +
                                              std::to_string(options.repeats) + " timed runs");
    c.tetgen = median_run(options, options.repeats, {runs[best]}, tetgen_once(c.tetgen_matching[best].max_volume));
  }
  c.time_ratio = c.ours.seconds > 0 ? c.tetgen.seconds / c.ours.seconds : 0;
  c.cpu_time_ratio = c.ours.cpu_seconds > 0 ? c.tetgen.cpu_seconds / c.ours.cpu_seconds : 0;
  return c;
}

// ---- renderings ----

std::string comparison_table(const Comparison& c) {
  std::vector<const MesherReport*> cols{&c.ours};
  if (c.has_tetgen) cols.push_back(&c.tetgen);
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "scene: %s, %lld inclusions, h = %g, finest levels %d\n",
                c.scene_source.empty() ? "(built in)" : c.scene_source.c_str(), static_cast<long long>(c.inclusions),
                c.h, c.levels);
  out += line;
  const auto row = [&](const std::string& label, auto cell) {
    std::snprintf(line, sizeof line, "%-32s", label.c_str());
    out += line;
    for (const MesherReport* r : cols) {
      std::snprintf(line, sizeof line, " %24s", cell(*r).c_str());
      out += line;
    }
    out += '\n';
  };
  row("", [](const MesherReport& r) { return r.name; });
  row("settings", [](const MesherReport& r) { return r.settings; });
  row("tetrahedra", [](const MesherReport& r) { return grouped(r.tets); });
  row("nodes", [](const MesherReport& r) { return grouped(r.nodes); });
  row("wall time (s)", [](const MesherReport& r) { return fixed(r.seconds, 3); });
  std::vector<std::string> phase_names;
  for (const MesherReport* r : cols)
    for (const auto& [name, s] : r->phase_seconds) phase_names.push_back(name);
  for (const std::string& name : phase_names)
    row("  " + name + " (s)", [&](const MesherReport& r) {
      for (const auto& [n, s] : r.phase_seconds)
        if (n == name) return fixed(s, 3);
      return std::string("-");
    });
  row("CPU time (s)", [](const MesherReport& r) { return fixed(r.cpu_seconds, 3); });
  if (c.ours.run_seconds.size() > 1 || c.tetgen.run_seconds.size() > 1)
    row("runs, wall (s) [median shown]", [](const MesherReport& r) {
      std::string list;
      for (double s : r.run_seconds) list += (list.empty() ? "" : " ") + fixed(s, 2);
      return list;
    });
  row("tets per second (wall)", [](const MesherReport& r) { return grouped(std::llround(r.tets_per_second)); });
  row("tets per CPU second", [](const MesherReport& r) {
    return grouped(r.cpu_seconds > 0 ? std::llround(double(r.tets) / r.cpu_seconds) : 0);
  });
  row("peak memory increase (MiB)", [](const MesherReport& r) { return fixed(r.peak_rss_delta_bytes / 1048576.0, 1); });
  row("bytes per tet", [](const MesherReport& r) { return fixed(r.bytes_per_tet, 0); });
  row("conforming", [](const MesherReport& r) {
    return !r.conformity_checked ? std::string("not checked") : r.conforming ? std::string("yes") : "NO: " + r.conformity_problems;
  });
  for (std::size_t p = 0; p < c.ours.phases.size(); ++p)
    row("volume error, phase " + c.ours.phases[p].name, [&](const MesherReport& r) {
      return p < r.phases.size() ? percent(r.phases[p].relative_error) : std::string("-");
    });
  row("inclusion volume error, worst", [](const MesherReport& r) { return percent(r.inclusion_error_worst); });
  row("inclusion volume error, mean", [](const MesherReport& r) { return percent(r.inclusion_error_mean); });
  row("  worst inclusion", [](const MesherReport& r) { return "inclusions[" + std::to_string(r.inclusion_worst) + "]"; });
  row("  inclusion tets in no inclusion", [](const MesherReport& r) { return grouped(r.tets_outside_inclusions); });
  row("aspect ratio max", [](const MesherReport& r) { return fixed(r.aspect_max, 3); });
  row("aspect ratio mean", [](const MesherReport& r) { return fixed(r.aspect_mean, 3); });
  for (std::size_t b = 0; b < kAspectBinLower.size(); ++b)
    row("  AR " + bin_label(b), [&](const MesherReport& r) {
      const double share = r.tets > 0 ? 100.0 * static_cast<double>(r.aspect_bins[b]) / static_cast<double>(r.tets) : 0;
      return grouped(r.aspect_bins[b]) + " (" + fixed(share, 2) + "%)";
    });
  row("tets with AR > 5", [](const MesherReport& r) { return grouped(r.above_5); });
  row("dihedral min / max (deg)",
      [](const MesherReport& r) { return fixed(r.min_dihedral_deg, 2) + " / " + fixed(r.max_dihedral_deg, 2); });
  if (c.has_tetgen) {
    std::snprintf(line, sizeof line, "time ratio TetGen / cisamr: %.2f (wall), %.2f (CPU); per tetrahedron: %.2f (wall), %.2f (CPU)\n",
                  c.time_ratio, c.cpu_time_ratio,
                  c.tetgen.tets_per_second > 0 ? c.ours.tets_per_second / c.tetgen.tets_per_second : 0.0,
                  c.tetgen.cpu_seconds > 0 && c.ours.cpu_seconds > 0
                      ? (double(c.ours.tets) / c.ours.cpu_seconds) / (double(c.tetgen.tets) / c.tetgen.cpu_seconds)
                      : 0.0);
    out += line;
    std::snprintf(line, sizeof line,
                  "aim (issue 3): > 1,000,000 tets/s on one core and 10x TetGen; now %s tets/s (wall), %s per CPU "
                  "second, %.1fx TetGen per tet (CPU)\n",
                  grouped(std::llround(c.ours.tets_per_second)).c_str(),
                  grouped(c.ours.cpu_seconds > 0 ? std::llround(double(c.ours.tets) / c.ours.cpu_seconds) : 0).c_str(),
                  c.tetgen.cpu_seconds > 0 && c.ours.cpu_seconds > 0
                      ? (double(c.ours.tets) / c.ours.cpu_seconds) / (double(c.tetgen.tets) / c.tetgen.cpu_seconds)
                      : 0.0);
    out += line;
    const double count_ratio = c.ours.tets > 0 ? double(c.tetgen.tets) / double(c.ours.tets) : 0;
    if (count_ratio < 0.8 || count_ratio > 1.25) {
      std::snprintf(line, sizeof line,
                    "WARNING: TetGen made %.2f x our tetrahedron count; compare per-tet figures, or set -a "
                    "(--tetgen-max-volume) and run again\n",
                    count_ratio);
      out += line;
    }
    if (!c.tetgen_matching.empty()) {
      out += "TetGen -a matched to our count by " + std::to_string(c.tetgen_matching.size()) + " run(s):";
      for (const MatchingRun& m : c.tetgen_matching) {
        std::snprintf(line, sizeof line, " -a%.6g -> %s (%.1f s);", m.max_volume, grouped(m.tets).c_str(), m.seconds);
        out += line;
      }
      std::snprintf(line, sizeof line, " the closest is reported; re-run with --tetgen-max-volume %.9g to skip matching\n",
                    extra_value(c.tetgen, "max_volume"));
      out += line;
    }
  }
  for (const MesherReport* r : cols)
    if (r->runs_differ) out += "WARNING: " + r->name + "'s repeated runs gave different meshes (not deterministic)\n";
  for (const MesherReport* r : cols) {
    if (r->extra.empty()) continue;
    out += r->name + ":";
    for (const auto& [name, v] : r->extra) {
      std::snprintf(line, sizeof line, " %s %.6g", name.c_str(), v);
      out += line;
    }
    out += "\n";
  }
  out += "memory: " + c.ours.memory_method + "\n";
  return out;
}

std::string comparison_json(const Comparison& c) {
  Json j = {{"format", "cisamr-compare/1"},
            {"scene", {{"source", c.scene_source}, {"inclusions", c.inclusions}, {"h", c.h}, {"levels", c.levels}}},
            {"cisamr", to_json(c.ours)}};
  if (c.has_tetgen) {
    j["tetgen"] = to_json(c.tetgen);
    Json matching = Json::array();
    for (const MatchingRun& m : c.tetgen_matching)
      matching.push_back({{"max_volume", m.max_volume}, {"tets", m.tets}, {"seconds", m.seconds}});
    j["tetgen_matching_runs"] = matching;
    j["tetgen_matching_seconds"] = c.tetgen_matching_seconds;
    j["time_ratio_tetgen_over_cisamr"] = c.time_ratio;
    j["cpu_time_ratio_tetgen_over_cisamr"] = c.cpu_time_ratio;
  }
  return j.dump(2) + "\n";
}

std::string comparison_html(const Comparison& c) {
  const auto escape = [](const std::string& s) {
    std::string out;
    for (char ch : s) {
      if (ch == '<') out += "&lt;";
      else if (ch == '>') out += "&gt;";
      else if (ch == '&') out += "&amp;";
      else out += ch;
    }
    return out;
  };
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>cisamr compare</title><style>"
      "body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}td,th{border:1px solid #ccc;"
      "padding:3px 8px;text-align:right}td:first-child{text-align:left}.bar{display:inline-block;height:10px;"
      "background:#4a7}.bar.t{background:#c74}</style></head><body>\n<h1>cisamr vs TetGen</h1>\n";
  html += "<pre>" + escape(comparison_table(c)) + "</pre>\n";
  html += "<h2>Aspect-ratio distribution (share of tetrahedra)</h2>\n<table><tr><th>AR</th>";
  std::vector<const MesherReport*> cols{&c.ours};
  if (c.has_tetgen) cols.push_back(&c.tetgen);
  for (const MesherReport* r : cols) html += "<th>" + escape(r->name) + "</th>";
  html += "</tr>\n";
  for (std::size_t b = 0; b < kAspectBinLower.size(); ++b) {
    html += "<tr><td>" + escape(bin_label(b)) + "</td>";
    for (std::size_t k = 0; k < cols.size(); ++k) {
      const MesherReport& r = *cols[k];
      const double share = r.tets > 0 ? 100.0 * static_cast<double>(r.aspect_bins[b]) / static_cast<double>(r.tets) : 0;
      html += "<td>" + fixed(share, 2) + " % <span class=\"bar" + std::string(k ? " t" : "") + "\" style=\"width:" +
              fixed(2 * share, 1) + "px\"></span></td>";
    }
    html += "</tr>\n";
  }
  html += "</table>\n</body></html>\n";
  return html;
}

}  // namespace cisamr::compare
