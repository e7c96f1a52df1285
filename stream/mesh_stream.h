#pragma once
/// Chunked streaming of meshes: a reader hands out vertices and triangles in chunks, so a
/// 20M-triangle file never needs two full copies in memory. Later stages (topology building,
/// voxel filling) consume the chunks directly.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"

namespace seamvox {

/// One chunk of a mesh stream. Vertices are numbered globally in stream order: the first
/// position of a chunk has id firstVertex. Triangles index that global numbering and may refer
/// to any vertex of the whole stream (validated by the reader once the vertex count is known).
struct MeshChunk {
  std::uint32_t firstVertex = 0;
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  /// Per-corner (u, v) of this chunk's triangles (3 per triangle) when the source has texture
  /// coordinates and they were asked for; empty otherwise.
  std::vector<Vec2d> cornerUV;
  /// Per-vertex properties of this chunk's positions (the same names and types in every chunk
  /// of a stream; no properties when the source has none).
  VertexAttributes attributes;
  /// TriangleMesh::origin of the positions (the same in every chunk of a stream).
  Vec3d origin = Vec3d::Zero();
  void clear() {
    positions.clear();
    triangles.clear();
    cornerUV.clear();
    attributes.clearValues();
    origin = Vec3d::Zero();
  }
};

/// A pull-style source of mesh chunks (files, generators, tile sets).
class MeshStream {
 public:
  virtual ~MeshStream() = default;
  /// Fills chunk (cleared first) with the next vertices and/or triangles. Returns false at the
  /// end of the stream. Throws IoError / InputError naming the source and location.
  virtual bool next(MeshChunk& chunk) = 0;
  /// Name used in messages (usually the file path).
  virtual const std::string& name() const = 0;
  /// Vertex and face counts when the format declares them up front (0 when unknown; faces are
  /// counted after triangulation only when known exactly).
  virtual std::uint64_t declaredVertices() const { return 0; }
  virtual std::uint64_t declaredFaces() const { return 0; }
  /// Triangles to reserve room for: a hint that may be inexact (0 when unknown).
  virtual std::uint64_t expectedTriangles() const { return declaredFaces(); }
  /// True when every face's corners are vertices of their own (STL): vertices at equal positions
  /// are one vertex, joined by the consumer (collectMesh, the out-of-core weld pass). Each chunk's
  /// triangles then refer only to its own positions.
  virtual bool cornerVertices() const { return false; }
};

/// The checks collectMesh makes, for passes that consume a stream chunk by chunk without
/// collecting it: chunks continue the vertex numbering, ids fit 32 bits, UVs on all triangles or
/// none, and (finish) every face's vertices exist. Memory: the faces whose largest vertex id
/// exceeds every earlier face's (a few), so the first bad face is named as collectMesh names it.
class StreamChecker {
 public:
  explicit StreamChecker(std::string name) : name_(std::move(name)) {}
  /// Throws InputError naming the stream.
  void check(const MeshChunk& chunk);
  /// After the last chunk: throws InputError naming the first face with a vertex that does not exist.
  void finish() const;
  std::uint64_t vertices() const { return vertices_; }
  std::uint64_t faces() const { return faces_; }
  bool hasUV() const { return withUV_; }
  /// The origin of the stream's positions (that of its first chunk with positions).
  const Vec3d& origin() const { return origin_; }

 private:
  struct Record {
    std::uint64_t face;
    Triangle triangle;
    VertexId largest;
  };
  std::string name_;
  std::uint64_t vertices_ = 0, faces_ = 0;
  bool uvDecided_ = false, withUV_ = false;
  Vec3d origin_ = Vec3d::Zero();
  std::vector<Record> records_;  ///< increasing largest ids
};

/// Drains a stream into one TriangleMesh (validating every index against the final vertex
/// count), vertex attributes concatenated; a stream of corner vertices welded at exactly equal
/// positions (-0 as +0), vertices numbered by first appearance. Only the chunk buffer is held besides the result.
TriangleMesh collectMesh(MeshStream& stream);

/// A stream over a mesh held in memory: its vertices (and their attributes), then its triangles
/// (and corner UVs) in chunks of chunkTriangles.
std::unique_ptr<MeshStream> makeMemoryStream(std::string name, std::shared_ptr<const TriangleMesh> mesh,
                                             std::size_t chunkTriangles = std::size_t(1) << 18);

}  // namespace seamvox
