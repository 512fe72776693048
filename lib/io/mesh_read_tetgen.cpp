// TetGen (and Triangle) .node/.ele reader: the two files of one stem, whichever is named.
// .node: "points dimension attributes markers", then "index x y [z] [attributes] [marker]".
// .ele:  "cells nodes_per_cell attributes", then "index n1 .. nk [attributes]".
// The first element attribute (TetGen's region attribute, -A) is the phase; indices may
// start at 0 or 1 (the .ele refers to the .node's indices, whatever they are).
#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io::detail {

LoadedMesh read_tetgen(const std::string& named_path) {
  std::filesystem::path stem(named_path);
  stem.replace_extension();
  const std::string node_path = stem.string() + ".node", ele_path = stem.string() + ".ele";
  RawMesh raw;
  std::vector<long long> node_tags;
  int dimension = 0;
  {
    const MappedFile file(node_path);
    Scanner s(file.view(), node_path, /*hash_comments=*/true);
    if (s.at_end()) throw InputError(node_path, "", "empty: not a .node file");
    const std::size_t points = s.count("points", 1);
    dimension = static_cast<int>(s.integer());
    if (dimension != 2 && dimension != 3) s.fail("dimension must be 2 or 3");
    const long long attributes = s.integer();
    const long long markers = s.integer();
    if (attributes < 0 || markers < 0 || markers > 1) s.fail("bad attribute or marker count");
    const long long per_point = 1 + dimension + attributes + markers;
    // Counts checked against the rest of the file before reserving.
    if (static_cast<unsigned long long>(attributes) > file.view().size() ||
        points > (file.view().size() - s.position()) / (2 * static_cast<std::size_t>(per_point)))
      s.fail(std::to_string(points) + " points are more than the file holds");
    node_tags.reserve(points);
    raw.coords.reserve(3 * points);
    for (std::size_t i = 0; i < points; ++i) {
      node_tags.push_back(s.integer());
      for (int d = 0; d < dimension; ++d) raw.coords.push_back(s.real());
      if (dimension == 2) raw.coords.push_back(0.0);
      for (long long k = 0; k < attributes + markers; ++k) s.real();
    }
  }
  TaggedCells cells;
  {
    const MappedFile file(ele_path);
    Scanner s(file.view(), ele_path, /*hash_comments=*/true);
    if (s.at_end()) throw InputError(ele_path, "", "empty: not a .ele file");
    const long long count = s.integer();
    const long long corners = s.integer();
    const long long attributes = s.integer();
    if (count < 0) s.fail("negative element count");
    if (dimension == 3 && corners != 4 && corners != 10)
      s.fail("nodes per tetrahedron must be 4 or 10, not " + std::to_string(corners));
    if (dimension == 2 && corners != 3 && corners != 6)
      s.fail("nodes per triangle must be 3 or 6, not " + std::to_string(corners));
    if (attributes < 0 || static_cast<unsigned long long>(attributes) > file.view().size())
      s.fail("bad attribute count");
    const long long per_cell = 1 + corners + attributes;
    if (static_cast<unsigned long long>(count) > (file.view().size() - s.position()) / (2 * static_cast<std::size_t>(per_cell)))
      s.fail(std::to_string(count) + " elements are more than the file holds");
    auto& list = dimension == 3 ? cells.tetrahedra : cells.triangles;
    list.reserve(static_cast<std::size_t>(count));
    const int kept_corners = dimension == 3 ? 4 : 3;
    for (long long i = 0; i < count; ++i) {
      const long long tag = s.integer();
      std::array<long long, 4> nodes{};
      for (long long k = 0; k < corners; ++k) {
        const long long node = s.integer();
        if (k < kept_corners) nodes[static_cast<std::size_t>(k)] = node;  // corners first, then mid-edge nodes
      }
      std::int32_t phase = 1;
      for (long long k = 0; k < attributes; ++k) {
        const double value = s.real();
        if (k > 0) continue;
        if (!(std::abs(value) <= 2147483647.0) || value != std::floor(value))
          s.fail("region attribute " + std::to_string(value) + " of element " + std::to_string(tag) +
                 " is not an integer phase id");
        phase = static_cast<std::int32_t>(value);
      }
      list.push_back({tag, phase, nodes});
    }
  }
  const TagMap map = sort_nodes_by_tag(raw, node_tags, node_path);
  cells.finish(raw, map, ele_path);
  return finish(std::move(raw), ele_path);
}

}  // namespace cisamr::io::detail
