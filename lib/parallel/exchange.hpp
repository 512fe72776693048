#pragma once
// Byte packing for core::Comm::alltoallv and the small collectives built on it
// (broadcast, all-gather). Plain trivially copyable values only; no MPI here.
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "core/comm.hpp"

namespace cisamr::parallel {

using Bytes = std::vector<std::uint8_t>;

class Packer {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(v.size());
    const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  Bytes& bytes() { return bytes_; }
  Bytes take() { return std::move(bytes_); }

 private:
  Bytes bytes_;
};

class Unpacker {
 public:
  explicit Unpacker(const Bytes& bytes) : bytes_(bytes) {}
  bool done() const { return at_ == bytes_.size(); }
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  template <class T>
  std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    need(n * sizeof(T));
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return v;
  }
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), n);
    at_ += n;
    return s;
  }

 private:
  void need(std::size_t n) const {
    if (at_ + n > bytes_.size()) throw std::logic_error("parallel: truncated message");
  }
  const Bytes& bytes_;
  std::size_t at_ = 0;
};

// Collective: every rank receives rank `root`'s bytes.
inline Bytes broadcast_bytes(const Comm& comm, const Bytes& bytes, int root = 0) {
  std::vector<Bytes> send(static_cast<std::size_t>(comm.size()));
  if (comm.rank() == root)
    for (auto& b : send) b = bytes;
  return std::move(comm.alltoallv(send)[static_cast<std::size_t>(root)]);
}

// Collective: every rank receives every rank's bytes, indexed by rank.
inline std::vector<Bytes> allgather_bytes(const Comm& comm, const Bytes& bytes) {
  return comm.alltoallv(std::vector<Bytes>(static_cast<std::size_t>(comm.size()), bytes));
}

// Collective: every rank's elements, concatenated in rank order, on every rank.
template <class T>
std::vector<T> allgather_vector(const Comm& comm, const std::vector<T>& mine) {
  Packer p;
  p.put_vector(mine);
  std::vector<T> all;
  for (const Bytes& bytes : allgather_bytes(comm, p.bytes())) {
    const std::vector<T> v = Unpacker(bytes).get_vector<T>();
    all.insert(all.end(), v.begin(), v.end());
  }
  return all;
}

// Collective: rank `root` receives every rank's bytes (others get empty buffers).
inline std::vector<Bytes> gather_bytes(const Comm& comm, Bytes bytes, int root = 0) {
  std::vector<Bytes> send(static_cast<std::size_t>(comm.size()));
  send[static_cast<std::size_t>(root)] = std::move(bytes);
  return comm.alltoallv(send);
}

// Collective: the sum modulo 2^64 (order-free checksums).
inline std::uint64_t allreduce_sum_u64(const Comm& comm, std::uint64_t v) {
  Packer p;
  p.put(v);
  std::uint64_t sum = 0;
  for (const Bytes& b : allgather_bytes(comm, p.bytes())) sum += Unpacker(b).get<std::uint64_t>();
  return sum;
}

}  // namespace cisamr::parallel
