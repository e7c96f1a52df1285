#pragma once
/// Records of a finished scratch file read by index through a small cache of pages (pread, no
/// mmap: resident memory is the cache). Lookups in a spatially coherent order (faces and vertices
/// in Morton order, their neighbours nearby) hit cached pages; a miss reads one page. A reader
/// belongs to one thread at a time: ReaderPool hands them to the blocks of a parallel loop.
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "stream/scratch_folder.h"

namespace seamvox {

/// Page sizes: passes that walk files in a coherent order read large pages; lookups scattered over
/// the mesh (the repair's window around flips far apart) small ones, so that the cache holds the
/// records they need rather than their neighbours.
constexpr std::size_t kScratchPageBytes = std::size_t(1) << 14;
constexpr std::size_t kWindowPageBytes = std::size_t(1) << 10;

/// Two-way set-associative cache of fixed-size records of one file.
class PageCache {
 public:
  /// cacheBytes: what the pages may hold (rounded up to a power of two of pages, at least two);
  /// a page holds as many records as fit pageBytes, a power of two (one at least).
  PageCache(const ScratchFile& file, std::size_t recordBytes, std::size_t cacheBytes,
            std::size_t pageBytes = kScratchPageBytes);
  /// Writable: a changed page is written back in place when it leaves the cache and on flush(),
  /// through `updater` (its writes counted in its folder; a full disk is the folder's IoError).
  PageCache(ScratchUpdater& updater, const ScratchFile& file, std::size_t recordBytes, std::size_t cacheBytes);
  ~PageCache();
  PageCache(const PageCache&) = delete;
  PageCache& operator=(const PageCache&) = delete;
  /// Record i (IoError past the end); valid until the next call. A hit is resolved here, inline
  /// (the field's sweeps and the cut look up billions of records at 100M faces).
  const char* record(std::uint64_t i) {
    const std::uint64_t page = i >> pageShift_;
    const std::size_t set = static_cast<std::size_t>(page) & setMask_;
    const std::size_t slot = 2 * set;
    if (i < numRecords_) {
      const std::size_t offset = static_cast<std::size_t>(i & (pageRecords_ - 1)) * recordBytes_;
      if (tags_[slot] == page) {
        older_[set] = 1;
        lastSlot_ = slot;
        return data_.data() + slot * pageBytes_ + offset;
      }
      if (tags_[slot + 1] == page) {
        older_[set] = 0;
        lastSlot_ = slot + 1;
        return data_.data() + (slot + 1) * pageBytes_ + offset;
      }
    }
    return slotFor(i);
  }
  /// Record i of a writable cache, its page marked changed; valid until the next call.
  char* recordForWrite(std::uint64_t i);
  /// Writes the changed pages back (a writable cache's changes are lost without it).
  void flush();
  /// Drops the cached pages holding records [first, first + count) of a read-only cache: the file
  /// changed there, and the next lookups read it again.
  void forget(std::uint64_t first, std::uint64_t count);
  std::uint64_t numRecords() const { return numRecords_; }
  std::uint64_t bytesRead() const { return bytesRead_; }
  std::size_t memoryBytes() const { return data_.size() + tags_.size() * sizeof(tags_[0]); }

 private:
  char* slotFor(std::uint64_t i);
  char* load(std::uint64_t page, std::size_t slot);
  void writeBack(std::size_t slot);
  ScratchUpdater* updater_ = nullptr;
  std::string path_;
  int fd_ = -1;
  std::size_t recordBytes_ = 0, pageRecords_ = 0, pageBytes_ = 0, setMask_ = 0, lastSlot_ = 0;
  unsigned pageShift_ = 0;
  std::uint64_t numRecords_ = 0, bytesRead_ = 0;
  std::vector<std::uint64_t> tags_;
  std::vector<std::uint8_t> dirty_;
  std::vector<std::uint8_t> older_;  // per set of two slots: the way replaced next
  std::vector<char> data_;
};

/// Records of type T (trivially copyable) by index.
template <class T>
class PagedReader {
 public:
  PagedReader(const ScratchFile& file, std::size_t cacheBytes, std::size_t pageBytes = kScratchPageBytes)
      : cache_(file, sizeof(T), cacheBytes, pageBytes) {}
  T operator[](std::uint64_t i) {
    T value;
    std::memcpy(static_cast<void*>(&value), cache_.record(i), sizeof(T));  // T is a plain record
    return value;
  }
  std::uint64_t size() const { return cache_.numRecords(); }
  std::uint64_t bytesRead() const { return cache_.bytesRead(); }
  std::size_t memoryBytes() const { return cache_.memoryBytes(); }
  /// See PageCache::forget.
  void forget(std::uint64_t first, std::uint64_t count) { cache_.forget(first, count); }

 private:
  PageCache cache_;
};

/// Records of type T read and changed by index through a writable page cache; flush() before the
/// file is read by anything else.
template <class T>
class PagedArray {
 public:
  PagedArray(ScratchFolder& folder, const ScratchFile& file, std::string stage, std::size_t cacheBytes)
      : updater_(folder, file, std::move(stage)), cache_(updater_, file, sizeof(T), cacheBytes) {}
  T operator[](std::uint64_t i) {
    T value;
    std::memcpy(static_cast<void*>(&value), cache_.record(i), sizeof(T));
    return value;
  }
  void set(std::uint64_t i, const T& value) { std::memcpy(cache_.recordForWrite(i), &value, sizeof(T)); }
  void flush() { cache_.flush(); }
  std::uint64_t size() const { return cache_.numRecords(); }
  std::uint64_t bytesRead() const { return cache_.bytesRead(); }

 private:
  ScratchUpdater updater_;
  PageCache cache_;
};

/// n records of T, all zero bytes at first: in memory while they fit memoryBytes, else in a
/// sparse scratch file (removed with the array) changed through a page cache of memoryBytes. For
/// per-face or per-vertex state that must not grow with the mesh beyond its share of a budget.
template <class T>
class ScratchArray {
 public:
  ScratchArray(ScratchFolder& folder, std::uint64_t n, std::uint64_t memoryBytes, const std::string& stage)
      : folder_(folder), size_(n) {
    if (n * sizeof(T) <= memoryBytes) {
      memory_.resize(n);  // value-initialized: zero bytes for plain records
      return;
    }
    file_ = folder.zeroFile(n * sizeof(T));
    paged_ = std::make_unique<PagedArray<T>>(folder, file_, stage, memoryBytes);
  }
  ~ScratchArray() {
    paged_.reset();
    if (!file_.path.empty()) folder_.remove(file_);
  }
  ScratchArray(const ScratchArray&) = delete;
  ScratchArray& operator=(const ScratchArray&) = delete;
  T get(std::uint64_t i) { return paged_ ? (*paged_)[i] : memory_[i]; }
  void set(std::uint64_t i, const T& value) {
    if (paged_) {
      paged_->set(i, value);
    } else {
      memory_[i] = value;
    }
  }
  std::uint64_t size() const { return size_; }
  bool onDisk() const { return paged_ != nullptr; }

 private:
  ScratchFolder& folder_;
  std::uint64_t size_ = 0;
  std::vector<T> memory_;
  ScratchFile file_;
  std::unique_ptr<PagedArray<T>> paged_;
};

/// Sets of readers for the blocks of a parallel loop: a block takes one (made on first need) and
/// gives it back when done, so at most one set per thread exists.
template <class Set>
class ReaderPool {
 public:
  explicit ReaderPool(std::function<std::unique_ptr<Set>()> make) : make_(std::move(make)) {}
  struct Lease {
    ReaderPool* pool;
    std::unique_ptr<Set> set;
    Lease(ReaderPool* p, std::unique_ptr<Set> s) : pool(p), set(std::move(s)) {}
    Lease(Lease&&) = default;
    ~Lease() {
      if (set) pool->giveBack(std::move(set));
    }
    Set& operator*() { return *set; }
    Set* operator->() { return set.get(); }
  };
  Lease take() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        std::unique_ptr<Set> set = std::move(free_.back());
        free_.pop_back();
        return Lease(this, std::move(set));
      }
    }
    return Lease(this, make_());
  }
  /// Calls f on every set made so far (none may be taken).
  template <class F>
  void forEach(F&& f) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& set : free_) f(*set);
  }

 private:
  void giveBack(std::unique_ptr<Set> set) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(set));
  }
  std::function<std::unique_ptr<Set>()> make_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Set>> free_;
};

}  // namespace seamvox
