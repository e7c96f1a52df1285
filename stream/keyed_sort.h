#pragma once
/// Sort of fixed-size records whose order starts with a dense integer key below keyCount (a
/// vertex or corner id): the records go to partitions of equal key ranges (kept in memory when
/// they all fit, else one scratch file each), and each partition (or run of consecutive ones that
/// fit together) is counting-sorted by key, then each key's few records by Less. No comparison
/// sort of the whole input and no merge: every record is written and read once. A partition over the memory limit (a key holding a large
/// share of the records) is sorted by an ExternalSorter instead. While a partition is served, the
/// next is read and sorted on a thread of its own. The records can be served in order more than
/// once (rewind()). Memory: about options.memoryBytes.
#include <algorithm>
#include <cstdint>
#include <future>
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
    // the limit, the rest for the partitions' write buffers. Beyond one partition, two are held
    // at once (the one served and the next, sorted ahead on a thread of its own).
    work_ = std::max<std::uint64_t>(1, options.memoryBytes / 4 * 3);
    const std::uint64_t need = 2 * expectedRecords * sizeof(Record) + 4 * keyCount_;
    const std::uint64_t needed = need <= work_ ? 1 : (2 * need + work_ - 1) / work_;
    // Beyond one, finer partitions than needed (8 to each, up to 512): keys bunched in part of
    // their range still fill the slots, consecutive partitions being sorted together while they
    // fit one.
    const std::uint64_t partitions = needed == 1 ? 1 : std::max(needed, std::min<std::uint64_t>(8 * needed, 512));
    keysPerPartition_ = (keyCount_ + partitions - 1) / partitions;
    partitions_ = static_cast<std::size_t>((keyCount_ + keysPerPartition_ - 1) / keysPerPartition_);
    if (partitions_ > 1) {
      files_.resize(partitions_);
      writers_.resize(partitions_);
      bufferBytes_ = std::clamp<std::size_t>(options.memoryBytes / 8 / partitions_, 4096, std::size_t(1) << 20);
    } else {
      // Room for the expected records at once: no doubling (three times the records for a moment).
      slots_[0].input.reserve(static_cast<std::size_t>(expectedRecords));
    }
  }
  ~KeyedSorter() {
    if (ahead_.valid()) ahead_.wait();  // its error, if any, no longer matters
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
    ++size_;
    std::vector<Record>& memory = slots_[0].input;
    if (partitions_ == 1 && !spilled_) {
      if (2 * (memory.size() + 1) * sizeof(Record) + 4 * keyCount_ <= work_) {
        memory.push_back(record);
        return;
      }
      // More than expected: partition 0 goes to a file after all.
      files_.resize(1);
      writers_.resize(1);
      writers_[0] = std::make_unique<ScratchWriter>(scratch_, options_.stage);
      writers_[0]->write(memory.data(), memory.size() * sizeof(Record));
      std::vector<Record>().swap(memory);
      spilled_ = true;
    }
    if (!writers_[p]) writers_[p] = std::make_unique<ScratchWriter>(scratch_, options_.stage, bufferBytes_);
    writers_[p]->write(&record, sizeof record);
  }

  /// Ends the input: the partitions' files written and their buffers freed (the records in memory
  /// stay), nothing read back yet. finish() does it too.
  void close() {
    for (std::size_t p = 0; p < writers_.size(); ++p) {
      if (writers_[p]) files_[p] = writers_[p]->finish();
    }
    writers_.clear();
    writers_.shrink_to_fit();
  }

  /// Ends the input; next() then returns the records in order.
  void finish() {
    close();
    if (partitions_ == 1 && !spilled_) {
      countingSort(slots_[0], 0, keyCount_);
      std::vector<Record>().swap(slots_[0].input);
      inMemory_ = true;
      return;
    }
    open(0);
  }

  bool next(Record& out) {
    served_ = true;
    for (;;) {
      const std::vector<Record>& sorted = slots_[current_].sorted;
      if (at_ < sorted.size()) {
        out = sorted[at_++];
        return true;
      }
      if (fallback_ && fallback_->next(out)) return true;
      if (inMemory_ || end_ >= partitions_) return false;
      open(end_);
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
    return static_cast<std::size_t>(
        std::count_if(files_.begin(), files_.end(), [](const ScratchFile& f) { return !f.path.empty(); }));
  }

 private:
  /// A partition's records as read, sorted, and the counting sort's per-key ends. Their room
  /// serves partition after partition (no fresh pages for the kernel to clear each time).
  struct Slot {
    std::vector<Record> input, sorted;
    std::vector<std::uint32_t> end;
  };

  /// The keys of partitions [p, q).
  std::uint64_t keysOf(std::size_t p, std::size_t q) const {
    return std::min(keyCount_, q * keysPerPartition_) - p * keysPerPartition_;
  }
  /// Whether partitions [p, q) sort together in a slot (half the sorts' share: two slots at once).
  bool fits(std::size_t p, std::size_t q) const {
    std::uint64_t n = 0;
    for (std::size_t k = p; k < q; ++k) n += files_[k].bytes / sizeof(Record);
    return 2 * n * sizeof(Record) + 4 * keysOf(p, q) <= work_ / 2 && n < (std::uint64_t(1) << 32);
  }
  /// The end of the partitions sorted together from p on: as many as fit a slot, one at least.
  std::size_t rangeEnd(std::size_t p) const {
    std::size_t q = p + 1;
    while (q < partitions_ && fits(p, q + 1)) ++q;
    return q;
  }

  /// Reads partitions [p, q) (that fit) into slot and sorts them; on any thread.
  void prepare(std::size_t p, std::size_t q, Slot& slot) {
    std::uint64_t n = 0;
    for (std::size_t k = p; k < q; ++k) n += files_[k].bytes / sizeof(Record);
    slot.input.resize(static_cast<std::size_t>(n));
    Record* to = slot.input.data();
    for (std::size_t k = p; k < q; ++k) {
      const ScratchFile& file = files_[k];
      if (file.path.empty()) continue;
      ScratchReader in(scratch_, file, options_.stage);
      if (!in.read(to, file.bytes)) throw IoError(file.path + ": scratch partition ends early");
      to += file.bytes / sizeof(Record);
    }
    countingSort(slot, p * keysPerPartition_, keysOf(p, q));
  }

  /// Serves partitions from p on: sorted ahead, else sorted now (by counting, or partition p alone
  /// by the ExternalSorter when it does not fit); then the next ones are sorted ahead.
  void open(std::size_t p) {
    at_ = 0;
    fallback_.reset();
    bool ready = false;
    if (ahead_.valid()) {
      const std::size_t aheadOf = aheadOf_;
      ahead_.get();  // the thread's error, if any, is the caller's
      if (aheadOf == p) {
        current_ ^= 1;
        end_ = aheadEnd_;
        ready = true;
      }
    }
    if (!ready && fits(p, p + 1)) {
      end_ = rangeEnd(p);
      prepare(p, end_, slots_[current_]);
    } else if (!ready) {
      end_ = p + 1;
      for (Slot& slot : slots_) slot = Slot{};  // the limit is the external sort's
      fallback_ = std::make_unique<ExternalSorter<Record, Less>>(scratch_, options_);
      ScratchReader in(scratch_, files_[p], options_.stage);
      Record record;
      while (in.read(&record, sizeof record)) fallback_->add(record);
      fallback_->finish();
      return;
    }
    if (end_ < partitions_ && fits(end_, end_ + 1)) {
      Slot& other = slots_[current_ ^ 1];
      aheadOf_ = end_;
      aheadEnd_ = rangeEnd(end_);
      ahead_ = std::async(std::launch::async, [this, &other, p = aheadOf_, q = aheadEnd_] { prepare(p, q, other); });
    }
  }

  /// slot.sorted := slot.input (keys [first, first + keys)) in Less order:
  /// stable by key, then each key's records sorted (they usually come in order already).
  void countingSort(Slot& slot, std::uint64_t first, std::uint64_t keys) const {
    std::vector<std::uint32_t>& end = slot.end;
    end.assign(static_cast<std::size_t>(keys) + 1, 0);
    for (const Record& r : slot.input) ++end[static_cast<std::size_t>(Key{}(r) - first) + 1];
    for (std::size_t k = 1; k < end.size(); ++k) end[k] += end[k - 1];
    std::vector<Record>& out = slot.sorted;
    out.resize(slot.input.size());
    for (const Record& r : slot.input) out[end[static_cast<std::size_t>(Key{}(r) - first)]++] = r;
    // end[k] is now where key k's records end.
    std::size_t begin = 0;
    for (std::size_t k = 0; k < keys; ++k) {
      const std::size_t stop = end[k];
      if (stop - begin > 1 && !std::is_sorted(out.begin() + begin, out.begin() + stop, Less{})) {
        std::sort(out.begin() + begin, out.begin() + stop, Less{});
      }
      begin = stop;
    }
  }

  ScratchFolder& scratch_;
  ExternalSortOptions options_;
  std::uint64_t keyCount_, keysPerPartition_ = 1, size_ = 0, work_ = 1;
  std::size_t partitions_ = 1, bufferBytes_ = 4096, end_ = 1, at_ = 0;  // end_: past the partitions served
  std::vector<ScratchFile> files_;
  std::vector<std::unique_ptr<ScratchWriter>> writers_;
  Slot slots_[2];  // slots_[0].input: the records while they fit in memory
  int current_ = 0;  // the slot served
  std::future<void> ahead_;  // sorts partitions [aheadOf_, aheadEnd_) into the other slot
  std::size_t aheadOf_ = 0, aheadEnd_ = 0;
  std::unique_ptr<ExternalSorter<Record, Less>> fallback_;
  bool spilled_ = false, inMemory_ = false, served_ = false;
};

}  // namespace seamvox
