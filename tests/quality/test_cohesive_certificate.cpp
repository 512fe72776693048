// The cohesive part of a certificate (certify_cohesive, Certificate::cohesive): the
// checker's counts, the set rules, and how JSON, HTML and the summary show them.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "mesh/cohesive.hpp"
#include "mesh_builders.hpp"
#include "quality/certificate.hpp"

namespace cisamr::quality {
namespace {
using namespace testing;

// A 4×4 square whose middle 2×2 squares are phase 3, split with cohesive cells.
mesh::Mesh2 split_square() {
  mesh::Mesh2 m = structured_triangles(4, 4, 0.25);
  for (std::size_t c = 0; c < m.cell_count(); ++c) {
    const std::size_t square = c / 2, i = square % 4, j = square / 4;
    m.cell_phase[c] = i >= 1 && i <= 2 && j >= 1 && j <= 2 ? 3 : 1;
  }
  mesh::insert_cohesive(m, 0);
  return m;
}

// The sets a .msh or .inp of this mesh carries: one set, named for phases 1 and 3.
CohesiveSetsInFile one_set(const mesh::Mesh2& m) {
  CohesiveSetsInFile sets;
  sets.sets.push_back({"COH_matrix_core", {{1, 3}}});
  sets.set_of_cell.assign(m.cohesive.count(), 0);
  return sets;
}

const CohesiveSection::Count& count_of(const CohesiveSection& s, const std::string& key) {
  for (const auto& k : s.checks)
    if (k.key == key) return k;
  throw std::out_of_range(key);
}

Certificate certificate_of(const mesh::Mesh2& m, const CohesiveSetsInFile* sets) {
  CertifyOptions o;
  o.expected_measure = 1.0;
  Certificate c = certify<2>(weld_view<2>(m).mesh, Box2{{0, 0}, {1, 1}}, o);
  c.cohesive = certify_cohesive<2>(m, sets);
  return c;
}

TEST(CohesiveCertificate, SplitMeshPassesWithItsSets) {
  const mesh::Mesh2 m = split_square();
  ASSERT_EQ(m.cohesive.count(), 8u);
  const CohesiveSetsInFile sets = one_set(m);
  const Certificate c = certificate_of(m, &sets);
  ASSERT_TRUE(c.cohesive);
  EXPECT_TRUE(c.cohesive->ok());
  EXPECT_TRUE(c.passed());
  EXPECT_EQ(c.cohesive->cells, 8u);
  EXPECT_EQ(c.cohesive->interface_facets, 8u);
  EXPECT_EQ(c.cohesive->nodes, m.node_count());
  ASSERT_EQ(c.cohesive->sets.size(), 1u);
  EXPECT_EQ(c.cohesive->sets[0].name, "COH_matrix_core");
  EXPECT_EQ(c.cohesive->sets[0].cells, 8u);

  const auto j = nlohmann::json::parse(certificate_json(c));
  EXPECT_EQ(j["passed"], true);
  EXPECT_EQ(j["cohesive"]["ok"], true);
  EXPECT_EQ(j["cohesive"]["elements"], 8);
  EXPECT_EQ(j["cohesive"]["uncovered"], 0);
  EXPECT_EQ(j["cohesive"]["cells_in_wrong_set"], 0);
  EXPECT_EQ(j["cohesive"]["sets"][0]["name"], "COH_matrix_core");
  EXPECT_EQ(j["cohesive"]["sets"][0]["phases"], nlohmann::json({1, 3}));
  EXPECT_NE(certificate_summary(c).find("cohesive: 8 elements in 1 set; every interface facet covered once\n"),
            std::string::npos)
      << certificate_summary(c);
  const std::string html = certificate_html(c);
  EXPECT_NE(html.find("<h2>Cohesive elements</h2>"), std::string::npos);
  EXPECT_NE(html.find("COH_matrix_core"), std::string::npos);
}

TEST(CohesiveCertificate, WithoutSetNamesTheClaimedPairsAreListed) {
  const mesh::Mesh2 m = split_square();
  const Certificate c = certificate_of(m, nullptr);
  EXPECT_TRUE(c.passed());
  EXPECT_FALSE(c.cohesive->sets_named);
  ASSERT_EQ(c.cohesive->sets.size(), 1u);
  EXPECT_EQ(c.cohesive->sets[0].lower, 1);
  EXPECT_EQ(c.cohesive->sets[0].upper, 3);
  const auto j = nlohmann::json::parse(certificate_json(c));
  EXPECT_TRUE(j["cohesive"]["sets"][0]["name"].is_null());
  EXPECT_FALSE(j["cohesive"].contains("cells_without_set"));  // not checked without names
  EXPECT_NE(certificate_summary(c).find("cohesive: 8 elements in 1 phase pair; every interface facet covered once"),
            std::string::npos);
}

TEST(CohesiveCertificate, BrokenCellsFailTheCertificate) {
  mesh::Mesh2 removed = split_square();  // the last cohesive cell dropped
  removed.cohesive.nodes.resize(removed.cohesive.nodes.size() - 4);
  removed.cohesive.phase.resize(removed.cohesive.phase.size() - 2);
  removed.cohesive.partition.pop_back();
  Certificate c = certificate_of(removed, nullptr);
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(count_of(*c.cohesive, "uncovered").value, 1u);
  EXPECT_NE(certificate_summary(c).find("cohesive: 7 elements in 1 phase pair; FAILED (1 interface facets without a "
                                        "cohesive cell)"),
            std::string::npos)
      << certificate_summary(c);
  EXPECT_EQ(nlohmann::json::parse(certificate_json(c))["passed"], false);

  mesh::Mesh2 swapped = split_square();  // bottom and top exchanged in cell 0
  std::swap_ranges(swapped.cohesive.nodes.begin(), swapped.cohesive.nodes.begin() + 2, swapped.cohesive.nodes.begin() + 2);
  c = certificate_of(swapped, nullptr);
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(count_of(*c.cohesive, "wrong_sides").value, 1u);
  ASSERT_FALSE(c.cohesive->examples.empty());
  EXPECT_NE(c.cohesive->examples[0].find("cohesive cell 0 at ("), std::string::npos) << c.cohesive->examples[0];
}

TEST(CohesiveCertificate, SetRulesAreCounted) {
  const mesh::Mesh2 m = split_square();
  CohesiveSetsInFile sets = one_set(m);
  sets.sets.push_back({"COH_matrix_other", {{1, 2}}});  // names another pair, holds cell 1
  sets.sets.push_back({"COH_EMPTY", {}});
  sets.set_of_cell[0] = CohesiveSetsInFile::kNoSet;
  sets.set_of_cell[1] = 1;
  sets.set_of_cell[2] = CohesiveSetsInFile::kSeveralSets;
  const Certificate c = certificate_of(m, &sets);
  EXPECT_FALSE(c.passed());
  EXPECT_EQ(count_of(*c.cohesive, "cells_without_set").value, 1u);
  EXPECT_EQ(count_of(*c.cohesive, "cells_in_wrong_set").value, 1u);
  EXPECT_EQ(count_of(*c.cohesive, "cells_in_several_sets").value, 1u);
  EXPECT_EQ(count_of(*c.cohesive, "empty_sets").value, 1u);
  EXPECT_EQ(count_of(*c.cohesive, "uncovered").value, 0u);  // the cells themselves are right
  ASSERT_EQ(c.cohesive->sets.size(), 3u);
  EXPECT_EQ(c.cohesive->sets[0].cells, 5u);
  EXPECT_EQ(c.cohesive->sets[1].cells, 1u);
  EXPECT_EQ(c.cohesive->sets[2].cells, 0u);
}

}  // namespace
}  // namespace cisamr::quality
