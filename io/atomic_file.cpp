#include "io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/system/errors.h"

namespace seamvox {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  tmpPath_ = path_ + ".tmp-" + std::to_string(::getpid());
  file_ = std::fopen(tmpPath_.c_str(), "wb");
  if (!file_) {
    throw IoError(path_ + ": cannot create output file: " + std::strerror(errno) +
                  " (does the folder exist and is it writable?)");
  }
  constexpr std::size_t kBufferBytes = 1 << 20;
  buffer_ = std::make_unique<char[]>(kBufferBytes);
  std::setvbuf(file_, buffer_.get(), _IOFBF, kBufferBytes);
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::remove(tmpPath_.c_str());
  }
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (bytes && std::fwrite(data, 1, bytes, file_) != bytes) {
    throw IoError(path_ + ": write failed: " + std::strerror(errno));
  }
}

void AtomicFile::commit() {
  const bool failed = std::fflush(file_) != 0 || std::ferror(file_);
  const int err = errno;
  const bool closeFailed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed || closeFailed) {
    std::remove(tmpPath_.c_str());
    throw IoError(path_ + ": write failed: " + std::strerror(err) + " (disk full?)");
  }
  if (std::rename(tmpPath_.c_str(), path_.c_str()) != 0) {
    const int renameErr = errno;
    std::remove(tmpPath_.c_str());
    throw IoError(path_ + ": cannot move the finished output into place: " + std::strerror(renameErr));
  }
}

}  // namespace seamvox
