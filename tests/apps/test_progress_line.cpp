// The progress renderer's two modes, driven by a fake clock.
#include <gtest/gtest.h>

#include <string>

#include "progress_line.hpp"

namespace {

using cisamr::app::ProgressLine;

struct Fixture {
  double now = 100;
  std::string written;
  ProgressLine make(ProgressLine::Mode mode, double interval = 5) {
    return ProgressLine(mode, [this](const std::string& s) { written += s; }, interval, [this] { return now; });
  }
};

TEST(ProgressLine, TerminalRedrawsOneLinePerPhaseInPlace) {
  Fixture f;
  {
    ProgressLine line(ProgressLine::Mode::terminal, [&](const std::string& s) { f.written += s; }, 5,
                      [&] { return f.now; });
    line.phase("samr");
    EXPECT_EQ(f.written.find('\n'), std::string::npos);
    EXPECT_EQ(f.written.rfind("\rcisamr: samr", 0), 0u) << f.written;
    f.now += 2;
    line.advance(1, 4);  // a quarter in 2 s: 6 s left
    EXPECT_NE(f.written.find("\rcisamr: samr  25% (about 6 s left)"), std::string::npos) << f.written;
    f.written.clear();
    f.now += 0.05;
    line.advance(2, 4);  // within 0.1 s of the last redraw: nothing
    EXPECT_EQ(f.written, "");
    f.now += 1;
    line.phase("radapt");  // the finished phase's line ends with a newline, the next starts
    EXPECT_NE(f.written.find("samr"), std::string::npos);
    const std::size_t newline = f.written.find('\n');
    ASSERT_NE(newline, std::string::npos);
    EXPECT_EQ(f.written.substr(newline + 1).rfind("\rcisamr: radapt", 0), 0u) << f.written;
    f.written.clear();
  }  // the end of the run ends the live line
  ASSERT_FALSE(f.written.empty());
  EXPECT_EQ(f.written.back(), '\n');
}

TEST(ProgressLine, LogPrintsPlainLinesAtMostEveryInterval) {
  Fixture f;
  ProgressLine line = f.make(ProgressLine::Mode::log, 5);
  line.phase("read");
  f.now += 1;
  line.phase("samr");
  line.advance(1, 10);
  EXPECT_EQ(f.written, "") << "a run shorter than the interval prints nothing";
  f.now += 4.5;
  line.advance(5, 10);  // 5.5 s since the start
  EXPECT_EQ(f.written, "cisamr: [6 s] samr  50% (about 5 s left)\n");
  f.written.clear();
  f.now += 3;
  line.advance(8, 10);
  EXPECT_EQ(f.written, "");
  f.now += 4;
  line.tick();  // a long phase without calls from the library: the line comes on time
  EXPECT_EQ(f.written, "cisamr: [12 s] samr  80% (about 3 s left)\n");
  f.written.clear();
  f.now += 5;
  line.phase("write");
  EXPECT_EQ(f.written, "cisamr: [18 s] write (0.0 s)\n");
  EXPECT_EQ(f.written.find('\r'), std::string::npos);
  f.written.clear();
  line.finish();
  EXPECT_EQ(f.written, "");
}

}  // namespace
