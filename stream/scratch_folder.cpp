#include "stream/scratch_folder.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <thread>

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

namespace {

/// Whether this process still has the file open: a reader alive after the file's removal keeps
/// reading it (as an unlinked file) and must not see another writer's bytes. Unknown: true.
bool openInThisProcess(const std::string& path) {
  struct stat target {};
  if (::stat(path.c_str(), &target) != 0) return false;
  DIR* dir = ::opendir("/proc/self/fd");
  if (!dir) return true;
  bool open = false;
  while (const dirent* entry = ::readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    struct stat s {};
    if (::fstat(std::atoi(entry->d_name), &s) == 0 && s.st_ino == target.st_ino && s.st_dev == target.st_dev) {
      open = true;
      break;
    }
  }
  ::closedir(dir);
  return open;
}

}  // namespace

void ScratchFolder::remove(const ScratchFile& file) {
  if (file.path.empty()) return;
  const bool unlinkNow = file.bytes == 0 || openInThisProcess(file.path);  // open: as its readers expect
  std::lock_guard<std::mutex> lock(freeMutex_);
  auto unlinkFile = [&](const ScratchFile& f) {
    if (::unlink(f.path.c_str()) == 0) onDisk_ -= std::min(onDisk_, f.bytes);
  };
  if (unlinkNow) return unlinkFile(file);
  // Kept: up to 1 GiB and half the bytes in use besides, the smallest given up first.
  free_.push_back(file);
  freeBytes_ += file.bytes;
  const std::uint64_t keep = (std::uint64_t(1) << 30) + (onDisk_ - std::min(onDisk_, freeBytes_)) / 2;
  std::sort(free_.begin(), free_.end(), [](const ScratchFile& a, const ScratchFile& b) { return a.bytes > b.bytes; });
  while (freeBytes_ > keep) {
    freeBytes_ -= free_.back().bytes;
    unlinkFile(free_.back());
    free_.pop_back();
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

void ScratchFolder::countRead(const std::string& name, std::uint64_t bytes) {
  std::lock_guard<std::mutex> lock(trafficMutex_);  // a sort's merge reads on a thread of its own
  stage(name).bytesRead += bytes;
}

void ScratchFolder::countWrite(const std::string& name, std::uint64_t bytes, std::uint64_t growth) {
  {
    std::lock_guard<std::mutex> lock(trafficMutex_);
    if (written_ + bytes > writeLimit_) throwDiskFull(path_, bytes, "write limit of the test hook");
    stage(name).bytesWritten += bytes;
    written_ += bytes;
  }
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

namespace detail {

/// A read or write of one buffer at an offset, done by the scratch I/O thread.
struct ScratchIoRequest {
  int fd = -1;
  char* data = nullptr;
  std::size_t bytes = 0;
  std::uint64_t offset = 0;
  bool write = false;
  // Set by the I/O thread:
  std::size_t done = 0;     ///< bytes read (fewer at the end of the file) or written
  int error = 0;            ///< errno of a failed call
  bool shortWrite = false;  ///< a write call that wrote nothing (a full disk)
  bool finished = false;
};

}  // namespace detail

namespace {

using detail::ScratchIoRequest;

/// One thread for every reader's and writer's system calls, in the order they are handed over:
/// the passes are mostly one thread each, so their kernel copies run on the other core.
class ScratchIoThread {
 public:
  /// Never destroyed: the thread waits for work until the process ends (a forked child, which
  /// has no such thread, does its reads and writes itself).
  static ScratchIoThread& instance() {
    static ScratchIoThread* thread = new ScratchIoThread;
    return *thread;
  }
  void submit(const std::shared_ptr<ScratchIoRequest>& request) {
    if (::getpid() != pid_) {  // a forked child has no I/O thread: done here
      perform(*request);
      request->finished = true;
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(request);
    }
    work_.notify_one();
  }
  void wait(const ScratchIoRequest& request) {
    if (::getpid() != pid_) return;  // done in submit
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return request.finished; });
  }

 private:
  ScratchIoThread() : pid_(::getpid()), thread_([this] { run(); }) {}
  void run() {
    for (;;) {
      std::shared_ptr<ScratchIoRequest> request;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        work_.wait(lock, [&] { return !queue_.empty(); });
        request = std::move(queue_.front());
        queue_.pop_front();
      }
      perform(*request);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        request->finished = true;
      }
      done_.notify_all();
    }
  }
  static void perform(ScratchIoRequest& r) {
    while (r.done < r.bytes) {
      const off_t at = static_cast<off_t>(r.offset + r.done);
      const ssize_t n = r.write ? ::pwrite(r.fd, r.data + r.done, r.bytes - r.done, at)
                                : ::pread(r.fd, r.data + r.done, r.bytes - r.done, at);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        r.error = errno;
        return;
      }
      if (n == 0) {  // the end of the file, or a disk that took nothing
        r.shortWrite = r.write;
        return;
      }
      r.done += static_cast<std::size_t>(n);
    }
  }

  std::mutex mutex_;
  std::condition_variable work_, done_;
  std::deque<std::shared_ptr<ScratchIoRequest>> queue_;
  pid_t pid_;  ///< the process the thread runs in
  std::thread thread_;
};

std::shared_ptr<ScratchIoRequest> submitIo(int fd, char* data, std::size_t bytes, std::uint64_t offset, bool write) {
  auto request = std::make_shared<ScratchIoRequest>();
  request->fd = fd;
  request->data = data;
  request->bytes = bytes;
  request->offset = offset;
  request->write = write;
  ScratchIoThread::instance().submit(request);
  return request;
}

/// Half of a buffer size, at least minimum.
std::size_t halfBuffer(std::size_t bytes, std::size_t minimum) { return std::max<std::size_t>(bytes / 2, minimum); }

}  // namespace

ScratchWriter::ScratchWriter(ScratchFolder& folder, std::string stage, std::size_t bufferBytes, std::uint64_t expectedBytes)
    : folder_(folder), stage_(std::move(stage)) {
  for (std::vector<char>& buffer : buffers_) buffer.resize(halfBuffer(bufferBytes, 4096));
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
  if (pending_) ScratchIoThread::instance().wait(*pending_);
  if (fd_ >= 0) ::close(fd_);
}

void ScratchWriter::write(const void* data, std::size_t bytes) {
  const char* from = static_cast<const char*>(data);
  while (bytes > 0) {
    if (used_ == buffers_[current_].size()) flush();
    const std::size_t n = std::min(bytes, buffers_[current_].size() - used_);
    std::memcpy(buffers_[current_].data() + used_, from, n);
    used_ += n, from += n, bytes -= n;
  }
}

ScratchFile ScratchWriter::written() {
  flush();
  settle();
  return ScratchFile{path_, bytes_};
}

void ScratchWriter::settle() {
  if (!pending_) return;
  ScratchIoThread::instance().wait(*pending_);
  const std::shared_ptr<ScratchIoRequest> r = std::move(pending_);
  pending_.reset();
  const std::size_t left = r->bytes - r->done;
  if (r->error == ENOSPC || r->error == EDQUOT) folder_.throwDiskFull(path_, left, std::strerror(r->error));
  if (r->error != 0) throw IoError(path_ + ": cannot write a scratch file (" + std::strerror(r->error) + ")");
  if (r->shortWrite) folder_.throwDiskFull(path_, left, "short write");
}

void ScratchWriter::flush() {
  if (used_ == 0) return;
  const std::uint64_t end = bytes_ + used_, had = std::max(bytes_, reused_);
  folder_.countWrite(stage_, used_, end > had ? end - had : 0);
  settle();  // the other buffer is free again
  pending_ = submitIo(fd_, buffers_[current_].data(), used_, bytes_, true);
  bytes_ += used_;
  used_ = 0;
  current_ ^= 1;
}

ScratchFile ScratchWriter::finish() {
  flush();
  settle();
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
    : folder_(&folder), stage_(std::move(stage)), path_(file.path), bytes_(file.bytes) {
  const std::size_t half = static_cast<std::size_t>(std::clamp<std::uint64_t>(file.bytes, 32, halfBuffer(bufferBytes, 32)));
  buffers_[0].resize(half);
  buffers_[1].resize(file.bytes > half ? half : 0);  // a file that fits one buffer needs no second
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path_ + ": cannot open a scratch file (" + std::strerror(errno) + ")");
  current_ = 1;  // the first read goes into buffer 0
  requestNext();
}

ScratchReader::~ScratchReader() {
  if (pending_) ScratchIoThread::instance().wait(*pending_);
  if (fd_ >= 0) ::close(fd_);
}

ScratchReader::ScratchReader(ScratchReader&& other) noexcept
    : folder_(other.folder_), stage_(std::move(other.stage_)), path_(std::move(other.path_)), fd_(other.fd_),
      buffers_{std::move(other.buffers_[0]), std::move(other.buffers_[1])}, current_(other.current_),
      pending_(std::move(other.pending_)), begin_(other.begin_), end_(other.end_), requested_(other.requested_),
      bytes_(other.bytes_) {
  other.fd_ = -1;
  other.pending_.reset();
}

void ScratchReader::requestNext() {
  // Into the buffer not being read (current_ is the one the caller has finished).
  const int next = current_ ^ 1;
  const std::size_t bytes = static_cast<std::size_t>(std::min<std::uint64_t>(buffers_[next].size(), bytes_ - requested_));
  if (bytes == 0) return;
  pending_ = submitIo(fd_, buffers_[next].data(), bytes, requested_, false);
  requested_ += bytes;
}

bool ScratchReader::refill() {
  if (!pending_) return false;
  ScratchIoThread::instance().wait(*pending_);
  const std::shared_ptr<ScratchIoRequest> r = std::move(pending_);
  pending_.reset();
  if (r->error != 0) throw IoError(path_ + ": cannot read a scratch file (" + std::strerror(r->error) + ")");
  folder_->countRead(stage_, r->done);
  current_ ^= 1;
  begin_ = 0;
  end_ = r->done;
  if (r->done < r->bytes) {
    requested_ = bytes_;  // the file ends early (it changed): nothing more to read
  } else {
    if (buffers_[current_ ^ 1].empty()) buffers_[current_ ^ 1].resize(buffers_[current_].size());
    requestNext();
  }
  return end_ > 0;
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
    std::memcpy(to + done, buffers_[current_].data() + begin_, n);
    begin_ += n, done += n;
  }
  return true;
}

std::size_t ScratchReader::readUpTo(void* out, std::size_t bytes) {
  if (begin_ == end_ && !refill()) return 0;
  const std::size_t n = std::min(bytes, end_ - begin_);
  std::memcpy(out, buffers_[current_].data() + begin_, n);
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
