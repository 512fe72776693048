// The command line itself: what `cisamr`, `cisamr help` and an unknown command say, --version
// after a subcommand, range checks of numeric options, defaults in --help, and requests
// refused up front (scales the mesher does not handle, meshes beyond the machine's memory).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "cli_fixture.hpp"

namespace {

using namespace cisamr;

namespace fs = std::filesystem;

using test::CommandResult;
CommandResult run(const std::string& args) { return test::run_cisamr(args); }

std::size_t lines(const std::string& text) {
  std::size_t n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

class CliOptions : public test::CliFolder {
 protected:
  std::string out() const { return (dir / "out.vtu").string(); }
  bool out_exists() const { return fs::exists(dir / "out.vtu"); }
};

std::string num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// A square (2D, a circle) or cube (3D, a sphere) of side `side` at the origin.
std::string scene(int dim, const std::string& side, const std::string& h, int levels) {
  const double s = std::stod(side);
  const std::string c = num(s / 2), r = num(0.31 * s);
  const std::string corner = dim == 2 ? "[" + side + ", " + side + "]" : "[" + side + ", " + side + ", " + side + "]";
  const std::string origin = dim == 2 ? "[0, 0]" : "[0, 0, 0]";
  const std::string inclusion = dim == 2 ? R"({"shape": "circle", "center": [)" + c + ", " + c + "], \"radius\": " + r + "}"
                                         : R"({"shape": "sphere", "center": [)" + c + ", " + c + ", " + c +
                                               "], \"radius\": " + r + "}";
  return R"({"format": "cisamr-scene/1", "dimension": )" + std::to_string(dim) + R"(, "domain": {"min": )" + origin +
         R"(, "max": )" + corner + R"(}, "mesh": {"h": )" + h + R"(, "levels": )" + std::to_string(levels) +
         R"(}, "inclusions": [)" + inclusion + "]}";
}

TEST_F(CliOptions, SaysWhatCommandsExist) {
  for (const char* command : {"mesh", "certify", "pack", "partition", "compare"}) {
    SCOPED_TRACE(command);
    const CommandResult alone = run("");
    EXPECT_EQ(alone.exit_code, 2);
    EXPECT_NE(alone.output.find(std::string("  ") + command + " "), std::string::npos) << alone.output;
    const CommandResult help = run("help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.output.find(std::string("  ") + command + " "), std::string::npos) << help.output;
    const CommandResult unknown = run("mseh x.json");
    EXPECT_EQ(unknown.exit_code, 2);
    EXPECT_NE(unknown.output.find("unknown command 'mseh'"), std::string::npos) << unknown.output;
    EXPECT_NE(unknown.output.find(std::string("  ") + command + " "), std::string::npos) << unknown.output;
    const CommandResult version = run(std::string(command) + " --version");
    EXPECT_EQ(version.exit_code, 0) << version.output;
    EXPECT_EQ(version.output, "cisamr 0.1.0\n");
  }
  const CommandResult help_mesh = run("help mesh");
  EXPECT_EQ(help_mesh.exit_code, 0);
  EXPECT_NE(help_mesh.output.find("--partitions"), std::string::npos);
}

TEST_F(CliOptions, HelpShowsDefaults) {
  const CommandResult mesh = run("mesh --help");
  EXPECT_NE(mesh.output.find("--alpha"), std::string::npos);
  EXPECT_NE(mesh.output.find("=0.5"), std::string::npos) << mesh.output;  // --alpha
  EXPECT_NE(mesh.output.find("=3\n"), std::string::npos) << mesh.output;    // --extra-levels
  EXPECT_NE(mesh.output.find("default 3 in 2D, 5 in 3D"), std::string::npos) << mesh.output;  // --bound
  const CommandResult partition = run("partition --help");
  EXPECT_NE(partition.output.find("=8"), std::string::npos) << partition.output;     // --oversubscription
  EXPECT_NE(partition.output.find("=best"), std::string::npos) << partition.output;  // --method
}

TEST_F(CliOptions, NumericOptionsAreRangeCheckedNamingTheOption) {
  const std::string s = write("ok.json", scene(2, "10", "1", 1));
  struct Case {
    std::string args, option;
  };
  const Case cases[] = {
      {"mesh " + s + " -o " + out() + " --bound -3", "--bound"},
      {"mesh " + s + " -o " + out() + " --bound nan", "--bound"},
      {"mesh " + s + " -o " + out() + " --bound 0", "--bound"},
      {"mesh " + s + " -o " + out() + " --alpha abc", "--alpha"},
      {"mesh " + s + " -o " + out() + " --extra-levels 1.5", "--extra-levels"},
      {"mesh " + s + " -o " + out() + " --partitions 0", "--partitions"},
      {"mesh " + s + " -o " + out() + " --partitions 100000", "--partitions"},
      {"mesh " + s + " -o " + out() + " --max-elements -1", "--max-elements"},
      {"mesh " + s + " -o ''", "--output"},
      {"mesh " + s + " -o " + out() + " --ghost-cubes -5", "--ghost-cubes"},  // hidden options too
      {"mesh " + s + " -o " + out() + " --ghost-windows -2", "--ghost-windows"},
      {"mesh " + s + " -o " + out() + " --ghost-closure-rounds abc", "--ghost-closure-rounds"},
      {"certify " + s + " --fidelity-tolerance nan", "--fidelity-tolerance"},
      {"certify " + s + " --bound 0.5", "--bound"},
      {"pack " + s + " -o x.json --seed abc", "--seed"},
      {"partition " + s + " -n 0 -o p.json", "--parts"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const CommandResult r = run(c.args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(lines(r.output), 1u) << r.output;
    EXPECT_LT(r.output.size(), 200u) << r.output;
    EXPECT_NE(r.output.find(c.option), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("<input>"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find(": n:"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("error: :"), std::string::npos) << r.output;
    EXPECT_FALSE(out_exists());
  }
}

TEST_F(CliOptions, ScalesBeyondTheSupportedRangeAreRefusedNamingTheField) {
  struct Case {
    int dim;
    const char *side, *h, *field;
  };
  // Before: 1e-200 looped for ever in r-adaptivity, 1e100 too, 1e-100 (3D) reported an aspect
  // ratio of inf or 0.
  const Case refused[] = {{2, "1e-200", "1e-201", "domain.max[0]"},
                          {3, "1e-200", "2e-201", "domain.max[0]"},
                          {2, "1e100", "1e99", "domain.max[0]"},
                          {3, "1e-100", "2e-101", "domain.max[0]"},
                          {3, "1e-25", "1e-31", "mesh.h"}};
  for (const Case& c : refused) {
    SCOPED_TRACE(c.side);
    const std::string s = write("tiny.json", scene(c.dim, c.side, c.h, 1));
    const CommandResult r = run("mesh " + s + " -o " + out());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(s + ": " + c.field + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("supported"), std::string::npos) << r.output;
    EXPECT_FALSE(out_exists());
  }
  // Within the range the mesh is the same at any scale: within the bound.
  for (const char* side : {"1e-25", "1e25"}) {
    SCOPED_TRACE(side);
    const std::string h = num(std::stod(side) / 6);
    const std::string s = write("scaled.json", scene(3, side, h, 1));
    const CommandResult r = run("mesh " + s + " -o " + out());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("inf"), std::string::npos) << r.output;
  }
}

TEST_F(CliOptions, RequestsBeyondMemoryAreRefusedUpFrontWithAnEstimate) {
  struct Case {
    std::string json, field;
  };
  // Before: bad_alloc (exit 1) after up to a minute.
  const Case cases[] = {{scene(2, "10", "1e-4", 0), "mesh.h"},
                        {scene(2, "10", "1", 20), "mesh.levels"},
                        {scene(3, "10", "1", 12), "mesh.levels"}};
  for (const Case& c : cases) {
    const std::string s = write("big.json", c.json);
    SCOPED_TRACE(c.json);
    const CommandResult r = run("mesh " + s + " -o " + out());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(s + ": " + c.field + ": the mesh would have about "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--max-elements"), std::string::npos) << r.output;
    EXPECT_LT(r.seconds, 10.0);
    EXPECT_FALSE(out_exists());
  }
  // The limit is an option: a small mesh above it is refused, below it meshed.
  const std::string s = write("ok.json", scene(2, "10", "1", 1));
  const CommandResult low = run("mesh " + s + " -o " + out() + " --max-elements 50");
  EXPECT_EQ(low.exit_code, 2) << low.output;
  EXPECT_NE(low.output.find("the limit of 50"), std::string::npos) << low.output;
  const CommandResult high = run("mesh " + s + " -o " + out() + " --max-elements 1e6");
  EXPECT_EQ(high.exit_code, 0) << high.output;
}

TEST_F(CliOptions, SvgOfA3DSceneIsASliceOrAnErrorNamingThePlane) {
  const std::string s = write("sphere.json", scene(3, "1", "0.1", 1));
  const std::string svg = (dir / "slice.svg").string();
  const CommandResult ok = run("mesh " + s + " -o " + out() + " --svg " + svg + " --svg-axis y --svg-at 0.4");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  std::ifstream in(svg);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<path fill=\"#e6550d\""), std::string::npos);  // the sphere's phase
  fs::remove(svg);
  fs::remove(out());
  const CommandResult outside = run("mesh " + s + " -o " + out() + " --svg " + svg + " --svg-at 2");
  EXPECT_EQ(outside.exit_code, 2) << outside.output;
  EXPECT_NE(outside.output.find("--svg-at"), std::string::npos) << outside.output;
  EXPECT_FALSE(out_exists());
  EXPECT_FALSE(fs::exists(svg));
}

TEST_F(CliOptions, MeshingErrorsNameTheSceneFile) {
  // A lattice beyond the 64-bit key: an error of the mesher, caused by the scene's h and levels.
  const std::string s = write("key.json", R"({"format": "cisamr-scene/1", "dimension": 3,
    "domain": {"min": [0, 0, 0], "max": [4000, 1, 1]}, "mesh": {"h": 1, "levels": 8}, "inclusions": []})");
  for (const char* extra : {"", " --partitions 2"}) {
    const CommandResult r = run("mesh " + s + " -o " + out() + extra);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(r.output.rfind("cisamr: error: " + s + ": mesh: ", 0), 0u) << r.output;
  }
}

}  // namespace
