#pragma once
/// IdMap: 32-bit ids to 32-bit values, open addressing with linear probing. For the sparse
/// per-vertex maps of a region (a rough spot's Dijkstra): one probe sequence in one array
/// instead of a node per entry, 8 B a slot, at most half the slots full. Internal.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace seamvox::detail {

class IdMap {
 public:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t(0);

  IdMap() { slots_.assign(std::size_t(1) << shift_, Slot{kEmpty, 0}); }

  std::size_t size() const { return size_; }

  /// The value of `key`, or kEmpty when it has none. key != kEmpty.
  std::uint32_t find(std::uint32_t key) const {
    for (std::size_t i = home(key);; i = (i + 1) & mask()) {
      if (slots_[i].key == key) return slots_[i].value;
      if (slots_[i].key == kEmpty) return kEmpty;
    }
  }

  /// {value of key, inserted}: `value` stored when key had none. key != kEmpty.
  std::pair<std::uint32_t, bool> emplace(std::uint32_t key, std::uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    for (std::size_t i = home(key);; i = (i + 1) & mask()) {
      if (slots_[i].key == key) return {slots_[i].value, false};
      if (slots_[i].key == kEmpty) {
        slots_[i] = Slot{key, value};
        ++size_;
        return {value, true};
      }
    }
  }

  /// Sets key's value (inserting it). key != kEmpty.
  void set(std::uint32_t key, std::uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    for (std::size_t i = home(key);; i = (i + 1) & mask()) {
      if (slots_[i].key == kEmpty) ++size_;
      if (slots_[i].key == key || slots_[i].key == kEmpty) {
        slots_[i] = Slot{key, value};
        return;
      }
    }
  }

  /// Calls f(key, value) for every entry, in slot order.
  template <class F>
  void forEach(F&& f) const {
    for (const Slot& s : slots_) {
      if (s.key != kEmpty) f(s.key, s.value);
    }
  }

 private:
  struct Slot {
    std::uint32_t key, value;
  };
  std::size_t mask() const { return slots_.size() - 1; }
  // Fibonacci hashing: the top bits of key * 2^32/phi, so that runs of ids spread.
  std::size_t home(std::uint32_t key) const {
    return static_cast<std::size_t>((std::uint64_t(key) * 0x9E3779B97F4A7C15ull) >> (64 - shift_));
  }
  void grow() {
    std::vector<Slot> old(std::size_t(1) << (shift_ + 1), Slot{kEmpty, 0});
    old.swap(slots_);
    ++shift_;
    for (const Slot& s : old) {
      if (s.key == kEmpty) continue;
      std::size_t i = home(s.key);
      while (slots_[i].key != kEmpty) i = (i + 1) & mask();
      slots_[i] = s;
    }
  }

  unsigned shift_ = 4;
  std::size_t size_ = 0;
  std::vector<Slot> slots_;
};

/// n zeroed 32-bit slots from calloc: pages are faulted in only where written (a per-vertex
/// map of a few regions of a large mesh). Throws std::bad_alloc when there is no memory.
using ZeroedIds = std::unique_ptr<std::uint32_t[], void (*)(void*)>;
inline ZeroedIds zeroedIds(std::size_t n) {
  ZeroedIds ids(static_cast<std::uint32_t*>(std::calloc(n, sizeof(std::uint32_t))), std::free);
  if (n > 0 && !ids) throw std::bad_alloc();
  return ids;
}

}  // namespace seamvox::detail
