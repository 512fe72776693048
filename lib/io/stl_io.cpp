#include "io/stl_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "core/error.hpp"
#include "core/input_file.hpp"

namespace cisamr::io {
namespace {

bool is_blank(char c) { return static_cast<unsigned char>(c) <= ' '; }

class AsciiStl {
 public:
  AsciiStl(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  // Every solid of the file, one after the other (some tools write one per part).
  std::vector<StlTriangle> parse() {
    std::vector<StlTriangle> triangles;
    do parse_solid(triangles);
    while (!at_end());
    return triangles;
  }

 private:
  void parse_solid(std::vector<StlTriangle>& triangles) {
    expect("solid");
    skip_line();  // the solid's name, possibly empty
    while (true) {
      const std::string_view word = token();
      if (word == "endsolid") break;
      if (word != "facet") fail("expected 'facet' or 'endsolid', got '" + std::string(word.substr(0, 40)) + "'");
      expect("normal");
      for (int k = 0; k < 3; ++k) number();  // recomputed from the vertices when needed
      expect("outer");
      expect("loop");
      StlTriangle t;
      for (auto& vertex : t) {
        expect("vertex");
        for (double& x : vertex) x = number();
      }
      expect("endloop");
      expect("endfacet");
      triangles.push_back(t);
    }
    skip_line();  // the name after endsolid
  }
  bool at_end() {
    while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
    return pos_ >= text_.size();
  }
  std::string_view token() {
    while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
    if (pos_ >= text_.size()) fail("unexpected end of file (no 'endsolid')");
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_blank(text_[pos_])) ++pos_;
    return text_.substr(start, pos_ - start);
  }
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }
  void expect(std::string_view word) {
    const std::string_view t = token();
    if (t != word) fail("expected '" + std::string(word) + "', got '" + std::string(t.substr(0, 40)) + "'");
  }
  double number() {
    const std::string_view t = token();
    double value = 0;
    const char* begin = t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(begin, t.data() + t.size(), value);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(value))
      fail("expected a number, got '" + std::string(t.substr(0, 40)) + "'");
    return value;
  }
  [[noreturn]] void fail(const std::string& problem) const {
    const std::size_t line =
        1 + static_cast<std::size_t>(std::count(text_.begin(), text_.begin() + std::min(pos_, text_.size()), '\n'));
    throw InputError(path_, "line " + std::to_string(line), problem);
  }

  std::string_view text_;
  const std::string& path_;
  std::size_t pos_ = 0;
};

}  // namespace

std::vector<StlTriangle> read_stl(const std::string& path) {
  const std::string bytes = read_input_file(path);

  std::vector<StlTriangle> triangles;
  std::uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() >= 84 && bytes.size() == 84 + 50 * static_cast<std::uint64_t>(count)) {
    triangles.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      const char* record = bytes.data() + 84 + 50 * static_cast<std::size_t>(i);
      float v[9];
      std::memcpy(v, record + 12, sizeof v);  // skip the normal; 2 attribute bytes follow
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) {
          const double x = v[3 * k + d];
          if (!std::isfinite(x))
            throw InputError(path, "triangle " + std::to_string(i), "coordinate is not finite");
          triangles[i][k][d] = x;
        }
    }
  } else if (bytes.compare(0, 5, "solid") == 0) {
    triangles = AsciiStl(bytes, path).parse();
  } else {
    throw InputError(path, "", "not an STL file (neither ASCII 'solid ...' nor binary 84 + 50·n bytes)");
  }
  if (triangles.empty()) throw InputError(path, "", "the STL file has no triangles");
  return triangles;
}

}  // namespace cisamr::io
