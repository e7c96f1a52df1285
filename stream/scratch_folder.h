#pragma once
/// Scratch files of the out-of-core passes: one folder per run, created under a parent folder
/// with a unique name and removed with everything in it on success, on failure (the destructor
/// runs while an exception unwinds) and on SIGINT/SIGTERM (io/interrupt_cleanup). Plain read and
/// write calls through fixed buffers (no mmap: resident memory stays what the buffers hold);
/// bytes read and written are counted per stage. A removed file is kept for the next writer to
/// overwrite (up to a share of the folder's bytes): its pages are still in the kernel's cache,
/// where a new file's pages must be allocated, which costs more than the copy itself. A full disk (ENOSPC, EDQUOT, a short write) is
/// an IoError naming the folder and the bytes the run needs.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/system/errors.h"

namespace seamvox {

/// Scratch traffic of one stage.
struct ScratchTraffic {
  std::string stage;
  std::uint64_t bytesRead = 0, bytesWritten = 0;
};

/// A finished scratch file.
struct ScratchFile {
  std::string path;
  std::uint64_t bytes = 0;
};

class ScratchFolder {
 public:
  /// Creates PARENT/seamvox-scratch-PID-N (IoError naming parent when it cannot). neededBytes:
  /// the run's estimate of its scratch, quoted when the disk fills (0: unknown).
  explicit ScratchFolder(const std::string& parent, std::uint64_t neededBytes = 0);
  ~ScratchFolder();
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::string& path() const { return path_; }
  /// The path of a new file in the folder (named by number, so a signal handler can find it).
  std::string newFilePath();
  /// A new file of `bytes` zero bytes, sparse (the disk fills as pages are written in place), counted
  /// on disk at its full size.
  ScratchFile zeroFile(std::uint64_t bytes);
  /// Removes a finished file now: unlinked, or kept for a later writer to overwrite (its bytes
  /// stay in bytesOnDisk until then).
  void remove(const ScratchFile& file);
  /// A removed file for a new writer to overwrite (path empty when there is none): the smallest
  /// one of at least expectedBytes, else the largest; the writer truncates it to what it wrote.
  ScratchFile reuse(std::uint64_t expectedBytes);
  /// Bytes a writer gave back by truncating a reused file.
  void shrink(std::uint64_t bytes);

  /// Per stage, in the order the stages first read or wrote.
  const std::vector<ScratchTraffic>& traffic() const { return traffic_; }
  std::uint64_t bytesOnDisk() const { return onDisk_; }
  /// Of bytesOnDisk, the removed files' kept for reuse.
  std::uint64_t bytesKeptForReuse() const { return freeBytes_; }
  /// Of bytesOnDisk, the files not removed.
  std::uint64_t bytesInUse() const { return onDisk_ - freeBytes_; }
  std::uint64_t peakBytesOnDisk() const { return peakOnDisk_; }
  std::uint64_t bytesWritten() const { return written_; }

  /// Test hook: writes fail as on a full disk once this many bytes are written in all.
  void setWriteLimit(std::uint64_t bytes) { writeLimit_ = bytes; }

  // Bookkeeping of ScratchWriter / ScratchReader.
  void countRead(const std::string& stage, std::uint64_t bytes);
  /// Counts a write about to happen, of which growth bytes extend a file on disk; throws the
  /// disk-full IoError when the test limit is reached.
  void countWrite(const std::string& stage, std::uint64_t bytes, std::uint64_t growth);
  [[noreturn]] void throwDiskFull(const std::string& file, std::uint64_t failedBytes, const char* reason) const;

 private:
  ScratchTraffic& stage(const std::string& name);

  std::string path_;
  std::uint64_t neededBytes_ = 0;
  std::atomic<std::uint64_t> files_{0};
  int cleanupSlot_ = -1;
  std::vector<ScratchTraffic> traffic_;
  std::uint64_t onDisk_ = 0, peakOnDisk_ = 0, written_ = 0;
  std::uint64_t writeLimit_ = ~std::uint64_t(0);
  std::mutex trafficMutex_;  ///< traffic_ and written_
  std::mutex freeMutex_;
  std::vector<ScratchFile> free_;  ///< removed files kept for reuse
  std::uint64_t freeBytes_ = 0;
};

namespace detail {
struct ScratchIoRequest;
}

/// Writes one new scratch file through two buffers: one fills while the other is written by the
/// scratch I/O thread (the kernel's copy overlaps the caller's work; the memory is bufferBytes).
class ScratchWriter {
 public:
  /// expectedBytes: the file's size when known (0: unknown), to pick a removed file to overwrite.
  ScratchWriter(ScratchFolder& folder, std::string stage, std::size_t bufferBytes = std::size_t(1) << 20,
                std::uint64_t expectedBytes = 0);
  ~ScratchWriter();
  ScratchWriter(const ScratchWriter&) = delete;
  ScratchWriter& operator=(const ScratchWriter&) = delete;
  void write(const void* data, std::size_t bytes);
  /// Flushes and closes the file.
  ScratchFile finish();
  /// Flushes: the bytes written so far, readable by other readers of the file while it grows.
  ScratchFile written();

 private:
  void flush();
  /// Waits for the write in flight; its failure thrown as the disk-full or I/O error.
  void settle();
  ScratchFolder& folder_;
  std::string stage_, path_;
  int fd_ = -1;
  std::vector<char> buffers_[2];
  int current_ = 0;
  std::shared_ptr<detail::ScratchIoRequest> pending_;
  std::size_t used_ = 0;
  std::uint64_t bytes_ = 0;   ///< handed to the I/O thread
  std::uint64_t reused_ = 0;  ///< bytes of the removed file this one overwrites
};

/// Reads a finished scratch file through two buffers, the next one read ahead by the scratch I/O
/// thread while the caller works on the other; up to the file's bytes (a reused file may hold
/// older bytes past them while it is written).
class ScratchReader {
 public:
  ScratchReader(ScratchFolder& folder, const ScratchFile& file, std::string stage,
                std::size_t bufferBytes = std::size_t(1) << 20);
  ~ScratchReader();
  ScratchReader(ScratchReader&& other) noexcept;
  ScratchReader(const ScratchReader&) = delete;
  ScratchReader& operator=(const ScratchReader&) = delete;
  /// Reads exactly `bytes` into out; false at the end of the file (IoError for a partial read).
  bool read(void* out, std::size_t bytes);
  /// Reads at most `bytes` into out; the bytes read, 0 at the end of the file.
  std::size_t readUpTo(void* out, std::size_t bytes);

 private:
  bool refill();
  void requestNext();
  ScratchFolder* folder_;
  std::string stage_, path_;
  int fd_ = -1;
  std::vector<char> buffers_[2];
  int current_ = 0;
  std::shared_ptr<detail::ScratchIoRequest> pending_;  ///< the read into the other buffer
  std::size_t begin_ = 0, end_ = 0;
  std::uint64_t requested_ = 0, bytes_ = 0;  ///< offset of the next read, the file's bytes
};

/// A whole scratch file of count records of T, in memory (IoError when the file is shorter).
template <class T>
std::vector<T> readWholeScratch(ScratchFolder& folder, const ScratchFile& file, std::uint64_t count, std::string stage) {
  std::vector<T> out(count);
  ScratchReader in(folder, file, std::move(stage));
  if (count > 0 && !in.read(out.data(), count * sizeof(T))) throw IoError(file.path + ": scratch file ends early");
  return out;
}

/// Reads exactly `bytes` at offset of the open file fd (named path in errors): IoError when it
/// cannot, or when the file ends first (it changed while it was read).
void readScratchAt(int fd, const std::string& path, std::uint64_t offset, void* out, std::size_t bytes);

/// Reads records of a finished scratch file at given offsets (pread: for sparse lookups).
class ScratchRandomReader {
 public:
  ScratchRandomReader(ScratchFolder& folder, const ScratchFile& file, std::string stage);
  ~ScratchRandomReader();
  ScratchRandomReader(const ScratchRandomReader&) = delete;
  ScratchRandomReader& operator=(const ScratchRandomReader&) = delete;
  /// Reads exactly `bytes` at offset into out (IoError when the file is shorter).
  void readAt(std::uint64_t offset, void* out, std::size_t bytes);

 private:
  ScratchFolder& folder_;
  std::string stage_, path_;
  int fd_ = -1;
};

/// Reads and rewrites records of a finished scratch file in place (pread / pwrite), for passes that
/// change some records of a file and keep the rest.
class ScratchUpdater {
 public:
  ScratchUpdater(ScratchFolder& folder, const ScratchFile& file, std::string stage);
  ~ScratchUpdater();
  ScratchUpdater(const ScratchUpdater&) = delete;
  ScratchUpdater& operator=(const ScratchUpdater&) = delete;
  void readAt(std::uint64_t offset, void* out, std::size_t bytes);
  /// Within the file's bytes; the disk-full IoError as ScratchWriter's.
  void writeAt(std::uint64_t offset, const void* data, std::size_t bytes);

 private:
  ScratchFolder& folder_;
  std::string stage_, path_;
  std::uint64_t bytes_ = 0;
  int fd_ = -1;
};

}  // namespace seamvox
