// cisamr-pack/1 parsing: every problem is an InputError naming the field.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <span>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "pack/pack.hpp"

namespace cisamr::pack {
namespace {

using nlohmann::json;

// What a spec may ask for, so that a typo cannot make the packer run for days or exhaust
// memory: placement trials per particle, particles per population.
constexpr std::int64_t kMaxTrials = 1'000'000'000;
constexpr std::int64_t kMaxCount = 100'000'000;

struct Reader {
  std::string source;

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(source, field, problem);
  }
  void only_keys(const json& j, const std::string& field, std::set<std::string> allowed) const {
    if (!j.is_object()) fail(field, "must be an object");
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!allowed.count(it.key()))
        fail(field.empty() ? it.key() : field + "." + it.key(), "unknown field");
  }
  static std::string join(const std::string& field, const std::string& key) {
    return field.empty() ? key : field + "." + key;
  }
  double number(const json& j, const std::string& field) const {
    if (!j.is_number()) fail(field, "must be a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(field, "must be finite");
    return v;
  }
  double positive(const json& j, const std::string& field) const {
    const double v = number(j, field);
    if (!(v > 0)) fail(field, "must be positive");
    return v;
  }
  std::int64_t integer(const json& j, const std::string& field) const {
    if (!j.is_number_integer()) fail(field, "must be an integer");
    return j.get<std::int64_t>();
  }
  std::string string(const json& j, const std::string& field) const {
    if (!j.is_string()) fail(field, "must be a string");
    return j.get<std::string>();
  }
  bool boolean(const json& j, const std::string& field) const {
    if (!j.is_boolean()) fail(field, "must be true or false");
    return j.get<bool>();
  }
  Vec3 vector(const json& j, const std::string& field, int dim) const {
    if (!j.is_array() || static_cast<int>(j.size()) != dim)
      fail(field, "must be an array of " + std::to_string(dim) + " numbers");
    Vec3 v{};
    for (int d = 0; d < dim; ++d) v[d] = number(j[d], field + "[" + std::to_string(d) + "]");
    return v;
  }
  geometry::Rotation3 rotation(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3) fail(field, "must be a 3×3 array");
    geometry::Rotation3 r{};
    for (int i = 0; i < 3; ++i) {
      const Vec3 row = vector(j[i], field + "[" + std::to_string(i) + "]", 3);
      for (int k = 0; k < 3; ++k) r[i][k] = row[k];
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double s = 0;
        for (int k = 0; k < 3; ++k) s += r[k][a] * r[k][b];
        if (std::abs(s - (a == b ? 1.0 : 0.0)) > 1e-6) fail(field, "must be a rotation matrix");
      }
    return r;
  }

  Law law(const json& j, const std::string& field, bool positive_only) const {
    Law l;
    if (j.is_number()) {  // shorthand: a fixed value
      l.value = positive_only ? positive(j, field) : number(j, field);
      return l;
    }
    only_keys(j, field, {"law", "value", "min", "max", "mean", "std"});
    if (!j.contains("law")) fail(field + ".law", "missing (fixed, uniform, normal or lognormal)");
    const std::string kind = string(j["law"], field + ".law");
    auto get = [&](const char* key, bool required) -> std::optional<double> {
      if (!j.contains(key)) {
        if (required) fail(join(field, key), "missing for law \"" + kind + "\"");
        return std::nullopt;
      }
      return number(j[key], join(field, key));
    };
    if (kind == "fixed") {
      l.kind = Law::Kind::fixed;
      l.value = *get("value", true);
      if (positive_only && !(l.value > 0)) fail(field + ".value", "must be positive");
    } else if (kind == "uniform") {
      l.kind = Law::Kind::uniform;
      l.min = *get("min", true);
      l.max = *get("max", true);
      l.has_min = l.has_max = true;
      if (!(l.max >= l.min)) fail(field + ".max", "must be ≥ min");
      if (positive_only && !(l.min > 0)) fail(field + ".min", "must be positive");
    } else if (kind == "normal" || kind == "lognormal") {
      l.kind = kind == "normal" ? Law::Kind::normal : Law::Kind::lognormal;
      l.mean = *get("mean", true);
      l.std = *get("std", true);
      if (!(l.std >= 0)) fail(field + ".std", "must be ≥ 0");
      if ((positive_only || l.kind == Law::Kind::lognormal) && !(l.mean > 0))
        fail(field + ".mean", "must be positive");
      if (auto v = get("min", false)) { l.min = *v; l.has_min = true; }
      if (auto v = get("max", false)) { l.max = *v; l.has_max = true; }
      if (l.has_min && l.has_max && !(l.max >= l.min)) fail(field + ".max", "must be ≥ min");
      if (l.has_max && positive_only && !(l.max > 0)) fail(field + ".max", "must be positive");
    } else {
      fail(field + ".law", "unknown law \"" + kind + "\" (fixed, uniform, normal or lognormal)");
    }
    return l;
  }
};

ShapeKind shape_kind(const Reader& r, const std::string& name, const std::string& field, int dim) {
  static const std::pair<const char*, ShapeKind> kinds2[] = {
      {"circle", ShapeKind::circle}, {"ellipse", ShapeKind::ellipse},
      {"polygon", ShapeKind::polygon}, {"nurbs", ShapeKind::nurbs}};
  static const std::pair<const char*, ShapeKind> kinds3[] = {
      {"sphere", ShapeKind::sphere}, {"ellipsoid", ShapeKind::ellipsoid},
      {"fibre", ShapeKind::fibre}, {"fiber", ShapeKind::fibre}, {"stl", ShapeKind::stl}};
  using Kinds = std::span<const std::pair<const char*, ShapeKind>>;
  const Kinds own = dim == 2 ? Kinds(kinds2) : Kinds(kinds3);
  const Kinds other = dim == 2 ? Kinds(kinds3) : Kinds(kinds2);
  for (const auto& [n, k] : own)
    if (name == n) return k;
  for (const auto& [n, k] : other)
    if (name == n)
      r.fail(field, "shape \"" + name + "\" is not a " + std::to_string(dim) + "D shape");
  r.fail(field, "unknown shape \"" + name + "\" (2D: circle, ellipse, polygon, nurbs; 3D: sphere, "
                "ellipsoid, fibre, stl)");
}

}  // namespace

PackSpec parse_pack_spec(const std::string& text, const std::string& source) {
  Reader r{source};
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {  // syntax, or a number beyond the double range (1e400)
    // Without nlohmann's prefix and the bytes it quotes ("last read: ..."): they may be
    // long or binary.
    std::string detail = e.what();
    if (const auto p = detail.find("] "); p != std::string::npos) detail = detail.substr(p + 2);
    if (const auto p = detail.find("; last read"); p != std::string::npos) detail.resize(p);
    if (detail.size() > 200) detail = detail.substr(0, 200) + "...";
    r.fail("", "not valid JSON: " + detail);
  }
  r.only_keys(doc, "", {"format", "dimension", "seed", "domain", "mesh", "phases", "matrix_phase",
                        "max_trials", "max_failures", "populations", "description"});
  PackSpec spec;
  spec.source = source;
  if (!doc.contains("format")) r.fail("format", "missing (expected \"cisamr-pack/1\")");
  if (r.string(doc["format"], "format") != "cisamr-pack/1")
    r.fail("format", "expected \"cisamr-pack/1\"");
  if (!doc.contains("dimension")) r.fail("dimension", "missing (2 or 3)");
  spec.dimension = static_cast<int>(r.integer(doc["dimension"], "dimension"));
  if (spec.dimension != 2 && spec.dimension != 3) r.fail("dimension", "must be 2 or 3");
  const int dim = spec.dimension;
  if (doc.contains("seed")) {
    const auto s = r.integer(doc["seed"], "seed");
    if (s < 0) r.fail("seed", "must be ≥ 0");
    spec.seed = static_cast<std::uint64_t>(s);
  }

  if (!doc.contains("domain")) r.fail("domain", "missing");
  const json& dom = doc["domain"];
  r.only_keys(dom, "domain", {"min", "max", "periodic"});
  if (!dom.contains("min")) r.fail("domain.min", "missing");
  if (!dom.contains("max")) r.fail("domain.max", "missing");
  spec.domain.min = r.vector(dom["min"], "domain.min", dim);
  spec.domain.max = r.vector(dom["max"], "domain.max", dim);
  for (int d = 0; d < dim; ++d)
    if (!(spec.domain.max[d] > spec.domain.min[d]))
      r.fail("domain.max", "must be greater than domain.min in every coordinate");
  if (dom.contains("periodic")) spec.periodic = r.boolean(dom["periodic"], "domain.periodic");

  if (!doc.contains("mesh")) r.fail("mesh", "missing");
  const json& mesh = doc["mesh"];
  r.only_keys(mesh, "mesh", {"h", "levels"});
  if (!mesh.contains("h")) r.fail("mesh.h", "missing");
  spec.h = r.positive(mesh["h"], "mesh.h");
  for (int d = 0; d < dim; ++d) {
    const double cells = (spec.domain.max[d] - spec.domain.min[d]) / spec.h;
    if (std::abs(cells - std::round(cells)) > 1e-9 * std::max(1.0, cells))
      r.fail("mesh.h", "must divide every domain extent");
  }
  if (mesh.contains("levels")) {
    spec.levels = static_cast<int>(r.integer(mesh["levels"], "mesh.levels"));
    if (spec.levels < 0 || spec.levels > 20) r.fail("mesh.levels", "must be between 0 and 20");
  }

  if (doc.contains("phases")) {
    const json& ph = doc["phases"];
    if (!ph.is_array() || ph.empty()) r.fail("phases", "must be a non-empty array");
    std::set<int> ids;
    for (std::size_t i = 0; i < ph.size(); ++i) {
      const std::string f = "phases[" + std::to_string(i) + "]";
      r.only_keys(ph[i], f, {"id", "name", "void"});
      geometry::Phase p;
      if (!ph[i].contains("id")) r.fail(f + ".id", "missing");
      p.id = static_cast<int>(r.integer(ph[i]["id"], f + ".id"));
      if (p.id <= 0) r.fail(f + ".id", "must be a positive integer");
      if (!ids.insert(p.id).second) r.fail(f + ".id", "duplicate phase id");
      if (ph[i].contains("name")) p.name = r.string(ph[i]["name"], f + ".name");
      if (ph[i].contains("void")) p.is_void = r.boolean(ph[i]["void"], f + ".void");
      spec.phases.push_back(p);
    }
  } else {
    spec.phases = {{1, "matrix", false}, {2, "inclusion", false}};
  }
  auto has_phase = [&](int id) {
    for (const auto& p : spec.phases)
      if (p.id == id) return true;
    return false;
  };
  if (doc.contains("matrix_phase"))
    spec.matrix_phase = static_cast<int>(r.integer(doc["matrix_phase"], "matrix_phase"));
  if (!has_phase(spec.matrix_phase)) r.fail("matrix_phase", "no phase with this id");
  if (doc.contains("max_trials")) {
    spec.max_trials = r.integer(doc["max_trials"], "max_trials");
    if (spec.max_trials < 1 || spec.max_trials > kMaxTrials)
      r.fail("max_trials", "must be between 1 and " + std::to_string(kMaxTrials));
  }
  if (doc.contains("max_failures")) {
    spec.max_failures = r.integer(doc["max_failures"], "max_failures");
    if (spec.max_failures < 0) r.fail("max_failures", "must be ≥ 0");
  }

  if (!doc.contains("populations")) r.fail("populations", "missing");
  const json& pops = doc["populations"];
  if (!pops.is_array() || pops.empty()) r.fail("populations", "must be a non-empty array");
  const std::filesystem::path base = std::filesystem::path(source).parent_path();
  for (std::size_t i = 0; i < pops.size(); ++i) {
    const std::string f = "populations[" + std::to_string(i) + "]";
    const json& pj = pops[i];
    r.only_keys(pj, f, {"name", "shape", "phase", "levels", "count", "volume_fraction", "tolerance",
                        "size", "aspect", "aspect_c", "orientation", "spatial", "min_gap", "overlap",
                        "region", "vertices", "roughness", "axis", "file"});
    Population p;
    p.field = f;
    p.name = pj.contains("name") ? r.string(pj["name"], f + ".name") : "population" + std::to_string(i);
    if (!pj.contains("shape")) r.fail(f + ".shape", "missing");
    p.shape = shape_kind(r, r.string(pj["shape"], f + ".shape"), f + ".shape", dim);
    if (pj.contains("phase")) p.phase = static_cast<int>(r.integer(pj["phase"], f + ".phase"));
    if (!has_phase(p.phase)) r.fail(f + ".phase", "no phase with this id");
    if (p.phase == spec.matrix_phase) r.fail(f + ".phase", "is the matrix phase");
    if (pj.contains("levels")) {
      p.levels = static_cast<int>(r.integer(pj["levels"], f + ".levels"));
      if (p.levels < 0 || p.levels > 20) r.fail(f + ".levels", "must be between 0 and 20");
    }
    if (pj.contains("count")) {
      p.count = r.integer(pj["count"], f + ".count");
      if (*p.count < 0 || *p.count > kMaxCount)
        r.fail(f + ".count", "must be between 0 and " + std::to_string(kMaxCount));
    }
    if (pj.contains("volume_fraction")) {
      p.volume_fraction = r.number(pj["volume_fraction"], f + ".volume_fraction");
      if (!(*p.volume_fraction > 0 && *p.volume_fraction < 1))
        r.fail(f + ".volume_fraction", "must be between 0 and 1");
    }
    if (!p.count && !p.volume_fraction)
      r.fail(f + ".count", "give a count, a volume_fraction, or both");
    if (pj.contains("tolerance")) {
      p.tolerance = r.number(pj["tolerance"], f + ".tolerance");
      if (!(p.tolerance > 0 && p.tolerance < 1)) r.fail(f + ".tolerance", "must be between 0 and 1");
    }
    if (!pj.contains("size")) r.fail(f + ".size", "missing");
    p.size = r.law(pj["size"], f + ".size", true);
    if (pj.contains("aspect")) p.aspect = r.law(pj["aspect"], f + ".aspect", true);
    if (pj.contains("aspect_c")) p.aspect_c = r.law(pj["aspect_c"], f + ".aspect_c", true);
    if (pj.contains("orientation")) {
      const json& oj = pj["orientation"];
      const std::string of = f + ".orientation";
      r.only_keys(oj, of, {"law", "angle", "mean", "std", "rotation"});
      const std::string kind = oj.contains("law") ? r.string(oj["law"], of + ".law") : "random";
      if (kind == "random") {
        p.orientation.kind = OrientationLaw::Kind::random;
      } else if (kind == "fixed" || kind == "normal") {
        p.orientation.kind = kind == "fixed" ? OrientationLaw::Kind::fixed : OrientationLaw::Kind::normal;
        if (dim == 2) {
          const char* key = kind == "fixed" ? "angle" : "mean";
          if (oj.contains(key)) p.orientation.angle = r.number(oj[key], of + "." + key);
        } else if (oj.contains("rotation")) {
          p.orientation.rotation = r.rotation(oj["rotation"], of + ".rotation");
        }
        if (kind == "normal") {
          if (!oj.contains("std")) r.fail(of + ".std", "missing for law \"normal\"");
          p.orientation.std = r.number(oj["std"], of + ".std");
          if (!(p.orientation.std >= 0)) r.fail(of + ".std", "must be ≥ 0");
        }
      } else {
        r.fail(of + ".law", "unknown orientation law \"" + kind + "\" (random, fixed or normal)");
      }
    }
    if (pj.contains("spatial")) {
      const json& sj = pj["spatial"];
      const std::string sf = f + ".spatial";
      r.only_keys(sj, sf, {"law", "clusters", "cluster_radius", "in_clusters"});
      const std::string kind = sj.contains("law") ? r.string(sj["law"], sf + ".law") : "uniform";
      if (kind == "clustered") {
        p.spatial.kind = SpatialLaw::Kind::clustered;
        for (const char* key : {"clusters", "cluster_radius", "in_clusters"})
          if (!sj.contains(key)) r.fail(sf + "." + key, "missing for law \"clustered\"");
        p.spatial.clusters = static_cast<int>(r.integer(sj["clusters"], sf + ".clusters"));
        if (p.spatial.clusters < 1) r.fail(sf + ".clusters", "must be ≥ 1");
        p.spatial.cluster_radius = r.positive(sj["cluster_radius"], sf + ".cluster_radius");
        p.spatial.in_clusters = r.number(sj["in_clusters"], sf + ".in_clusters");
        if (!(p.spatial.in_clusters >= 0 && p.spatial.in_clusters <= 1))
          r.fail(sf + ".in_clusters", "must be between 0 and 1");
      } else if (kind != "uniform") {
        r.fail(sf + ".law", "unknown spatial law \"" + kind + "\" (uniform or clustered)");
      }
    }
    if (pj.contains("min_gap")) {
      p.min_gap = r.number(pj["min_gap"], f + ".min_gap");
      if (!(p.min_gap >= 0)) r.fail(f + ".min_gap", "must be ≥ 0");
    }
    if (pj.contains("overlap")) p.overlap = r.boolean(pj["overlap"], f + ".overlap");
    if (pj.contains("region")) {
      const json& rj = pj["region"];
      r.only_keys(rj, f + ".region", {"min", "max"});
      if (!rj.contains("min") || !rj.contains("max")) r.fail(f + ".region", "needs min and max");
      Box3 b{r.vector(rj["min"], f + ".region.min", dim), r.vector(rj["max"], f + ".region.max", dim)};
      for (int d = 0; d < dim; ++d)
        if (!(b.max[d] > b.min[d]) || b.min[d] < spec.domain.min[d] - 1e-12 ||
            b.max[d] > spec.domain.max[d] + 1e-12)
          r.fail(f + ".region", "must be a non-empty box inside the domain");
      p.region = b;
    }
    if (pj.contains("vertices")) {
      p.vertices = static_cast<int>(r.integer(pj["vertices"], f + ".vertices"));
      if (p.vertices < (p.shape == ShapeKind::nurbs ? 4 : 3) || p.vertices > 256)
        r.fail(f + ".vertices", "must be between 3 (4 for nurbs) and 256");
    }
    if (pj.contains("roughness")) {
      p.roughness = r.number(pj["roughness"], f + ".roughness");
      if (!(p.roughness >= 0 && p.roughness <= 0.6)) r.fail(f + ".roughness", "must be between 0 and 0.6");
    }
    if (pj.contains("axis")) {
      const std::string a = r.string(pj["axis"], f + ".axis");
      if (a == "x") p.axis = 0;
      else if (a == "y") p.axis = 1;
      else if (a == "z") p.axis = 2;
      else r.fail(f + ".axis", "must be \"x\", \"y\" or \"z\"");
    }
    if (p.shape == ShapeKind::stl) {
      if (!pj.contains("file")) r.fail(f + ".file", "missing for shape \"stl\"");
      std::filesystem::path file = r.string(pj["file"], f + ".file");
      if (file.is_relative()) file = base / file;
      p.file = file.string();
      // Checked without opening: a FIFO would block, /dev/zero never ends.
      if (const std::string problem = input_file_problem(p.file); !problem.empty())
        r.fail(f + ".file", "\"" + p.file + "\": " + problem);
      std::ifstream probe(p.file, std::ios::binary);
      if (!probe) r.fail(f + ".file", "cannot open \"" + p.file + "\"");
    }
    spec.populations.push_back(std::move(p));
  }
  return spec;
}

PackSpec read_pack_spec(const std::string& path) {
  return parse_pack_spec(read_input_file(path), path);
}

}  // namespace cisamr::pack
