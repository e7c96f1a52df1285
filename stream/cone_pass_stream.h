#pragma once
/// The later cone passes of the out-of-core param, as parameterize's in memory: the cone pairs a
/// map put on one point (coincidentCones), found on the out-of-core map, and which of them have a
/// face still flipped next to them.
#include <cstdint>
#include <utility>
#include <vector>

#include "stream/clean_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/field_stream.h"
#include "stream/untangle_stream.h"

namespace seamvox {

/// coincidentCones of the out-of-core map (the singularities' cones) whose indices may merge
/// (canMergeCoincident). Memory: the cones' wedges and the searches' balls.
std::vector<std::pair<VertexId, VertexId>> scratchMergeableCoincidentCones(ScratchFolder& folder,
                                                                           const CleanScratch& scratch,
                                                                           const ScratchSingularities& singularities,
                                                                           const ScratchMap& map, double maxDistance,
                                                                           const StreamPassOptions& pass);

/// The faces whose centroid lies within distance of a cone of the pairs.
FacesNearPoints facesNearConePairs(const CleanScratch& scratch, const std::vector<std::pair<VertexId, VertexId>>& pairs,
                                   double distance, const StreamPassOptions& pass);

/// Of scratchMergeableCoincidentCones(maxDistance), the pairs with a face the map flips (h: the
/// grid spacing) whose centroid lies within maxDistance of one of their cones, measured only
/// among faces that near the pairs: one pass over the faces when there is a pair, none otherwise.
std::vector<std::pair<VertexId, VertexId>> scratchFoldedCoincidentCones(ScratchFolder& folder, const CleanScratch& scratch,
                                                                        const ScratchSingularities& singularities,
                                                                        const ScratchMap& map, double h,
                                                                        double maxDistance, const StreamPassOptions& pass);

/// After the repair (parameterize's foldedConesAfterRepair): the pairs of
/// scratchFoldedCoincidentCones, and close cones (within maxDistance along interior edges, on two
/// points) whose indices may merge and whose own fans both hold a flipped face.
std::vector<std::pair<VertexId, VertexId>> scratchFoldedConesAfterRepair(ScratchFolder& folder,
                                                                         const CleanScratch& scratch,
                                                                         const ScratchSingularities& singularities,
                                                                         const ScratchMap& map, double h,
                                                                         double maxDistance,
                                                                         const StreamPassOptions& pass);

}  // namespace seamvox
