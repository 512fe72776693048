// Every stage of the 2D and 3D pipeline reports its progress: each phase's advance calls
// have a fixed total, never go back, and end at done == total; reporting changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "geometry/oracle.hpp"
#include "pipeline/pipeline.hpp"

namespace cisamr {
namespace {

class RecordingProgress final : public Progress {
 public:
  struct Call {
    std::int64_t done, total;
  };
  std::vector<std::string> phases;
  std::map<std::string, std::vector<Call>> calls;  // per phase name (each begins once per run)

  void phase(const std::string& name) override {
    phases.push_back(name);
    EXPECT_TRUE(calls.emplace(name, std::vector<Call>{}).second) << name << " began twice";
  }
  void advance(std::int64_t done, std::int64_t total) override {
    ASSERT_FALSE(phases.empty()) << "advance before any phase";
    calls[phases.back()].push_back({done, total});
  }
};

// The stage phases' calls: at least one, one total, done non-decreasing, ending at total.
void expect_stages_advance(const RecordingProgress& progress, const std::vector<std::string>& stages) {
  for (const std::string& stage : stages) {
    SCOPED_TRACE(stage);
    const auto it = progress.calls.find(stage);
    ASSERT_NE(it, progress.calls.end()) << "phase never began";
    const auto& calls = it->second;
    ASSERT_FALSE(calls.empty()) << "no advance";
    for (std::size_t i = 0; i < calls.size(); ++i) {
      EXPECT_EQ(calls[i].total, calls.back().total) << "call " << i;
      EXPECT_GE(calls[i].done, 0) << "call " << i;
      EXPECT_LE(calls[i].done, calls[i].total) << "call " << i;
      if (i > 0) EXPECT_GE(calls[i].done, calls[i - 1].done) << "call " << i;
    }
    EXPECT_GT(calls.back().total, 0);
    EXPECT_EQ(calls.back().done, calls.back().total);
  }
}

geometry::SceneDesc circles() {
  geometry::SceneDesc s;
  s.source = "test.json";
  s.dimension = 2;
  s.domain_min = {0, 0};
  s.domain_max = {1, 1};
  s.h = 0.01;  // 10,000 roots: the stages report along the way, not only at the end
  s.levels = 2;
  s.phases = {{1, "matrix", false}, {2, "fibre", false}};
  s.matrix_phase = 1;
  s.inclusions.push_back({geometry::Circle{{0.3, 0.4}, 0.2}, 2, 2});
  s.inclusions.push_back({geometry::Circle{{0.75, 0.7}, 0.15}, 2, 3});
  return s;
}

geometry::SceneDesc spheres() {
  geometry::SceneDesc s;
  s.source = "test.json";
  s.dimension = 3;
  s.domain_min = {0, 0, 0};
  s.domain_max = {1, 1, 1};
  s.h = 0.1;
  s.levels = 2;
  s.phases = {{1, "matrix", false}, {2, "sphere", false}};
  s.matrix_phase = 1;
  s.inclusions.push_back({geometry::Sphere{{0.3, 0.3, 0.3}, 0.2}, 2, 2});
  s.inclusions.push_back({geometry::Sphere{{0.72, 0.7, 0.68}, 0.15}, 2, 2});
  return s;
}

template <int Dim>
void expect_same_mesh(const pipeline::Result<Dim>& a, const pipeline::Result<Dim>& b) {
  EXPECT_EQ(a.mesh.coords, b.mesh.coords);
  EXPECT_EQ(a.mesh.cell_phase, b.mesh.cell_phase);
  EXPECT_EQ(a.mesh.cell_count(), b.mesh.cell_count());
}

TEST(StageProgress, EveryStageOf2DAdvancesToItsTotal) {
  const geometry::Oracle2 oracle(circles());
  RecordingProgress progress;
  pipeline::Options options;
  options.progress = &progress;
  const pipeline::Result<2> reported = pipeline::mesh(oracle, options);
  expect_stages_advance(progress, {"samr", "radapt", "subdivide"});
  // The phases pipeline::run begins (levels is mesh's): as many as kRunPhases says.
  ASSERT_FALSE(progress.phases.empty());
  EXPECT_EQ(progress.phases.front(), "levels");
  EXPECT_EQ(static_cast<int>(progress.phases.size()) - 1, pipeline::kRunPhases<2>);
  // Intermediate calls, not only the last one.
  EXPECT_GT(progress.calls.at("samr").size(), 1U);
  EXPECT_GT(progress.calls.at("radapt").size(), 1U);
  expect_same_mesh(reported, pipeline::mesh(oracle, pipeline::Options{}));
}

TEST(StageProgress, EveryStageOf3DAdvancesToItsTotal) {
  const geometry::Oracle3 oracle(spheres());
  RecordingProgress progress;
  pipeline::Options options;
  options.progress = &progress;
  const pipeline::Result<3> reported = pipeline::mesh(oracle, options);
  expect_stages_advance(progress, {"samr", "radapt", "faceswap", "subdivide"});
  ASSERT_FALSE(progress.phases.empty());
  EXPECT_EQ(progress.phases.front(), "levels");
  EXPECT_EQ(static_cast<int>(progress.phases.size()) - 1, pipeline::kRunPhases<3>);
  EXPECT_GT(progress.calls.at("samr").size(), 1U);  // one call per sweep at least
  expect_same_mesh(reported, pipeline::mesh(oracle, pipeline::Options{}));
}

}  // namespace
}  // namespace cisamr
