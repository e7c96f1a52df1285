// PLY reading (ascii, binary little/big endian; vertex, face and tristrips elements; any other
// element skipped with a warning) and writing (binary little endian or ascii). Every scalar
// vertex property besides x, y, z is kept with its name and type (TriangleMesh::attributes) and
// written back as it was read.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {
namespace {

using PlyType = ScalarType;  // PLY's scalar types are the vertex attributes' types

std::size_t sizeOf(PlyType t) { return scalarSize(t); }
bool isFloating(PlyType t) { return isFloatingType(t); }

bool parseType(std::string_view name, PlyType& type) {
  static const std::pair<std::string_view, PlyType> kNames[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},      {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},    {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},  {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},    {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, t] : kNames) {
    if (n == name) {
      type = t;
      return true;
    }
  }
  return false;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;  ///< value type (item type for a list)
  bool isList = false;
  PlyType countType = PlyType::UInt8;
};

enum class Role { Skip, Vertex, Face, Strips };

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  Role role = Role::Skip;
  int x = -1, y = -1, z = -1;       ///< vertex: property positions
  std::vector<int> kept;            ///< vertex: attribute of each property (-1: not kept)
  int indices = -1, texcoord = -1;  ///< face / tristrips: property positions
  bool hasList = false;
  std::uint64_t minBytes = 0;  ///< binary size of one instance with empty lists
};

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

struct PlyHeader {
  Encoding encoding = Encoding::Ascii;
  std::vector<PlyElement> elements;
};

/// A problem found while reading the body; the reader adds file and location.
struct Fault {
  bool truncated;
  std::string problem;
};

[[noreturn]] void headerError(const InputFile& in, const std::string& problem) {
  throw InputError(in.path() + ": line " + std::to_string(in.lineNumber()) + " of the PLY header: " +
                   problem);
}

void classify(const InputFile& in, PlyElement& e) {
  auto find = [&](std::string_view name) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      if (e.properties[i].name == name) return static_cast<int>(i);
    }
    return -1;
  };
  if (e.name == "vertex") {
    e.role = Role::Vertex;
    e.x = find("x"), e.y = find("y"), e.z = find("z");
    for (const int p : {e.x, e.y, e.z}) {
      if (p < 0 || e.properties[p].isList) {
        throw InputError(in.path() + ": PLY element 'vertex' needs scalar properties x, y and z");
      }
    }
    int next = 0;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const int p = static_cast<int>(i);
      e.kept.push_back(p == e.x || p == e.y || p == e.z || e.properties[i].isList ? -1 : next++);
    }
  } else if (e.name == "face" || e.name == "tristrips") {
    e.role = e.name == "face" ? Role::Face : Role::Strips;
    e.indices = find("vertex_indices");
    if (e.indices < 0) e.indices = find("vertex_index");
    if (e.indices < 0 || !e.properties[e.indices].isList) {
      throw InputError(in.path() + ": PLY element '" + e.name +
                       "' needs a list property vertex_indices (or vertex_index)");
    }
    if (e.role == Role::Face) {
      e.texcoord = find("texcoord");
      if (e.texcoord >= 0 && !e.properties[e.texcoord].isList) e.texcoord = -1;
    }
  }
}

PlyHeader readHeader(InputFile& in) {
  constexpr std::size_t kMaxHeaderLine = 1 << 16;
  in.skipByteOrderMark();
  if (!in.ensure(3) || std::string_view(in.data(), 3) != "ply") {
    throw InputError(in.path() + ": not a PLY file (it does not start with 'ply')");
  }
  std::string_view line;
  in.readLine(line, kMaxHeaderLine);
  if (line != "ply") throw InputError(in.path() + ": not a PLY file (first line is not 'ply')");
  PlyHeader header;
  bool sawFormat = false;
  for (;;) {
    if (!in.readLine(line, kMaxHeaderLine)) {
      throw InputError(in.path() + ": the PLY header has no end_header line");
    }
    const std::string_view keyword = nextToken(line);
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      const std::string_view format = nextToken(line);
      if (format == "ascii") header.encoding = Encoding::Ascii;
      else if (format == "binary_little_endian") header.encoding = Encoding::BinaryLittle;
      else if (format == "binary_big_endian") header.encoding = Encoding::BinaryBig;
      else headerError(in, "unknown PLY format '" + std::string(format) + "'");
      sawFormat = true;
    } else if (keyword == "element") {
      PlyElement e;
      e.name = std::string(nextToken(line));
      const std::string_view count = nextToken(line);
      if (e.name.empty() || !parseNumber(count, e.count)) {
        headerError(in, "expected 'element NAME COUNT'");
      }
      for (const PlyElement& other : header.elements) {
        if (other.name == e.name) headerError(in, "element '" + e.name + "' is declared twice");
      }
      header.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (header.elements.empty()) headerError(in, "property before any element");
      PlyProperty p;
      std::string_view type = nextToken(line);
      if (type == "list") {
        p.isList = true;
        const std::string_view countType = nextToken(line);
        if (!parseType(countType, p.countType) || isFloating(p.countType)) {
          headerError(in, "unsupported PLY list count type '" + std::string(countType) + "'");
        }
        type = nextToken(line);
      }
      if (!parseType(type, p.type)) headerError(in, "unsupported PLY type '" + std::string(type) + "'");
      p.name = std::string(nextToken(line));
      if (p.name.empty()) headerError(in, "property without a name");
      PlyElement& e = header.elements.back();
      e.hasList = e.hasList || p.isList;
      e.minBytes += p.isList ? sizeOf(p.countType) : sizeOf(p.type);
      e.properties.push_back(std::move(p));
    } else {
      headerError(in, "unknown PLY header keyword '" + std::string(keyword) + "'");
    }
  }
  if (!sawFormat) throw InputError(in.path() + ": the PLY header has no format line");

  // Counts must be possible for the bytes that follow, so nothing is sized from a bogus header.
  long double needed = 0;
  bool hasVertex = false;
  for (PlyElement& e : header.elements) {
    classify(in, e);
    hasVertex = hasVertex || e.role == Role::Vertex;
    // ASCII: every value takes at least one character (and lists at least their count).
    const long double perInstance = header.encoding == Encoding::Ascii
                                        ? static_cast<long double>(e.properties.size())
                                        : static_cast<long double>(e.minBytes);
    needed += perInstance * static_cast<long double>(e.count);
    if (needed > static_cast<long double>(in.remaining())) {
      throw IoError(in.path() + ": the PLY header declares " + std::to_string(e.count) + " '" +
                    e.name + "' elements, more than the " + std::to_string(in.remaining()) +
                    " bytes after the header can hold: the file is truncated or its header is wrong");
    }
    if (e.role == Role::Vertex && e.count >= std::numeric_limits<std::uint32_t>::max()) {
      throw InputError(in.path() + ": " + std::to_string(e.count) +
                       " vertices is more than 32-bit ids allow");
    }
  }
  if (!hasVertex) throw InputError(in.path() + ": the PLY file has no 'vertex' element");
  return header;
}

// --- value sources: the same element readers run on binary and on ascii bodies -----------------

template <class T>
T loadRaw(const char* p, bool swap) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

double loadReal(PlyType t, const char* p, bool swap) {
  switch (t) {
    case PlyType::Int8: return static_cast<std::int8_t>(*p);
    case PlyType::UInt8: return static_cast<std::uint8_t>(*p);
    case PlyType::Int16: return loadRaw<std::int16_t>(p, swap);
    case PlyType::UInt16: return loadRaw<std::uint16_t>(p, swap);
    case PlyType::Int32: return loadRaw<std::int32_t>(p, swap);
    case PlyType::UInt32: return loadRaw<std::uint32_t>(p, swap);
    case PlyType::Float32: return loadRaw<float>(p, swap);
    case PlyType::Float64: return loadRaw<double>(p, swap);
  }
  return 0;
}

/// The strip restart marker as read from an index of type t: -1, or all bits set when unsigned.
std::int64_t restartIndex(PlyType t) {
  switch (t) {
    case PlyType::UInt8: return 0xFF;
    case PlyType::UInt16: return 0xFFFF;
    case PlyType::UInt32: return 0xFFFFFFFF;
    default: return -1;
  }
}

/// Integer value of an integral real; false when it is not one (or is out of range).
bool integral(double d, std::int64_t& value) {
  if (!(d == std::floor(d)) || std::fabs(d) > 9.0e18) return false;
  value = static_cast<std::int64_t>(d);
  return true;
}

class BinarySource {
 public:
  static constexpr bool kAscii = false;
  BinarySource(InputFile& in, bool swap) : in_(in), swap_(swap) {}

  const char* take(std::size_t n) {
    if (!in_.ensure(n)) throw Fault{true, "the file ends early (truncated)"};
    const char* p = in_.data();
    in_.advance(n);
    return p;
  }
  double real(PlyType t) { return loadReal(t, take(sizeOf(t)), swap_); }
  /// A coordinate as the float it was read as, and as the double the file holds.
  void coordinate(PlyType t, bool, float& f, double& d) {
    if (t == PlyType::Float32) {
      f = loadRaw<float>(take(4), swap_);
      d = f;
      return;
    }
    d = real(t);
    f = static_cast<float>(d);
  }
  bool integer(PlyType t, std::int64_t& value) {
    const char* p = take(sizeOf(t));
    switch (t) {
      case PlyType::Int8: value = static_cast<std::int8_t>(*p); return true;
      case PlyType::UInt8: value = static_cast<std::uint8_t>(*p); return true;
      case PlyType::Int16: value = loadRaw<std::int16_t>(p, swap_); return true;
      case PlyType::UInt16: value = loadRaw<std::uint16_t>(p, swap_); return true;
      case PlyType::Int32: value = loadRaw<std::int32_t>(p, swap_); return true;
      case PlyType::UInt32: value = loadRaw<std::uint32_t>(p, swap_); return true;
      default: return integral(loadReal(t, p, swap_), value);
    }
  }
  void skip(PlyType t) { take(sizeOf(t)); }
  /// The next n bytes without taking them, or nullptr when the input ends first; drop(n) takes them.
  const char* peek(std::size_t n) { return in_.ensure(n) ? in_.data() : nullptr; }
  void drop(std::size_t n) { in_.advance(n); }
  bool swaps() const { return swap_; }
  /// Appends one value of type t in native byte order.
  void value(PlyType t, std::vector<std::uint8_t>& into) {
    const std::size_t n = sizeOf(t);
    const char* p = take(n);
    const std::size_t at = into.size();
    into.insert(into.end(), p, p + n);
    if (swap_) std::reverse(into.begin() + at, into.end());
  }
  /// Announces n list items of type t (fails at once when the file cannot hold them).
  void expect(PlyType t, std::int64_t n) {
    if (!in_.ensure(static_cast<std::size_t>(n) * sizeOf(t))) {
      throw Fault{true, "the file ends early (truncated) inside a list of " + std::to_string(n) +
                            " items"};
    }
  }
  void skipList(PlyType t, std::int64_t n) {
    if (!in_.skip(static_cast<std::uint64_t>(n) * sizeOf(t))) {
      throw Fault{true, "the file ends early (truncated)"};
    }
  }
  /// Skips count instances of an element without lists in one step.
  bool skipFixed(const PlyElement& e, std::uint64_t count) {
    if (e.hasList) return false;
    if (!in_.skip(count * e.minBytes)) throw Fault{true, "the file ends early (truncated)"};
    return true;
  }
  std::string where() const { return "byte " + std::to_string(in_.offset()); }

 private:
  InputFile& in_;
  bool swap_;
};

class AsciiSource {
 public:
  static constexpr bool kAscii = true;
  explicit AsciiSource(InputFile& in) : in_(in) {}

  std::string_view token() {
    for (;;) {
      const std::string_view t = nextToken(line_);
      if (!t.empty()) return t;
      if (!in_.readLine(line_)) throw Fault{true, "the file ends early (truncated)"};
    }
  }
  double real(PlyType) {
    const std::string_view t = token();
    double value;
    if (!parseNumber(t, value)) bad(t);
    return value;
  }
  /// A coordinate as the float it was read as, and (when asked for) as the double the file holds.
  void coordinate(PlyType type, bool wantDouble, float& f, double& d) {
    if (type == PlyType::Float64) {
      d = real(type);
      f = static_cast<float>(d);
      return;
    }
    const std::string_view t = token();
    if (!parseNumber(t, f)) bad(t);
    d = f;
    if (wantDouble && !parseNumber(t, d)) bad(t);
  }
  bool integer(PlyType type, std::int64_t& value) {
    if (isFloating(type)) return integral(real(type), value);
    const std::string_view t = token();
    if (!parseNumber(t, value)) bad(t);
    return true;
  }
  void skip(PlyType) { token(); }
  void value(PlyType type, std::vector<std::uint8_t>& into) {
    switch (type) {
      case PlyType::Int8: return put<std::int8_t>(into);
      case PlyType::UInt8: return put<std::uint8_t>(into);
      case PlyType::Int16: return put<std::int16_t>(into);
      case PlyType::UInt16: return put<std::uint16_t>(into);
      case PlyType::Int32: return put<std::int32_t>(into);
      case PlyType::UInt32: return put<std::uint32_t>(into);
      case PlyType::Float32: return put<float>(into);
      case PlyType::Float64: return put<double>(into);
    }
  }
  void expect(PlyType, std::int64_t) {}
  void skipList(PlyType, std::int64_t n) {
    for (std::int64_t i = 0; i < n; ++i) token();
  }
  bool skipFixed(const PlyElement&, std::uint64_t) { return false; }
  std::string where() const { return "line " + std::to_string(in_.lineNumber()); }

 private:
  [[noreturn]] static void bad(std::string_view t) {
    throw Fault{false, "bad number '" + std::string(t.substr(0, 40)) + "'"};
  }
  /// Parses the next token as a T (integers must fit T) and appends its bytes.
  template <class T>
  void put(std::vector<std::uint8_t>& into) {
    const std::string_view t = token();
    T value;
    if (!parseNumber(t, value)) bad(t);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
    into.insert(into.end(), bytes, bytes + sizeof(T));
  }
  InputFile& in_;
  std::string_view line_;
};

// --- the reader ---------------------------------------------------------------------------------

template <class Source>
class PlyReader final : public MeshStream {
 public:
  PlyReader(std::unique_ptr<InputFile> in, PlyHeader header, const ReadOptions& options,
            Source source)
      : in_(std::move(in)),
        header_(std::move(header)),
        source_(source),
        shift_(options.origin),
        limit_(std::max<std::size_t>(options.chunkTriangles, 1)) {
    bool hasStrips = false;
    for (const PlyElement& e : header_.elements) {
      if (e.role == Role::Vertex) vertexCount_ = e.count;
      if (e.role == Role::Face) faceCount_ = e.count;
      hasStrips = hasStrips || e.role == Role::Strips;
    }
    // Strip triangles carry no texture coordinates, so a file with strips is read without UVs.
    for (const PlyElement& e : header_.elements) {
      if (e.role == Role::Face && e.texcoord >= 0 && options.readUV && !hasStrips) withUV_ = true;
    }
    for (const PlyElement& e : header_.elements) {
      if (e.role != Role::Vertex) continue;
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        if (e.kept[k] >= 0) layout_.add(e.properties[k].name, e.properties[k].type, 0);
      }
    }
    warnUnkept(options);
  }

  bool next(MeshChunk& chunk) override {
    chunk.clear();
    chunk.firstVertex = static_cast<std::uint32_t>(verticesRead_);
    try {
      while (element_ < header_.elements.size()) {
        const PlyElement& e = header_.elements[element_];
        if (instance_ >= e.count) {
          ++element_;
          instance_ = 0;
          continue;
        }
        if (chunk.triangles.size() >= limit_ || chunk.positions.size() >= limit_) return true;
        switch (e.role) {
          case Role::Vertex: readVertices(e, chunk); break;
          case Role::Face: readFaces(e, chunk); break;
          case Role::Strips: readStrips(e, chunk); break;
          case Role::Skip: skipElement(e); break;
        }
      }
    } catch (const Fault& fault) {
      const PlyElement& e = header_.elements[element_];
      const std::string element = "element '" + e.name + "' " + std::to_string(instance_);
      const std::string message =
          in_->path() + ": " +
          (Source::kAscii ? source_.where() + " (" + element + ")" : element + " (" + source_.where() + ")") +
          ": " + fault.problem;
      if (fault.truncated) throw IoError(message);
      throw InputError(message);
    }
    return !chunk.positions.empty() || !chunk.triangles.empty();
  }

  const std::string& name() const override { return in_->path(); }
  // Hints to reserve by: the counts were checked against the size of a file, not of a pipe.
  std::uint64_t declaredVertices() const override { return in_->isRegular() ? vertexCount_ : 0; }
  std::uint64_t expectedTriangles() const override { return in_->isRegular() ? faceCount_ : 0; }

 private:
  /// One warning naming what the file has and the mesh will not: list properties of vertices,
  /// face properties besides vertex_indices and texcoord, elements other than vertex and faces.
  void warnUnkept(const ReadOptions& options) const {
    std::string unkept;
    auto add = [&](const std::string& what) { unkept += (unkept.empty() ? "" : ", ") + what; };
    for (const PlyElement& e : header_.elements) {
      if (e.role == Role::Skip && e.count > 0) add("element '" + e.name + "'");
      for (std::size_t k = 0; k < e.properties.size() && e.role != Role::Skip; ++k) {
        const int ik = static_cast<int>(k);
        const bool kept = e.role == Role::Vertex ? ik == e.x || ik == e.y || ik == e.z || e.kept[k] >= 0
                                                 : ik == e.indices || ik == e.texcoord;
        if (!kept) add(e.name + " property '" + e.properties[k].name + "'");
      }
    }
    if (!unkept.empty()) warn(options.warn, in_->path() + ": not kept: " + unkept);
  }

  /// At most `most` binary records of `bytes` bytes each, a run at a time, while take(record)
  /// accepts them (false: that record is left unread, for the general path); stops at the
  /// file's end too. Returns how many were taken.
  template <class Take>
  std::uint64_t readRuns(std::uint64_t most, std::size_t bytes, Take&& take) {
    constexpr std::uint64_t kRun = 4096;
    std::uint64_t done = 0;
    while (done < most) {
      const std::size_t want = static_cast<std::size_t>(std::min(most - done, kRun));
      const char* p = source_.peek(want * bytes);
      if (!p) break;
      std::size_t k = 0;
      while (k < want && take(p + k * bytes)) ++k;
      source_.drop(k * bytes);
      done += k;
      if (k < want) break;
    }
    return done;
  }

  /// Binary vertices of three float properties x, y, z in the machine's byte order, read a run
  /// at a time once the first vertex has decided that no origin is needed: the general path's
  /// positions without its per-value dispatch. A vertex that is not finite (and the file's end)
  /// is left to that path, which reports it. False when nothing was read.
  bool readVertexRuns(const PlyElement& e, MeshChunk& chunk) {
    if constexpr (!Source::kAscii) {
      if (e.properties.size() != 3 || e.x != 0 || e.y != 1 || e.z != 2 || shift_.needsDoubles() || source_.swaps()) {
        return false;
      }
      for (const PlyProperty& prop : e.properties) {
        if (prop.isList || prop.type != PlyType::Float32) return false;
      }
      const auto take = [&](const char* record) {
        Vec3f f;
        std::memcpy(f.data(), record, 12);
        if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2])) return false;
        chunk.positions.push_back(f);
        return true;
      };
      const std::uint64_t read = readRuns(std::min<std::uint64_t>(e.count - instance_, limit_ - chunk.positions.size()), 12, take);
      instance_ += read;
      verticesRead_ += read;
      chunk.origin = shift_.origin();
      return read > 0;
    }
    return false;
  }

  void readVertices(const PlyElement& e, MeshChunk& chunk) {
    const std::size_t numProperties = e.properties.size();
    if (chunk.attributes.properties.size() != layout_.properties.size()) chunk.attributes = layout_.emptyCopy();
    std::vector<VertexProperty>& attributes = chunk.attributes.properties;
    while (instance_ < e.count && chunk.positions.size() < limit_) {
      if (readVertexRuns(e, chunk)) continue;
      Vec3f f;
      Vec3d d;
      for (std::size_t k = 0; k < numProperties; ++k) {
        const PlyProperty& prop = e.properties[k];
        const int ik = static_cast<int>(k);
        if (ik == e.x || ik == e.y || ik == e.z) {
          const int axis = ik == e.x ? 0 : ik == e.y ? 1 : 2;
          source_.coordinate(prop.type, shift_.needsDoubles(), f[axis], d[axis]);
        } else if (e.kept[k] >= 0) {
          source_.value(prop.type, attributes[e.kept[k]].bytes);
        } else {
          skipProperty(prop);
        }
      }
      const Vec3f p = shift_.relative(d, f);
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        throw Fault{false, "vertex coordinate is NaN or infinite (or beyond float range)"};
      }
      chunk.origin = shift_.origin();
      chunk.positions.push_back(p);
      ++verticesRead_;
      ++instance_;
    }
  }

  void skipProperty(const PlyProperty& prop) {
    if (!prop.isList) {
      source_.skip(prop.type);
      return;
    }
    const std::int64_t n = listCount(prop);
    source_.skipList(prop.type, n);
  }

  std::int64_t listCount(const PlyProperty& prop) {
    std::int64_t n = 0;
    if (!source_.integer(prop.countType, n) || n < 0) {
      throw Fault{false, "bad list length in property '" + prop.name + "'"};
    }
    return n;
  }

  /// Reads one instance of a face or strip element into indices_ (and texcoords_ when asked).
  void readIndexInstance(const PlyElement& e, bool wantUV) {
    indices_.clear();
    texcoords_.clear();
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& prop = e.properties[k];
      const int ik = static_cast<int>(k);
      if (ik == e.indices) {
        const std::int64_t n = listCount(prop);
        source_.expect(prop.type, n);
        for (std::int64_t i = 0; i < n; ++i) {
          std::int64_t v;
          if (!source_.integer(prop.type, v)) throw Fault{false, "vertex index is not an integer"};
          indices_.push_back(v);
        }
      } else if (ik == e.texcoord && wantUV) {
        const std::int64_t n = listCount(prop);
        source_.expect(prop.type, n);
        for (std::int64_t i = 0; i < n; ++i) {
          const double t = source_.real(prop.type);
          if (!std::isfinite(t)) throw Fault{false, "texture coordinate is NaN or infinite"};
          texcoords_.push_back(t);
        }
      } else {
        skipProperty(prop);
      }
    }
  }

  VertexId checkedIndex(std::int64_t v) const {
    if (v < 0 || static_cast<std::uint64_t>(v) >= vertexCount_) {
      throw Fault{false, "vertex index " + std::to_string(v) + " is out of range (the file has " +
                             std::to_string(vertexCount_) + " vertices)"};
    }
    return static_cast<VertexId>(v);
  }

  /// Binary faces whose one property is a list of a one-byte count and 32-bit indices in the
  /// machine's byte order, read a run at a time while each is a triangle with valid indices: the
  /// general path's triangles without its per-value dispatch (a scan's faces are almost all
  /// such). Any other face (a polygon, a bad index, the end of the file) is left to that path,
  /// which reads it and reports what is wrong.
  void readTriangleRuns(const PlyElement& e, MeshChunk& chunk) {
    if constexpr (!Source::kAscii) {
      if (e.properties.size() != 1 || e.indices != 0 || withUV_ || source_.swaps()) return;
      const PlyProperty& prop = e.properties[0];
      const bool signedIndices = prop.type == PlyType::Int32;
      if (!prop.isList || sizeOf(prop.countType) != 1 || !(signedIndices || prop.type == PlyType::UInt32)) return;
      const auto take = [&](const char* record) {
        if (record[0] != 3) return false;
        Triangle t;
        for (int i = 0; i < 3; ++i) {
          std::uint32_t raw;
          std::memcpy(&raw, record + 1 + 4 * i, 4);
          const std::int64_t v = signedIndices ? std::int64_t(static_cast<std::int32_t>(raw)) : std::int64_t(raw);
          if (v < 0 || static_cast<std::uint64_t>(v) >= vertexCount_) return false;
          t[i] = static_cast<VertexId>(raw);
        }
        chunk.triangles.push_back(t);
        return true;
      };
      instance_ += readRuns(std::min<std::uint64_t>(e.count - instance_, limit_ - chunk.triangles.size()), 13, take);
    }
  }

  void readFaces(const PlyElement& e, MeshChunk& chunk) {
    readTriangleRuns(e, chunk);
    while (instance_ < e.count && chunk.triangles.size() < limit_) {
      readIndexInstance(e, withUV_);
      const std::size_t n = indices_.size();
      if (n < 3) {
        throw Fault{false, "face has " + std::to_string(n) + " vertices (at least 3 are needed)"};
      }
      if (withUV_ && texcoords_.size() != 2 * n) {
        throw Fault{false, "face has " + std::to_string(n) + " vertices but " +
                               std::to_string(texcoords_.size()) + " texcoord values (expected " +
                               std::to_string(2 * n) + ")"};
      }
      const VertexId first = checkedIndex(indices_[0]);
      VertexId previous = checkedIndex(indices_[1]);
      for (std::size_t k = 2; k < n; ++k) {
        const VertexId current = checkedIndex(indices_[k]);
        chunk.triangles.push_back({first, previous, current});
        if (withUV_) {
          for (const std::size_t corner : {std::size_t(0), k - 1, k}) {
            chunk.cornerUV.emplace_back(texcoords_[2 * corner], texcoords_[2 * corner + 1]);
          }
        }
        previous = current;
      }
      ++instance_;
    }
  }

  void readStrips(const PlyElement& e, MeshChunk& chunk) {
    while (instance_ < e.count && chunk.triangles.size() < limit_) {
      readIndexInstance(e, false);
      // Triangle i of a strip is (s[i], s[i+1], s[i+2]) with every odd one flipped so that all
      // keep the orientation of the first; -1 restarts (for an unsigned index type, its -1 bit
      // pattern: 0xFFFFFFFF for uint). Degenerate triangles still count for the parity (strips
      // use them to turn) but are not emitted.
      const std::int64_t restart = restartIndex(e.properties[e.indices].type);
      std::size_t run = 0;
      VertexId a = 0, b = 0;
      for (const std::int64_t value : indices_) {
        if (value == restart) {
          run = 0;
          continue;
        }
        const VertexId c = checkedIndex(value);
        if (run >= 2 && a != b && b != c && a != c) {
          if (run % 2 == 0) chunk.triangles.push_back({a, b, c});
          else chunk.triangles.push_back({b, a, c});
        }
        a = b;
        b = c;
        ++run;
      }
      ++instance_;
    }
  }

  void skipElement(const PlyElement& e) {
    if (e.properties.empty()) {
      instance_ = e.count;
      return;
    }
    if (source_.skipFixed(e, e.count - instance_)) {
      instance_ = e.count;
      return;
    }
    for (; instance_ < e.count; ++instance_) {
      for (const PlyProperty& prop : e.properties) skipProperty(prop);
    }
  }

  std::unique_ptr<InputFile> in_;
  PlyHeader header_;
  VertexAttributes layout_;  ///< the kept vertex properties, without values
  Source source_;
  OriginShift shift_;
  std::size_t limit_;
  bool withUV_ = false;
  std::uint64_t vertexCount_ = 0, faceCount_ = 0, verticesRead_ = 0;
  std::size_t element_ = 0;
  std::uint64_t instance_ = 0;
  std::vector<std::int64_t> indices_;
  std::vector<double> texcoords_;
};

}  // namespace

std::unique_ptr<MeshStream> openPlyStream(std::unique_ptr<InputFile> in, const ReadOptions& options) {
  PlyHeader header = readHeader(*in);
  InputFile& file = *in;
  if (header.encoding == Encoding::Ascii) {
    return std::make_unique<PlyReader<AsciiSource>>(std::move(in), std::move(header), options,
                                                    AsciiSource(file));
  }
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  const bool swap = header.encoding == Encoding::BinaryLittle;
#else
  const bool swap = header.encoding == Encoding::BinaryBig;
#endif
  return std::make_unique<PlyReader<BinarySource>>(std::move(in), std::move(header), options,
                                                   BinarySource(file, swap));
}

namespace {

/// A property name as a PLY header token: whitespace becomes '_', an empty name "unnamed".
std::string plyName(std::string name) {
  for (char& c : name) {
    if (std::isspace(static_cast<unsigned char>(c))) c = '_';
  }
  return name.empty() ? "unnamed" : name;
}

template <class T>
T loadValue(const VertexProperty& p, std::size_t v) {
  T value;
  std::memcpy(&value, p.bytes.data() + v * sizeof(T), sizeof(T));
  return value;
}

/// Calls f with the value of vertex v as its own C++ type.
template <class F>
void withValue(const VertexProperty& p, std::size_t v, F&& f) {
  switch (p.type) {
    case PlyType::Int8: return f(loadValue<std::int8_t>(p, v));
    case PlyType::UInt8: return f(loadValue<std::uint8_t>(p, v));
    case PlyType::Int16: return f(loadValue<std::int16_t>(p, v));
    case PlyType::UInt16: return f(loadValue<std::uint16_t>(p, v));
    case PlyType::Int32: return f(loadValue<std::int32_t>(p, v));
    case PlyType::UInt32: return f(loadValue<std::uint32_t>(p, v));
    case PlyType::Float32: return f(loadValue<float>(p, v));
    case PlyType::Float64: return f(loadValue<double>(p, v));
  }
}

void putLittleValue(OutputBuffer& out, const VertexProperty& p, std::size_t v) {
  withValue(p, v, [&](auto value) { out.putLittle(value); });
}

void putTextValue(OutputBuffer& out, const VertexProperty& p, std::size_t v) {
  withValue(p, v, [&](auto value) {
    // 8-bit values print as numbers, not characters.
    if constexpr (sizeof(value) == 1) out.putNumber(static_cast<int>(value));
    else out.putNumber(value);
  });
}

}  // namespace

void putPlyHeader(OutputBuffer& out, std::uint64_t vertices, std::uint64_t faces, const VertexAttributes& attributes,
                  bool withUV, bool binary, const Vec3d& origin) {
  const bool wideIndices = vertices > std::uint64_t(std::numeric_limits<std::int32_t>::max());
  out.put("ply\nformat ");
  out.put(binary ? "binary_little_endian" : "ascii");
  out.put(" 1.0\ncomment written by seamvox\nelement vertex ");
  out.putNumber(vertices);
  out.put(origin.isZero(0.0) ? "\nproperty float x\nproperty float y\nproperty float z\n"
                              : "\nproperty double x\nproperty double y\nproperty double z\n");
  for (const VertexProperty& p : attributes.properties) {
    out.put("property ");
    out.put(scalarTypeName(p.type));
    out.put(' ');
    out.put(plyName(p.name));
    out.put('\n');
  }
  out.put("element face ");
  out.putNumber(faces);
  out.put(wideIndices ? "\nproperty list uchar uint vertex_indices\n"
                      : "\nproperty list uchar int vertex_indices\n");
  if (withUV) out.put("property list uchar double texcoord\n");
  out.put("end_header\n");
}

void putPlyVertices(OutputBuffer& out, const std::vector<Vec3f>& positions, const VertexAttributes& attributes,
                    std::size_t begin, std::size_t end, bool binary, const Vec3d& origin) {
  const std::vector<VertexProperty>& properties = attributes.properties;
  const bool shifted = !origin.isZero(0.0);
  if (binary) {
    for (std::size_t v = begin; v < end; ++v) {
      const Vec3f& p = positions[v];
      if (shifted) {
        const Vec3d world = origin + p.cast<double>();
        out.putLittle(world[0]);
        out.putLittle(world[1]);
        out.putLittle(world[2]);
      } else {
        out.putLittle(p[0]);
        out.putLittle(p[1]);
        out.putLittle(p[2]);
      }
      for (const VertexProperty& property : properties) putLittleValue(out, property, v);
    }
    return;
  }
  for (std::size_t v = begin; v < end; ++v) {
    const char last = properties.empty() ? '\n' : ' ';
    if (shifted) {
      const Vec3d world = origin + positions[v].cast<double>();
      out.putRow(world.data(), 3, last);
    } else {
      out.putRow(positions[v].data(), 3, last);
    }
    for (std::size_t k = 0; k < properties.size(); ++k) {
      putTextValue(out, properties[k], v);
      out.put(k + 1 < properties.size() ? ' ' : '\n');
    }
  }
}

void putPlyFaces(OutputBuffer& out, const Triangle* triangles, const Vec2d* uv, std::size_t count, bool binary) {
  for (std::size_t f = 0; f < count; ++f) {
    if (binary) {
      out.putLittle(std::uint8_t(3));
      for (const VertexId v : triangles[f]) out.putLittle(v);
      if (!uv) continue;
      out.putLittle(std::uint8_t(6));
      for (int k = 0; k < 3; ++k) {
        out.putLittle(uv[3 * f + k][0]);
        out.putLittle(uv[3 * f + k][1]);
      }
    } else {
      out.put("3 ");
      out.putRow(triangles[f].data(), 3, uv ? ' ' : '\n');
      if (!uv) continue;
      out.put("6 ");
      for (int k = 0; k < 3; ++k) out.putRow(uv[3 * f + k].data(), 2, k < 2 ? ' ' : '\n');
    }
  }
}

void writePly(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  const bool withUV = options.writeUV && mesh.hasUV();
  OutputBuffer out(file);
  putPlyHeader(out, mesh.positions.size(), mesh.triangles.size(), mesh.attributes, withUV, options.binary, mesh.origin);
  putPlyVertices(out, mesh.positions, mesh.attributes, 0, mesh.positions.size(), options.binary, mesh.origin);
  // Faces in blocks whose corner UVs are gathered from the wedge map.
  constexpr std::size_t kBlock = 1 << 14;
  std::vector<Vec2d> uv;
  for (std::size_t first = 0; first < mesh.triangles.size(); first += kBlock) {
    const std::size_t count = std::min(kBlock, mesh.triangles.size() - first);
    if (withUV) {
      uv.resize(3 * count);
      for (std::size_t c = 0; c < 3 * count; ++c) uv[c] = mesh.cornerUV[3 * first + c];
    }
    putPlyFaces(out, mesh.triangles.data() + first, withUV ? uv.data() : nullptr, count, options.binary);
  }
  out.flush();
}

}  // namespace seamvox::detail
