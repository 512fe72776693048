// TetGen 1.5 through libtet: scene → PLC → tetrahedralize → Mesh3. See tetgen_mesh.hpp.
#define TETLIBRARY
#include <tetgen.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "mesh/metrics.hpp"
#include "compare/tetgen_mesh.hpp"

namespace cisamr::compare {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The regular icosahedron on the unit sphere: 12 vertices, 20 outward triangles.
void icosahedron(std::vector<Vec3>& v, std::vector<std::array<int, 3>>& f) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
}

Vec3 normalized(const Vec3& p) {
  const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  return {p[0] / n, p[1] / n, p[2] / n};
}

// Geodesic icosphere on the unit sphere. A grid point of a face is a combination of
// icosahedron vertices with integer weights summing to f; points on shared edges and
// corners are merged through that combination (sorted by vertex), so the surface is closed.
Surface unit_geodesic(int frequency) {
  std::vector<Vec3> ico;
  std::vector<std::array<int, 3>> faces;
  icosahedron(ico, faces);
  Surface s;
  std::map<std::array<int, 6>, std::int32_t> index_of;
  const auto point = [&](const std::array<int, 3>& face, int i, int j) {
    const int k = frequency - i - j;
    std::array<std::pair<int, int>, 3> terms{{{face[0], i}, {face[1], j}, {face[2], k}}};
    std::sort(terms.begin(), terms.end());
    std::array<int, 6> key{};
    int n = 0;
    for (const auto& [vertex, weight] : terms)
      if (weight > 0) key[n++] = vertex, key[n++] = weight;
    for (; n < 6; ++n) key[n] = -1;
    const auto [it, inserted] = index_of.emplace(key, static_cast<std::int32_t>(s.points.size()));
    if (inserted) {
      Vec3 p{};
      for (int d = 0; d < 3; ++d)
        p[d] = (i * ico[face[0]][d] + j * ico[face[1]][d] + k * ico[face[2]][d]) / frequency;
      s.points.push_back(normalized(p));
    }
    return it->second;
  };
  for (const auto& face : faces)
    for (int i = 0; i < frequency; ++i)
      for (int j = 0; i + j < frequency; ++j) {
        // Same orientation as the face: weights (i, j, k) → (i+1, j, k-1) → (i, j+1, k-1).
        s.triangles.push_back({point(face, i, j), point(face, i + 1, j), point(face, i, j + 1)});
        if (i + j + 1 < frequency)
          s.triangles.push_back({point(face, i + 1, j), point(face, i + 1, j + 1), point(face, i, j + 1)});
      }
  return s;
}

// The scene's finest interface element size: h / 2^(largest level).
double finest_interface_size(const geometry::SceneDesc& scene) {
  int levels = scene.levels;
  for (const auto& inc : scene.inclusions) levels = std::max(levels, inc.levels);
  return scene.h / std::ldexp(1.0, levels);
}

struct Body {  // a sphere or an ellipsoid as centre + R·diag(semi_axes)
  Vec3 center{};
  Vec3 semi_axes{};
  geometry::Rotation3 rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  double bounding_radius() const { return std::max({semi_axes[0], semi_axes[1], semi_axes[2]}); }
};

Body body_of(const geometry::SceneDesc& scene, std::size_t i) {
  const geometry::Shape& shape = scene.inclusions[i].shape;
  if (const auto* s = std::get_if<geometry::Sphere>(&shape)) {
    Body b;
    b.center = s->center;
    b.semi_axes = {s->radius, s->radius, s->radius};
    return b;
  }
  if (const auto* e = std::get_if<geometry::Ellipsoid>(&shape)) return Body{e->center, e->semi_axes, e->rotation};
  throw InputError(scene.source, geometry::inclusion_field(scene, i) + ".shape",
                   "the TetGen reference meshes spheres and ellipsoids only");
}

Vec3 body_point(const Body& b, const Vec3& unit) {
  Vec3 local{b.semi_axes[0] * unit[0], b.semi_axes[1] * unit[1], b.semi_axes[2] * unit[2]};
  Vec3 p = b.center;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p[r] += b.rotation[r][c] * local[c];
  return p;
}

void check_scene(const geometry::SceneDesc& scene, const std::vector<Body>& bodies) {
  if (scene.any_periodic())
    throw InputError(scene.source, "domain.periodic", "the TetGen reference does not mesh periodic scenes");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Body& b = bodies[i];
    for (int d = 0; d < 3; ++d)
      if (b.center[d] - b.bounding_radius() <= scene.domain_min[d] ||
          b.center[d] + b.bounding_radius() >= scene.domain_max[d])
        throw InputError(scene.source, geometry::inclusion_field(scene, i),
                         "the TetGen reference needs inclusions strictly inside the domain (this one may touch it)");
  }
  // Spheres: exact overlap test on a uniform grid hash of the centres. Ellipsoids that
  // overlap make TetGen report intersecting facets (code 3).
  double largest = 0;
  for (const Body& b : bodies) largest = std::max(largest, b.bounding_radius());
  if (bodies.empty()) return;
  const double cell = 2 * largest;
  std::map<std::array<long, 3>, std::vector<std::size_t>> grid;
  const auto cell_of = [&](const Vec3& p) {
    return std::array<long, 3>{static_cast<long>(std::floor(p[0] / cell)), static_cast<long>(std::floor(p[1] / cell)),
                               static_cast<long>(std::floor(p[2] / cell))};
  };
  for (std::size_t i = 0; i < bodies.size(); ++i) grid[cell_of(bodies[i].center)].push_back(i);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const auto c = cell_of(bodies[i].center);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (std::size_t j : it->second) {
            if (j <= i) continue;
            const double gap = mesh::distance<3>(bodies[i].center, bodies[j].center) -
                               bodies[i].bounding_radius() - bodies[j].bounding_radius();
            const bool both_spheres = std::holds_alternative<geometry::Sphere>(scene.inclusions[i].shape) &&
                                      std::holds_alternative<geometry::Sphere>(scene.inclusions[j].shape);
            if (both_spheres && gap <= 0)
              throw InputError(scene.source, geometry::inclusion_field(scene, j),
                               "overlaps " + geometry::inclusion_field(scene, i) +
                                   ": the TetGen reference needs disjoint inclusions");
          }
        }
  }
}

// A matrix point: outside every inclusion's bounding sphere, away from the box faces.
Vec3 matrix_seed(const geometry::SceneDesc& scene, const std::vector<Body>& bodies) {
  for (int n = 2; n <= 64; n *= 2)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const int ijk[3] = {i, j, k};
          Vec3 p{};
          for (int d = 0; d < 3; ++d)
            p[d] = scene.domain_min[d] + (ijk[d] + 0.5) / n * (scene.domain_max[d] - scene.domain_min[d]);
          bool free = true;
          for (const Body& b : bodies)
            if (mesh::distance<3>(p, b.center) <= b.bounding_radius() * 1.001) { free = false; break; }
          if (free) return p;
        }
  throw InputError(scene.source, "inclusions", "the TetGen reference found no matrix point for its region seed");
}

template <class T>
T* new_array(std::size_t n) {
  return new T[n];  // tetgenio frees its arrays with delete[]
}

std::string tetgen_error(int code) {
  switch (code) {
    case 1: return "out of memory";
    case 2: return "internal error";
    case 3: return "the input surfaces intersect (overlapping inclusions?)";
    case 4: return "a very small input feature size was detected";
    case 5: return "two very close input facets were detected";
    case 10: return "an input error was detected";
    default: return "error code " + std::to_string(code);
  }
}

}  // namespace

void check_tetgen_scene(const geometry::SceneDesc& scene) {
  if (scene.dimension != 3)
    throw InputError(scene.source, "dimension", "the TetGen reference meshes 3D scenes only (this one is " +
                                                    std::to_string(scene.dimension) + "D)");
  std::vector<Body> bodies;
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) bodies.push_back(body_of(scene, i));
  check_scene(scene, bodies);
}

int geodesic_frequency(double radius, double edge, int min_frequency) {
  // Icosahedron edge on a sphere of radius r: 1.0515·r; subdividing f times divides it by ~f.
  const double f = edge > 0 ? std::ceil(1.0515 * radius / edge) : 1.0;
  return std::max(min_frequency, static_cast<int>(std::min(f, 1000.0)));
}

Surface inclusion_surface(const geometry::Shape& shape, int frequency) {
  geometry::SceneDesc one;
  one.dimension = 3;
  one.inclusions.push_back({shape, 2, 0});
  const Body b = body_of(one, 0);
  Surface s = unit_geodesic(frequency);
  for (Vec3& p : s.points) p = body_point(b, p);
  return s;
}

TetgenMesh mesh_scene_with_tetgen(const geometry::SceneDesc& scene, const TetgenOptions& options) {
  TetgenMesh result;
  const auto plc_start = std::chrono::steady_clock::now();
  check_tetgen_scene(scene);
  std::vector<Body> bodies;
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) bodies.push_back(body_of(scene, i));
  const double edge = options.surface_edge > 0 ? options.surface_edge : finest_interface_size(scene);

  // Surfaces: one geodesic template per frequency, mapped onto each body.
  std::map<int, Surface> templates;
  std::vector<int> frequency(bodies.size());
  std::size_t point_count = 8, facet_count = 6;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    frequency[i] = geodesic_frequency(bodies[i].bounding_radius(), edge, options.min_frequency);
    auto it = templates.find(frequency[i]);
    if (it == templates.end()) it = templates.emplace(frequency[i], unit_geodesic(frequency[i])).first;
    point_count += it->second.points.size();
    facet_count += it->second.triangles.size();
  }

  tetgenio in;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(point_count);
  in.pointlist = new_array<REAL>(3 * point_count);
  in.numberoffacets = static_cast<int>(facet_count);
  in.facetlist = new_array<tetgenio::facet>(facet_count);
  std::size_t next_point = 0, next_facet = 0;
  const auto add_point = [&](const Vec3& p) {
    for (int d = 0; d < 3; ++d) in.pointlist[3 * next_point + d] = p[d];
    return static_cast<int>(next_point++);
  };
  const auto add_facet = [&](std::initializer_list<int> corners) {
    tetgenio::facet& f = in.facetlist[next_facet++];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new_array<tetgenio::polygon>(1);
    tetgenio::polygon& p = f.polygonlist[0];
    tetgenio::init(&p);
    p.numberofvertices = static_cast<int>(corners.size());
    p.vertexlist = new_array<int>(corners.size());
    std::copy(corners.begin(), corners.end(), p.vertexlist);
  };
  // The box: corner c has bit d set when it is at domain_max along d.
  for (int c = 0; c < 8; ++c)
    add_point({(c & 1) ? scene.domain_max[0] : scene.domain_min[0], (c & 2) ? scene.domain_max[1] : scene.domain_min[1],
               (c & 4) ? scene.domain_max[2] : scene.domain_min[2]});
  add_facet({0, 2, 3, 1});  // z min
  add_facet({4, 5, 7, 6});  // z max
  add_facet({0, 1, 5, 4});  // y min
  add_facet({2, 6, 7, 3});  // y max
  add_facet({0, 4, 6, 2});  // x min
  add_facet({1, 3, 7, 5});  // x max
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Surface& t = templates.at(frequency[i]);
    const int base = static_cast<int>(next_point);
    for (const Vec3& u : t.points) add_point(body_point(bodies[i], u));
    for (const auto& tri : t.triangles) add_facet({base + tri[0], base + tri[1], base + tri[2]});
  }
  result.surface_points = static_cast<std::int64_t>(point_count - 8);
  result.surface_triangles = static_cast<std::int64_t>(facet_count - 6);

  // Regions: attribute 0 = matrix, i + 1 = inclusion i; void inclusions are holes.
  std::vector<std::size_t> solid, voids;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const int phase = scene.phase_index(scene.inclusions[i].phase);
    (phase >= 0 && scene.phases[static_cast<std::size_t>(phase)].is_void ? voids : solid).push_back(i);
  }
  const Vec3 seed = matrix_seed(scene, bodies);
  in.numberofregions = static_cast<int>(solid.size() + 1);
  in.regionlist = new_array<REAL>(5 * (solid.size() + 1));
  const auto set_region = [&](std::size_t r, const Vec3& p, double attribute) {
    for (int d = 0; d < 3; ++d) in.regionlist[5 * r + d] = p[d];
    in.regionlist[5 * r + 3] = attribute;
    in.regionlist[5 * r + 4] = -1;  // no regional volume bound
  };
  set_region(0, seed, 0);
  for (std::size_t r = 0; r < solid.size(); ++r) set_region(r + 1, bodies[solid[r]].center, double(solid[r] + 1));
  if (!voids.empty()) {
    in.numberofholes = static_cast<int>(voids.size());
    in.holelist = new_array<REAL>(3 * voids.size());
    for (std::size_t h = 0; h < voids.size(); ++h)
      for (int d = 0; d < 3; ++d) in.holelist[3 * h + d] = bodies[voids[h]].center[d];
  }
  result.plc_seconds = seconds_since(plc_start);

  char number[64];
  std::snprintf(number, sizeof number, "%g", options.radius_edge_ratio);
  result.switches = std::string("pq") + number;
  if (options.max_volume > 0) {
    std::snprintf(number, sizeof number, "%.9g", options.max_volume);
    result.switches += std::string("a") + number;
  }
  result.switches += "AQ" + options.extra_switches;
  tetgenio out;
  std::vector<char> switches(result.switches.begin(), result.switches.end());
  switches.push_back('\0');
  const auto tetgen_start = std::chrono::steady_clock::now();
  try {
    tetrahedralize(switches.data(), &in, &out);
  } catch (int code) {
    throw std::runtime_error("TetGen (-" + result.switches + ") stopped: " + tetgen_error(code));
  }
  result.tetgen_seconds = seconds_since(tetgen_start);
  if (options.on_tetrahedralized) options.on_tetrahedralized();

  const auto copy_start = std::chrono::steady_clock::now();
  if (out.numberofcorners != 4 || out.numberoftetrahedronattributes < 1)
    throw std::runtime_error("TetGen returned no region attributes");
  mesh::Mesh3& m = result.mesh;
  const std::size_t nodes = static_cast<std::size_t>(out.numberofpoints);
  const std::size_t tets = static_cast<std::size_t>(out.numberoftetrahedra);
  m.coords.assign(out.pointlist, out.pointlist + 3 * nodes);
  m.node_global_id.resize(nodes);
  for (std::size_t n = 0; n < nodes; ++n) m.node_global_id[n] = static_cast<GlobalId>(n);
  m.cell_nodes.resize(4 * tets);
  m.cell_phase.resize(tets);
  m.cell_partition.assign(tets, 0);
  result.cell_region.resize(tets);
  const int attributes = out.numberoftetrahedronattributes;
  for (std::size_t t = 0; t < tets; ++t) {
    LocalId* c = &m.cell_nodes[4 * t];
    for (int k = 0; k < 4; ++k) c[k] = out.tetrahedronlist[4 * t + k] - out.firstnumber;
    if (mesh::signed_volume(m.point(c[0]), m.point(c[1]), m.point(c[2]), m.point(c[3])) < 0) std::swap(c[2], c[3]);
    const long region = std::lround(out.tetrahedronattributelist[attributes * t]);
    if (region < 0 || region > static_cast<long>(bodies.size()))
      throw std::runtime_error("TetGen returned an unknown region attribute " + std::to_string(region));
    result.cell_region[t] = static_cast<std::int32_t>(region - 1);
    m.cell_phase[t] = region == 0 ? scene.matrix_phase : scene.inclusions[static_cast<std::size_t>(region - 1)].phase;
  }
  result.copy_seconds = seconds_since(copy_start);
  return result;
}

}  // namespace cisamr::compare
