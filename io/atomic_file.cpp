#include "io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/system/errors.h"
#include "io/interrupt_cleanup.h"

namespace seamvox {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  tmpPath_ = path_ + ".tmp-" + std::to_string(::getpid());
  cleanupSlot_ = registerTemporary(tmpPath_.c_str());  // before the file exists: no gap
  file_ = std::fopen(tmpPath_.c_str(), "wb");
  if (!file_) {
    const int err = errno;
    unregisterTemporary(cleanupSlot_);
    throw IoError(path_ + ": cannot create output file: " + std::strerror(err) +
                  (err == ENAMETOOLONG ? "" : " (does the folder exist and is it writable?)"));
  }
  constexpr std::size_t kBufferBytes = 1 << 20;
  buffer_ = std::make_unique<char[]>(kBufferBytes);
  std::setvbuf(file_, buffer_.get(), _IOFBF, kBufferBytes);
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!renamed_) std::remove(tmpPath_.c_str());
  unregisterTemporary(cleanupSlot_);
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (!file_) throw IoError(path_ + ": write after the file was closed");
  if (bytes && std::fwrite(data, 1, bytes, file_) != bytes) {
    throw IoError(path_ + ": write failed: " + std::strerror(errno));
  }
}

void AtomicFile::close() {
  if (!file_) return;
  const bool failed = std::fflush(file_) != 0 || std::ferror(file_);
  const int err = errno;
  const bool closeFailed = std::fclose(file_) != 0;
  const int closeErr = errno;
  file_ = nullptr;
  if (failed || closeFailed) {
    throw IoError(path_ + ": write failed: " + std::strerror(failed ? err : closeErr) + " (disk full?)");
  }
}

void AtomicFile::adopt(const std::string& finished) {
  close();
  if (std::rename(finished.c_str(), tmpPath_.c_str()) != 0) {
    throw IoError(path_ + ": cannot take " + finished + " as its content: " + std::strerror(errno));
  }
}

void AtomicFile::commit() {
  close();
  if (std::rename(tmpPath_.c_str(), path_.c_str()) != 0) {
    throw IoError(path_ + ": cannot move the finished output into place: " + std::strerror(errno));
  }
  renamed_ = true;
  unregisterTemporary(cleanupSlot_);
  cleanupSlot_ = -1;
}

}  // namespace seamvox
