// Medit/INRIA MESH reader (ASCII).

#include "core/error.hpp"
#include "io/mesh_read_internal.hpp"

namespace cisamr::io::detail {
namespace {

// Phase names from comment lines "# phase ID NAME" (what our writer puts after Dimension);
// other comments are ignored.
void read_phase_comments(std::string_view text, RawMesh& raw) {
  constexpr std::string_view kMarker = "# phase ";
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    const std::string_view line = trim(text.substr(pos, end - pos));
    pos = end + 1;
    if (line.substr(0, kMarker.size()) != kMarker) continue;
    const std::string_view rest = trim(line.substr(kMarker.size()));
    const std::size_t space = std::min(rest.find(' '), rest.size());
    int id = 0;
    const auto r = std::from_chars(rest.data(), rest.data() + space, id);
    const std::string_view name = trim(rest.substr(space));
    if (r.ec == std::errc() && r.ptr == rest.data() + space && !name.empty()) raw.phase_names[id] = std::string(name);
  }
}

}  // namespace

LoadedMesh read_medit(const std::string& path) {
  const MappedFile file(path);
  const std::string_view text = file.view();
  Scanner s(text, path, /*hash_comments=*/true);
  RawMesh raw;
  TaggedCells cells;
  int dimension = 0;
  bool seen_version = false;
  while (!s.at_end()) {
    const std::string_view keyword = s.token();
    const std::string word = upper(keyword);
    if (word == "END") break;
    if (word == "MESHVERSIONFORMATTED") {
      seen_version = true;
      const long long version = s.integer();
      if (version < 1 || version > 4) s.fail("unsupported MeshVersionFormatted " + std::to_string(version));
      continue;
    }
    if (!seen_version)
      s.fail_at(keyword, "not a Medit mesh (it must start with MeshVersionFormatted)");
    if (word == "DIMENSION") {
      dimension = static_cast<int>(s.integer());
      if (dimension != 2 && dimension != 3) s.fail("Dimension must be 2 or 3");
      continue;
    }
    // Sections we skip, with the number of values per entry (-1: the dimension).
    static const std::map<std::string, int> kSkipped = {
        {"EDGES", 3},          {"CORNERS", 1},           {"REQUIREDVERTICES", 1},
        {"RIDGES", 1},         {"REQUIREDEDGES", 1},     {"REQUIREDTRIANGLES", 1},
        {"NORMALATVERTICES", 2}, {"TANGENTATVERTICES", 2}, {"NORMALATTRIANGLEVERTICES", 3},
        {"NORMALS", -1},       {"TANGENTS", -1}};
    static const std::map<std::string, int> kRejected = {
        {"QUADRILATERALS", 5}, {"HEXAHEDRA", 9}, {"PRISMS", 7}, {"PYRAMIDS", 6}};
    const auto skipped = kSkipped.find(word);
    const auto rejected = kRejected.find(word);
    if (word != "VERTICES" && word != "TRIANGLES" && word != "TETRAHEDRA" && skipped == kSkipped.end() &&
        rejected == kRejected.end())
      s.fail_at(keyword, "unknown Medit keyword '" + std::string(keyword.substr(0, 40)) + "'");
    const int values_per_entry = word == "VERTICES"     ? dimension + 1
                                 : word == "TRIANGLES"  ? 4
                                 : word == "TETRAHEDRA" ? 5
                                 : rejected != kRejected.end() ? rejected->second
                                 : skipped->second < 0  ? dimension
                                                        : skipped->second;
    const long long count = static_cast<long long>(s.count(keyword.substr(0, 40), values_per_entry));
    if (word == "VERTICES") {
      if (dimension == 0) s.fail("Vertices before Dimension");
      raw.coords.reserve(3 * static_cast<std::size_t>(count));
      for (long long i = 0; i < count; ++i) {
        for (int d = 0; d < dimension; ++d) raw.coords.push_back(s.real());
        if (dimension == 2) raw.coords.push_back(0.0);
        s.integer();  // vertex reference
      }
    } else if (word == "TRIANGLES" || word == "TETRAHEDRA") {
      const int n = word == "TRIANGLES" ? 3 : 4;
      auto& list = n == 3 ? cells.triangles : cells.tetrahedra;
      for (long long i = 0; i < count; ++i) {
        std::array<long long, 4> nodes{};
        for (int k = 0; k < n; ++k) nodes[static_cast<std::size_t>(k)] = s.integer();
        list.push_back({i, static_cast<std::int32_t>(s.integer()), nodes});
      }
    } else if (skipped != kSkipped.end()) {
      for (long long i = 0; i < count * values_per_entry; ++i) s.token();
    } else if (count > 0) {
      s.fail_at(keyword, "unsupported element type '" + std::string(keyword) +
                             "': only triangles and tetrahedra are read");
    }
  }
  if (!seen_version) throw InputError(path, "", "not a Medit mesh (it must start with MeshVersionFormatted)");
  read_phase_comments(text, raw);
  // Medit nodes are numbered 1..n in file order.
  std::vector<long long> tags(raw.coords.size() / 3);
  for (std::size_t i = 0; i < tags.size(); ++i) tags[i] = static_cast<long long>(i + 1);
  const TagMap map = sort_nodes_by_tag(raw, tags, path);
  cells.finish(raw, map, path);
  return finish(std::move(raw), path);
}

}  // namespace cisamr::io::detail
