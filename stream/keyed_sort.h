#pragma once
/// Sort of fixed-size records whose order starts with a dense integer key below keyCount (a
/// vertex or corner id): the records go to partitions of equal key ranges (kept in memory when
/// they all fit, else one scratch file each), and each partition is counting-sorted by key, then
/// each key's few records by Less. No comparison sort of the whole input and no merge: every
/// record is written and read once. A partition over the memory limit (a key holding a large
/// share of the records) is sorted by an ExternalSorter instead. The records can be served in
/// order more than once (rewind()). Memory: about options.memoryBytes.
#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "stream/external_sort.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// Less: a strict total order of Records whose first criterion is Key (Key{}(a) < Key{}(b)
/// implies Less{}(a, b)).
template <class Record, class Less, class Key>
class KeyedSorter {
  static_assert(std::is_trivially_copyable_v<Record>, "records are written as bytes");

 public:
  /// expectedRecords sizes the partitions; more records are sorted all the same (a partition
  /// over the limit goes through the ExternalSorter).
  KeyedSorter(ScratchFolder& scratch, std::uint64_t keyCount, std::uint64_t expectedRecords,
              const ExternalSortOptions& options)
      : scratch_(scratch), options_(options), keyCount_(std::max<std::uint64_t>(1, keyCount)) {
    // A partition's sort holds its records twice and a 4-byte count per key: three quarters of
    // the limit, the rest for the partitions' write buffers.
    work_ = std::max<std::uint64_t>(1, options.memoryBytes / 4 * 3);
    const std::uint64_t need = 2 * expectedRecords * sizeof(Record) + 4 * keyCount_;
    const std::uint64_t partitions = std::max<std::uint64_t>(1, (need + work_ - 1) / work_);
    keysPerPartition_ = (keyCount_ + partitions - 1) / partitions;
    partitions_ = static_cast<std::size_t>((keyCount_ + keysPerPartition_ - 1) / keysPerPartition_);
    counts_.assign(partitions_, 0);
    if (partitions_ > 1) {
      files_.resize(partitions_);
      writers_.resize(partitions_);
      bufferBytes_ = std::clamp<std::size_t>(options.memoryBytes / 8 / partitions_, 4096, std::size_t(1) << 20);
    }
  }
  ~KeyedSorter() {
    writers_.clear();
    fallback_.reset();
    for (const ScratchFile& file : files_) scratch_.remove(file);
  }
  KeyedSorter(const KeyedSorter&) = delete;
  KeyedSorter& operator=(const KeyedSorter&) = delete;

  void add(const Record& record) {
    const std::uint64_t key = Key{}(record);
    if (key >= keyCount_) {
      throw std::out_of_range("KeyedSorter: key " + std::to_string(key) + " of a record is not below " +
                              std::to_string(keyCount_));
    }
    const std::size_t p = static_cast<std::size_t>(key / keysPerPartition_);
    ++counts_[p];
    ++size_;
    if (partitions_ == 1 && !spilled_) {
      if (2 * (memory_.size() + 1) * sizeof(Record) + 4 * keyCount_ <= work_) {
        memory_.push_back(record);
        return;
      }
      // More than expected: partition 0 goes to a file after all.
      files_.resize(1);
      writers_.resize(1);
      writers_[0] = std::make_unique<ScratchWriter>(scratch_, options_.stage);
      writers_[0]->write(memory_.data(), memory_.size() * sizeof(Record));
      std::vector<Record>().swap(memory_);
      spilled_ = true;
    }
    if (!writers_[p]) writers_[p] = std::make_unique<ScratchWriter>(scratch_, options_.stage, bufferBytes_);
    writers_[p]->write(&record, sizeof record);
  }

  /// Ends the input; next() then returns the records in order.
  void finish() {
    for (std::size_t p = 0; p < writers_.size(); ++p) {
      if (writers_[p]) files_[p] = writers_[p]->finish();
    }
    writers_.clear();
    if (partitions_ == 1 && !spilled_) {
      sorted_ = countingSort(memory_, 0);
      std::vector<Record>().swap(memory_);
      inMemory_ = true;
      return;
    }
    open(0);
  }

  bool next(Record& out) {
    served_ = true;
    for (;;) {
      if (at_ < sorted_.size()) {
        out = sorted_[at_++];
        return true;
      }
      if (fallback_ && fallback_->next(out)) return true;
      if (inMemory_ || partition_ + 1 >= partitions_) return false;
      open(partition_ + 1);
    }
  }

  /// Serves the records from the first again (after finish()).
  void rewind() {
    if (!served_) return;
    served_ = false;
    if (inMemory_) {
      at_ = 0;
      return;
    }
    open(0);
  }

  std::uint64_t size() const { return size_; }
  /// Partitions written to scratch files (0 when the records stayed in memory).
  std::size_t filesWritten() const {
    return static_cast<std::size_t>(std::count_if(files_.begin(), files_.end(), [](const ScratchFile& f) { return !f.path.empty(); }));
  }

 private:
  /// Reads partition p and sorts it (counting sort, or the ExternalSorter when it does not fit).
  void open(std::size_t p) {
    partition_ = p;
    at_ = 0;
    std::vector<Record>().swap(sorted_);
    fallback_.reset();
    const ScratchFile& file = files_[p];
    if (file.path.empty()) return;
    const std::uint64_t n = file.bytes / sizeof(Record);
    const std::uint64_t keys = std::min(keyCount_ - p * keysPerPartition_, keysPerPartition_);
    ScratchReader in(scratch_, file, options_.stage);
    if (2 * n * sizeof(Record) + 4 * keys <= options_.memoryBytes && n < (std::uint64_t(1) << 32)) {
      std::vector<Record> records(static_cast<std::size_t>(n));
      if (n > 0 && !in.read(records.data(), records.size() * sizeof(Record))) {
        throw IoError(file.path + ": scratch partition ends early");
      }
      sorted_ = countingSort(records, p * keysPerPartition_);
      return;
    }
    fallback_ = std::make_unique<ExternalSorter<Record, Less>>(scratch_, options_);
    Record record;
    while (in.read(&record, sizeof record)) fallback_->add(record);
    fallback_->finish();
  }

  /// records (keys from first on, in this partition's range) in Less order: stable by key,
  /// then each key's records sorted (they usually come in order already).
  std::vector<Record> countingSort(const std::vector<Record>& records, std::uint64_t first) const {
    const std::uint64_t keys = std::min(keyCount_ - first, keysPerPartition_);
    std::vector<std::uint32_t> end(static_cast<std::size_t>(keys) + 1, 0);
    for (const Record& r : records) ++end[static_cast<std::size_t>(Key{}(r) - first) + 1];
    for (std::size_t k = 1; k < end.size(); ++k) end[k] += end[k - 1];
    std::vector<Record> out(records.size());
    for (const Record& r : records) out[end[static_cast<std::size_t>(Key{}(r) - first)]++] = r;
    // end[k] is now where key k's records end.
    std::size_t begin = 0;
    for (std::size_t k = 0; k < keys; ++k) {
      const std::size_t stop = end[k];
      if (stop - begin > 1 && !std::is_sorted(out.begin() + begin, out.begin() + stop, Less{})) {
        std::sort(out.begin() + begin, out.begin() + stop, Less{});
      }
      begin = stop;
    }
    return out;
  }

  ScratchFolder& scratch_;
  ExternalSortOptions options_;
  std::uint64_t keyCount_, keysPerPartition_ = 1, size_ = 0, work_ = 1;
  std::size_t partitions_ = 1, bufferBytes_ = 4096, partition_ = 0, at_ = 0;
  std::vector<std::uint64_t> counts_;
  std::vector<ScratchFile> files_;
  std::vector<std::unique_ptr<ScratchWriter>> writers_;
  std::vector<Record> memory_, sorted_;
  std::unique_ptr<ExternalSorter<Record, Less>> fallback_;
  bool spilled_ = false, inMemory_ = false, served_ = false;
};

}  // namespace seamvox
