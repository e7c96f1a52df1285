#pragma once
/// The local refinement's regions paged in from the scratch folder: the region's faces, their
/// vertices' fans, positions, field and cut read through page caches into a RegionMesh, as
/// extractRegion cuts it out of a mesh in memory.
#include <vector>

#include "core/refine/refine.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/field_stream.h"

namespace seamvox {

/// extractRegion on readCleanScratch's mesh, the field's directions and the cut (equal to it).
/// regionFaces: increasing face ids (InputError otherwise). Cost: the region times the valence.
RegionMesh extractScratchRegion(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                                const std::vector<FaceId>& regionFaces, const StreamPassOptions& pass);

}  // namespace seamvox
