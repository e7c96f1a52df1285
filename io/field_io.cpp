// Field files: `.crossfield` and the plain per-face format (see io/field_io.h).
#include "io/field_io.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/detail_mesh_io.h"

namespace seamvox {

namespace {

/// Splits a line into whitespace-separated tokens (at most maxTokens + 1 are kept, enough to
/// tell "too many").
int splitTokens(std::string_view line, const char** begin, const char** end, int maxTokens) {
  int n = 0;
  const char* p = line.data();
  const char* const stop = p + line.size();
  while (p != stop) {
    while (p != stop && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    if (p == stop) break;
    const char* start = p;
    while (p != stop && *p != ' ' && *p != '\t' && *p != '\r') ++p;
    if (n <= maxTokens) {
      begin[n] = start;
      end[n] = p;
    }
    ++n;
  }
  return n;
}

class LineError {
 public:
  LineError(const std::string& path, std::uint64_t line) : path_(path), line_(line) {}
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_ + ":" + std::to_string(line_) + ": " + what);
  }

 private:
  const std::string& path_;
  std::uint64_t line_;
};

double parseNumber(const char* begin, const char* end, const LineError& where) {
  // from_chars: no locale, no allocation (several times faster than strtod on 10M-line files).
  double x = 0.0;
  if (!detail::parseNumber(std::string_view(begin, static_cast<std::size_t>(end - begin)), x)) {
    where.fail("'" + std::string(begin, end) + "' is not a number");
  }
  if (!std::isfinite(x)) where.fail("non-finite value '" + std::string(begin, end) + "'");
  return x;
}

std::uint64_t parseCount(const char* begin, const char* end, const LineError& where) {
  const std::string token(begin, end);
  char* stop = nullptr;
  errno = 0;
  const unsigned long long x = std::strtoull(token.c_str(), &stop, 10);
  if (stop != token.c_str() + token.size() || token.empty() || token[0] == '-' || errno == ERANGE) {
    where.fail("'" + token + "' is not a non-negative integer");
  }
  return x;
}

}  // namespace

std::vector<Vec3d> readFieldVectors(const std::string& path, std::uint32_t expectedFaces) {
  // Like mesh files: a BOM and any line ends are accepted, devices refused, pipes streamed.
  detail::InputFile in(path);
  enum class Kind { Unknown, Plain, CrossField } kind = Kind::Unknown;
  bool haveHeader = false;
  std::vector<Vec3d> vectors;
  vectors.reserve(expectedFaces);
  std::string_view line;
  std::uint64_t lineNo = 0;
  const char* begin[8];
  const char* end[8];
  const std::string expected = std::to_string(expectedFaces);
  while (in.readLine(line)) {
    lineNo = in.lineNumber();
    const LineError where(path, lineNo);
    const int n = splitTokens(line, begin, end, 7);
    if (n == 0 || *begin[0] == '#') continue;
    if (kind == Kind::Unknown && n == 2) {
      const std::uint64_t perFace = parseCount(begin[0], end[0], where);
      const std::uint64_t faces = parseCount(begin[1], end[1], where);
      if (perFace != 1 && perFace != 2) {
        where.fail("header '" + std::string(line) + "': expected '1 F' (plain) or '2 F' (crossfield)");
      }
      if (faces != expectedFaces) {
        where.fail("header declares " + std::to_string(faces) + " faces but the mesh has " + expected);
      }
      kind = perFace == 1 ? Kind::Plain : Kind::CrossField;
      haveHeader = true;
      continue;
    }
    if (kind == Kind::Unknown) kind = Kind::Plain;  // headerless plain file
    const int want = kind == Kind::Plain ? 3 : 7;
    if (n != want) {
      where.fail("expected " + std::to_string(want) +
                 (kind == Kind::Plain ? " numbers (x y z)" : " values (flag x1 y1 z1 x2 y2 z2)") +
                 ", found " + std::to_string(n));
    }
    if (vectors.size() == expectedFaces) {
      where.fail("more field lines than the mesh's " + expected + " faces");
    }
    const int first = kind == Kind::Plain ? 0 : 1;
    if (kind == Kind::CrossField) {
      parseCount(begin[0], end[0], where);  // the constraint flag
      for (int k = 4; k < 7; ++k) parseNumber(begin[k], end[k], where);  // checked, unused
    }
    vectors.emplace_back(parseNumber(begin[first], end[first], where),
                         parseNumber(begin[first + 1], end[first + 1], where),
                         parseNumber(begin[first + 2], end[first + 2], where));
  }
  if (vectors.size() != expectedFaces) {
    throw InputError(path + ":" + std::to_string(lineNo) + ": file ends after " +
                     std::to_string(vectors.size()) + " field lines but the mesh has " + expected +
                     " faces" + (haveHeader ? "" : " (no header line)"));
  }
  return vectors;
}

CrossField importField(const std::string& path, const TriangleMesh& mesh) {
  return projectToTangent(mesh, readFieldVectors(path, mesh.numFaces()));
}

CrossField importField(const std::string& path, const TriangleMesh& mesh,
                       const std::vector<FaceId>& faceOrigin, std::uint32_t inputFaces) {
  const std::vector<Vec3d> vectors = readFieldVectors(path, inputFaces);
  if (faceOrigin.size() != mesh.numFaces()) {
    throw InputError(path + ": importField needs one origin per mesh face");
  }
  std::vector<Vec3d> perFace(mesh.numFaces());
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (faceOrigin[f] >= inputFaces) throw InputError(path + ": face origin out of range");
    perFace[f] = vectors[faceOrigin[f]];
  }
  return projectToTangent(mesh, std::move(perFace));
}

void writeField(const std::string& path, const std::vector<Vec3d>& vectors) {
  AtomicFile file(path);
  writeField(file, vectors);
  file.commit();
}

void writeField(AtomicFile& file, const std::vector<Vec3d>& vectors) {
  writeFieldHeader(file, vectors.size());
  appendFieldVectors(file, vectors.data(), vectors.size());
}

void writeFieldHeader(AtomicFile& file, std::uint64_t faces) {
  file.write("# seamvox field: one tangent vector (x y z) per face, in face order\n1 " + std::to_string(faces) + "\n");
}

void appendFieldVectors(AtomicFile& file, const Vec3d* vectors, std::size_t count) {
  std::string chunk;
  char buf[96];
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3d& v = vectors[i];
    const int len = std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", v.x(), v.y(), v.z());
    chunk.append(buf, static_cast<std::size_t>(len));
    if (chunk.size() > (1u << 20)) {
      file.write(chunk);
      chunk.clear();
    }
  }
  file.write(chunk);
}

}  // namespace seamvox
