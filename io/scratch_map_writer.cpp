#include "io/scratch_map_writer.h"

#include <algorithm>

#include "core/system/errors.h"
#include "io/chunked_mesh_writer.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"

namespace seamvox {

void writeScratchMap(AtomicFile& file, ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                     const WriteOptions& options, const StreamPassOptions& pass) {
  const char* stage = "write";
  if (map.cornerWedge.bytes != 3 * scratch.numFaces * sizeof(std::uint32_t) ||
      map.wedgeValues.bytes != map.numWedges * sizeof(Vec2d)) {
    throw InputError("write: the map's files do not match the mesh (" + std::to_string(scratch.numFaces) + " faces)");
  }
  ChunkedMeshLayout layout;
  layout.countsKnown = true;
  layout.hasUV = true;
  layout.vertices = scratch.numVertices;
  layout.faces = scratch.numFaces;
  layout.origin = scratch.origin;
  layout.memoryBytes = pass.memoryBytes / 4;
  ChunkedMeshWriter writer(file, layout, options, &folder);
  const std::uint64_t chunkRecords = std::max<std::uint64_t>(1, pass.blockRecords);
  MeshChunk chunk;
  {
    ScratchReader positions(folder, scratch.positions, stage);
    for (std::uint64_t first = 0; first < scratch.numVertices; first += chunkRecords) {
      const std::size_t n = static_cast<std::size_t>(std::min(chunkRecords, scratch.numVertices - first));
      chunk.positions.resize(n);
      if (!positions.read(chunk.positions.data(), n * sizeof(Vec3f))) {
        throw IoError(scratch.positions.path + ": scratch positions end early");
      }
      chunk.firstVertex = static_cast<std::uint32_t>(first);
      writer.write(chunk);
    }
  }
  chunk.clear();
  chunk.firstVertex = static_cast<std::uint32_t>(scratch.numVertices);
  {
    ScratchReader faces(folder, scratch.faces, stage), wedges(folder, map.cornerWedge, stage);
    PagedReader<Vec2d> values(map.wedgeValues, pageCacheBytes(pass.memoryBytes));
    std::vector<CleanFace> block;
    std::vector<std::uint32_t> cornerWedge;
    for (std::uint64_t first = 0; first < scratch.numFaces; first += chunkRecords) {
      const std::size_t n = static_cast<std::size_t>(std::min(chunkRecords, scratch.numFaces - first));
      block.resize(n);
      cornerWedge.resize(3 * n);
      if (!faces.read(block.data(), n * sizeof(CleanFace)) ||
          !wedges.read(cornerWedge.data(), cornerWedge.size() * sizeof(std::uint32_t))) {
        throw IoError(scratch.faces.path + ": scratch faces or their wedges end early");
      }
      chunk.triangles.resize(n);
      chunk.cornerUV.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i) {
        chunk.triangles[i] = block[i].triangle;
        for (int k = 0; k < 3; ++k) chunk.cornerUV[3 * i + k] = values[cornerWedge[3 * i + k]];
      }
      writer.write(chunk);
    }
    folder.countRead(stage, values.bytesRead());
  }
  writer.finish();
}

}  // namespace seamvox
