// The certificate: assembling the checks and rendering them as JSON, HTML and text.
#include "quality/certificate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

namespace cisamr::quality {
namespace {

using Json = nlohmann::ordered_json;

std::string num(double v, int digits = 6) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string html_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

// Non-finite numbers become null (JSON has no inf/NaN).
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

// What differs between the renderings of a 2D and a 3D certificate.
struct DimensionWords {
  int coordinates;  // per point shown
  const char* cells;
  const char* regular_cell;    // the cell of aspect ratio 1
  const char* aspect_formula;  // Verdict's definition, plain text
  const char* aspect_formula_html;
  const char* angle_key;  // JSON: min_<key>_deg, max_<key>_deg
  const char* angle;      // the angles reported
};

// A certificate of dimension other than 3 is rendered as 2D.
const DimensionWords& words(int dimension) {
  static const DimensionWords two{2, "triangles", "equilateral triangle", "l_max / (2 sqrt(3) r_in)",
                                  "l_max / (2&#8730;3 r_in)", "angle", "angle"};
  static const DimensionWords three{3, "tetrahedra", "regular tetrahedron", "l_max / (2 sqrt(6) r_in)",
                                    "l_max / (2&#8730;6 r_in)", "dihedral", "dihedral angle"};
  return dimension == 3 ? three : two;
}

// Appends an item to a comma-separated list.
void add_item(std::string& list, const std::string& item) { list += (list.empty() ? "" : ", ") + item; }

void examples_html(std::ostringstream& o, const std::vector<std::string>& examples) {
  if (examples.empty()) return;
  o << "<ul>\n";
  for (const auto& e : examples) o << "<li class=\"ex\">" << html_escape(e) << "</li>\n";
  o << "</ul>\n";
}

std::string phase_label(const Certificate& c, int id) {
  for (const auto& [pid, name] : c.phase_names)
    if (pid == id && !name.empty()) return std::to_string(id) + " (" + name + ")";
  return std::to_string(id);
}

// ---- the conformity counters, in one table for every rendering ------------------------
struct Counter {
  const char* key;
  const char* label;
  std::size_t value;
  bool is_error;
};

std::vector<Counter> conformity_counters(const ConformityReport& r) {
  return {
      {"duplicate_nodes", "duplicate nodes", r.duplicate_nodes, true},
      {"degenerate_cells", "degenerate cells", r.degenerate_cells, true},
      {"inverted_cells", "inverted cells", r.inverted_cells, true},
      {"bad_node_references", "cells naming missing nodes", r.bad_node_references, true},
      {"non_manifold_facets", "facets shared by more than 2 cells", r.non_manifold_facets, true},
      {"mismatched_orientation_facets", "facets with mismatched orientation", r.mismatched_orientation_facets, true},
      {"open_facets_inside", "open facets inside the domain", r.open_facets_inside, true},
      {"hanging_nodes", "hanging nodes (T-junctions)", r.hanging_nodes, true},
      {"unused_nodes", "unused nodes", r.unused_nodes, true},
      {"inner_boundary_facets", "void-boundary facets (allowed)", r.inner_boundary_facets, false},
      {"boundary_facets", "facets on the domain box", r.boundary_facets, false},
  };
}

std::vector<Counter> fidelity_counters(const FidelityReport& f) {
  std::vector<Counter> counters{
      {"nodes_off_phase", "nodes off their phase", f.nodes_off_phase, true},
      {"interface_nodes_off_interface", "interface nodes off the interface", f.interface_nodes_off_interface, true},
      {"boundary_nodes_off_void", "void-boundary nodes off every void", f.boundary_nodes_off_void, true},
      {"cells_unknown_phase", "cells of an unknown or void phase", f.cells_unknown_phase, true},
  };
  if (f.centroids_checked) {
    counters.push_back({"cells_wrong_phase", "cells lying in another phase (centroid beyond half their size)",
                        f.cells_wrong_phase, true});
    counters.push_back({"cells_off_phase", "cells straddling an interface beyond the slack (allowed)", f.cells_off_phase,
                        false});
  }
  return counters;
}

// "cohesive: 184760 elements in 1 set; every interface facet covered once", or the failures.
std::string cohesive_line(const CohesiveSection& s) {
  std::string line = "cohesive: " + std::to_string(s.cells) + " elements in " + std::to_string(s.sets.size()) +
                     (s.sets_named ? (s.sets.size() == 1 ? " set" : " sets") : (s.sets.size() == 1 ? " phase pair" : " phase pairs")) +
                     "; ";
  if (s.ok()) return line + "every interface facet covered once";
  std::string problems;
  for (const CohesiveSection::Count& k : s.checks)
    if (k.value > 0) add_item(problems, std::to_string(k.value) + " " + k.label);
  return line + "FAILED (" + problems + ")";
}

bool measure_checked(const ConformityReport& r) { return r.expected_measure >= 0; }
bool measure_ok(const ConformityReport& r) { return !measure_checked(r) || r.measure_error <= r.measure_tolerance; }

// ---- the SVG histogram -----------------------------------------------------------------
std::string histogram_svg(const AspectStats& s) {
  const std::size_t bins = s.histogram.size();
  std::ostringstream o;
  if (bins == 0 || s.bin_edges.empty()) return "<p>No cells.</p>";
  const double width = 760, height = 320, left = 64, right = 16, top = 16, bottom = 44;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const double bar_w = plot_w / static_cast<double>(bins);
  const std::size_t peak = *std::max_element(s.histogram.begin(), s.histogram.end());
  const double log_peak = std::log10(1.0 + static_cast<double>(std::max<std::size_t>(peak, 1)));
  auto y_of = [&](double count) { return top + plot_h * (1 - std::log10(1.0 + count) / log_peak); };
  auto x_of_ar = [&](double ar) { return left + (ar - s.bin_edges.front()) / kHistogramBinWidth * bar_w; };

  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" viewBox=\"0 0 " << width << ' ' << height << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  o << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << plot_w << "\" height=\"" << plot_h
    << "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
  // Log-scale count ticks: 1, 10, 100, ...
  for (double t = 1; t <= static_cast<double>(std::max<std::size_t>(peak, 1)) * 1.0001; t *= 10) {
    const double y = y_of(t);
    o << "<line x1=\"" << left - 4 << "\" y1=\"" << y << "\" x2=\"" << left + plot_w << "\" y2=\"" << y
      << "\" stroke=\"#ddd\"/>\n";
    o << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << num(t) << "</text>\n";
  }
  for (std::size_t i = 0; i < bins; ++i) {
    if (s.histogram[i] == 0) continue;
    const bool overflow = i + 1 == bins;
    const double y = y_of(static_cast<double>(s.histogram[i]));
    const double lo = s.bin_edges[std::min(i, s.bin_edges.size() - 1)];
    const bool above = overflow || lo >= s.bound;
    std::ostringstream range;
    if (overflow)
      range << "&#8805; " << num(lo);
    else
      range << '[' << num(lo) << ", " << num(s.bin_edges[i + 1]) << ')';
    o << "<rect x=\"" << left + bar_w * static_cast<double>(i) << "\" y=\"" << y << "\" width=\""
      << std::max(bar_w - 0.5, 0.5) << "\" height=\"" << top + plot_h - y << "\" fill=\""
      << (overflow ? "#7a1f1f" : above ? "#d9822b" : "#3b73b9") << "\"><title>" << range.str() << ": "
      << s.histogram[i] << "</title></rect>\n";
  }
  // Aspect-ratio ticks every 0.5 (or coarser when there are many bins).
  const double span = s.bin_edges.back() - s.bin_edges.front();
  const double step = span <= 6 ? 0.5 : span <= 20 ? 1 : span <= 60 ? 5 : 10;
  for (double t = s.bin_edges.front(); t <= s.bin_edges.back() + 1e-9; t += step) {
    const double x = x_of_ar(t);
    o << "<line x1=\"" << x << "\" y1=\"" << top + plot_h << "\" x2=\"" << x << "\" y2=\"" << top + plot_h + 4
      << "\" stroke=\"#333\"/>\n";
    o << "<text x=\"" << x << "\" y=\"" << top + plot_h + 16 << "\" text-anchor=\"middle\">" << num(t) << "</text>\n";
  }
  o << "<text x=\"" << left + plot_w - bar_w / 2 << "\" y=\"" << top + plot_h + 28
    << "\" text-anchor=\"middle\" fill=\"#7a1f1f\">&#8805;</text>\n";
  o << "<text x=\"" << left + plot_w / 2 << "\" y=\"" << height - 4 << "\" text-anchor=\"middle\">aspect ratio</text>\n";
  o << "<text x=\"14\" y=\"" << top + plot_h / 2 << "\" text-anchor=\"middle\" transform=\"rotate(-90 14 "
    << top + plot_h / 2 << ")\">cells (log scale)</text>\n";
  if (s.bound >= s.bin_edges.front() && s.bound <= s.bin_edges.back()) {
    const double x = x_of_ar(s.bound);
    o << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + plot_h
      << "\" stroke=\"red\" stroke-width=\"2\"/>\n";
    o << "<text x=\"" << x + 4 << "\" y=\"" << top + 12 << "\" fill=\"red\">bound " << num(s.bound) << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

std::string status_cell(bool good) {
  return good ? "<td class=\"ok\">ok</td>" : "<td class=\"bad\">FAIL</td>";
}

}  // namespace

// ---------------------------------------------------------------------------------------

template <int Dim>
Certificate certify(const mesh::SimplexMesh<Dim>& m, const Box<Dim>& domain, const CertifyOptions& options) {
  Certificate c;
  c.dimension = Dim;
  c.node_count = m.node_count();
  c.cell_count = m.cell_count();
  for (int d = 0; d < Dim; ++d) c.domain.min[d] = domain.min[d], c.domain.max[d] = domain.max[d];
  std::map<int, std::size_t> per_phase;
  for (std::size_t i = 0; i < m.cell_count(); ++i) ++per_phase[i < m.cell_phase.size() ? m.cell_phase[i] : 0];
  c.cells_per_phase.assign(per_phase.begin(), per_phase.end());
  const double bound = options.bound > 0 ? options.bound : default_bound(Dim);
  c.aspect = aspect_statistics<Dim>(m, bound, options.worst_count);
  c.conformity = check_conformity<Dim>(m, domain, options.expected_measure, options.allow_inner_boundary,
                                       options.measure_tolerance);
  if (options.expected_measure < 0) c.notes.push_back("total measure not checked (no expected measure)");
  return c;
}

template Certificate certify<2>(const mesh::SimplexMesh<2>&, const Box<2>&, const CertifyOptions&);
template Certificate certify<3>(const mesh::SimplexMesh<3>&, const Box<3>&, const CertifyOptions&);

// ---------------------------------------------------------------------------------------

bool CohesiveSection::ok() const {
  return std::all_of(checks.begin(), checks.end(), [](const Count& k) { return k.value == 0; });
}

template <int Dim>
CohesiveSection certify_cohesive(const mesh::SimplexMesh<Dim>& m, const CohesiveSetsInFile* sets,
                                 const CohesivePeriodicity<Dim>* periodic) {
  constexpr std::size_t kExamplesPerKind = 3, kExamplesTotal = 24;
  const CohesiveReport<Dim> r = check_cohesive<Dim>(m, periodic);
  CohesiveSection s;
  s.cells = r.cohesive_cells;
  s.interface_facets = r.interface_facets;
  s.nodes = m.node_count();
  const auto example = [&](const std::string& text) {
    if (s.examples.size() < kExamplesTotal) s.examples.push_back(text);
  };
  const auto add = [&](const char* key, const char* label, const CohesiveFinding<Dim>& f, const char* what) {
    s.checks.push_back({key, label, f.count});
    for (std::size_t i = 0; i < f.ids.size() && i < kExamplesPerKind; ++i) {
      if (f.ids[i] < 0) {
        example(std::string(label) + ": arrays of inconsistent sizes");
        continue;
      }
      std::string at;
      for (int d = 0; d < Dim; ++d) at += (d ? ", " : "") + num(f.points[i][d], 10);
      example(std::string(label) + ": " + what + " " + std::to_string(f.ids[i]) + " at (" + at + ")");
    }
  };
  add("malformed", "cohesive cells with missing or out-of-range nodes", r.malformed, "cohesive cell");
  add("phase_mixed_nodes", "nodes used by bulk cells of two phases", r.phase_mixed_nodes, "node");
  add("duplicate_copies", "nodes repeating a copy (same position and phase)", r.duplicate_copies, "node");
  add("uncovered", "interface facets without a cohesive cell", r.uncovered, "facet of bulk cell");
  add("covered_twice", "interface facets with several cohesive cells", r.covered_twice, "facet of bulk cell");
  add("misplaced", "cohesive cells not on an interface facet of their two phases", r.misplaced, "cohesive cell");
  add("not_coincident", "cohesive cells whose top is off their bottom", r.not_coincident, "cohesive cell");
  add("wrong_sides", "cohesive cells whose bottom/top are not the lower/upper phase's nodes", r.wrong_sides,
      "cohesive cell");
  add("wrong_orientation", "cohesive cells whose bottom normal does not point into the top phase",
      r.wrong_orientation, "cohesive cell");
  add("node_phase_mismatch", "nodes whose node_phase is not their bulk cells' phase", r.node_phase_mismatch, "node");

  const auto& coh = m.cohesive;
  const auto claimed = [&](std::size_t c) {
    return 2 * c + 1 < coh.phase.size() ? std::array<std::int32_t, 2>{coh.phase[2 * c], coh.phase[2 * c + 1]}
                                        : std::array<std::int32_t, 2>{0, 0};
  };
  s.sets_named = sets != nullptr;
  if (!sets) {  // no names: the pairs the cells claim, for the report
    std::map<std::array<std::int32_t, 2>, std::size_t> pairs;
    for (std::size_t c = 0; c < coh.count(); ++c) ++pairs[claimed(c)];
    for (const auto& [pair, n] : pairs) s.sets.push_back({"", pair[0], pair[1], n});
    return s;
  }
  std::vector<std::size_t> members(sets->sets.size(), 0);
  std::size_t without = 0, several = 0, wrong = 0;
  for (std::size_t c = 0; c < coh.count(); ++c) {
    const std::int32_t set = c < sets->set_of_cell.size() ? sets->set_of_cell[c] : CohesiveSetsInFile::kNoSet;
    if (set == CohesiveSetsInFile::kSeveralSets) {
      if (several++ < kExamplesPerKind) example("cohesive cell " + std::to_string(c) + " is in several sets");
      continue;
    }
    if (set < 0 || static_cast<std::size_t>(set) >= members.size()) {
      if (without++ < kExamplesPerKind) example("cohesive cell " + std::to_string(c) + " is in no set");
      continue;
    }
    ++members[static_cast<std::size_t>(set)];
    const auto& named = sets->sets[static_cast<std::size_t>(set)].named_pairs;
    if (std::find(named.begin(), named.end(), claimed(c)) == named.end() && wrong++ < kExamplesPerKind)
      example("cohesive cell " + std::to_string(c) + " between phases " + std::to_string(claimed(c)[0]) + " and " +
              std::to_string(claimed(c)[1]) + " is in set " + sets->sets[static_cast<std::size_t>(set)].name +
              ", named for " + (named.empty() ? std::string("no pair of the file's phases")
                                              : "phases " + std::to_string(named[0][0]) + " and " + std::to_string(named[0][1])));
  }
  std::size_t empty = 0;
  for (std::size_t k = 0; k < sets->sets.size(); ++k) {
    const auto& set = sets->sets[k];
    s.sets.push_back({set.name, set.named_pairs.size() == 1 ? set.named_pairs[0][0] : 0,
                      set.named_pairs.size() == 1 ? set.named_pairs[0][1] : 0, members[k]});
    if (members[k] == 0 && empty++ < kExamplesPerKind) example("set " + set.name + " holds no cohesive cell");
  }
  s.checks.push_back({"cells_without_set", "cohesive cells in no set", without});
  s.checks.push_back({"cells_in_several_sets", "cohesive cells in several sets", several});
  s.checks.push_back({"cells_in_wrong_set", "cohesive cells in a set not named for their phases", wrong});
  s.checks.push_back({"empty_sets", "cohesive sets without cells", empty});
  return s;
}

template CohesiveSection certify_cohesive<2>(const mesh::SimplexMesh<2>&, const CohesiveSetsInFile*,
                                             const CohesivePeriodicity<2>*);
template CohesiveSection certify_cohesive<3>(const mesh::SimplexMesh<3>&, const CohesiveSetsInFile*,
                                             const CohesivePeriodicity<3>*);

// ---------------------------------------------------------------------------------------

std::string certificate_json(const Certificate& c) {
  Json j;
  j["format"] = "cisamr-certificate/1";
  j["passed"] = c.passed();
  j["mesh"] = c.mesh_source;
  j["scene"] = c.scene_source.empty() ? Json(nullptr) : Json(c.scene_source);
  j["dimension"] = c.dimension;
  j["nodes"] = c.node_count;
  j["cells"] = c.cell_count;
  Json phases = Json::array();
  for (const auto& [id, n] : c.cells_per_phase) {
    Json p;
    p["phase"] = id;
    for (const auto& [pid, name] : c.phase_names)
      if (pid == id) p["name"] = name;
    p["cells"] = n;
    phases.push_back(p);
  }
  j["cells_per_phase"] = phases;
  const DimensionWords& w = words(c.dimension);
  const int dim = w.coordinates;
  j["domain"] = {{"min", std::vector<double>(c.domain.min.begin(), c.domain.min.begin() + dim)},
                 {"max", std::vector<double>(c.domain.max.begin(), c.domain.max.begin() + dim)},
                 {"from", c.domain_from_scene ? "scene" : "mesh bounding box"}};

  const AspectStats& a = c.aspect;
  Json ar;
  ar["definition"] = w.aspect_formula;
  ar["passed"] = c.quality_ok();
  ar["bound"] = a.bound;
  ar["max"] = number(a.max);
  ar["mean"] = number(a.mean);
  ar["count"] = a.count;
  ar["above_bound"] = a.above_bound;
  ar[std::string("min_") + w.angle_key + "_deg"] = number(a.min_angle_deg);
  ar[std::string("max_") + w.angle_key + "_deg"] = number(a.max_angle_deg);
  ar["histogram"] = {{"bin_edges", a.bin_edges},
                     {"counts", a.histogram},
                     {"note", "counts[i] is [bin_edges[i], bin_edges[i+1]); the last count is >= the last edge"}};
  Json worst = Json::array();
  for (const auto& cell : a.worst) {
    worst.push_back({{"cell", cell.cell},
                     {"aspect_ratio", number(cell.aspect_ratio)},
                     {"centroid", std::vector<double>(cell.centroid.begin(), cell.centroid.begin() + dim)},
                     {"phase", cell.phase}});
  }
  ar["worst"] = worst;
  j["aspect_ratio"] = ar;

  const ConformityReport& r = c.conformity;
  Json conf;
  conf["ok"] = r.ok;
  for (const Counter& k : conformity_counters(r)) conf[k.key] = k.value;
  conf["measure"] = number(r.measure);
  conf["expected_measure"] = measure_checked(r) ? number(r.expected_measure) : Json(nullptr);
  conf["measure_error"] = measure_checked(r) ? number(r.measure_error) : Json(nullptr);
  conf["measure_tolerance"] = r.measure_tolerance;
  conf["examples"] = r.examples;
  j["conformity"] = conf;

  if (c.fidelity) {
    const FidelityReport& f = *c.fidelity;
    Json fid;
    fid["ok"] = f.ok;
    fid["tolerance"] = f.tolerance;
    for (const Counter& k : fidelity_counters(f)) fid[k.key] = k.value;
    fid["max_deviation"] = number(f.max_deviation);
    if (f.centroids_checked) fid["max_centroid_ratio"] = number(f.max_centroid_ratio);
    Json per = Json::array();
    for (std::size_t k = 0; k < f.phase_id.size(); ++k)
      per.push_back({{"phase", f.phase_id[k]},
                     {"name", f.phase_name[k]},
                     {"void", bool(f.phase_is_void[k])},
                     {"measure", number(f.phase_measure[k])},
                     {"exact_measure", number(f.exact_phase_measure[k])},
                     {"relative_error", number(f.relative_error[k])}});
    fid["phases"] = per;
    fid["examples"] = f.examples;
    j["fidelity"] = fid;
  } else {
    j["fidelity"] = nullptr;
  }
  if (c.periodic) {
    Json per = Json::array();
    for (const PeriodicAxisReport& a : c.periodic->axes)
      per.push_back({{"axis", std::string(1, "xyz"[a.axis])}, {"min_facets", a.min_facets}, {"max_facets", a.max_facets},
                     {"unmatched", a.unmatched}, {"facing_void", a.facing_void}, {"near_face_nodes", a.near_face_nodes}});
    j["periodic"] = {{"ok", c.periodic->ok}, {"axes", per}};
  }
  if (c.cohesive) {
    const CohesiveSection& s = *c.cohesive;
    Json coh;
    coh["ok"] = s.ok();
    coh["elements"] = s.cells;
    coh["interface_facets"] = s.interface_facets;
    coh["nodes"] = s.nodes;
    for (const CohesiveSection::Count& k : s.checks) coh[k.key] = k.value;
    coh["sets_named"] = s.sets_named;
    Json sets = Json::array();
    for (const CohesiveSection::SetRow& row : s.sets) {
      Json set;
      set["name"] = s.sets_named ? Json(row.name) : Json(nullptr);
      set["phases"] = row.lower != 0 || row.upper != 0 ? Json({row.lower, row.upper}) : Json(nullptr);
      set["elements"] = row.cells;
      sets.push_back(set);
    }
    coh["sets"] = sets;
    coh["examples"] = s.examples;
    j["cohesive"] = coh;
  }
  j["notes"] = c.notes;
  return j.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------------

std::string certificate_html(const Certificate& c) {
  const AspectStats& a = c.aspect;
  const ConformityReport& r = c.conformity;
  const DimensionWords& w = words(c.dimension);
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>cisamr certificate: "
    << html_escape(c.mesh_source) << "</title>\n<style>\n"
    << "body{font-family:sans-serif;margin:2em;max-width:60em;color:#222}\n"
    << "table{border-collapse:collapse;margin:0.5em 0 1.5em}\n"
    << "td,th{border:1px solid #ccc;padding:0.25em 0.6em;text-align:left}\n"
    << "td.n{text-align:right;font-variant-numeric:tabular-nums}\n"
    << ".ok{background:#e3f4e3;color:#175c17}.bad{background:#f9dcdc;color:#8a1414;font-weight:bold}\n"
    << ".verdict{display:inline-block;padding:0.3em 1em;font-size:1.4em;border-radius:4px}\n"
    << "code,li.ex{font-family:monospace;font-size:0.9em}\n</style>\n</head>\n<body>\n";
  o << "<h1>Mesh certificate</h1>\n<p class=\"verdict " << (c.passed() ? "ok\">PASSED" : "bad\">FAILED") << "</p>\n";

  o << "<h2>Mesh</h2>\n<table>\n";
  o << "<tr><th>mesh file</th><td><code>" << html_escape(c.mesh_source) << "</code></td></tr>\n";
  o << "<tr><th>scene</th><td>"
    << (c.scene_source.empty() ? "none (domain = bounding box of the mesh)" : "<code>" + html_escape(c.scene_source) + "</code>")
    << "</td></tr>\n";
  o << "<tr><th>dimension</th><td>" << c.dimension << "D (" << w.cells << ")</td></tr>\n";
  o << "<tr><th>nodes</th><td class=\"n\">" << c.node_count << "</td></tr>\n";
  o << "<tr><th>cells</th><td class=\"n\">" << c.cell_count << "</td></tr>\n";
  for (const auto& [id, n] : c.cells_per_phase)
    o << "<tr><th>cells of phase " << html_escape(phase_label(c, id)) << "</th><td class=\"n\">" << n << "</td></tr>\n";
  o << "</table>\n";

  o << "<h2>Aspect ratio</h2>\n<p>Verdict definition: <code>" << w.aspect_formula_html << "</code>, 1 for the "
    << w.regular_cell << ".</p>\n<table>\n";
  o << "<tr><th>bound</th><td class=\"n\">" << num(a.bound) << "</td><td></td></tr>\n";
  o << "<tr><th>maximum</th><td class=\"n\">" << num(a.max) << "</td>" << status_cell(c.quality_ok()) << "</tr>\n";
  o << "<tr><th>mean</th><td class=\"n\">" << num(a.mean) << "</td><td></td></tr>\n";
  o << "<tr><th>cells above the bound</th><td class=\"n\">" << a.above_bound << "</td>" << status_cell(a.above_bound == 0)
    << "</tr>\n";
  o << "<tr><th>smallest " << w.angle << "</th><td class=\"n\">"
    << num(a.min_angle_deg, 4) << "&#176;</td><td></td></tr>\n";
  o << "<tr><th>largest " << w.angle << "</th><td class=\"n\">"
    << num(a.max_angle_deg, 4) << "&#176;</td><td></td></tr>\n</table>\n";
  o << histogram_svg(a);

  o << "<h3>Worst elements</h3>\n<table>\n<tr><th>#</th><th>cell</th><th>aspect ratio</th><th>centroid</th><th>phase</th></tr>\n";
  for (std::size_t i = 0; i < a.worst.size(); ++i) {
    const auto& cell = a.worst[i];
    o << "<tr><td class=\"n\">" << i + 1 << "</td><td class=\"n\">" << cell.cell << "</td><td class=\"n"
      << (cell.aspect_ratio > a.bound ? " bad" : "") << "\">" << num(cell.aspect_ratio) << "</td><td><code>(";
    for (int d = 0; d < w.coordinates; ++d) o << (d ? ", " : "") << num(cell.centroid[d], 8);
    o << ")</code></td><td>" << html_escape(phase_label(c, cell.phase)) << "</td></tr>\n";
  }
  o << "</table>\n";

  o << "<h2>Conformity</h2>\n<table>\n<tr><th>check</th><th>count</th><th></th></tr>\n";
  for (const Counter& k : conformity_counters(r))
    o << "<tr><td>" << k.label << "</td><td class=\"n\">" << k.value << "</td>"
      << (k.is_error ? status_cell(k.value == 0) : std::string("<td></td>")) << "</tr>\n";
  o << "<tr><td>total measure</td><td class=\"n\">" << num(r.measure, 12) << "</td><td></td></tr>\n";
  if (measure_checked(r)) {
    o << "<tr><td>expected measure</td><td class=\"n\">" << num(r.expected_measure, 12) << "</td><td></td></tr>\n";
    o << "<tr><td>relative measure error (tolerance " << num(r.measure_tolerance) << ")</td><td class=\"n\">"
      << num(r.measure_error, 3) << "</td>" << status_cell(measure_ok(r)) << "</tr>\n";
  }
  o << "</table>\n";
  examples_html(o, r.examples);

  if (c.periodic)
    o << "<h2>Periodicity</h2>\n<p>" << html_escape(periodic_summary(*c.periodic)) << "</p>\n";
  if (c.cohesive) {
    const CohesiveSection& s = *c.cohesive;
    o << "<h2>Cohesive elements</h2>\n<p>" << s.cells << " cohesive elements on " << s.interface_facets
      << " interface facets; the checks above ran on the bulk mesh with its " << s.nodes
      << " nodes welded by exact coordinates.</p>\n<table>\n<tr><th>check</th><th>count</th><th></th></tr>\n";
    for (const CohesiveSection::Count& k : s.checks)
      o << "<tr><td>" << html_escape(k.label) << "</td><td class=\"n\">" << k.value << "</td>" << status_cell(k.value == 0)
        << "</tr>\n";
    o << "</table>\n<table>\n<tr><th>" << (s.sets_named ? "set" : "phase pair") << "</th><th>phases</th><th>elements</th></tr>\n";
    for (const CohesiveSection::SetRow& row : s.sets)
      o << "<tr><td>" << (s.sets_named ? "<code>" + html_escape(row.name) + "</code>" : std::string("&#8212;")) << "</td><td>"
        << (row.lower != 0 || row.upper != 0 ? html_escape(phase_label(c, row.lower) + " | " + phase_label(c, row.upper))
                                             : std::string("none"))
        << "</td><td class=\"n\">" << row.cells << "</td></tr>\n";
    o << "</table>\n";
    examples_html(o, s.examples);
  }
  o << "<h2>Phase fidelity</h2>\n";
  if (c.fidelity) {
    const FidelityReport& f = *c.fidelity;
    o << "<p>Tolerance " << num(f.tolerance, 3) << "; largest deviation found " << num(f.max_deviation, 3);
    if (f.centroids_checked)
      o << "; largest centroid distance to its cell's phase " << num(f.max_centroid_ratio, 3)
        << " of the cell's longest edge (allowed " << num(kCentroidSlack) << ", " << num(kInterfaceCentroidSlack)
        << " for cells with every vertex on an interface)";
    o << ".</p>\n";
    o << "<table>\n<tr><th>check</th><th>count</th><th></th></tr>\n";
    for (const Counter& k : fidelity_counters(f))
      o << "<tr><td>" << k.label << "</td><td class=\"n\">" << k.value << "</td>" << status_cell(k.value == 0) << "</tr>\n";
    o << "</table>\n<table>\n<tr><th>phase</th><th>meshed measure</th><th>exact measure</th><th>relative error</th></tr>\n";
    for (std::size_t k = 0; k < f.phase_id.size(); ++k) {
      o << "<tr><td>" << f.phase_id[k] << (f.phase_name[k].empty() ? "" : " (" + html_escape(f.phase_name[k]) + ")")
        << "</td>";
      if (f.phase_is_void[k])
        o << "<td>void (not meshed)</td><td class=\"n\">" << num(f.exact_phase_measure[k], 10) << "</td><td></td></tr>\n";
      else
        o << "<td class=\"n\">" << num(f.phase_measure[k], 10) << "</td><td class=\"n\">" << num(f.exact_phase_measure[k], 10)
          << "</td><td class=\"n\">" << num(f.relative_error[k], 3) << "</td></tr>\n";
    }
    o << "</table>\n";
    examples_html(o, f.examples);
  } else {
    o << "<p>Not checked.</p>\n";
  }
  if (!c.notes.empty()) {
    o << "<h2>Notes</h2>\n<ul>\n";
    for (const auto& n : c.notes) o << "<li>" << html_escape(n) << "</li>\n";
    o << "</ul>\n";
  }
  o << "</body>\n</html>\n";
  return o.str();
}

// ---------------------------------------------------------------------------------------

std::string certificate_summary(const Certificate& c) {
  const AspectStats& a = c.aspect;
  const ConformityReport& r = c.conformity;
  const DimensionWords& w = words(c.dimension);
  std::ostringstream o;
  o << "mesh: " << (c.mesh_source.empty() ? "(in memory)" : c.mesh_source) << ": " << c.dimension << "D, " << c.node_count
    << " nodes, " << c.cell_count << " " << w.cells << "\n";
  o << "aspect ratio: max " << num(a.max, 5) << ", mean " << num(a.mean, 5) << ", " << a.above_bound
    << " above the bound " << num(a.bound) << "\n";
  o << w.angle << "s: " << num(a.min_angle_deg, 4) << " to "
    << num(a.max_angle_deg, 4) << " degrees\n";
  o << "conformity: ";
  if (r.ok) {
    o << "ok";
  } else {
    std::string problems;
    for (const Counter& k : conformity_counters(r))
      if (k.is_error && k.value > 0) add_item(problems, std::to_string(k.value) + " " + k.label);
    if (!measure_ok(r)) add_item(problems, "measure off by " + num(r.measure_error, 3));
    o << "FAILED (" << problems << ")";
  }
  if (measure_checked(r)) o << "; measure " << num(r.measure, 10) << " (relative error " << num(r.measure_error, 3) << ")";
  o << "\n";
  if (c.fidelity) {
    const FidelityReport& f = *c.fidelity;
    o << "fidelity: ";
    if (f.ok) {
      o << "ok (largest deviation " << num(f.max_deviation, 3) << ", tolerance " << num(f.tolerance, 3) << ")";
    } else {
      std::string problems;
      for (const Counter& k : fidelity_counters(f))
        if (k.value > 0) add_item(problems, std::to_string(k.value) + " " + k.label);
      o << "FAILED (" << problems << "; largest deviation " << num(f.max_deviation, 3) << ")";
    }
    o << "\n";
    if (c.dimension == 3)  // the volumes converge as h → 0: reported, not judged
      for (std::size_t k = 0; k < f.phase_id.size(); ++k) {
        o << "phase " << f.phase_id[k] << (f.phase_name[k].empty() ? "" : " (" + f.phase_name[k] + ")") << ": ";
        if (f.phase_is_void[k])
          o << "void, exact volume " << num(f.exact_phase_measure[k], 6) << "\n";
        else
          o << "volume " << num(f.phase_measure[k], 6) << ", exact " << num(f.exact_phase_measure[k], 6)
            << ", relative error " << num(f.relative_error[k], 3) << "\n";
      }
  }
  if (c.periodic) o << "periodicity: " << periodic_summary(*c.periodic) << "\n";
  if (c.cohesive) o << cohesive_line(*c.cohesive) << "\n";
  for (const auto& n : c.notes) o << "note: " << n << "\n";
  o << "certificate: " << (c.passed() ? "PASSED" : "FAILED") << "\n";
  return o.str();
}

}  // namespace cisamr::quality
