#include "stream/scratch_folder.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/system/errors.h"
#include "core/system/memory_budget.h"
#include "io/interrupt_cleanup.h"

namespace seamvox {

ScratchFolder::ScratchFolder(const std::string& parent, std::uint64_t neededBytes) : neededBytes_(neededBytes) {
  std::string pattern = (parent.empty() ? std::string(".") : parent) + "/seamvox-scratch-XXXXXX";
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  if (!::mkdtemp(name.data())) {
    throw IoError(parent + ": cannot create a scratch folder there (" + std::strerror(errno) +
                  "); choose another with --scratch DIR");
  }
  path_ = name.data();
  cleanupSlot_ = registerNumberedFolder(path_.c_str(), &files_);
}

ScratchFolder::~ScratchFolder() {
  const std::uint64_t count = files_.load();
  for (std::uint64_t i = 0; i < count; ++i) ::unlink((path_ + "/" + std::to_string(i)).c_str());
  ::rmdir(path_.c_str());
  unregisterNumberedFolder(cleanupSlot_);
}

std::string ScratchFolder::newFilePath() { return path_ + "/" + std::to_string(files_.fetch_add(1)); }

ScratchFile ScratchFolder::zeroFile(std::uint64_t bytes) {
  const std::string path = newFilePath();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw IoError(path + ": cannot create a scratch file (" + std::strerror(errno) + ")");
  const int failed = ::ftruncate(fd, static_cast<off_t>(bytes));
  const int error = errno;
  ::close(fd);
  if (failed != 0) {
    if (error == ENOSPC || error == EDQUOT || error == EFBIG) throwDiskFull(path, bytes, std::strerror(error));
    throw IoError(path + ": cannot size a scratch file (" + std::strerror(error) + ")");
  }
  onDisk_ += bytes;
  peakOnDisk_ = std::max(peakOnDisk_, onDisk_);
  return {path, bytes};
}

void ScratchFolder::remove(const ScratchFile& file) {
  if (file.path.empty()) return;
  std::lock_guard<std::mutex> lock(freeMutex_);
  // Kept: up to 1 GiB and half the bytes in use besides, the smallest given up first.
  free_.push_back(file);
  freeBytes_ += file.bytes;
  const std::uint64_t keep = (std::uint64_t(1) << 30) + (onDisk_ - std::min(onDisk_, freeBytes_)) / 2;
  std::sort(free_.begin(), free_.end(), [](const ScratchFile& a, const ScratchFile& b) { return a.bytes > b.bytes; });
  while (!free_.empty() && (freeBytes_ > keep || free_.back().bytes == 0)) {
    const ScratchFile dropped = free_.back();
    free_.pop_back();
    freeBytes_ -= dropped.bytes;
    if (::unlink(dropped.path.c_str()) == 0) onDisk_ -= std::min(onDisk_, dropped.bytes);
  }
}

ScratchFile ScratchFolder::reuse(std::uint64_t expectedBytes) {
  std::lock_guard<std::mutex> lock(freeMutex_);
  if (free_.empty()) return {};
  // free_ runs from the largest file down. A known size takes the smallest file that holds it,
  // and none when that is over twice the size (a larger writer may come for it).
  auto it = free_.begin();
  while (expectedBytes > 0 && std::next(it) != free_.end() && std::next(it)->bytes >= expectedBytes) ++it;
  if (expectedBytes > 0 && it->bytes > 2 * expectedBytes) return {};
  const ScratchFile file = *it;
  free_.erase(it);
  freeBytes_ -= file.bytes;
  return file;
}

void ScratchFolder::shrink(std::uint64_t bytes) {
  std::lock_guard<std::mutex> lock(freeMutex_);
  onDisk_ -= std::min(onDisk_, bytes);
}

ScratchTraffic& ScratchFolder::stage(const std::string& name) {
  for (ScratchTraffic& t : traffic_) {
    if (t.stage == name) return t;
  }
  traffic_.push_back({name, 0, 0});
  return traffic_.back();
}

void ScratchFolder::countRead(const std::string& name, std::uint64_t bytes) { stage(name).bytesRead += bytes; }

void ScratchFolder::countWrite(const std::string& name, std::uint64_t bytes, std::uint64_t growth) {
  if (written_ + bytes > writeLimit_) throwDiskFull(path_, bytes, "write limit of the test hook");
  stage(name).bytesWritten += bytes;
  written_ += bytes;
  std::lock_guard<std::mutex> lock(freeMutex_);
  onDisk_ += growth;
  peakOnDisk_ = std::max(peakOnDisk_, onDisk_);
}

void ScratchFolder::throwDiskFull(const std::string& file, std::uint64_t failedBytes, const char* reason) const {
  std::string need = neededBytes_ > 0 ? "this run needs about " + formatByteSize(neededBytes_) + " of scratch"
                                      : "a write of " + formatByteSize(failedBytes) + " failed";
  throw IoError("scratch folder " + path_ + " is full (" + reason + ") after " + formatByteSize(written_) +
                " written, at " + file + ": " + need + "; free space there or choose another folder with --scratch DIR");
}

ScratchWriter::ScratchWriter(ScratchFolder& folder, std::string stage, std::size_t bufferBytes, std::uint64_t expectedBytes)
    : folder_(folder), stage_(std::move(stage)), buffer_(std::max<std::size_t>(bufferBytes, 4096)) {
  const ScratchFile old = folder.reuse(expectedBytes);
  if (!old.path.empty()) {
    fd_ = ::open(old.path.c_str(), O_WRONLY | O_CLOEXEC);  // overwritten from the start
    if (fd_ >= 0) {
      path_ = old.path;
      reused_ = old.bytes;
      return;
    }
    folder.shrink(old.bytes);  // gone: not on disk any more
  }
  path_ = folder.newFilePath();
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd_ < 0) throw IoError(path_ + ": cannot create a scratch file (" + std::strerror(errno) + ")");
}

ScratchWriter::~ScratchWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void ScratchWriter::write(const void* data, std::size_t bytes) {
  const char* from = static_cast<const char*>(data);
  while (bytes > 0) {
    if (used_ == buffer_.size()) flush();
    const std::size_t n = std::min(bytes, buffer_.size() - used_);
    std::memcpy(buffer_.data() + used_, from, n);
    used_ += n, from += n, bytes -= n;
  }
}

ScratchFile ScratchWriter::written() {
  flush();
  return ScratchFile{path_, bytes_};
}

void ScratchWriter::flush() {
  if (used_ == 0) return;
  const std::uint64_t end = bytes_ + used_, had = std::max(bytes_, reused_);
  folder_.countWrite(stage_, used_, end > had ? end - had : 0);
  std::size_t done = 0;
  while (done < used_) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, used_ - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == ENOSPC || errno == EDQUOT)) folder_.throwDiskFull(path_, used_ - done, std::strerror(errno));
    if (n < 0) throw IoError(path_ + ": cannot write a scratch file (" + std::strerror(errno) + ")");
    if (n == 0) folder_.throwDiskFull(path_, used_ - done, "short write");
    done += static_cast<std::size_t>(n);
  }
  bytes_ += used_;
  used_ = 0;
}

ScratchFile ScratchWriter::finish() {
  flush();
  if (reused_ > bytes_) {  // the older bytes past this file's end
    if (::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0) {
      throw IoError(path_ + ": cannot truncate a scratch file (" + std::strerror(errno) + ")");
    }
    folder_.shrink(reused_ - bytes_);
    reused_ = bytes_;
  }
  if (::close(fd_) != 0) {
    fd_ = -1;
    if (errno == ENOSPC || errno == EDQUOT) folder_.throwDiskFull(path_, 0, std::strerror(errno));
    throw IoError(path_ + ": cannot close a scratch file (" + std::strerror(errno) + ")");
  }
  fd_ = -1;
  return {path_, bytes_};
}

ScratchReader::ScratchReader(ScratchFolder& folder, const ScratchFile& file, std::string stage, std::size_t bufferBytes)
    : folder_(&folder), stage_(std::move(stage)), path_(file.path),
      buffer_(static_cast<std::size_t>(std::clamp<std::uint64_t>(file.bytes, 64, std::max<std::size_t>(bufferBytes, 64)))),
      left_(file.bytes) {
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path_ + ": cannot open a scratch file (" + std::strerror(errno) + ")");
}

ScratchReader::~ScratchReader() {
  if (fd_ >= 0) ::close(fd_);
}

ScratchReader::ScratchReader(ScratchReader&& other) noexcept
    : folder_(other.folder_), stage_(std::move(other.stage_)), path_(std::move(other.path_)), fd_(other.fd_),
      buffer_(std::move(other.buffer_)), begin_(other.begin_), end_(other.end_), left_(other.left_) {
  other.fd_ = -1;
}

bool ScratchReader::refill() {
  if (begin_ < end_) std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
  end_ -= begin_;
  begin_ = 0;
  const std::size_t wanted = static_cast<std::size_t>(std::min<std::uint64_t>(buffer_.size() - end_, left_));
  if (wanted == 0) return false;
  for (;;) {
    const ssize_t n = ::read(fd_, buffer_.data() + end_, wanted);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw IoError(path_ + ": cannot read a scratch file (" + std::strerror(errno) + ")");
    folder_->countRead(stage_, static_cast<std::uint64_t>(n));
    end_ += static_cast<std::size_t>(n);
    left_ -= static_cast<std::uint64_t>(n);
    return n > 0;
  }
}

bool ScratchReader::read(void* out, std::size_t bytes) {
  char* to = static_cast<char*>(out);
  std::size_t done = 0;
  while (done < bytes) {
    if (begin_ == end_ && !refill()) {
      if (done == 0) return false;
      throw IoError(path_ + ": scratch file ends inside a record (it changed while it was read)");
    }
    const std::size_t n = std::min(bytes - done, end_ - begin_);
    std::memcpy(to + done, buffer_.data() + begin_, n);
    begin_ += n, done += n;
  }
  return true;
}

std::size_t ScratchReader::readUpTo(void* out, std::size_t bytes) {
  if (begin_ == end_ && !refill()) return 0;
  const std::size_t n = std::min(bytes, end_ - begin_);
  std::memcpy(out, buffer_.data() + begin_, n);
  begin_ += n;
  return n;
}

ScratchRandomReader::ScratchRandomReader(ScratchFolder& folder, const ScratchFile& file, std::string stage)
    : folder_(folder), stage_(std::move(stage)), path_(file.path) {
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path_ + ": cannot open a scratch file (" + std::strerror(errno) + ")");
}

ScratchRandomReader::~ScratchRandomReader() {
  if (fd_ >= 0) ::close(fd_);
}

void readScratchAt(int fd, const std::string& path, std::uint64_t offset, void* out, std::size_t bytes) {
  char* to = static_cast<char*>(out);
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pread(fd, to + done, bytes - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw IoError(path + ": cannot read a scratch file (" + std::strerror(errno) + ")");
    if (n == 0) throw IoError(path + ": scratch file ends inside a record (it changed while it was read)");
    done += static_cast<std::size_t>(n);
  }
}

void ScratchRandomReader::readAt(std::uint64_t offset, void* out, std::size_t bytes) {
  readScratchAt(fd_, path_, offset, out, bytes);
  folder_.countRead(stage_, bytes);
}

ScratchUpdater::ScratchUpdater(ScratchFolder& folder, const ScratchFile& file, std::string stage)
    : folder_(folder), stage_(std::move(stage)), path_(file.path), bytes_(file.bytes) {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path_ + ": cannot open a scratch file (" + std::strerror(errno) + ")");
}

ScratchUpdater::~ScratchUpdater() {
  if (fd_ >= 0) ::close(fd_);
}

void ScratchUpdater::readAt(std::uint64_t offset, void* out, std::size_t bytes) {
  readScratchAt(fd_, path_, offset, out, bytes);
  folder_.countRead(stage_, bytes);
}

void ScratchUpdater::writeAt(std::uint64_t offset, const void* data, std::size_t bytes) {
  if (offset + bytes > bytes_) throw IoError(path_ + ": a write in place past the end of a scratch file");
  folder_.countWrite(stage_, bytes, 0);  // in place: the file does not grow
  const char* from = static_cast<const char*>(data);
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pwrite(fd_, from + done, bytes - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == ENOSPC || errno == EDQUOT)) folder_.throwDiskFull(path_, bytes - done, std::strerror(errno));
    if (n < 0) throw IoError(path_ + ": cannot write a scratch file (" + std::strerror(errno) + ")");
    if (n == 0) folder_.throwDiskFull(path_, bytes - done, "short write");
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace seamvox
