#pragma once
/// The field stage of the out-of-core param, on the cleaned mesh in the scratch folder
/// (clean_stream): each step equals its in-memory counterpart on readCleanScratch's mesh, and
/// reads the scratch through page caches (paged_reader) in the faces' Morton order.
#include <cstdint>

#include "stream/clean_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// smoothPositions(mesh, topology, iterations) of the cleaned mesh: Vec3f per vertex, a new file
/// (the cleaned positions themselves when iterations is 0). memoryBytes: the page caches' share.
ScratchFile smoothScratchPositions(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t iterations,
                                   std::uint64_t memoryBytes);

}  // namespace seamvox
