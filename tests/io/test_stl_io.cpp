#include "io/stl_io.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "core/error.hpp"
#include "temp_dir.hpp"

namespace cisamr::io {
namespace {

using testing::TempDir;

// A binary STL whose 80-byte header starts with "solid", as some exporters write.
std::string binary_stl(const std::vector<std::array<float, 9>>& triangles) {
  std::string bytes(80, ' ');
  std::memcpy(bytes.data(), "solid but binary", 16);
  const std::uint32_t count = static_cast<std::uint32_t>(triangles.size());
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 1};
    bytes.append(reinterpret_cast<const char*>(normal), 12);
    bytes.append(reinterpret_cast<const char*>(t.data()), 36);
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(StlIo, ReadsBinaryRecognisedBySize) {
  TempDir dir;
  const std::string path =
      dir.write("b.stl", binary_stl({{0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 0, 0, 1, 0, 0.5f, 0.25f, -1}}));
  const auto triangles = read_stl(path);
  ASSERT_EQ(triangles.size(), 2u);
  EXPECT_EQ(triangles[0][1], (Vec3{1, 0, 0}));
  EXPECT_EQ(triangles[1][2], (Vec3{0.5, 0.25, -1}));
}

TEST(StlIo, ReadsAsciiWithNamesAndExponents) {
  TempDir dir;
  const std::string path = dir.write("a.stl",
                                     "solid my part\n facet normal 0 0 1\n  outer loop\n"
                                     "   vertex 1e-3 0 0\n   vertex 1.5E+1 0 0\n   vertex 0 -2 +3\n"
                                     "  endloop\n endfacet\nendsolid my part\n");
  const auto triangles = read_stl(path);
  ASSERT_EQ(triangles.size(), 1u);
  EXPECT_EQ(triangles[0][0], (Vec3{1e-3, 0, 0}));
  EXPECT_EQ(triangles[0][1], (Vec3{15, 0, 0}));
  EXPECT_EQ(triangles[0][2], (Vec3{0, -2, 3}));
}

TEST(StlIo, BadFilesAreInputErrors) {
  TempDir dir;
  EXPECT_THROW(read_stl(dir.file("missing.stl")), InputError);
  EXPECT_THROW(read_stl(dir.write("empty.stl", "solid x\nendsolid x\n")), InputError);
  EXPECT_THROW(read_stl(dir.write("junk.stl", "hello")), InputError);
  EXPECT_THROW(read_stl(dir.write("cut.stl", "solid x\n facet normal 0 0 1\n outer loop\n")), InputError);
  std::string truncated = binary_stl({{0, 0, 0, 1, 0, 0, 0, 1, 0}});
  truncated.pop_back();
  EXPECT_THROW(read_stl(dir.write("short.stl", truncated)), InputError);
}

TEST(StlIo, ReadsEverySolidOfAnAsciiFile) {
  TempDir dir;
  const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 Z\nvertex 1 0 Z\nvertex 0 1 Z\nendloop\nendfacet\n";
  auto at = [&](const char* z) {
    std::string f = facet;
    for (std::size_t p; (p = f.find('Z')) != std::string::npos;) f.replace(p, 1, z);
    return f;
  };
  const auto triangles = read_stl(dir.write("two.stl", "solid a\n" + at("0") + "endsolid a\nsolid b\n" + at("2") +
                                                           at("3") + "endsolid b\n"));
  ASSERT_EQ(triangles.size(), 3u);  // the first solid alone was kept before
  EXPECT_EQ(triangles[2][0], (Vec3{0, 0, 3}));
  EXPECT_THROW(read_stl(dir.write("junk.stl", "solid a\n" + at("0") + "endsolid a\ngarbage\n")), InputError);
}

}  // namespace
}  // namespace cisamr::io
