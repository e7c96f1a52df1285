#pragma once
/// Writes the cleaned mesh of the out-of-core param (stream/clean_stream) with the map evaluated
/// into the scratch folder (stream/evaluate_stream) as corner (u, v), chunk by chunk
/// (ChunkedMeshWriter): the bytes writeMesh writes for that mesh in memory. Draco is refused
/// (it encodes whole meshes).
#include "io/atomic_file.h"
#include "io/mesh_io.h"
#include "stream/clean_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/field_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// Vertices from the scratch positions, then faces with their corners' wedge values (a page
/// cache over the values); the caller commits file. Memory: a chunk, the writer's buffers, the
/// cache, and for OBJ the vertices' first corners (24 B per vertex) within a quarter of
/// pass.memoryBytes, on disk beyond it.
void writeScratchMap(AtomicFile& file, ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                     const WriteOptions& options, const StreamPassOptions& pass);

}  // namespace seamvox
