#include "progress_line.hpp"

#include <cmath>

namespace cisamr::app {

ProgressLine::ProgressLine(Mode mode, std::function<void(const std::string&)> write, double interval, Clock clock)
    : mode_(mode), write_(std::move(write)), interval_(interval), clock_(std::move(clock)) {
  start_ = clock_();
  last_shown_ = start_;
}

double ProgressLine::steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::function<void(const std::string&)> ProgressLine::to_stderr() {
  return [](const std::string& text) {
    std::fputs(text.c_str(), stderr);
    std::fflush(stderr);
  };
}

std::string ProgressLine::describe(double now) const {
  char text[160];
  const double elapsed = now - phase_start_;
  if (total_ > 0 && done_ > 0 && done_ < total_) {
    // Time left: the phase's pace so far applied to the rest of its work.
    const double left = elapsed * static_cast<double>(total_ - done_) / static_cast<double>(done_);
    std::snprintf(text, sizeof text, "%s %3.0f%% (about %.0f s left)", phase_.c_str(),
                  100.0 * static_cast<double>(done_) / static_cast<double>(total_), std::ceil(left));
  } else if (total_ > 0) {
    std::snprintf(text, sizeof text, "%s %3.0f%% (%.1f s)", phase_.c_str(),
                  100.0 * static_cast<double>(done_) / static_cast<double>(total_), elapsed);
  } else {
    std::snprintf(text, sizeof text, "%s (%.1f s)", phase_.c_str(), elapsed);
  }
  return text;
}

void ProgressLine::show(double now, bool forced) {
  if (mode_ == Mode::terminal) {
    if (!forced && now - last_shown_ < 0.1) return;
    // \r and the line padded over what a longer previous text left.
    std::string line = "\rcisamr: " + describe(now);
    line.resize(std::max<std::size_t>(line.size(), 60), ' ');
    write_(line);
    line_open_ = true;
  } else {
    if (now - last_shown_ < interval_) return;
    char elapsed[32];
    std::snprintf(elapsed, sizeof elapsed, "[%.0f s] ", now - start_);
    write_("cisamr: " + std::string(elapsed) + describe(now) + "\n");
  }
  last_shown_ = now;
}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::start_ticker() {
  ticker_ = std::thread([this] {
    std::unique_lock lock(mutex_);
    while (!stop_signal_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stopping_; })) {
      lock.unlock();
      tick();
      lock.lock();
    }
  });
}

void ProgressLine::tick() {
  const std::lock_guard lock(mutex_);
  if (!phase_.empty() && !stopping_) show(clock_(), false);
}

void ProgressLine::phase(const std::string& name) {
  const std::lock_guard lock(mutex_);
  const double now = clock_();
  if (mode_ == Mode::terminal && line_open_) {
    show(now, true);  // the finished phase's final figures
    write_("\n");
    line_open_ = false;
  }
  phase_ = name;
  phase_start_ = now;
  done_ = total_ = 0;
  show(now, mode_ == Mode::terminal);
}

void ProgressLine::advance(std::int64_t done, std::int64_t total) {
  const std::lock_guard lock(mutex_);
  done_ = done;
  total_ = total;
  show(clock_(), false);
}

void ProgressLine::finish() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  stop_signal_.notify_all();
  if (ticker_.joinable()) ticker_.join();
  const std::lock_guard lock(mutex_);
  if (mode_ == Mode::terminal && line_open_) {
    show(clock_(), true);
    write_("\n");
    line_open_ = false;
  }
}

}  // namespace cisamr::app
