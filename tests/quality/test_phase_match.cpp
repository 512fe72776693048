#include "quality/phase_match.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"

namespace cisamr::quality {
namespace {

const std::vector<geometry::Phase> kScene = {{5, "matrix", false}, {9, "fiber", false}, {12, "pore", true}};

std::string error_of(const std::vector<MeshPhase>& mesh, const std::vector<PhaseMapEntry>& map = {}) {
  try {
    match_phases(mesh, kScene, map, "m.msh");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(PhaseMatch, ByNameWhenTheFileNamesThePhases) {
  // Tags 1 and 2 in the file, 5 and 9 in the scene: only the names can match them.
  EXPECT_EQ(match_phases({{1, "matrix"}, {2, "fiber"}}, kScene, {}, "m.msh"), (std::map<int, int>{{1, 5}, {2, 9}}));
  // Names win over numbers: a file whose tag 9 is named matrix.
  EXPECT_EQ(match_phases({{9, "matrix"}, {5, "fiber"}}, kScene, {}, "m.msh"), (std::map<int, int>{{9, 5}, {5, 9}}));
}

TEST(PhaseMatch, ByNumberWithoutNamesOrWithTheDefaultName) {
  EXPECT_EQ(match_phases({{5, ""}, {9, ""}}, kScene, {}, "m.msh"), (std::map<int, int>{{5, 5}, {9, 9}}));
  EXPECT_EQ(match_phases({{5, "phase5"}}, kScene, {}, "m.msh"), (std::map<int, int>{{5, 5}}));
}

TEST(PhaseMatch, MapByIdOrNameOnEitherSide) {
  EXPECT_EQ(match_phases({{1, ""}, {2, ""}}, kScene, parse_phase_map("1=5,2=fiber"), "m.msh"),
            (std::map<int, int>{{1, 5}, {2, 9}}));
  // By the mesh's name; the map wins over a matching name; two mesh phases onto one.
  EXPECT_EQ(match_phases({{1, "Volume1"}, {2, "matrix"}, {3, ""}}, kScene, parse_phase_map("Volume1=9,2=9,3=matrix"), "m.msh"),
            (std::map<int, int>{{1, 9}, {2, 9}, {3, 5}}));
}

TEST(PhaseMatch, MismatchesAreOneLineErrors) {
  EXPECT_EQ(error_of({{1, ""}}), "m.msh: phase: mesh phase 1 is not a phase of the scene (5 matrix, 9 fiber, 12 pore); "
                                 "use --phase-map 1=SCENE_ID");
  EXPECT_EQ(error_of({{5, "glass"}}), "m.msh: phase: mesh phase 5 'glass' has no scene phase of that name (scene phases: "
                                      "5 matrix, 9 fiber, 12 pore); use --phase-map 5=SCENE_ID");
  EXPECT_NE(error_of({{1, ""}}, {{"1", "7"}}).find("--phase-map: '7' is not a phase of the scene"), std::string::npos);
  EXPECT_NE(error_of({{1, ""}}, {{"1", "5"}, {"4", "9"}}).find("--phase-map: '4' is not a phase of the mesh m.msh"),
            std::string::npos);
  for (const std::string bad : {"", "1", "=5", "1=", "1=2=3", "1=5,", ",1=5"}) {
    try {
      parse_phase_map(bad);
      ADD_FAILURE() << "'" << bad << "' parsed";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--phase-map"), std::string::npos) << e.what();
    }
  }
}

TEST(PhaseMatch, RelabelRewritesEveryCell) {
  mesh::Mesh2 m;
  m.cell_phase = {1, 2, 1};
  relabel_phases<2>(m, {{1, 5}, {2, 9}});
  EXPECT_EQ(m.cell_phase, (std::vector<std::int32_t>{5, 9, 5}));
}

}  // namespace
}  // namespace cisamr::quality
