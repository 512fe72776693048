// The certificate: assembly and its JSON / HTML / text renderings.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <numeric>
#include <string>

#include "mesh_builders.hpp"
#include "quality/certificate.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

Certificate good_certificate() {
  const mesh::Mesh2 m = structured_triangles(4, 4, 0.25);
  CertifyOptions o;
  o.expected_measure = 1.0;
  o.worst_count = 5;
  Certificate c = certify<2>(m, Box2{{0, 0}, {1, 1}}, o);
  c.mesh_source = "square <&> .vtu";
  return c;
}

TEST(Certificate, GoodMeshPasses) {
  const Certificate c = good_certificate();
  EXPECT_TRUE(c.passed());
  EXPECT_EQ(c.aspect.bound, 3.0);  // default in 2D
  EXPECT_EQ(c.cell_count, 32u);
  ASSERT_EQ(c.cells_per_phase.size(), 1u);
  EXPECT_EQ(c.cells_per_phase[0], (std::pair<int, std::size_t>{1, 32}));
  EXPECT_FALSE(c.fidelity.has_value());
}

TEST(Certificate, JsonHasTheNumbers) {
  const Certificate c = good_certificate();
  const auto j = nlohmann::json::parse(certificate_json(c));
  EXPECT_EQ(j["format"], "cisamr-certificate/1");
  EXPECT_EQ(j["passed"], true);
  EXPECT_EQ(j["cells"], 32);
  EXPECT_EQ(j["aspect_ratio"]["bound"], 3.0);
  EXPECT_NEAR(j["aspect_ratio"]["max"].get<double>(), (1 + std::sqrt(2.0)) / std::sqrt(3.0), 1e-12);
  const auto counts = j["aspect_ratio"]["histogram"]["counts"].get<std::vector<std::size_t>>();
  const auto edges = j["aspect_ratio"]["histogram"]["bin_edges"].get<std::vector<double>>();
  EXPECT_EQ(counts.size(), edges.size());
  EXPECT_EQ(std::accumulate(counts.begin(), counts.end(), std::size_t(0)), 32u);
  EXPECT_EQ(j["aspect_ratio"]["worst"].size(), 5u);
  EXPECT_EQ(j["conformity"]["ok"], true);
  EXPECT_EQ(j["conformity"]["boundary_facets"], 16);
  EXPECT_TRUE(j["fidelity"].is_null());
  EXPECT_TRUE(j["scene"].is_null());
}

TEST(Certificate, HtmlIsSelfContained) {
  const Certificate c = good_certificate();
  const std::string html = certificate_html(c);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("PASSED"), std::string::npos);
  EXPECT_EQ(occurrences(html, "<svg"), 1u);
  EXPECT_EQ(occurrences(html, "stroke=\"red\""), 1u);  // the bound
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://") , html.find("http://www.w3.org/2000/svg"));  // no external resources
  EXPECT_NE(html.find("square &lt;&amp;&gt; .vtu"), std::string::npos);  // escaped
  EXPECT_EQ(html.find("square <&>"), std::string::npos);
  EXPECT_NE(html.find("<h3>Worst elements</h3>"), std::string::npos);
  EXPECT_NE(html.find("</html>"), std::string::npos);
}

TEST(Certificate, BrokenMeshFails) {
  mesh::Mesh2 m = structured_triangles(3, 3);
  std::swap(m.cell_nodes[3 * 8 + 1], m.cell_nodes[3 * 8 + 2]);
  const LocalId a = add_node(m, 0, 4), b = add_node(m, 1, 4), d = add_node(m, 2, 4);
  add_cell<2>(m, {a, b, d});  // degenerate: infinite aspect ratio
  CertifyOptions o;
  o.expected_measure = 9.0;
  const Certificate c = certify<2>(m, Box2{{0, 0}, {3, 3}}, o);
  EXPECT_FALSE(c.passed());
  EXPECT_FALSE(c.quality_ok());
  EXPECT_FALSE(c.conformity.ok);

  const auto j = nlohmann::json::parse(certificate_json(c));
  EXPECT_EQ(j["passed"], false);
  EXPECT_TRUE(j["aspect_ratio"]["max"].is_null());  // +inf has no JSON spelling
  EXPECT_EQ(j["aspect_ratio"]["above_bound"], 1);
  EXPECT_EQ(j["conformity"]["inverted_cells"], 1);
  EXPECT_EQ(j["conformity"]["degenerate_cells"], 1);
  EXPECT_FALSE(j["conformity"]["examples"].empty());

  const std::string text = certificate_summary(c);
  EXPECT_NE(text.find("certificate: FAILED"), std::string::npos);
  EXPECT_NE(text.find("1 inverted cells"), std::string::npos);
  EXPECT_NE(text.find("max inf"), std::string::npos);
  const std::string html = certificate_html(c);
  EXPECT_NE(html.find("FAILED"), std::string::npos);
  EXPECT_NE(html.find("inverted cell 8"), std::string::npos);
}

TEST(Certificate, ThreeDimensionalDefaults) {
  const Certificate c = certify<3>(structured_tets(1, 1, 2), Box3{{0, 0, 0}, {1, 1, 2}}, CertifyOptions{});
  EXPECT_EQ(c.aspect.bound, 5.0);
  EXPECT_TRUE(c.passed());
  EXPECT_FALSE(c.notes.empty());  // the measure was not checked
  const auto j = nlohmann::json::parse(certificate_json(c));
  EXPECT_TRUE(j["aspect_ratio"].contains("min_dihedral_deg"));
  EXPECT_EQ(j["domain"]["max"].size(), 3u);
  EXPECT_TRUE(j["conformity"]["expected_measure"].is_null());
}

}  // namespace
}  // namespace cisamr::quality
