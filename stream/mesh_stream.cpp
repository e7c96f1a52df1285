#include "stream/mesh_stream.h"

#include <algorithm>
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

TriangleMesh collectMesh(MeshStream& stream) {
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
