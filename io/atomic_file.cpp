#include "io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "core/system/errors.h"
#include "io/interrupt_cleanup.h"

namespace seamvox {

/// Buffers filled by the caller and written in order by a thread: at most kBuffers of kBytes.
struct AtomicFile::Writer {
  static constexpr std::size_t kBytes = std::size_t(4) << 20, kBuffers = 3;
  std::vector<char> filling;               // the caller's
  std::deque<std::vector<char>> full;      // handed over, in order
  std::vector<std::vector<char>> empty;    // written, for the caller to fill again
  std::size_t buffers = 1;                 // made so far
  std::mutex mutex;
  std::condition_variable changed;
  bool stop = false, busy = false;
  int error = 0;  // errno of the first failed write; nothing is written after it
  std::thread thread;
};

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), writer_(std::make_unique<Writer>()) {
  tmpPath_ = path_ + ".tmp-" + std::to_string(::getpid());
  cleanupSlot_ = registerTemporary(tmpPath_.c_str());  // before the file exists: no gap
  file_ = std::fopen(tmpPath_.c_str(), "wb");
  if (!file_) {
    const int err = errno;
    unregisterTemporary(cleanupSlot_);
    throw IoError(path_ + ": cannot create output file: " + std::strerror(err) +
                  (err == ENAMETOOLONG ? "" : " (does the folder exist and is it writable?)"));
  }
  std::setvbuf(file_, nullptr, _IONBF, 0);  // the writer's buffers are the buffering
  writer_->filling.reserve(Writer::kBytes);
}

AtomicFile::~AtomicFile() {
  finishWriter();
  if (file_) std::fclose(file_);
  if (!renamed_) std::remove(tmpPath_.c_str());
  unregisterTemporary(cleanupSlot_);
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (!file_) throw IoError(path_ + ": write after the file was closed");
  Writer& w = *writer_;
  const char* from = static_cast<const char*>(data);
  while (bytes > 0) {
    const std::size_t n = std::min(bytes, Writer::kBytes - w.filling.size());
    w.filling.insert(w.filling.end(), from, from + n);
    from += n, bytes -= n;
    if (w.filling.size() == Writer::kBytes) handOver();
  }
}

void AtomicFile::handOver() {
  Writer& w = *writer_;
  std::unique_lock<std::mutex> lock(w.mutex);
  if (w.error != 0) throw IoError(path_ + ": write failed: " + std::strerror(w.error));
  if (!w.thread.joinable()) {
    w.thread = std::thread([&w, file = file_] {
      std::unique_lock<std::mutex> lock(w.mutex);
      for (;;) {
        w.changed.wait(lock, [&] { return !w.full.empty() || w.stop; });
        if (w.full.empty()) return;  // stopped with everything written
        std::vector<char> buffer = std::move(w.full.front());
        w.full.pop_front();
        w.busy = true;
        const bool skip = w.error != 0;
        lock.unlock();
        int error = 0;
        if (!skip && std::fwrite(buffer.data(), 1, buffer.size(), file) != buffer.size()) error = errno ? errno : EIO;
        buffer.clear();
        lock.lock();
        if (error != 0 && w.error == 0) w.error = error;
        w.busy = false;
        w.empty.push_back(std::move(buffer));
        w.changed.notify_all();
      }
    });
  }
  w.full.push_back(std::move(w.filling));
  w.changed.notify_all();
  if (w.empty.empty() && w.buffers < Writer::kBuffers) {
    ++w.buffers;
    w.filling = std::vector<char>();
  } else {
    w.changed.wait(lock, [&] { return !w.empty.empty(); });
    w.filling = std::move(w.empty.back());
    w.empty.pop_back();
  }
  w.filling.reserve(Writer::kBytes);
}

int AtomicFile::finishWriter() noexcept {
  Writer& w = *writer_;
  std::unique_lock<std::mutex> lock(w.mutex);
  w.stop = true;
  w.changed.notify_all();
  lock.unlock();
  if (w.thread.joinable()) w.thread.join();
  lock.lock();
  w.stop = false;  // a later handOver would start a new thread (none comes after close)
  return w.error;
}

void AtomicFile::close() {
  if (!file_) return;
  Writer& w = *writer_;
  int err = finishWriter();
  if (err == 0 && !w.filling.empty() && std::fwrite(w.filling.data(), 1, w.filling.size(), file_) != w.filling.size()) {
    err = errno ? errno : EIO;
  }
  w.filling = std::vector<char>();
  if (err == 0 && (std::fflush(file_) != 0 || std::ferror(file_))) err = errno ? errno : EIO;
  const bool closeFailed = std::fclose(file_) != 0;
  const int closeErr = errno;
  file_ = nullptr;
  if (err != 0 || closeFailed) {
    throw IoError(path_ + ": write failed: " + std::strerror(err != 0 ? err : closeErr) + " (disk full?)");
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
