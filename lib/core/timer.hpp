#pragma once
// Wall-clock phase timers, collected by name in call order.
#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "core/progress.hpp"

namespace cisamr {

class PhaseTimes {
 public:
  void add(const std::string& name, double seconds) {
    for (auto& [n, s] : phases_)
      if (n == name) { s += seconds; return; }
    phases_.emplace_back(name, seconds);
  }
  const std::vector<std::pair<std::string, double>>& phases() const { return phases_; }

  Progress* progress = nullptr;  // told when each ScopedPhase on these times begins

 private:
  std::vector<std::pair<std::string, double>> phases_;
};

// Adds the time between construction and destruction to `times` under `name`.
class ScopedPhase {
 public:
  ScopedPhase(PhaseTimes* times, std::string name)
      : times_(times), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {
    if (times_ != nullptr) begin_phase(times_->progress, name_);
  }
  ~ScopedPhase() {
    if (times_)
      times_->add(name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
  }
  ScopedPhase(const ScopedPhase&) = delete;
  ScopedPhase& operator=(const ScopedPhase&) = delete;

 private:
  PhaseTimes* times_;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace cisamr
