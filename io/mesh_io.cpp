#include "io/mesh_io.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/detail_mesh_io.h"

namespace seamvox {
namespace detail {

namespace {

/// What a path that is neither a regular file nor a pipe is, for messages.
const char* describeNonFile(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device (like /dev/zero or a terminal)";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

[[noreturn]] void throwNotAFile(const std::string& path, mode_t mode) {
  throw IoError(path + ": is " + describeNonFile(mode) +
                ", not a mesh file (seamvox reads regular files and pipes)");
}

/// Waits until a pipe opened without blocking has data or was closed by its writer.
void waitForWriter(int fd, const std::string& path, double seconds) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(std::max(seconds, 0.0)));
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    pollfd request{fd, POLLIN, 0};
    const int ready = ::poll(&request, 1, static_cast<int>(std::max<std::int64_t>(left.count(), 0)));
    if (ready > 0) return;  // data, or the writer closed its end
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) throw IoError(path + ": cannot wait for the pipe: " + std::strerror(errno));
    char waited[32];
    std::snprintf(waited, sizeof waited, "%g", seconds);
    throw IoError(path + ": is a pipe and nothing was written to it within " + waited +
                  " s (is a writer running?)");
  }
}

}  // namespace

InputFile::InputFile(std::string path, double pipeWaitSeconds) : path_(std::move(path)) {
  // Checked before opening: opening a device can block or have side effects.
  struct stat info {};
  if (::stat(path_.c_str(), &info) != 0) {
    throw IoError(path_ + ": cannot open: " + std::strerror(errno));
  }
  if (!S_ISREG(info.st_mode) && !S_ISFIFO(info.st_mode)) throwNotAFile(path_, info.st_mode);
  // Without O_NONBLOCK, opening a FIFO waits for a writer forever.
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) throw IoError(path_ + ": cannot open: " + std::strerror(errno));
  try {
    if (::fstat(fd_, &info) != 0) throw IoError(path_ + ": cannot open: " + std::strerror(errno));
    if (!S_ISREG(info.st_mode) && !S_ISFIFO(info.st_mode)) throwNotAFile(path_, info.st_mode);
    regular_ = S_ISREG(info.st_mode);
    if (!regular_) waitForWriter(fd_, path_, pipeWaitSeconds);
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags < 0 || ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK) != 0) {
      throw IoError(path_ + ": cannot open: " + std::strerror(errno));
    }
  } catch (...) {
    ::close(fd_);
    throw;
  }
  size_ = regular_ ? static_cast<std::uint64_t>(info.st_size) : std::numeric_limits<std::uint64_t>::max();
  modifiedSeconds_ = info.st_mtim.tv_sec;
  modifiedNanoseconds_ = info.st_mtim.tv_nsec;
  buffer_.resize(static_cast<std::size_t>(std::clamp<std::uint64_t>(size_, 4096, std::uint64_t(1) << 22)));
}

InputFile::~InputFile() { ::close(fd_); }

std::size_t InputFile::readSome(char* into, std::size_t n) {
  for (;;) {
    const ssize_t got = ::read(fd_, into, n);
    if (got >= 0) {
      checkUnchanged();
      return static_cast<std::size_t>(got);
    }
    if (errno != EINTR) throw IoError(path_ + ": read failed: " + std::strerror(errno));
  }
}

void InputFile::checkUnchanged() const {
  if (!regular_) return;
  struct stat info {};
  if (::fstat(fd_, &info) != 0) throw IoError(path_ + ": cannot check the file: " + std::strerror(errno));
  if (static_cast<std::uint64_t>(info.st_size) == size_ && info.st_mtim.tv_sec == modifiedSeconds_ &&
      info.st_mtim.tv_nsec == modifiedNanoseconds_) {
    return;
  }
  throw IoError(path_ + ": the file changed while it was read (" +
                (static_cast<std::uint64_t>(info.st_size) != size_
                     ? "its size went from " + std::to_string(size_) + " to " + std::to_string(info.st_size) + " bytes"
                     : std::string("it was modified")) +
                "); nothing was written: run again once it is complete");
}

bool InputFile::refill(std::size_t n) {
  // Never grow the buffer beyond what the file can still deliver (absurd counts in headers).
  if (n > remaining()) return false;
  if (!regular_ && n > kMaxStreamBytes) {
    throw IoError(path_ + ": needs " + std::to_string(n) + " bytes at once from a pipe, more than the " +
                  std::to_string(kMaxStreamBytes >> 30) + " GiB limit for pipes");
  }
  if (pos_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + pos_, end_ - pos_);
    consumed_ += pos_;
    end_ -= pos_;
    pos_ = 0;
  }
  // A file holds the bytes asked for; a pipe's buffer only grows as its data arrives.
  if (regular_ && buffer_.size() < n) buffer_.resize(std::max(n, 2 * buffer_.size()));
  while (end_ < n) {
    if (end_ == buffer_.size()) {
      buffer_.resize(std::max<std::size_t>(n, std::min<std::uint64_t>(2 * buffer_.size(), kMaxStreamBytes)));
    }
    const std::size_t got = readSome(buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) return false;
    end_ += got;
  }
  return true;
}

bool InputFile::skip(std::uint64_t n) {
  const std::size_t inBuffer = end_ - pos_;
  if (n <= inBuffer) {
    pos_ += static_cast<std::size_t>(n);
    return true;
  }
  if (n > remaining()) return false;
  n -= inBuffer;
  consumed_ += end_;
  pos_ = end_ = 0;
  if (regular_) {
    if (::lseek(fd_, static_cast<off_t>(n), SEEK_CUR) < 0) {
      throw IoError(path_ + ": seek failed: " + std::strerror(errno));
    }
    consumed_ += n;
    return true;
  }
  while (n > 0) {  // a pipe cannot seek: read and drop
    const std::size_t got = readSome(buffer_.data(), static_cast<std::size_t>(std::min<std::uint64_t>(n, buffer_.size())));
    if (got == 0) return false;
    consumed_ += got;
    n -= got;
  }
  return true;
}

std::size_t InputFile::readToEnd() {
  if (regular_) {
    if (!ensure(static_cast<std::size_t>(remaining()))) {
      throw IoError(path_ + ": the file ended before its " + std::to_string(size_) +
                    " bytes were read (did it change while being read?)");
    }
    return end_ - pos_;
  }
  for (;;) {
    if (end_ - pos_ >= kMaxStreamBytes) {
      throw IoError(path_ + ": the pipe delivers more than the " + std::to_string(kMaxStreamBytes >> 30) +
                    " GiB limit for pipes");
    }
    if (!refill(end_ - pos_ + 1)) return end_ - pos_;
  }
}

bool InputFile::skipByteOrderMark() {
  if (!ensure(3) || std::memcmp(data(), "\xEF\xBB\xBF", 3) != 0) return false;
  advance(3);
  return true;
}

void InputFile::detectLineEnd() {
  if (offset() == 0) skipByteOrderMark();
  // A lone '\r' before any '\n' in the first 64 KB: lines end in '\r' (classic Mac OS).
  constexpr std::size_t kLook = std::size_t(1) << 16;
  while (end_ - pos_ < kLook && refill(end_ - pos_ + 1)) {
  }
  const std::string_view head(buffer_.data() + pos_, std::min(end_ - pos_, kLook));
  const std::size_t first = head.find_first_of("\r\n");
  const bool loneCR = first != std::string_view::npos && head[first] == '\r' &&
                      first + 1 < end_ - pos_ && buffer_[pos_ + first + 1] != '\n';
  lineEnd_ = loneCR ? '\r' : '\n';
}

bool InputFile::readLine(std::string_view& line, std::size_t maxLength) {
  if (!lineEnd_) detectLineEnd();
  std::size_t scanFrom = pos_;
  for (;;) {
    const void* found = std::memchr(buffer_.data() + scanFrom, lineEnd_, end_ - scanFrom);
    std::size_t lineEnd = 0, next = 0;
    if (found) {
      lineEnd = static_cast<std::size_t>(static_cast<const char*>(found) - buffer_.data());
      next = lineEnd + 1;
    } else if (end_ - pos_ > maxLength) {
      throw InputError(path_ + ": line " + std::to_string(line_ + 1) + ": line is too long (over " +
                       std::to_string(maxLength) + " bytes)");
    } else {
      const std::size_t scanned = end_ - pos_;
      if (refill(scanned + 1)) {
        scanFrom = pos_ + scanned;
        continue;
      }
      // refill() may have moved the partial line to the front before finding the end of file.
      if (pos_ == end_) return false;
      lineEnd = next = end_;
    }
    if (lineEnd - pos_ > maxLength) {
      throw InputError(path_ + ": line " + std::to_string(line_ + 1) + ": line is too long (over " +
                       std::to_string(maxLength) + " bytes)");
    }
    line = std::string_view(buffer_.data() + pos_, lineEnd - pos_);
    // "\r\n" ends a line in either mode (a CR file may mix them in).
    if (lineEnd_ == '\n' && !line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (lineEnd_ == '\r' && !line.empty() && line.front() == '\n') line.remove_prefix(1);
    pos_ = next;
    ++line_;
    return true;
  }
}

void warn(const WarningFn& warn, const std::string& message) {
  if (warn) warn(message);
  else std::fprintf(stderr, "seamvox: warning: %s\n", message.c_str());
}

namespace {

/// Positions of the named properties when all are present with one type (floating if asked).
std::vector<std::size_t> propertyGroup(const VertexAttributes& attributes,
                                       std::initializer_list<const char*> names, bool floating) {
  std::vector<std::size_t> out;
  for (const char* name : names) {
    const VertexProperty* p = attributes.find(name);
    if (!p || p->type != attributes.find(*names.begin())->type || (floating && !isFloatingType(p->type))) {
      return {};
    }
    out.push_back(static_cast<std::size_t>(p - attributes.properties.data()));
  }
  return out;
}

}  // namespace

std::vector<std::size_t> colorProperties(const VertexAttributes& attributes) {
  std::vector<std::size_t> rgba = propertyGroup(attributes, {"red", "green", "blue", "alpha"}, false);
  return rgba.empty() ? propertyGroup(attributes, {"red", "green", "blue"}, false) : rgba;
}

std::vector<std::size_t> normalProperties(const VertexAttributes& attributes) {
  return propertyGroup(attributes, {"nx", "ny", "nz"}, true);
}

double normalizedColor(const VertexProperty& property, VertexId v) {
  static constexpr double kLargest[] = {127.0, 255.0, 32767.0, 65535.0, 2147483647.0, 4294967295.0, 1.0, 1.0};
  return std::clamp(property.value(v) / kLargest[static_cast<int>(property.type)], 0.0, 1.0);
}

}  // namespace detail

std::vector<std::string> droppedVertexProperties(const TriangleMesh& mesh, MeshFormat format) {
  std::vector<std::string> dropped;
  const std::vector<VertexProperty>& properties = mesh.attributes.properties;
  if (format == MeshFormat::Obj || format == MeshFormat::Off) {
    const std::vector<std::size_t> kept =
        format == MeshFormat::Obj ? detail::colorProperties(mesh.attributes) : std::vector<std::size_t>{};
    for (std::size_t i = 0; i < properties.size(); ++i) {
      // OBJ's `v x y z r g b` has no alpha.
      const bool written = std::find(kept.begin(), kept.end(), i) != kept.end() && properties[i].name != "alpha";
      if (!written) dropped.push_back(properties[i].name);
    }
  }
  return dropped;
}

MeshFormat formatFromPath(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) {
    return MeshFormat::Unknown;
  }
  std::string extension = path.substr(dot + 1);
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == "ply") return MeshFormat::Ply;
  if (extension == "obj") return MeshFormat::Obj;
  if (extension == "off") return MeshFormat::Off;
  if (extension == "drc") return MeshFormat::Draco;
  if (extension == "stl") return MeshFormat::Stl;
  return MeshFormat::Unknown;
}

bool isWritableFormat(MeshFormat format) { return format != MeshFormat::Unknown && format != MeshFormat::Stl; }

namespace {

[[noreturn]] void throwUnknownFormat(const std::string& path) {
  throw IoError(path + ": unknown mesh format (the extension must be .ply, .obj, .off, .drc or, to read, .stl)");
}

/// Before anything is written: a known format that can be written.
void checkOutputFormat(const std::string& path) {
  const MeshFormat format = formatFromPath(path);
  if (format == MeshFormat::Stl) {
    throw IoError(path + ": STL is read, not written (it holds no texture coordinates and no shared vertices): "
                         "write .ply, .obj, .off or .drc");
  }
  if (format == MeshFormat::Unknown) throwUnknownFormat(path);
}

}  // namespace

std::unique_ptr<MeshStream> openMeshStream(const std::string& path, const ReadOptions& options) {
  const MeshFormat format = formatFromPath(path);
  if (format == MeshFormat::Unknown) throwUnknownFormat(path);
  if (format == MeshFormat::Draco) {
    auto mesh = std::make_shared<const TriangleMesh>(detail::readDraco(path, options));
    return makeMemoryStream(path, std::move(mesh), options.chunkTriangles);
  }
  auto in = std::make_unique<detail::InputFile>(path, options.pipeWaitSeconds);
  switch (format) {
    case MeshFormat::Ply: return detail::openPlyStream(std::move(in), options);
    case MeshFormat::Obj: return detail::openObjStream(std::move(in), options);
    case MeshFormat::Stl: return detail::openStlStream(std::move(in), options);
    default: return detail::openOffStream(std::move(in), options);
  }
}

TriangleMesh readMesh(const std::string& path, const ReadOptions& options) {
  return readMesh(*openMeshStream(path, options));
}

TriangleMesh readMesh(MeshStream& stream) {
  TriangleMesh mesh = collectMesh(stream);
  if (mesh.triangles.empty()) throw InputError(stream.name() + ": the mesh has no faces");
  return mesh;
}

namespace {

/// Rejects meshes a writer would turn into an invalid file.
void checkWritable(const std::string& path, const TriangleMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (const VertexId v : mesh.triangles[f]) {
      if (v >= n) {
        throw InputError(path + ": cannot write: face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(v) + " but the mesh has " + std::to_string(n) + " vertices");
      }
    }
  }
  try {
    mesh.attributes.checkSize(n);
  } catch (const InputError& e) {
    throw InputError(path + ": cannot write: " + e.what());
  }
  if (mesh.hasUV() && mesh.cornerUV.size() != 3 * mesh.triangles.size()) {
    throw InputError(path + ": cannot write: the mesh has " + std::to_string(mesh.cornerUV.size()) +
                     " corner UVs for " + std::to_string(mesh.triangles.size()) +
                     " faces (3 per face expected)");
  }
}

}  // namespace

void writeMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options) {
  checkOutputFormat(path);  // before a file
  AtomicFile file(path);
  writeMesh(file, mesh, options);
  file.commit();
}

void writeMesh(AtomicFile& file, TriangleMesh&& mesh, const WriteOptions& options) {
  if (formatFromPath(file.path()) != MeshFormat::Draco) {
    writeMesh(file, static_cast<const TriangleMesh&>(mesh), options);
    mesh = TriangleMesh();
    return;
  }
  checkWritable(file.path(), mesh);
  detail::writeDraco(file, std::move(mesh), options);
}

void writeMesh(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  const std::string& path = file.path();
  checkOutputFormat(path);
  const MeshFormat format = formatFromPath(path);
  checkWritable(path, mesh);
  const std::vector<std::string> dropped = droppedVertexProperties(mesh, format);
  if (!dropped.empty()) {
    std::string names;
    for (const std::string& name : dropped) names += (names.empty() ? "" : ", ") + name;
    detail::warn(options.warn, path + ": the format cannot hold the vertex properties " + names +
                                   ": they are not written");
  }
  switch (format) {
    case MeshFormat::Ply: detail::writePly(file, mesh, options); break;
    case MeshFormat::Obj: detail::writeObj(file, mesh, options); break;
    case MeshFormat::Off: detail::writeOff(file, mesh, options); break;
    default: detail::writeDraco(file, mesh, options); break;
  }
}

}  // namespace seamvox
