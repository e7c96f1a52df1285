#pragma once
/// External sort of fixed-size records: records are buffered up to a memory limit, each full
/// buffer is sorted and written to the scratch folder as a run, and the runs are merged k ways
/// (in several rounds when there are more runs than the limit holds read buffers) into a stream
/// read with next(). Input that fits the limit never touches the disk. Memory: about the limit.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <tbb/parallel_sort.h>

#include "stream/scratch_folder.h"

namespace seamvox {

struct ExternalSortOptions {
  std::uint64_t memoryBytes = std::uint64_t(64) << 20;  ///< records buffered plus merge buffers
  std::string stage = "sort";                           ///< names the scratch traffic
  /// The same options naming another stage.
  ExternalSortOptions named(const char* name) const {
    ExternalSortOptions o = *this;
    o.stage = name;
    return o;
  }
};

namespace detail {

/// The record-type-free part: runs on disk and their merge. less compares two records' bytes.
class ExternalMerge {
 public:
  using Less = bool (*)(const void*, const void*);
  ExternalMerge(ScratchFolder& scratch, std::size_t recordBytes, Less less, const ExternalSortOptions& options);
  ~ExternalMerge();
  /// Writes count sorted records as one run.
  void writeRun(const void* records, std::size_t count);
  /// Sorted runs written (before any merge round).
  std::size_t runs() const { return written_; }
  /// Merges rounds of runs until one pass can merge the rest, then opens that pass.
  void startMerge();
  /// The next record of the final merge into out; false at the end.
  bool next(void* out) {
    if (at_ == end_ && !nextBlock()) return false;
    std::memcpy(out, at_, recordBytes_);
    at_ += recordBytes_;
    return true;
  }

 private:
  struct Source;
  struct Prefetch;
  /// The next block of the final merge (merged ahead by another thread); false at the end.
  bool nextBlock();
  void stopPrefetch() noexcept;
  ScratchFile mergeRuns(std::size_t first, std::size_t count);
  /// Closes the merged runs' readers, then removes their files.
  void removeSources();
  bool pop(void* out);
  /// Pops records into out until `bytes` (whole records) are filled or the merge ends; the bytes
  /// filled.
  std::size_t fill(char* out, std::size_t bytes);

  ScratchFolder& scratch_;
  std::size_t recordBytes_;
  Less less_;
  ExternalSortOptions options_;
  std::size_t readBuffer_ = 0, fanIn_ = 2;
  std::vector<ScratchFile> runs_;
  std::size_t written_ = 0;
  std::vector<std::unique_ptr<Source>> sources_;
  std::vector<std::size_t> heap_;  // indices into sources_, smallest record first
  std::vector<const char*> records_;  // per source, its current record
  std::unique_ptr<Prefetch> prefetch_;
  std::vector<char> block_;  // the block next() serves from
  const char* at_ = nullptr;
  const char* end_ = nullptr;
};

}  // namespace detail

/// Sorts Records (trivially copyable) by Less (default-constructible, strict weak order).
/// Usage: add() every record, finish(), then next() until it returns false.
template <class Record, class Less = std::less<Record>>
class ExternalSorter {
  static_assert(std::is_trivially_copyable_v<Record>, "records are written as bytes");

 public:
  ExternalSorter(ScratchFolder& scratch, const ExternalSortOptions& options = {})
      : merge_(scratch, sizeof(Record), &lessBytes, options),
        capacity_(std::max<std::size_t>(1, options.memoryBytes / 2 / sizeof(Record))) {}

  void add(const Record& record) {
    if (buffer_.size() == capacity_) spill();
    if (buffer_.capacity() == 0) buffer_.reserve(capacity_);  // no doubling past the limit
    buffer_.push_back(record);
    ++count_;
  }
  /// Ends the input; next() then returns the records in order.
  void finish() {
    tbb::parallel_sort(buffer_.begin(), buffer_.end(), Less{});
    onDisk_ = merge_.runs() > 0;
    if (onDisk_) {
      if (!buffer_.empty()) merge_.writeRun(buffer_.data(), buffer_.size());
      std::vector<Record>().swap(buffer_);
      merge_.startMerge();
    }
  }
  bool next(Record& out) {
    if (onDisk_) return merge_.next(&out);
    if (served_ == buffer_.size()) return false;
    out = buffer_[served_++];
    return true;
  }
  std::uint64_t size() const { return count_; }
  /// Sorted runs written to disk (0 when the input fitted the memory limit).
  std::size_t runs() const { return merge_.runs(); }

 private:
  static bool lessBytes(const void* a, const void* b) {
    Record x, y;
    std::memcpy(&x, a, sizeof(Record));
    std::memcpy(&y, b, sizeof(Record));
    return Less{}(x, y);
  }
  void spill() {
    tbb::parallel_sort(buffer_.begin(), buffer_.end(), Less{});
    merge_.writeRun(buffer_.data(), buffer_.size());
    buffer_.clear();
  }

  detail::ExternalMerge merge_;
  std::size_t capacity_;
  std::vector<Record> buffer_;
  std::uint64_t count_ = 0;
  std::size_t served_ = 0;
  bool onDisk_ = false;
};

}  // namespace seamvox
