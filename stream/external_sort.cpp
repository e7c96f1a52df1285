#include "stream/external_sort.h"

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

namespace seamvox::detail {

/// The final merge run ahead by a thread of its own, a block of records at a time, at most
/// kBlocks blocks ahead: the pass reading the sorted records works meanwhile on its core.
struct ExternalMerge::Prefetch {
  static constexpr std::size_t kBlocks = 3;
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<std::vector<char>> full;  // merged blocks, in order
  std::vector<std::vector<char>> empty;  // blocks served, for the thread to fill again
  bool done = false, stop = false;
  std::exception_ptr error;
  std::thread thread;
};

/// One run being merged: its reader and its current record.
struct ExternalMerge::Source {
  ScratchFile file;
  ScratchReader reader;
  std::vector<char> record;
};

ExternalMerge::ExternalMerge(ScratchFolder& scratch, std::size_t recordBytes, Less less,
                             const ExternalSortOptions& options)
    : scratch_(scratch), recordBytes_(recordBytes), less_(less), options_(options) {
  // Half the limit for read buffers of the runs merged at once (a 128th of the limit each, so
  // 64 runs merge in one round; at most 1 MiB, at least a record), the other half for the output
  // buffer and the sort buffer before.
  readBuffer_ = std::clamp<std::size_t>(options.memoryBytes / 128, recordBytes, std::size_t(1) << 20);
  fanIn_ = std::max<std::size_t>(2, options.memoryBytes / 2 / readBuffer_);
}

ExternalMerge::~ExternalMerge() {
  stopPrefetch();
  removeSources();
  for (const ScratchFile& run : runs_) scratch_.remove(run);
}

void ExternalMerge::removeSources() {
  // Readers closed first: a closed file can be overwritten by the next writer.
  std::vector<ScratchFile> files;
  for (const auto& source : sources_) files.push_back(source->file);
  sources_.clear();
  for (const ScratchFile& file : files) scratch_.remove(file);
}

void ExternalMerge::writeRun(const void* records, std::size_t count) {
  ScratchWriter writer(scratch_, options_.stage, std::min<std::size_t>(readBuffer_ * 4, count * recordBytes_ + 1),
                       count * recordBytes_);
  writer.write(records, count * recordBytes_);
  runs_.push_back(writer.finish());
  ++written_;
}

ScratchFile ExternalMerge::mergeRuns(std::size_t first, std::size_t count) {
  sources_.clear();
  heap_.clear();
  for (std::size_t i = first; i < first + count; ++i) {
    sources_.push_back(std::make_unique<Source>(
        Source{runs_[i], ScratchReader(scratch_, runs_[i], options_.stage, readBuffer_), std::vector<char>(recordBytes_)}));
  }
  records_.clear();
  for (const auto& source : sources_) records_.push_back(source->record.data());
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    if (sources_[i]->reader.read(sources_[i]->record.data(), recordBytes_)) {
      heap_.push_back(i);
      std::push_heap(heap_.begin(), heap_.end(),
                     [&](std::size_t a, std::size_t b) { return less_(records_[b], records_[a]); });
    }
  }
  if (count == runs_.size() && first == 0) return {};  // the final pass: next() pops it
  std::uint64_t bytes = 0;
  for (std::size_t i = first; i < first + count; ++i) bytes += runs_[i].bytes;
  ScratchWriter writer(scratch_, options_.stage, readBuffer_ * 4, bytes);
  std::vector<char> record(recordBytes_);
  while (pop(record.data())) writer.write(record.data(), recordBytes_);
  removeSources();
  return writer.finish();
}

void ExternalMerge::startMerge() {
  // Rounds: merge the first fanIn runs into one appended at the end until one pass is left.
  while (runs_.size() > fanIn_) {
    ScratchFile merged = mergeRuns(0, fanIn_);
    runs_.erase(runs_.begin(), runs_.begin() + static_cast<std::ptrdiff_t>(fanIn_));
    runs_.push_back(merged);
  }
  mergeRuns(0, runs_.size());
  runs_.clear();  // now owned by sources_
  if (heap_.empty()) return;
  prefetch_ = std::make_unique<Prefetch>();
  Prefetch& p = *prefetch_;
  const std::size_t blockBytes = std::max<std::size_t>(1, readBuffer_ / recordBytes_) * recordBytes_;
  for (std::size_t k = 0; k < Prefetch::kBlocks; ++k) p.empty.emplace_back(blockBytes);
  try {
    p.thread = std::thread([this, &p, blockBytes] {
      try {
        for (;;) {
          std::vector<char> block;
          {
            std::unique_lock<std::mutex> lock(p.mutex);
            p.changed.wait(lock, [&] { return !p.empty.empty() || p.stop; });
            if (p.stop) break;
            block = std::move(p.empty.back());
            p.empty.pop_back();
          }
          block.resize(blockBytes);
          const std::size_t bytes = fill(block.data(), blockBytes);
          block.resize(bytes);
          std::lock_guard<std::mutex> lock(p.mutex);
          if (bytes > 0) p.full.push_back(std::move(block));
          if (bytes < blockBytes) break;
          p.changed.notify_all();
        }
      } catch (...) {
        std::lock_guard<std::mutex> lock(p.mutex);
        p.error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(p.mutex);
        p.done = true;
      }
      p.changed.notify_all();
    });
  } catch (const std::system_error&) {
    prefetch_.reset();  // no thread: next() merges here
  }
}

bool ExternalMerge::pop(void* out) {
  if (heap_.empty()) return false;
  // The smallest run's record goes out and its next record takes its place at the top, sifted
  // down (one pass instead of a pop and a push); a run that ends gives the top to the last leaf.
  Source& source = *sources_[heap_[0]];
  std::memcpy(out, source.record.data(), recordBytes_);
  if (!source.reader.read(source.record.data(), recordBytes_)) {
    heap_[0] = heap_.back();
    heap_.pop_back();
  }
  const std::size_t n = heap_.size();
  std::size_t at = 0;
  const std::size_t moving = n ? heap_[0] : 0;
  while (2 * at + 1 < n) {
    std::size_t child = 2 * at + 1;
    if (child + 1 < n && less_(records_[heap_[child + 1]], records_[heap_[child]])) ++child;
    if (!less_(records_[heap_[child]], records_[moving])) break;
    heap_[at] = heap_[child];
    at = child;
  }
  if (n) heap_[at] = moving;
  return true;
}

std::size_t ExternalMerge::fill(char* out, std::size_t bytes) {
  std::size_t done = 0;
  while (done < bytes && pop(out + done)) done += recordBytes_;
  return done;
}

void ExternalMerge::stopPrefetch() noexcept {
  if (!prefetch_) return;
  {
    std::lock_guard<std::mutex> lock(prefetch_->mutex);
    prefetch_->stop = true;
  }
  prefetch_->changed.notify_all();
  prefetch_->thread.join();
  prefetch_.reset();
}

bool ExternalMerge::nextBlock() {
  if (!prefetch_) {
    // Merged here: the final pass of few records, or one whose thread could not start.
    block_.resize(std::max<std::size_t>(1, readBuffer_ / recordBytes_) * recordBytes_);
    const std::size_t bytes = fill(block_.data(), block_.size());
    at_ = block_.data();
    end_ = at_ + bytes;
    return bytes > 0;
  }
  Prefetch& p = *prefetch_;
  std::unique_lock<std::mutex> lock(p.mutex);
  if (!block_.empty()) p.empty.push_back(std::move(block_));
  p.changed.notify_all();
  p.changed.wait(lock, [&] { return !p.full.empty() || p.done; });
  if (p.full.empty()) {
    if (p.error) std::rethrow_exception(p.error);
    block_.clear();
    at_ = end_ = nullptr;
    return false;
  }
  block_ = std::move(p.full.front());
  p.full.pop_front();
  at_ = block_.data();
  end_ = at_ + block_.size();
  return true;
}

}  // namespace seamvox::detail
