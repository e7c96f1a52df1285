// Wavefront OBJ reading (v with optional r g b colors, vt, f; vn named in a warning, everything
// else ignored) and
// writing (v with colors when the mesh has them, per-corner vt, f).
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {
namespace {

class ObjReader final : public MeshStream {
 public:
  ObjReader(std::unique_ptr<InputFile> in, const ReadOptions& options)
      : in_(std::move(in)),
        readUV_(options.readUV),
        limit_(std::max<std::size_t>(options.chunkTriangles, 1)),
        warn_(options.warn),
        shift_(options.origin) {}

  bool next(MeshChunk& chunk) override {
    chunk.clear();
    chunk.firstVertex = static_cast<std::uint32_t>(vertices_);
    if (done_) return false;
    std::string_view line;
    while (chunk.triangles.size() < limit_ && chunk.positions.size() < limit_) {
      if (!in_->readLine(line)) {
        finish();
        break;
      }
      const std::string_view keyword = nextToken(line);
      if (keyword == "v") readVertex(line, chunk);
      else if (keyword == "vt") readTexcoord(line);
      else if (keyword == "f") readFace(line, chunk);
      else if (keyword == "vn" && !warnedNormals_) {
        // Normals are per corner in OBJ (f v/vt/vn), not vertex properties.
        warn(warn_, in_->path() + ": line " + std::to_string(in_->lineNumber()) + ": vn normals not kept");
        warnedNormals_ = true;
      }
    }
    return !chunk.positions.empty() || !chunk.triangles.empty();
  }

  const std::string& name() const override { return in_->path(); }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(in_->path() + ": line " + std::to_string(in_->lineNumber()) + ": " + problem);
  }

  void readVertex(std::string_view line, MeshChunk& chunk) {
    Vec3f f;
    Vec3d d;
    std::string_view tokens[3];
    for (int k = 0; k < 3; ++k) {
      const std::string_view token = tokens[k] = nextToken(line);
      if (token.empty()) fail("vertex has fewer than 3 coordinates");
      if (!parseCoordinate(token, shift_, f[k], d[k])) fail("bad vertex coordinate '" + std::string(token.substr(0, 40)) + "'");
    }
    const Vec3f p = shift_.relative(d, f);
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p[k])) fail("vertex coordinate '" + std::string(tokens[k].substr(0, 40)) + "' is NaN or infinite (or beyond float range)");
    }
    chunk.origin = shift_.origin();
    if (vertices_ + 1 >= std::numeric_limits<std::uint32_t>::max()) {
      fail("more vertices than 32-bit ids allow");
    }
    readColor(line, chunk);
    chunk.positions.push_back(p);
    ++vertices_;
  }

  /// `v x y z r g b`: the first vertex decides whether vertices have colors (float red, green,
  /// blue); then every vertex must have one. Colors after a first vertex without are not kept.
  void readColor(std::string_view line, MeshChunk& chunk) {
    std::string_view tokens[4];
    int n = 0;
    while (n < 4 && !(tokens[n] = nextToken(line)).empty()) ++n;
    if (vertices_ == 0) {
      colors_ = n == 3;
      for (const char* name : {"red", "green", "blue"}) colorLayout_.add(name, ScalarType::Float32, 0);
    }
    if (!colors_) {
      if (n == 3 && !warnedColors_) {
        warn(warn_, in_->path() + ": line " + std::to_string(in_->lineNumber()) +
                        ": vertex colors not kept (the first vertex has none)");
        warnedColors_ = true;
      }
      return;
    }
    if (n != 3) fail("vertex has no r g b color but the first vertex has one");
    if (chunk.attributes.properties.size() != 3) chunk.attributes = colorLayout_.emptyCopy();
    for (int k = 0; k < 3; ++k) {
      float c;
      if (!parseNumber(tokens[k], c) || !std::isfinite(c)) fail("bad vertex color '" + std::string(tokens[k].substr(0, 40)) + "'");
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(&c);
      std::vector<std::uint8_t>& into = chunk.attributes.properties[k].bytes;
      into.insert(into.end(), bytes, bytes + sizeof c);
    }
  }

  void readTexcoord(std::string_view line) {
    if (!readUV_) return;
    Vec2d t(0.0, 0.0);
    for (int k = 0; k < 2; ++k) {
      const std::string_view token = nextToken(line);
      if (token.empty() && k == 1) break;  // v is optional and defaults to 0
      if (!parseNumber(token, t[k])) fail("bad texture coordinate '" + std::string(token.substr(0, 40)) + "'");
      if (!std::isfinite(t[k])) fail("texture coordinate '" + std::string(token.substr(0, 40)) + "' is NaN or infinite");
    }
    texcoords_.push_back(t);
  }

  /// 0-based index of an OBJ index (1-based, or negative = relative to the count so far).
  std::uint64_t resolve(std::string_view token, std::uint64_t count, const char* what) const {
    std::int64_t value;
    if (!parseNumber(token, value)) fail(std::string("bad ") + what + " index '" + std::string(token.substr(0, 40)) + "'");
    if (value == 0) fail(std::string(what) + " index 0 is invalid (OBJ indices start at 1)");
    if (value > 0) {
      if (static_cast<std::uint64_t>(value) >= std::numeric_limits<std::uint32_t>::max()) {
        fail(std::string(what) + " index " + std::to_string(value) + " is beyond 32-bit ids");
      }
      return static_cast<std::uint64_t>(value - 1);
    }
    if (static_cast<std::uint64_t>(-value) > count) {
      fail("relative " + std::string(what) + " index " + std::to_string(value) + " reaches before the first " +
           what + " (only " + std::to_string(count) + " so far)");
    }
    return count - static_cast<std::uint64_t>(-value);
  }

  void readFace(std::string_view line, MeshChunk& chunk) {
    corners_.clear();
    cornerUV_.clear();
    bool anyTexcoord = false, allTexcoords = true;
    for (std::string_view token = nextToken(line); !token.empty() && token[0] != '#';
         token = nextToken(line)) {
      const std::size_t slash = token.find('/');
      const std::uint64_t v = resolve(token.substr(0, slash), vertices_, "vertex");
      if (v >= vertices_ && (maxIndexLine_ == 0 || v > maxIndex_)) {
        maxIndex_ = v;  // a forward reference: checked once every vertex is known
        maxIndexLine_ = in_->lineNumber();
      }
      corners_.push_back(static_cast<VertexId>(v));
      std::string_view texcoord;
      if (slash != std::string_view::npos) {
        std::string_view rest = token.substr(slash + 1);
        const std::size_t slash2 = rest.find('/');
        texcoord = rest.substr(0, slash2);
        if (slash2 != std::string_view::npos) {
          std::int64_t normal;
          const std::string_view n = rest.substr(slash2 + 1);
          if (!n.empty() && !parseNumber(n, normal)) fail("bad face corner '" + std::string(token.substr(0, 40)) + "'");
        }
      }
      if (texcoord.empty()) {
        allTexcoords = false;
        continue;
      }
      anyTexcoord = true;
      if (!readUV_) continue;
      const std::uint64_t t = resolve(texcoord, texcoords_.size(), "texture coordinate");
      if (t >= texcoords_.size()) {
        fail("texture coordinate " + std::to_string(t + 1) + " is used before it is defined (" +
             std::to_string(texcoords_.size()) + " vt so far)");
      }
      cornerUV_.push_back(texcoords_[t]);
    }
    const std::size_t n = corners_.size();
    if (n < 3) fail("face has " + std::to_string(n) + " vertices (at least 3 are needed)");

    bool withUV = false;
    if (readUV_) {
      if (anyTexcoord && !allTexcoords) fail("face gives texture coordinates for some corners only");
      if (uvState_ == UVState::Unknown) uvState_ = anyTexcoord ? UVState::With : UVState::Without;
      withUV = uvState_ == UVState::With;
      if (withUV != anyTexcoord) {
        fail("some faces have texture coordinates and others do not (read without UVs to ignore them)");
      }
    }
    for (std::size_t k = 2; k < n; ++k) {
      chunk.triangles.push_back({corners_[0], corners_[k - 1], corners_[k]});
      if (withUV) {
        chunk.cornerUV.push_back(cornerUV_[0]);
        chunk.cornerUV.push_back(cornerUV_[k - 1]);
        chunk.cornerUV.push_back(cornerUV_[k]);
      }
    }
  }

  void finish() {
    done_ = true;
    if (maxIndexLine_ > 0 && maxIndex_ >= vertices_) {
      throw InputError(in_->path() + ": line " + std::to_string(maxIndexLine_) + ": face refers to vertex " +
                       std::to_string(maxIndex_ + 1) + " but the file has only " +
                       std::to_string(vertices_) + " vertices");
    }
  }

  enum class UVState { Unknown, With, Without };

  std::unique_ptr<InputFile> in_;
  bool readUV_;
  std::size_t limit_;
  WarningFn warn_;
  OriginShift shift_;
  bool done_ = false;
  bool colors_ = false, warnedColors_ = false, warnedNormals_ = false;
  VertexAttributes colorLayout_;  ///< red, green, blue without values
  std::uint64_t vertices_ = 0;
  std::uint64_t maxIndex_ = 0, maxIndexLine_ = 0;
  UVState uvState_ = UVState::Unknown;
  std::vector<Vec2d> texcoords_;
  std::vector<VertexId> corners_;
  std::vector<Vec2d> cornerUV_;
};

}  // namespace

std::unique_ptr<MeshStream> openObjStream(std::unique_ptr<InputFile> in, const ReadOptions& options) {
  return std::make_unique<ObjReader>(std::move(in), options);
}

void putObjVertices(OutputBuffer& out, const std::vector<Vec3f>& positions, const VertexAttributes& attributes,
                    std::size_t begin, std::size_t end, const Vec3d& origin) {
  // Colors as the common `v x y z r g b` extension, in [0, 1] (other properties: writeMesh warns).
  std::vector<std::size_t> color = colorProperties(attributes);
  color.resize(std::min<std::size_t>(color.size(), 3));
  for (std::size_t v = begin; v < end; ++v) {
    out.put("v ");
    if (origin.isZero(0.0)) {
      out.putRow(positions[v].data(), 3, color.empty() ? '\n' : ' ');
    } else {
      const Vec3d world = origin + positions[v].cast<double>();
      out.putRow(world.data(), 3, color.empty() ? '\n' : ' ');
    }
    if (color.empty()) continue;
    float rgb[3];
    for (int k = 0; k < 3; ++k) {
      rgb[k] = static_cast<float>(normalizedColor(attributes.properties[color[k]], static_cast<VertexId>(v)));
    }
    out.putRow(rgb, 3);
  }
}

void putObjFaces(OutputBuffer& out, const Triangle* triangles, std::size_t count) {
  for (std::size_t f = 0; f < count; ++f) putObjFace(out, triangles[f], nullptr);
}

void putObjTexcoord(OutputBuffer& out, const Vec2d& uv) {
  out.put("vt ");
  out.putRow(uv.data(), 2);
}

void putObjFace(OutputBuffer& out, const Triangle& t, const std::uint32_t* texcoord) {
  out.put('f');
  for (int k = 0; k < 3; ++k) {
    out.put(' ');
    out.putNumber(std::uint64_t(t[k]) + 1);
    if (texcoord) {
      out.put('/');
      out.putNumber(std::uint64_t(texcoord[k]) + 1);
    }
  }
  out.put('\n');
}

void writeObj(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  const bool withUV = options.writeUV && mesh.hasUV();
  OutputBuffer out(file);
  out.put("# written by seamvox\n");
  putObjVertices(out, mesh.positions, mesh.attributes, 0, mesh.positions.size(), mesh.origin);
  if (!withUV) {
    putObjFaces(out, mesh.triangles.data(), mesh.triangles.size());
    out.flush();
    return;
  }
  // Texture coordinates: the first corner of each vertex (in corner order) gets a vt line that
  // every later corner of the vertex with the same (u, v) shares; a corner with another value (the
  // other side of a seam) gets its own. A seamless map thus writes about one vt per vertex instead
  // of one per corner. Both passes walk the corners in the same order, so they number alike.
  const std::size_t numCorners = 3 * mesh.triangles.size();
  std::vector<CornerId> firstCorner(mesh.positions.size(), kInvalidId);
  std::vector<std::uint32_t> firstTexcoord(firstCorner.size(), 0);
  auto ownsTexcoord = [&](std::size_t c) {  // does corner c write (and number) a vt line?
    const CornerId first = firstCorner[mesh.triangles[c / 3][c % 3]];
    return first == c || mesh.cornerUV[c] != mesh.cornerUV[first];
  };
  {
    std::uint32_t count = 0;
    for (std::size_t c = 0; c < numCorners; ++c) {
      const VertexId v = mesh.triangles[c / 3][c % 3];
      if (firstCorner[v] == kInvalidId) {
        firstCorner[v] = static_cast<CornerId>(c);
        firstTexcoord[v] = count;
      }
      if (ownsTexcoord(c)) {
        putObjTexcoord(out, mesh.cornerUV[c]);
        ++count;
      }
    }
  }
  std::uint32_t next = 0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    std::uint32_t texcoord[3];
    for (int k = 0; k < 3; ++k) texcoord[k] = ownsTexcoord(3 * f + k) ? next++ : firstTexcoord[mesh.triangles[f][k]];
    putObjFace(out, mesh.triangles[f], texcoord);
  }
  out.flush();
}

}  // namespace seamvox::detail
