#pragma once
/// Atomic output: write to a temporary file next to the target, rename on commit.
#include <cstdio>
#include <memory>
#include <string>

namespace seamvox {

/// Opens "<path>.tmp-<pid>" for binary writing; commit() flushes, checks for write errors and
/// renames it onto path. If the object is destroyed without commit() the temporary is removed,
/// and so it is when the process is interrupted (io/interrupt_cleanup.h). Writes fill buffers
/// that a thread of the file's own hands to the kernel, so the kernel's copy of a large output
/// overlaps the caller's formatting of the next bytes.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Throws IoError naming the target path when an earlier buffer could not be written.
  void write(const void* data, std::size_t bytes);
  void write(const std::string& text) { write(text.data(), text.size()); }
  /// Flushes and closes the temporary, which stays until commit() or destruction. Throws
  /// IoError (disk full) naming the target path. Does nothing when already closed.
  void close();
  /// close(), then renames the temporary onto path. Throws IoError (disk full, permissions)
  /// naming the target path.
  void commit();
  /// Takes a finished file on the same filesystem as the content instead of what was written:
  /// closes the temporary and renames `finished` onto it (no copy). Throws IoError naming both.
  void adopt(const std::string& finished);
  const std::string& path() const { return path_; }
  const std::string& temporaryPath() const { return tmpPath_; }

 private:
  struct Writer;
  /// Hands the filled buffer to the writer thread (started on the first full buffer).
  void handOver();
  /// Waits until every handed buffer is written, stops the thread; the first error's errno.
  int finishWriter() noexcept;

  std::string path_, tmpPath_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<Writer> writer_;
  int cleanupSlot_ = -1;
  bool renamed_ = false;
};

}  // namespace seamvox
