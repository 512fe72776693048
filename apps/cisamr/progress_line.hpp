#pragma once
// Renders the library's Progress on stderr (DESIGN.md §6):
//  - terminal: one live line per phase, "cisamr: samr 42% (about 3 s left)" (or the
//    phase's elapsed seconds while its amount of work is unknown), redrawn in place with \r
//    at most every 0.1 s and ended with a newline when the next phase begins or the run ends;
//  - log (not a terminal: a file, a pipe, mpiexec's forwarding): a plain line, with the
//    time since the start, at most every `interval` seconds (5 by default), and only once
//    that long has passed, so that a short run prints nothing.
// Between the library's calls (a long phase makes none) a ticker thread redraws the line
// (terminal) or prints the next line (log) on time: tick() every 0.1 s.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "core/progress.hpp"

namespace cisamr::app {

class ProgressLine final : public Progress {
 public:
  enum class Mode { terminal, log };
  using Clock = std::function<double()>;  // seconds, increasing
  static constexpr double kLogInterval = 5.0;

  ProgressLine(Mode mode, std::function<void(const std::string&)> write, double interval = kLogInterval,
               Clock clock = steady_seconds);
  ~ProgressLine() override;
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void phase(const std::string& name) override;
  void advance(std::int64_t done, std::int64_t total) override;
  // Ends the terminal's live line (a newline); nothing in log mode; stops the ticker.
  // Idempotent.
  void finish();
  // Shows the current phase again if it is due (what the ticker calls).
  void tick();
  // Starts the ticker thread (tests call tick() with their clock instead).
  void start_ticker();

  // Writes to stderr, flushed.
  static std::function<void(const std::string&)> to_stderr();

 private:
  static double steady_seconds();
  std::string describe(double now) const;
  void show(double now, bool forced);

  Mode mode_;
  std::function<void(const std::string&)> write_;
  double interval_;
  Clock clock_;
  double start_, phase_start_ = 0, last_shown_;
  std::string phase_;
  std::int64_t done_ = 0, total_ = 0;
  bool line_open_ = false;  // terminal: a live line without its newline yet
  std::mutex mutex_;        // the ticker and the library's calls
  std::condition_variable stop_signal_;
  bool stopping_ = false;
  std::thread ticker_;
};

}  // namespace cisamr::app
