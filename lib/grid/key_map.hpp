#pragma once
// Open-addressing hash maps from keys to local ids (the node registry, the parallel merge's
// identities). Much faster than std::unordered_map for the millions of lookups of one mesh.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace cisamr::grid {

// Open addressing with linear probing from a key to a non-negative id. `Hash` maps a key
// to 64 well-mixed bits; the table keeps its load at most one half.
template <class Key, class Hash>
class OpenKeyMap {
 public:
  static constexpr std::int32_t kNone = -1;

  explicit OpenKeyMap(std::size_t expected = 1024) { rehash(capacity_for(expected)); }

  std::size_t size() const { return size_; }

  std::int32_t find(const Key& key) const {
    std::size_t i = slot(key);
    while (true) {
      const std::int32_t v = values_[i];
      if (v == kNone) return kNone;
      if (keys_[i] == key) return v;
      i = (i + 1) & mask_;
    }
  }

  // Returns the id stored for key, inserting `value` if the key is new; `inserted` tells.
  std::int32_t insert(const Key& key, std::int32_t value, bool& inserted) {
    if ((size_ + 1) * 2 > values_.size()) rehash(values_.size() * 2);
    std::size_t i = slot(key);
    while (true) {
      const std::int32_t v = values_[i];
      if (v == kNone) {
        keys_[i] = key;
        values_[i] = value;
        ++size_;
        inserted = true;
        return value;
      }
      if (keys_[i] == key) {
        inserted = false;
        return v;
      }
      i = (i + 1) & mask_;
    }
  }

 private:
  std::vector<Key> keys_;
  std::vector<std::int32_t> values_;
  std::size_t mask_ = 0, size_ = 0;

  static std::size_t capacity_for(std::size_t n) {
    std::size_t c = 16;
    while (c < 2 * n) c <<= 1;
    return c;
  }
  std::size_t slot(const Key& key) const { return static_cast<std::size_t>(Hash{}(key)) & mask_; }
  void rehash(std::size_t capacity) {
    std::vector<Key> old_keys;
    std::vector<std::int32_t> old_values;
    old_keys.swap(keys_);
    old_values.swap(values_);
    keys_.assign(capacity, Key{});
    values_.assign(capacity, kNone);
    mask_ = capacity - 1;
    size_ = 0;
    for (std::size_t i = 0; i < old_values.size(); ++i)
      if (old_values[i] != kNone) {
        bool inserted;
        insert(old_keys[i], old_values[i], inserted);
      }
  }
};

// Open addressing (linear probing, load at most one half) from a key to an id, where the
// keys are the caller's: the table holds ids only and compares `keys[id]`. Half the bytes
// of OpenKeyMap where the caller keeps every key in an array anyway (the 3D node registry,
// one of the largest tables at the mesher's peak), for the same memory reads per probe.
template <class Key, class Hash>
class KeyIndex {
 public:
  static constexpr std::int32_t kNone = -1;

  explicit KeyIndex(std::size_t expected = 1024) { slots_.assign(capacity_for(expected), kNone); }

  std::size_t size() const { return size_; }

  std::int32_t find(const Key& key, std::span<const Key> keys) const {
    for (std::size_t i = slot(key);; i = (i + 1) & mask()) {
      const std::int32_t v = slots_[i];
      if (v == kNone || keys[static_cast<std::size_t>(v)] == key) return v;
    }
  }

  // The id of `key`, or `next` when it is new (`inserted` tells); the caller then appends
  // `key` to `keys` (position `next`) before the next call. `keys` holds every id's key.
  std::int32_t insert(const Key& key, std::int32_t next, std::span<const Key> keys, bool& inserted) {
    if ((size_ + 1) * 2 > slots_.size()) grow(keys);
    for (std::size_t i = slot(key);; i = (i + 1) & mask()) {
      const std::int32_t v = slots_[i];
      if (v == kNone) {
        slots_[i] = next;
        ++size_;
        inserted = true;
        return next;
      }
      if (keys[static_cast<std::size_t>(v)] == key) {
        inserted = false;
        return v;
      }
    }
  }

 private:
  std::vector<std::int32_t> slots_;
  std::size_t size_ = 0;

  static std::size_t capacity_for(std::size_t n) {
    std::size_t c = 16;
    while (c < 2 * n) c <<= 1;
    return c;
  }
  std::size_t mask() const { return slots_.size() - 1; }
  std::size_t slot(const Key& key) const { return static_cast<std::size_t>(Hash{}(key)) & mask(); }
  void grow(std::span<const Key> keys) {
    std::vector<std::int32_t> old(slots_.size() * 2, kNone);
    old.swap(slots_);
    for (const std::int32_t v : old) {
      if (v == kNone) continue;
      std::size_t i = slot(keys[static_cast<std::size_t>(v)]);
      while (slots_[i] != kNone) i = (i + 1) & mask();
      slots_[i] = v;
    }
  }
};

// The murmur3 finaliser, enough to spread lattice keys (whose low bits repeat).
struct LatticeKeyHash {
  std::uint64_t operator()(std::uint64_t key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return key;
  }
};

// The node registry: lattice key to local node id.
using KeyMap = OpenKeyMap<std::uint64_t, LatticeKeyHash>;
// The same, over the caller's array of keys.
using LatticeKeyIndex = KeyIndex<std::uint64_t, LatticeKeyHash>;

}  // namespace cisamr::grid
