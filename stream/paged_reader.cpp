#include "stream/paged_reader.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>

#include "core/system/errors.h"

namespace seamvox {

namespace {
constexpr std::uint64_t kNoPage = ~std::uint64_t(0);
}  // namespace

PageCache::PageCache(ScratchUpdater& updater, const ScratchFile& file, std::size_t recordBytes, std::size_t cacheBytes)
    : PageCache(file, recordBytes, cacheBytes) {
  updater_ = &updater;
  dirty_.assign(tags_.size(), 0);
}

PageCache::PageCache(const ScratchFile& file, std::size_t recordBytes, std::size_t cacheBytes, std::size_t pageBytes)
    : path_(file.path), recordBytes_(recordBytes) {
  if (recordBytes == 0 || file.bytes % recordBytes != 0) {
    throw IoError(path_ + ": scratch file of " + std::to_string(file.bytes) + " bytes is not a whole number of " +
                  std::to_string(recordBytes) + "-byte records");
  }
  numRecords_ = file.bytes / recordBytes;
  // Powers of two (records per page, pages in the cache): a lookup is a shift, a mask and two
  // compares. Two ways per set, the older one replaced: pages of a moving front (a breadth-first
  // walk over the surface) that fall on one set no longer evict each other at once.
  while ((std::size_t(2) << pageShift_) * recordBytes <= pageBytes) ++pageShift_;
  pageRecords_ = std::size_t(1) << pageShift_;
  pageBytes_ = pageRecords_ * recordBytes;
  const std::uint64_t pagesInFile = (numRecords_ + pageRecords_ - 1) / pageRecords_;
  const std::uint64_t wanted = std::min<std::uint64_t>(pagesInFile, std::max<std::size_t>(2, cacheBytes / pageBytes_));
  std::size_t slots = 2;  // one set of two ways at least
  while (slots < wanted) slots *= 2;
  setMask_ = slots / 2 - 1;
  tags_.assign(slots, kNoPage);
  older_.assign(slots / 2, 0);
  data_.resize(slots * pageBytes_);
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path_ + ": cannot open a scratch file (" + std::strerror(errno) + ")");
}

PageCache::~PageCache() {
  if (fd_ >= 0) ::close(fd_);
}

char* PageCache::recordForWrite(std::uint64_t i) {
  if (!updater_) throw IoError(path_ + ": a write through a read-only page cache");
  char* at = slotFor(i);
  dirty_[lastSlot_] = 1;
  return at;
}

void PageCache::flush() {
  for (std::size_t slot = 0; slot < dirty_.size(); ++slot) writeBack(slot);
}

void PageCache::forget(std::uint64_t first, std::uint64_t count) {
  if (updater_) throw IoError(path_ + ": forget() on a writable page cache would lose its changes");
  if (count == 0 || first >= numRecords_) return;
  const std::uint64_t last = (std::min(first + count, numRecords_) - 1) >> pageShift_;
  for (std::uint64_t page = first >> pageShift_; page <= last; ++page) {
    const std::size_t slot = 2 * (static_cast<std::size_t>(page) & setMask_);
    if (tags_[slot] == page) tags_[slot] = kNoPage;
    if (tags_[slot + 1] == page) tags_[slot + 1] = kNoPage;
  }
}

void PageCache::writeBack(std::size_t slot) {
  if (!dirty_[slot]) return;
  const std::uint64_t offset = tags_[slot] * pageBytes_;
  const std::size_t bytes = static_cast<std::size_t>(std::min<std::uint64_t>(pageBytes_, numRecords_ * recordBytes_ - offset));
  updater_->writeAt(offset, data_.data() + slot * pageBytes_, bytes);
  dirty_[slot] = 0;
}

char* PageCache::slotFor(std::uint64_t i) {
  if (i >= numRecords_) {
    throw IoError(path_ + ": record " + std::to_string(i) + " past the end of a scratch file of " +
                  std::to_string(numRecords_) + " records");
  }
  const std::uint64_t page = i >> pageShift_;
  const std::size_t set = static_cast<std::size_t>(page) & setMask_;
  std::size_t slot = 2 * set;
  char* base;
  if (tags_[slot] == page) {
    base = data_.data() + slot * pageBytes_;
    older_[set] = 1;
  } else if (tags_[slot + 1] == page) {
    base = data_.data() + ++slot * pageBytes_;
    older_[set] = 0;
  } else {
    slot += older_[set];
    base = load(page, slot);
    older_[set] ^= 1;
  }
  lastSlot_ = slot;
  return base + (i & (pageRecords_ - 1)) * recordBytes_;
}

char* PageCache::load(std::uint64_t page, std::size_t slot) {
  if (updater_) writeBack(slot);
  char* to = data_.data() + slot * pageBytes_;
  const std::uint64_t offset = page * pageBytes_;
  const std::size_t bytes = static_cast<std::size_t>(std::min<std::uint64_t>(pageBytes_, numRecords_ * recordBytes_ - offset));
  readScratchAt(fd_, path_, offset, to, bytes);
  bytesRead_ += bytes;
  tags_[slot] = page;
  return to;
}

}  // namespace seamvox
