// OFF reading (OFF and its ST/C/N/4 variants, whose extra per-vertex values are ignored; face
// colours ignored; '#' comments) and writing (plain OFF).
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {
namespace {

class OffReader final : public MeshStream {
 public:
  OffReader(std::unique_ptr<InputFile> in, const ReadOptions& options)
      : in_(std::move(in)), limit_(std::max<std::size_t>(options.chunkTriangles, 1)), shift_(options.origin) {
    readHeader();
  }

  bool next(MeshChunk& chunk) override {
    chunk.clear();
    chunk.firstVertex = static_cast<std::uint32_t>(verticesRead_);
    std::string_view line;
    while (chunk.triangles.size() < limit_ && chunk.positions.size() < limit_) {
      if (verticesRead_ < numVertices_) {
        if (!contentLine(line)) truncated();
        readVertex(line, chunk);
      } else if (facesRead_ < numFaces_) {
        if (!contentLine(line)) truncated();
        readFace(line, chunk);
      } else {
        break;
      }
    }
    return !chunk.positions.empty() || !chunk.triangles.empty();
  }

  const std::string& name() const override { return in_->path(); }
  // Hints to reserve by: the counts were checked against the size of a file, not of a pipe.
  std::uint64_t declaredVertices() const override { return in_->isRegular() ? numVertices_ : 0; }
  std::uint64_t expectedTriangles() const override { return in_->isRegular() ? numFaces_ : 0; }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(in_->path() + ": line " + std::to_string(in_->lineNumber()) + ": " + problem);
  }
  [[noreturn]] void truncated() const {
    throw IoError(in_->path() + ": the file ends early (truncated) after " +
                  std::to_string(verticesRead_) + " of " + std::to_string(numVertices_) +
                  " vertices and " + std::to_string(facesRead_) + " of " +
                  std::to_string(numFaces_) + " faces (line " + std::to_string(in_->lineNumber()) + ")");
  }

  /// The next line with something on it, '#' comments removed.
  bool contentLine(std::string_view& line) {
    while (in_->readLine(line)) {
      const std::size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      std::string_view probe = line;
      if (!nextToken(probe).empty()) return true;
    }
    return false;
  }

  void readHeader() {
    constexpr std::size_t kMaxHeaderLine = 1 << 16;
    std::string_view line;
    // Only the header lines are length-limited: a binary file must not be read as one line.
    bool found = false;
    while (in_->readLine(line, kMaxHeaderLine)) {
      const std::size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      std::string_view probe = line;
      if (!nextToken(probe).empty()) {
        found = true;
        break;
      }
    }
    if (!found) throw InputError(in_->path() + ": not an OFF file (it has no OFF header)");
    const std::string_view keyword = nextToken(line);
    std::string_view rest = keyword;
    if (rest.substr(0, 2) == "ST") rest.remove_prefix(2);
    if (rest.substr(0, 1) == "C") rest.remove_prefix(1);
    if (rest.substr(0, 1) == "N") rest.remove_prefix(1);
    if (rest.substr(0, 1) == "4") {
      dimension_ = 4;
      rest.remove_prefix(1);
    }
    if (rest.substr(0, 1) == "n") fail("nOFF (arbitrary dimension) is not supported");
    if (rest != "OFF") {
      fail("not an OFF file (it starts with '" + std::string(keyword.substr(0, 40)) + "', not OFF)");
    }
    std::string_view counts = line;
    std::string_view probe = counts;
    const std::string_view first = nextToken(probe);
    if (first == "BINARY") fail("binary OFF is not supported");
    if (first.empty() && !contentLine(counts)) fail("the OFF header has no vertex and face counts");
    const std::string_view v = nextToken(counts), f = nextToken(counts);
    if (!parseNumber(v, numVertices_) || !parseNumber(f, numFaces_)) {
      fail("expected the vertex and face counts 'V F E'");
    }
    // Each vertex line takes at least 6 bytes ("0 0 0\n"), each face at least 8 ("3 0 1 2\n").
    const long double needed = 6.0L * numVertices_ + 8.0L * numFaces_;
    if (needed > static_cast<long double>(in_->remaining()) + 1.0L) {
      throw IoError(in_->path() + ": line " + std::to_string(in_->lineNumber()) +
                    ": the header declares " + std::to_string(numVertices_) + " vertices and " +
                    std::to_string(numFaces_) + " faces, more than the " +
                    std::to_string(in_->remaining()) +
                    " bytes that follow can hold: the file is truncated or its header is wrong");
    }
    if (numVertices_ >= std::numeric_limits<std::uint32_t>::max()) {
      fail(std::to_string(numVertices_) + " vertices is more than 32-bit ids allow");
    }
  }

  void readVertex(std::string_view line, MeshChunk& chunk) {
    Vec3f f;
    Vec3d d;
    std::string_view tokens[3];
    for (int k = 0; k < dimension_; ++k) {
      const std::string_view token = nextToken(line);
      if (token.empty()) fail("vertex has fewer than " + std::to_string(dimension_) + " coordinates");
      float value;
      double exact;
      if (!parseCoordinate(token, shift_, value, exact)) fail("bad vertex coordinate '" + std::string(token.substr(0, 40)) + "'");
      if (k >= 3 && !std::isfinite(value)) fail("vertex coordinate '" + std::string(token.substr(0, 40)) + "' is NaN or infinite (or beyond float range)");
      if (k < 3) f[k] = value, d[k] = exact, tokens[k] = token;
    }
    const Vec3f p = shift_.relative(d, f);
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p[k])) fail("vertex coordinate '" + std::string(tokens[k].substr(0, 40)) + "' is NaN or infinite (or beyond float range)");
    }
    chunk.origin = shift_.origin();
    chunk.positions.push_back(p);
    ++verticesRead_;
  }

  void readFace(std::string_view line, MeshChunk& chunk) {
    std::uint64_t n;
    const std::string_view count = nextToken(line);
    if (!parseNumber(count, n)) fail("bad face vertex count '" + std::string(count.substr(0, 40)) + "'");
    if (n < 3) fail("face " + std::to_string(facesRead_) + " has " + std::to_string(n) + " vertices (at least 3 are needed)");
    corners_.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::string_view token = nextToken(line);
      if (token.empty()) fail("face " + std::to_string(facesRead_) + " lists fewer than its " + std::to_string(n) + " vertices");
      std::int64_t v;
      if (!parseNumber(token, v)) fail("bad vertex index '" + std::string(token.substr(0, 40)) + "'");
      if (v < 0 || static_cast<std::uint64_t>(v) >= numVertices_) {
        fail("face " + std::to_string(facesRead_) + ": vertex index " + std::to_string(v) +
             " is out of range (the file has " + std::to_string(numVertices_) + " vertices)");
      }
      corners_.push_back(static_cast<VertexId>(v));
    }
    for (std::size_t k = 2; k < corners_.size(); ++k) {
      chunk.triangles.push_back({corners_[0], corners_[k - 1], corners_[k]});
    }
    ++facesRead_;
  }

  std::unique_ptr<InputFile> in_;
  std::size_t limit_;
  OriginShift shift_;
  int dimension_ = 3;
  std::uint64_t numVertices_ = 0, numFaces_ = 0;
  std::uint64_t verticesRead_ = 0, facesRead_ = 0;
  std::vector<VertexId> corners_;
};

}  // namespace

std::unique_ptr<MeshStream> openOffStream(std::unique_ptr<InputFile> in, const ReadOptions& options) {
  return std::make_unique<OffReader>(std::move(in), options);
}

void putOffHeader(OutputBuffer& out, std::uint64_t vertices, std::uint64_t faces) {
  out.put("OFF\n");
  out.putNumber(vertices);
  out.put(' ');
  out.putNumber(faces);
  out.put(" 0\n");
}

void putOffVertices(OutputBuffer& out, const Vec3f* positions, std::size_t count, const Vec3d& origin) {
  if (origin.isZero(0.0)) {
    for (std::size_t v = 0; v < count; ++v) out.putRow(positions[v].data(), 3);
    return;
  }
  for (std::size_t v = 0; v < count; ++v) {
    const Vec3d world = origin + positions[v].cast<double>();
    out.putRow(world.data(), 3);
  }
}

void putOffFaces(OutputBuffer& out, const Triangle* triangles, std::size_t count) {
  for (std::size_t f = 0; f < count; ++f) {
    out.put("3 ");
    out.putRow(triangles[f].data(), 3);
  }
}

void writeOff(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions&) {
  OutputBuffer out(file);
  putOffHeader(out, mesh.positions.size(), mesh.triangles.size());
  putOffVertices(out, mesh.positions.data(), mesh.positions.size(), mesh.origin);
  putOffFaces(out, mesh.triangles.data(), mesh.triangles.size());
  out.flush();
}

}  // namespace seamvox::detail
