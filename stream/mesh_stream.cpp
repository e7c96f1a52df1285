#include "stream/mesh_stream.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include "core/system/errors.h"

namespace seamvox {

void StreamChecker::check(const MeshChunk& chunk) {
  constexpr std::uint64_t kMaxIds = std::numeric_limits<std::uint32_t>::max();
  if (chunk.firstVertex != vertices_) {
    throw InputError(name_ + ": stream chunk starts at vertex " + std::to_string(chunk.firstVertex) + " but " +
                     std::to_string(vertices_) + " vertices came before it");
  }
  if (vertices_ + chunk.positions.size() >= kMaxIds || faces_ + chunk.triangles.size() >= kMaxIds) {
    throw InputError(name_ + ": more than 2^32 - 1 vertices or faces (ids are 32-bit)");
  }
  if (!chunk.positions.empty()) {
    try {
      chunk.attributes.checkSize(chunk.positions.size());
    } catch (const InputError& e) {
      throw InputError(name_ + ": " + e.what());
    }
    if (vertices_ == 0) origin_ = chunk.origin;
    if (chunk.origin != origin_) throw InputError(name_ + ": stream chunks have positions about different origins");
  }
  vertices_ += chunk.positions.size();
  if (chunk.triangles.empty()) return;
  const bool chunkUV = !chunk.cornerUV.empty();
  if (chunkUV && chunk.cornerUV.size() != 3 * chunk.triangles.size()) {
    throw InputError(name_ + ": stream chunk has " + std::to_string(chunk.cornerUV.size()) + " corner UVs for " +
                     std::to_string(chunk.triangles.size()) + " triangles");
  }
  if (!uvDecided_) {
    withUV_ = chunkUV;
    uvDecided_ = true;
  } else if (withUV_ != chunkUV) {
    throw InputError(name_ + ": some triangles have texture coordinates and others do not");
  }
  for (std::size_t f = 0; f < chunk.triangles.size(); ++f) {
    const Triangle& t = chunk.triangles[f];
    const VertexId largest = std::max({t[0], t[1], t[2]});
    if (largest >= vertices_ && (records_.empty() || largest > records_.back().largest)) {
      records_.push_back({faces_ + f, t, largest});
    }
  }
  faces_ += chunk.triangles.size();
}

void StreamChecker::finish() const {
  // The first face whose largest id is out of range is the first record that is.
  for (const Record& r : records_) {
    if (r.largest < vertices_) continue;
    for (const VertexId v : r.triangle) {
      if (v >= vertices_) {
        throw InputError(name_ + ": face " + std::to_string(r.face) + " refers to vertex " + std::to_string(v) +
                         " but there are only " + std::to_string(vertices_) + " vertices");
      }
    }
  }
}

namespace {

/// Vertices at exactly equal positions (-0 as +0) made one, numbered by first appearance: the
/// welding of a stream whose faces' corners are vertices of their own (STL). An open-addressing
/// table of vertex ids (4 bytes per slot, at most half full) over the welded positions.
class ExactWeld {
 public:
  ExactWeld(std::vector<Vec3f>& positions, std::uint64_t expectedVertices) : positions_(positions) {
    std::size_t slots = 1024;
    while (slots < 2 * expectedVertices) slots *= 2;
    slots_.assign(slots, kInvalidId);
  }

  VertexId add(const Vec3f& p) {
    std::size_t i = hashOf(p) & (slots_.size() - 1);
    while (slots_[i] != kInvalidId) {
      if (positions_[slots_[i]] == p) return slots_[i];
      i = (i + 1) & (slots_.size() - 1);
    }
    const VertexId id = static_cast<VertexId>(positions_.size());
    positions_.push_back(p);
    slots_[i] = id;
    if (2 * positions_.size() > slots_.size()) grow();
    return id;
  }

 private:
  static std::size_t hashOf(const Vec3f& p) {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int k = 0; k < 3; ++k) {
      const float x = p[k] + 0.0f;  // -0 + 0 = +0: equal floats hash alike
      std::uint32_t bits;
      std::memcpy(&bits, &x, 4);
      h = (h ^ bits) * 0xFF51AFD7ED558CCDull;
      h ^= h >> 32;
    }
    return static_cast<std::size_t>(h);
  }

  void grow() {
    slots_.assign(2 * slots_.size(), kInvalidId);
    for (VertexId v = 0; v < positions_.size(); ++v) {
      std::size_t i = hashOf(positions_[v]) & (slots_.size() - 1);
      while (slots_[i] != kInvalidId) i = (i + 1) & (slots_.size() - 1);
      slots_[i] = v;
    }
  }

  std::vector<Vec3f>& positions_;
  std::vector<VertexId> slots_;
};

/// collectMesh for a stream of corner vertices: each chunk's triangles refer to its own positions.
TriangleMesh collectWelded(MeshStream& stream) {
  TriangleMesh mesh;
  const std::uint64_t faces = std::min<std::uint64_t>(stream.expectedTriangles(), std::numeric_limits<std::uint32_t>::max());
  // A closed surface has about half as many vertices as faces.
  mesh.positions.reserve(static_cast<std::size_t>(faces / 2 + 16));
  mesh.triangles.reserve(static_cast<std::size_t>(faces));
  ExactWeld weld(mesh.positions, faces / 2);
  StreamChecker checker(stream.name());
  MeshChunk chunk;
  std::vector<VertexId> welded;
  while (stream.next(chunk)) {
    checker.check(chunk);
    if (checker.hasUV() || !chunk.attributes.properties.empty()) {
      throw InputError(stream.name() + ": a stream of per-corner vertices with texture coordinates or vertex "
                                       "properties cannot be welded");
    }
    welded.resize(chunk.positions.size());
    for (std::size_t i = 0; i < chunk.positions.size(); ++i) welded[i] = weld.add(chunk.positions[i]);
    for (const Triangle& t : chunk.triangles) {
      Triangle out;
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t local = std::uint64_t(t[k]) - chunk.firstVertex;
        if (t[k] < chunk.firstVertex || local >= welded.size()) {
          throw InputError(stream.name() + ": face " + std::to_string(mesh.triangles.size()) +
                           " refers to a vertex outside its own chunk in a stream of per-corner vertices");
        }
        out[k] = welded[local];
      }
      mesh.triangles.push_back(out);
    }
  }
  checker.finish();
  mesh.weldedAtRead = checker.vertices() - mesh.positions.size();
  mesh.origin = checker.origin();
  return mesh;
}

}  // namespace

TriangleMesh collectMesh(MeshStream& stream) {
  if (stream.cornerVertices()) return collectWelded(stream);
  constexpr std::uint64_t kMaxIds = std::numeric_limits<std::uint32_t>::max();
  TriangleMesh mesh;
  // Readers check declared counts against the file size, so these hints are safe to reserve.
  mesh.positions.reserve(static_cast<std::size_t>(std::min(stream.declaredVertices(), kMaxIds)));
  mesh.triangles.reserve(static_cast<std::size_t>(std::min(stream.expectedTriangles(), kMaxIds)));

  StreamChecker checker(stream.name());
  MeshChunk chunk;
  WedgeMapBuilder uv;
  while (stream.next(chunk)) {
    checker.check(chunk);
    if (!chunk.positions.empty()) {
      if (mesh.positions.empty()) {
        mesh.attributes = chunk.attributes.emptyCopy();
        for (VertexProperty& p : mesh.attributes.properties) p.bytes.reserve(mesh.positions.capacity() * scalarSize(p.type));
      }
      try {
        mesh.attributes.append(chunk.attributes);
      } catch (const InputError& e) {
        throw InputError(stream.name() + ": " + e.what());
      }
    }
    mesh.positions.insert(mesh.positions.end(), chunk.positions.begin(), chunk.positions.end());
    if (chunk.triangles.empty()) continue;
    if (checker.hasUV() && mesh.triangles.empty()) uv.reserve(3 * std::max<std::size_t>(mesh.triangles.capacity(), 1));
    mesh.triangles.insert(mesh.triangles.end(), chunk.triangles.begin(), chunk.triangles.end());
    // Corners at a vertex not read yet (validated below) get wedges of their own.
    for (std::size_t c = 0; c < chunk.cornerUV.size(); ++c) {
      const VertexId v = chunk.triangles[c / 3][c % 3];
      uv.add(v < mesh.positions.size() ? v : kInvalidId, chunk.cornerUV[c]);
    }
  }
  if (checker.hasUV()) mesh.cornerUV = uv.finish();
  checker.finish();
  mesh.origin = checker.origin();
  return mesh;
}

namespace {

class MemoryStream final : public MeshStream {
 public:
  MemoryStream(std::string name, std::shared_ptr<const TriangleMesh> mesh, std::size_t chunk)
      : name_(std::move(name)), mesh_(std::move(mesh)), chunk_(std::max<std::size_t>(chunk, 1)) {}

  bool next(MeshChunk& chunk) override {
    chunk.clear();
    const TriangleMesh& m = *mesh_;
    chunk.firstVertex = static_cast<std::uint32_t>(vertex_);
    chunk.origin = m.origin;
    if (vertex_ < m.positions.size()) {
      const std::size_t end = std::min(m.positions.size(), vertex_ + chunk_);
      chunk.positions.assign(m.positions.begin() + vertex_, m.positions.begin() + end);
      chunk.attributes = m.attributes.emptyCopy();
      for (std::size_t i = 0; i < m.attributes.properties.size(); ++i) {
        const VertexProperty& from = m.attributes.properties[i];
        const std::size_t width = scalarSize(from.type);
        chunk.attributes.properties[i].bytes.assign(from.bytes.begin() + vertex_ * width, from.bytes.begin() + end * width);
      }
      vertex_ = end;
      return true;
    }
    if (face_ >= m.triangles.size()) return false;
    const std::size_t end = std::min(m.triangles.size(), face_ + chunk_);
    chunk.triangles.assign(m.triangles.begin() + face_, m.triangles.begin() + end);
    if (m.hasUV()) {
      chunk.cornerUV.reserve(3 * (end - face_));
      for (std::size_t c = 3 * face_; c < 3 * end; ++c) chunk.cornerUV.push_back(m.cornerUV[c]);
    }
    face_ = end;
    return true;
  }
  const std::string& name() const override { return name_; }
  std::uint64_t declaredVertices() const override { return mesh_->positions.size(); }
  std::uint64_t declaredFaces() const override { return mesh_->triangles.size(); }

 private:
  std::string name_;
  std::shared_ptr<const TriangleMesh> mesh_;
  std::size_t chunk_;
  std::size_t vertex_ = 0, face_ = 0;
};

}  // namespace

std::unique_ptr<MeshStream> makeMemoryStream(std::string name, std::shared_ptr<const TriangleMesh> mesh,
                                             std::size_t chunkTriangles) {
  return std::make_unique<MemoryStream>(std::move(name), std::move(mesh), chunkTriangles);
}

}  // namespace seamvox
