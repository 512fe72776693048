#pragma once
// The communicator facade. MPI lives only in lib/parallel (MpiComm); everything else,
// tests and one-process runs use SerialComm. All calls are collective.
#include <cstdint>
#include <vector>

namespace cisamr {

class Comm {
 public:
  virtual ~Comm() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual void barrier() const = 0;
  virtual std::int64_t allreduce_max(std::int64_t v) const = 0;
  virtual std::int64_t allreduce_sum(std::int64_t v) const = 0;
  virtual double allreduce_max(double v) const = 0;
  virtual double allreduce_min(double v) const = 0;
  virtual double allreduce_sum(double v) const = 0;
  virtual std::int64_t exclusive_scan_sum(std::int64_t v) const = 0;
  // Sends sendbufs[r] to rank r, returns what every rank sent to this one (indexed by source).
  virtual std::vector<std::vector<std::uint8_t>> alltoallv(
      const std::vector<std::vector<std::uint8_t>>& sendbufs) const = 0;
};

class SerialComm final : public Comm {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void barrier() const override {}
  std::int64_t allreduce_max(std::int64_t v) const override { return v; }
  std::int64_t allreduce_sum(std::int64_t v) const override { return v; }
  double allreduce_max(double v) const override { return v; }
  double allreduce_min(double v) const override { return v; }
  double allreduce_sum(double v) const override { return v; }
  std::int64_t exclusive_scan_sum(std::int64_t) const override { return 0; }
  std::vector<std::vector<std::uint8_t>> alltoallv(
      const std::vector<std::vector<std::uint8_t>>& sendbufs) const override {
    return sendbufs;
  }
};

}  // namespace cisamr
