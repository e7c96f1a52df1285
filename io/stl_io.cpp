// STL reading, binary and ASCII (read only: STL holds no texture coordinates). STL stores every
// facet's three corners apart; the stream hands them out as three vertices per face
// (MeshStream::cornerVertices) and its consumers weld equal positions: collectMesh in memory, the
// weld pass out of core. Facet normals are ignored (the corner order gives the orientation).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {
namespace {

constexpr std::uint64_t kHeaderBytes = 84, kFacetBytes = 50;

/// The STL keyword at the front of text (case-insensitive), cut off; false when another word is there.
bool takeKeyword(std::string_view& text, std::string_view keyword) {
  std::string_view probe = text;
  const std::string_view token = nextToken(probe);
  if (token.size() != keyword.size()) return false;
  for (std::size_t i = 0; i < token.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(token[i])) != keyword[i]) return false;
  }
  text = probe;
  return true;
}

bool startsWithSolid(const char* data, std::size_t n) {
  std::size_t i = 0;
  while (i < n && std::isspace(static_cast<unsigned char>(data[i]))) ++i;
  if (n - i < 5) return false;
  for (std::size_t k = 0; k < 5; ++k) {
    if (std::tolower(static_cast<unsigned char>(data[i + k])) != "solid"[k]) return false;
  }
  return i + 5 == n || std::isspace(static_cast<unsigned char>(data[i + 5]));
}

/// The first word of the second line of the first n bytes: "facet" or "endsolid" in an ASCII STL.
bool secondLineIsAscii(const char* data, std::size_t n) {
  const char* end = data + n;
  const char* p = std::find(data, end, '\n');
  if (p == end) p = std::find(data, end, '\r');
  if (p == end) return false;
  while (p != end && std::isspace(static_cast<unsigned char>(*p))) ++p;
  std::string word;
  while (p != end && std::isalpha(static_cast<unsigned char>(*p))) word += static_cast<char>(std::tolower(*p++));
  return word == "facet" || word == "endsolid";
}

class StlReader final : public MeshStream {
 public:
  StlReader(std::unique_ptr<InputFile> in, const ReadOptions& options)
      : in_(std::move(in)), limit_(std::max<std::size_t>(options.chunkTriangles, 1)), warn_(options.warn),
        shift_(options.origin) {
    detectEncoding();
  }

  bool next(MeshChunk& chunk) override {
    chunk.clear();
    chunk.firstVertex = static_cast<std::uint32_t>(3 * facesRead_);
    if (binary_) readBinary(chunk);
    else readAscii(chunk);
    return !chunk.triangles.empty();
  }

  const std::string& name() const override { return in_->path(); }
  std::uint64_t declaredVertices() const override { return binary_ && in_->isRegular() ? 3 * numFaces_ : 0; }
  std::uint64_t declaredFaces() const override { return binary_ && in_->isRegular() ? numFaces_ : 0; }
  // An ASCII facet takes about 250 bytes.
  std::uint64_t expectedTriangles() const override {
    if (!in_->isRegular()) return 0;
    return binary_ ? numFaces_ : in_->size() / 250;
  }
  bool cornerVertices() const override { return true; }

 private:
  [[noreturn]] void failAtLine(const std::string& problem) const {
    throw InputError(in_->path() + ": line " + std::to_string(in_->lineNumber()) + ": " + problem);
  }

  /// Binary when the size is exactly 84 + 50 N for the N the header declares (a binary header may
  /// start with "solid" too), ASCII when the file starts with "solid"; a pipe is ASCII when its
  /// second line starts with "facet" or "endsolid".
  void detectEncoding() {
    // The first 4 KiB (or the whole input when shorter) to look at; nothing is consumed yet.
    constexpr std::size_t kProbe = 4096;
    const std::size_t available = in_->ensure(kProbe) ? kProbe : in_->readToEnd();
    const char* head = in_->data();
    const bool full = available >= kHeaderBytes;
    std::uint32_t declared = 0;
    if (full) std::memcpy(&declared, head + 80, 4);
    const std::uint64_t binaryBytes = kHeaderBytes + kFacetBytes * std::uint64_t(declared);
    const bool ascii = startsWithSolid(head, available) && secondLineIsAscii(head, available);
    if (in_->isRegular()) {
      binary_ = full && in_->size() == binaryBytes;
      if (!binary_ && !ascii) {
        throw InputError(in_->path() + ": not an STL file: a binary STL declaring " + std::to_string(declared) +
                         " facets has 84 + 50 x " + std::to_string(declared) + " = " + std::to_string(binaryBytes) +
                         " bytes, this one " + std::to_string(in_->size()) +
                         " (truncated?), and an ASCII STL starts with 'solid', then 'facet' or 'endsolid'");
      }
    } else {
      binary_ = !ascii;
      if (binary_ && !full) {
        throw InputError(in_->path() + ": not an STL file: neither ASCII ('solid', then 'facet' or 'endsolid') nor "
                                       "binary (it ends within the 84-byte header)");
      }
    }
    if (binary_) {
      numFaces_ = declared;
      in_->advance(kHeaderBytes);
      if (3 * numFaces_ >= std::numeric_limits<std::uint32_t>::max()) {
        throw InputError(in_->path() + ": " + std::to_string(numFaces_) + " facets have more corners than 32-bit ids allow");
      }
    }
  }

  /// A facet of corners f (floats) or d (doubles, when the shift needs them; else null).
  void addFacet(const float* f, const double* d, MeshChunk& chunk, std::uint64_t facet) {
    Vec3f p[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3f corner(f[3 * k], f[3 * k + 1], f[3 * k + 2]);
      p[k] = shift_.relative(d ? Vec3d(d[3 * k], d[3 * k + 1], d[3 * k + 2]) : corner.cast<double>(), corner);
      if (!p[k].allFinite()) {
        throw InputError(in_->path() + ": facet " + std::to_string(facet) + " has a NaN or infinite coordinate");
      }
    }
    chunk.origin = shift_.origin();
    const VertexId first = static_cast<VertexId>(3 * facesRead_);
    for (int k = 0; k < 3; ++k) chunk.positions.push_back(p[k]);
    chunk.triangles.push_back({first, first + 1, first + 2});
    ++facesRead_;
  }

  void readBinary(MeshChunk& chunk) {
    while (chunk.triangles.size() < limit_ && facesRead_ < numFaces_) {
      if (!in_->ensure(kFacetBytes)) {
        throw IoError(in_->path() + ": the file ends early (truncated) after " + std::to_string(facesRead_) + " of " +
                      std::to_string(numFaces_) + " facets");
      }
      const char* record = in_->data();
      float p[9];
      std::memcpy(p, record + 12, sizeof p);  // after the facet normal; little endian as written
      std::uint16_t attribute;
      std::memcpy(&attribute, record + 48, 2);
      if (attribute != 0 && !warnedAttribute_) {
        warnedAttribute_ = true;
        warn(warn_, in_->path() + ": the facets' attribute bytes (a colour in some writers) are not kept");
      }
      addFacet(p, nullptr, chunk, facesRead_);
      in_->advance(kFacetBytes);
    }
    if (facesRead_ == numFaces_ && !in_->isRegular() && in_->ensure(1)) {
      throw InputError(in_->path() + ": more bytes follow the " + std::to_string(numFaces_) +
                       " facets its binary header declares");
    }
  }

  /// The next line with something on it.
  bool contentLine(std::string_view& line) {
    while (in_->readLine(line)) {
      std::string_view probe = line;
      if (!nextToken(probe).empty()) return true;
    }
    return false;
  }

  void expectLine(std::string_view keyword, std::string_view second = {}) {
    std::string_view line;
    if (!contentLine(line)) {
      throw IoError(in_->path() + ": the file ends early (truncated) within facet " + std::to_string(facesRead_) +
                    " (line " + std::to_string(in_->lineNumber()) + ")");
    }
    if (!takeKeyword(line, keyword) || (!second.empty() && !takeKeyword(line, second))) {
      failAtLine("expected '" + std::string(keyword) + (second.empty() ? "" : " " + std::string(second)) + "'");
    }
  }

  void readAscii(MeshChunk& chunk) {
    std::string_view line;
    while (chunk.triangles.size() < limit_ && !ended_) {
      if (!contentLine(line)) {
        if (!inSolid_ && sawSolid_) {
          ended_ = true;
          break;
        }
        throw IoError(in_->path() + ": the file ends early (truncated): no 'endsolid' after " +
                      std::to_string(facesRead_) + " facets (line " + std::to_string(in_->lineNumber()) + ")");
      }
      if (!inSolid_) {
        if (!takeKeyword(line, "solid")) failAtLine("expected 'solid'");
        inSolid_ = sawSolid_ = true;
        continue;
      }
      if (takeKeyword(line, "endsolid")) {
        inSolid_ = false;
        continue;
      }
      if (!takeKeyword(line, "facet")) failAtLine("expected 'facet' or 'endsolid'");
      expectLine("outer", "loop");
      corners_.clear();
      exact_.clear();
      for (;;) {
        if (!contentLine(line)) {
          throw IoError(in_->path() + ": the file ends early (truncated) within facet " + std::to_string(facesRead_) +
                        " (line " + std::to_string(in_->lineNumber()) + ")");
        }
        if (takeKeyword(line, "endloop")) break;
        if (!takeKeyword(line, "vertex")) failAtLine("expected 'vertex' or 'endloop'");
        Vec3f p;
        Vec3d x;
        for (int k = 0; k < 3; ++k) {
          const std::string_view token = nextToken(line);
          if (!parseCoordinate(token, shift_, p[k], x[k])) {
            failAtLine("bad vertex coordinate '" + std::string(token.substr(0, 40)) + "'");
          }
          if (!std::isfinite(x[k])) {
            failAtLine("vertex coordinate '" + std::string(token.substr(0, 40)) + "' is NaN or infinite");
          }
        }
        corners_.push_back(p);
        exact_.push_back(x);
      }
      expectLine("endfacet");
      if (corners_.size() < 3) {
        failAtLine("facet " + std::to_string(facesRead_) + " has " + std::to_string(corners_.size()) +
                   " vertices (at least 3 are needed)");
      }
      // A polygon facet (not standard, written by a few tools) is split into a fan.
      for (std::size_t k = 2; k < corners_.size(); ++k) {
        float f[9];
        double d[9];
        for (int i = 0; i < 3; ++i) {
          const std::size_t corner = i == 0 ? 0 : k - 2 + i;
          for (int j = 0; j < 3; ++j) f[3 * i + j] = corners_[corner][j], d[3 * i + j] = exact_[corner][j];
        }
        if (3 * (facesRead_ + 1) >= std::numeric_limits<std::uint32_t>::max()) {
          failAtLine("more facet corners than 32-bit ids allow");
        }
        try {
          addFacet(f, d, chunk, facesRead_);
        } catch (const InputError&) {
          failAtLine("a vertex coordinate is beyond float range");
        }
      }
    }
  }

  std::unique_ptr<InputFile> in_;
  std::size_t limit_;
  WarningFn warn_;
  OriginShift shift_;
  bool binary_ = false;
  std::uint64_t numFaces_ = 0, facesRead_ = 0;
  bool inSolid_ = false, sawSolid_ = false, ended_ = false, warnedAttribute_ = false;
  std::vector<Vec3f> corners_;
  std::vector<Vec3d> exact_;
};

}  // namespace

std::unique_ptr<MeshStream> openStlStream(std::unique_ptr<InputFile> in, const ReadOptions& options) {
  return std::make_unique<StlReader>(std::move(in), options);
}

}  // namespace seamvox::detail
