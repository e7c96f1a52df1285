#pragma once
/// Private pieces shared by the mesh readers and writers (io/*_io.cpp): buffered file input,
/// token parsing, buffered output, and the per-format entry points. Not part of the public API.
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/mesh/mesh.h"
#include "io/atomic_file.h"
#include "io/mesh_io.h"
#include "stream/mesh_stream.h"

namespace seamvox::detail {

/// A file read through one large buffer: binary blocks (ensure/data/advance) and text lines.
/// Regular files and pipes (named FIFOs, /dev/stdin when piped) are read; a pipe is read as a
/// stream of unknown size. Folders, devices (/dev/zero, a terminal) and sockets are refused, so a
/// link named x.obj to /dev/zero fails at once. A pipe is opened without blocking and waited on
/// for at most ReadOptions::pipeWaitSeconds until a writer sends data or closes it.
class InputFile {
 public:
  /// Opens path for reading. Throws IoError when it is missing, a folder, a device or socket,
  /// unreadable, or a pipe nobody writes to within pipeWaitSeconds.
  explicit InputFile(std::string path, double pipeWaitSeconds = ReadOptions().pipeWaitSeconds);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  /// Most bytes a pipe is buffered up to at once (a whole Draco file, one list, one line).
  static constexpr std::uint64_t kMaxStreamBytes = std::uint64_t(4) << 30;
  /// Longest text line readLine accepts by default (a binary or endless input is not a line).
  static constexpr std::size_t kMaxLineBytes = std::size_t(1) << 26;

  const std::string& path() const { return path_; }
  /// False for a pipe: its size is unknown until it ends.
  bool isRegular() const { return regular_; }
  /// Size in bytes (the maximum value when the input is a pipe).
  std::uint64_t size() const { return size_; }
  /// Bytes consumed so far.
  std::uint64_t offset() const { return consumed_ + pos_; }
  std::uint64_t remaining() const { return size_ > offset() ? size_ - offset() : 0; }

  /// Makes n bytes available at data(); false when the input ends first (never allocates more
  /// than the rest of a file, or more than the bytes a pipe delivered plus one buffer).
  bool ensure(std::size_t n) { return end_ - pos_ >= n || refill(n); }
  const char* data() const { return buffer_.data() + pos_; }
  void advance(std::size_t n) { pos_ += n; }
  /// Skips n bytes; false when the input ends first.
  bool skip(std::uint64_t n);
  /// Buffers everything up to the end of the input and returns its size (at data()). Throws
  /// IoError when a pipe delivers more than kMaxStreamBytes.
  std::size_t readToEnd();
  /// Skips a UTF-8 byte order mark at the current position; true when there was one.
  bool skipByteOrderMark();

  /// Next line without its end ("\n", "\r\n", or "\r" in a file whose first line ends in a lone
  /// "\r"); false at the end of the input. A UTF-8 byte order mark before the first line is
  /// skipped. The view stays valid until the next call. A line longer than maxLength throws
  /// InputError.
  bool readLine(std::string_view& line, std::size_t maxLength = kMaxLineBytes);
  /// Number of the line last returned by readLine (1-based).
  std::uint64_t lineNumber() const { return line_; }

 private:
  bool refill(std::size_t n);
  std::size_t readSome(char* into, std::size_t n);
  void detectLineEnd();
  /// A regular file whose size or modification time differs from when it was opened changed
  /// while it was read: IoError naming it (checked after every read from the file).
  void checkUnchanged() const;

  std::string path_;
  int fd_ = -1;
  bool regular_ = true;
  std::uint64_t size_ = 0;
  std::int64_t modifiedSeconds_ = 0, modifiedNanoseconds_ = 0;  ///< st_mtim at open (regular files)
  std::uint64_t consumed_ = 0;  ///< input bytes before buffer_[0]
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uint64_t line_ = 0;
  char lineEnd_ = 0;  ///< '\n' or '\r' once the first line was read
};

/// TriangleMesh::origin while a file is read: originFor its first vertex (or a forced one).
/// Positions are then kept relative to it, computed from the file's values in double precision.
class OriginShift {
 public:
  OriginShift() = default;
  /// With a forced origin (ReadOptions::origin), the first vertex decides nothing.
  explicit OriginShift(const std::optional<Vec3d>& forced) {
    if (!forced) return;
    decided_ = true;
    active_ = !forced->isZero(0.0);
    origin_ = *forced;
  }
  /// True while the readers must hand over coordinates as doubles (before the first vertex, and
  /// with an origin); otherwise their floats are the positions, as read without an origin.
  bool needsDoubles() const { return !decided_ || active_; }
  /// The position of the file's point x (values as doubles) or, without an origin, f (as floats).
  Vec3f relative(const Vec3d& x, const Vec3f& f) {
    if (!decided_) {
      decided_ = true;
      origin_ = originFor(x);
      active_ = !origin_.isZero(0.0);
    }
    if (!active_) return f;
    return (x - origin_).cast<float>();
  }
  const Vec3d& origin() const { return origin_; }

 private:
  bool decided_ = false, active_ = false;
  Vec3d origin_ = Vec3d::Zero();
};

/// Cuts the next whitespace-separated token off the front of text ("" when none is left).
inline std::string_view nextToken(std::string_view& text) {
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == '\f' ||
                   text[i] == '\v')) {
    ++i;
  }
  std::size_t j = i;
  while (j < n && !(text[j] == ' ' || text[j] == '\t' || text[j] == '\r' || text[j] == '\f' ||
                    text[j] == '\v')) {
    ++j;
  }
  const std::string_view token = text.substr(i, j - i);
  text.remove_prefix(j);
  return token;
}

/// A token std::from_chars found out of T's range: +-infinity beyond it, the nearest denormal or
/// zero below it (strtod's rounding; the rare path).
template <class T>
T outOfRangeReal(std::string_view token) {
  const std::string text(token);
  if constexpr (std::is_same_v<T, float>) return std::strtof(text.c_str(), nullptr);
  else if constexpr (std::is_same_v<T, double>) return std::strtod(text.c_str(), nullptr);
  else return static_cast<T>(std::strtold(text.c_str(), nullptr));
}

/// Whole-token number parsing (std::from_chars, a leading '+' allowed). False on any garbage
/// and on integer overflow. Reals beyond the type's range read as +-infinity and "nan"/"inf"
/// parse (callers check finiteness); reals below it read as a denormal or zero (1e-320 is valid).
template <class T>
inline bool parseNumber(std::string_view token, T& value) {
  if (!token.empty() && token[0] == '+') {
    token.remove_prefix(1);
    if (!token.empty() && token[0] == '-') return false;  // "+-1"
  }
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  if (result.ptr != end) return false;
  if (result.ec == std::errc()) return true;
  if constexpr (std::is_floating_point_v<T>) {
    if (result.ec == std::errc::result_out_of_range) {
      value = outOfRangeReal<T>(token);
      return true;
    }
  }
  return false;
}

/// A coordinate token as a float and, when shift needs it, as a double (else the float's value).
/// False on garbage.
inline bool parseCoordinate(std::string_view token, const OriginShift& shift, float& f, double& d) {
  if (!parseNumber(token, f)) return false;
  d = f;
  return !shift.needsDoubles() || parseNumber(token, d);
}

/// Buffered output into an AtomicFile (or any sink of bytes): numbers are formatted with
/// std::to_chars (shortest round-trip form for float and double) into one large block.
class OutputBuffer {
 public:
  using Sink = std::function<void(const char*, std::size_t)>;
  explicit OutputBuffer(AtomicFile& file, std::size_t capacity = std::size_t(1) << 22)
      : OutputBuffer([&file](const char* data, std::size_t n) { file.write(data, n); }, capacity) {}
  explicit OutputBuffer(Sink sink, std::size_t capacity = std::size_t(1) << 22)
      : sink_(std::move(sink)), buffer_(capacity) {}
  ~OutputBuffer() = default;  // call flush(); an exception path must not write

  /// Makes room for n more bytes (n at most the capacity).
  void reserve(std::size_t n) {
    if (buffer_.size() - used_ < n) flush();
  }
  void put(char c) {
    reserve(1);
    buffer_[used_++] = c;
  }
  void put(std::string_view text) {
    if (text.size() > buffer_.size()) {
      flush();
      sink_(text.data(), text.size());
      return;
    }
    reserve(text.size());
    std::memcpy(buffer_.data() + used_, text.data(), text.size());
    used_ += text.size();
  }
  /// A number in text (shortest round-trip form for floating point).
  template <class T>
  void putNumber(T value) {
    reserve(40);
    char* begin = buffer_.data() + used_;
    used_ += static_cast<std::size_t>(std::to_chars(begin, begin + 40, value).ptr - begin);
  }
  /// n numbers separated by spaces, then `end` (a text row: "x y z\n").
  template <class T>
  void putRow(const T* values, int n, char end = '\n') {
    for (int i = 0; i < n; ++i) {
      if (i) put(' ');
      putNumber(values[i]);
    }
    put(end);
  }
  /// A value in little-endian binary.
  template <class T>
  void putLittle(T value) {
    reserve(sizeof(T));
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
#endif
    std::memcpy(buffer_.data() + used_, bytes, sizeof(T));
    used_ += sizeof(T);
  }
  void flush() {
    if (used_ > 0) sink_(buffer_.data(), used_);
    used_ = 0;
  }

 private:
  Sink sink_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
};

/// Passes a warning to warn, or prints it on stderr when warn is empty.
void warn(const WarningFn& warn, const std::string& message);

/// Positions in attributes.properties of red, green, blue and (when present) alpha, all of one
/// type; empty when the mesh has no such colors.
std::vector<std::size_t> colorProperties(const VertexAttributes& attributes);
/// Positions of nx, ny, nz of one floating type; empty when absent.
std::vector<std::size_t> normalProperties(const VertexAttributes& attributes);
/// A color value in [0, 1]: integers over their type's largest value, floats as they are.
double normalizedColor(const VertexProperty& property, VertexId v);

// Per-format entry points (io/ply_io.cpp, io/obj_io.cpp, io/off_io.cpp, io/draco_io.cpp).
std::unique_ptr<MeshStream> openPlyStream(std::unique_ptr<InputFile> in, const ReadOptions& options);
std::unique_ptr<MeshStream> openObjStream(std::unique_ptr<InputFile> in, const ReadOptions& options);
std::unique_ptr<MeshStream> openOffStream(std::unique_ptr<InputFile> in, const ReadOptions& options);
std::unique_ptr<MeshStream> openStlStream(std::unique_ptr<InputFile> in, const ReadOptions& options);
void writePly(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options);
// Pieces of the PLY, OFF and OBJ writers, shared with ChunkedMeshWriter (the same bytes). The
// positions are written at origin + position (TriangleMesh::origin): as floats when the origin is
// zero, else in double precision (PLY: double x, y, z).
void putPlyHeader(OutputBuffer& out, std::uint64_t vertices, std::uint64_t faces, const VertexAttributes& attributes,
                  bool withUV, bool binary, const Vec3d& origin);
/// Vertices [begin, end) of positions, with their values in attributes (indexed alike).
void putPlyVertices(OutputBuffer& out, const std::vector<Vec3f>& positions, const VertexAttributes& attributes,
                    std::size_t begin, std::size_t end, bool binary, const Vec3d& origin);
/// count triangles; uv: 3 (u, v) per triangle, or null for none.
void putPlyFaces(OutputBuffer& out, const Triangle* triangles, const Vec2d* uv, std::size_t count, bool binary);
void putOffHeader(OutputBuffer& out, std::uint64_t vertices, std::uint64_t faces);
void putOffVertices(OutputBuffer& out, const Vec3f* positions, std::size_t count, const Vec3d& origin);
void putOffFaces(OutputBuffer& out, const Triangle* triangles, std::size_t count);
/// `v x y z [r g b]` lines of vertices [begin, end) (colors when attributes has them).
void putObjVertices(OutputBuffer& out, const std::vector<Vec3f>& positions, const VertexAttributes& attributes,
                    std::size_t begin, std::size_t end, const Vec3d& origin);
/// `f a b c` lines without texture coordinates.
void putObjFaces(OutputBuffer& out, const Triangle* triangles, std::size_t count);
/// A `vt u v` line.
void putObjTexcoord(OutputBuffer& out, const Vec2d& uv);
/// An `f a/ta b/tb c/tc` line (texcoord: 0-based vt numbers), or `f a b c` when texcoord is null.
void putObjFace(OutputBuffer& out, const Triangle& t, const std::uint32_t* texcoord);
void writeObj(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options);
void writeOff(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options);
/// Draco decodes whole files (no streaming in the library); readDraco returns the mesh.
TriangleMesh readDraco(const std::string& path, const ReadOptions& options);
void writeDraco(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options);
/// The same, freeing the mesh's arrays as the Draco mesh takes them.
void writeDraco(AtomicFile& file, TriangleMesh&& mesh, const WriteOptions& options);

}  // namespace seamvox::detail
