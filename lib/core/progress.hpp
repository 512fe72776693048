#pragma once
// How a long run tells its progress without printing (the library never prints): the app
// passes a Progress, the library calls it where a phase begins (every ScopedPhase of a
// PhaseTimes that holds it, and the phases without a timer: reading, levels) and, where a
// phase knows its amount of work, as units of it are done (a few calls per phase: cheap).
#include <cstdint>
#include <string>

namespace cisamr {

class Progress {
 public:
  virtual ~Progress() = default;
  // A phase begins (its work unknown until advance says).
  virtual void phase(const std::string& name) = 0;
  // `done` of the current phase's `total` units are finished.
  virtual void advance(std::int64_t done, std::int64_t total) = 0;
};

inline void begin_phase(Progress* progress, const std::string& name) {
  if (progress != nullptr) progress->phase(name);
}

inline void advance(Progress* progress, std::int64_t done, std::int64_t total) {
  if (progress != nullptr) progress->advance(done, total);
}

// For a stage's inner loop: tells `progress` at every 4096th unit only, so that the call
// costs nothing measurable; the stage ends with advance(progress, total, total).
inline void advance_sometimes(Progress* progress, std::int64_t done, std::int64_t total) {
  if (progress != nullptr && (done & 4095) == 0) progress->advance(done, total);
}

}  // namespace cisamr
