#include "io/mesh_io.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/detail_mesh_io.h"

namespace seamvox {
namespace detail {

InputFile::InputFile(std::string path) : path_(std::move(path)) {
  struct stat info {};
  if (::stat(path_.c_str(), &info) != 0) {
    throw IoError(path_ + ": cannot open: " + std::strerror(errno));
  }
  if (S_ISDIR(info.st_mode)) throw IoError(path_ + ": is a folder, not a mesh file");
  file_ = std::fopen(path_.c_str(), "rb");
  if (!file_) throw IoError(path_ + ": cannot open: " + std::strerror(errno));
  size_ = S_ISREG(info.st_mode) ? static_cast<std::uint64_t>(info.st_size)
                                : std::numeric_limits<std::uint64_t>::max();
  buffer_.resize(std::size_t(1) << 22);
}

InputFile::~InputFile() {
  if (file_) std::fclose(file_);
}

bool InputFile::refill(std::size_t n) {
  // Never grow the buffer beyond what the file can still deliver (absurd counts in headers).
  if (n > remaining()) return false;
  if (pos_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + pos_, end_ - pos_);
    consumed_ += pos_;
    end_ -= pos_;
    pos_ = 0;
  }
  if (buffer_.size() < n) buffer_.resize(std::max(n, 2 * buffer_.size()));
  while (end_ < n) {
    const std::size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    if (got == 0) {
      if (std::ferror(file_)) throw IoError(path_ + ": read failed: " + std::strerror(errno));
      return false;
    }
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
  if (std::fseek(file_, static_cast<long>(n), SEEK_CUR) != 0) {
    throw IoError(path_ + ": seek failed: " + std::strerror(errno));
  }
  consumed_ += n;
  return true;
}

bool InputFile::readLine(std::string_view& line, std::size_t maxLength) {
  std::size_t scanFrom = pos_;
  for (;;) {
    const void* found = std::memchr(buffer_.data() + scanFrom, '\n', end_ - scanFrom);
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
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = next;
    ++line_;
    return true;
  }
}

}  // namespace detail

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
  return MeshFormat::Unknown;
}

namespace {

[[noreturn]] void throwUnknownFormat(const std::string& path) {
  throw IoError(path + ": unknown mesh format (the extension must be .ply, .obj, .off or .drc)");
}

}  // namespace

std::unique_ptr<MeshStream> openMeshStream(const std::string& path, const ReadOptions& options) {
  const MeshFormat format = formatFromPath(path);
  if (format == MeshFormat::Unknown) throwUnknownFormat(path);
  if (format == MeshFormat::Draco) {
    auto mesh = std::make_shared<const TriangleMesh>(detail::readDraco(path, options));
    return makeMemoryStream(path, std::move(mesh), options.chunkTriangles);
  }
  auto in = std::make_unique<detail::InputFile>(path);
  switch (format) {
    case MeshFormat::Ply: return detail::openPlyStream(std::move(in), options);
    case MeshFormat::Obj: return detail::openObjStream(std::move(in), options);
    default: return detail::openOffStream(std::move(in), options);
  }
}

TriangleMesh readMesh(const std::string& path, const ReadOptions& options) {
  const std::unique_ptr<MeshStream> stream = openMeshStream(path, options);
  TriangleMesh mesh = collectMesh(*stream);
  if (mesh.triangles.empty()) throw InputError(path + ": the mesh has no faces");
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
  if (mesh.hasUV() && mesh.cornerUV.size() != 3 * mesh.triangles.size()) {
    throw InputError(path + ": cannot write: the mesh has " + std::to_string(mesh.cornerUV.size()) +
                     " corner UVs for " + std::to_string(mesh.triangles.size()) +
                     " faces (3 per face expected)");
  }
}

}  // namespace

void writeMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options) {
  if (formatFromPath(path) == MeshFormat::Unknown) throwUnknownFormat(path);  // before a file
  AtomicFile file(path);
  writeMesh(file, mesh, options);
  file.commit();
}

void writeMesh(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  const std::string& path = file.path();
  const MeshFormat format = formatFromPath(path);
  if (format == MeshFormat::Unknown) throwUnknownFormat(path);
  checkWritable(path, mesh);
  switch (format) {
    case MeshFormat::Ply: detail::writePly(file, mesh, options); break;
    case MeshFormat::Obj: detail::writeObj(file, mesh, options); break;
    case MeshFormat::Off: detail::writeOff(file, mesh, options); break;
    default: detail::writeDraco(file, mesh, options); break;
  }
}

}  // namespace seamvox
