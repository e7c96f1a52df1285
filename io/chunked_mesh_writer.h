#pragma once
/// Writing a mesh chunk by chunk (PLY, OBJ, OFF) with the bytes writeMesh writes for the whole
/// mesh, for meshes larger than memory. Draco encodes whole meshes and is refused. When the
/// counts are not known up front, the bodies wait in scratch files and the header (PLY, OFF)
/// follows once they are counted: a second copy of the body passes through the disk.
#include <cstdint>
#include <memory>

#include "core/mesh/mesh.h"
#include "io/mesh_io.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// What a chunked write must know before its first chunk.
struct ChunkedMeshLayout {
  VertexAttributes attributes;  ///< names and types of the vertex properties (values ignored)
  /// With countsKnown: the triangles carry corner UVs (written when WriteOptions::writeUV).
  /// Otherwise the first chunk with triangles tells.
  bool hasUV = false;
  /// Counts known up front (a generator): headers first, every chunk straight into the output,
  /// no scratch. Otherwise the bodies wait in scratch until finish().
  bool countsKnown = false;
  std::uint64_t vertices = 0, faces = 0;
  /// TriangleMesh::origin of the chunks' positions (written at origin + position); without the
  /// counts known, that of the first chunk with positions instead.
  Vec3d origin = Vec3d::Zero();
  /// OBJ with UVs and counts known: the per-vertex first corners (24 B per vertex) are held in
  /// memory up to this, on disk through a page cache of this size beyond it.
  std::uint64_t memoryBytes = ~std::uint64_t(0);
};

/// Writes chunks of a mesh stream (vertices numbered on from firstVertex) into an open output
/// whose path names the format; the caller commits it after finish(). Memory: output buffers,
/// plus for OBJ with UVs each vertex's first (u, v) and vt number (24 bytes per vertex; within
/// layout.memoryBytes when the counts are known).
class ChunkedMeshWriter {
 public:
  /// scratch: where bodies wait (needed unless countsKnown). Throws InputError for Draco and for
  /// OBJ with UVs without scratch; warns (WriteOptions::warn) about properties the format drops.
  ChunkedMeshWriter(AtomicFile& file, ChunkedMeshLayout layout, const WriteOptions& options, ScratchFolder* scratch);
  ~ChunkedMeshWriter();
  ChunkedMeshWriter(const ChunkedMeshWriter&) = delete;
  ChunkedMeshWriter& operator=(const ChunkedMeshWriter&) = delete;

  /// Writes a chunk (its vertices, then its triangles). Chunks are checked by the caller
  /// (StreamChecker); corners of a vertex not given yet are refused for OBJ with UVs.
  void write(const MeshChunk& chunk);
  /// Writes what waited in scratch; InputError when countsKnown and the counts differ.
  void finish();
  std::uint64_t vertices() const;
  std::uint64_t faces() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace seamvox
