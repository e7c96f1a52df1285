#pragma once
/// The local refinement's regions paged in from the scratch folder: the region's faces, their
/// vertices' fans, positions, field and cut read through page caches into a RegionMesh, as
/// extractRegion cuts it out of a mesh in memory.
#include <complex>
#include <vector>

#include "core/refine/refine.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/field_stream.h"

namespace seamvox {

/// extractRegion on readCleanScratch's mesh, the field's directions and the cut (equal to it);
/// onFieldSurface: extractRegionOnFieldSurface, the surface read from field.framePositions.
/// regionFaces: increasing face ids (InputError otherwise). Cost: the region times the valence,
/// read through small pages (windowCacheBytes of them per file); the bytes read are added to
/// *bytesRead when given.
RegionMesh extractScratchRegion(const CleanScratch& scratch, const ScratchField& field, const ScratchCut& cut,
                                const std::vector<FaceId>& regionFaces, const StreamPassOptions& pass,
                                std::uint64_t* bytesRead = nullptr, bool onFieldSurface = false);

/// selectRefineRegion on the out-of-core map (evaluate_stream): options.markedFaces, the faces the
/// map collapses or flips (with options.seedFromMap; one pass over the faces, their corners'
/// wedges in order, positions and values through page caches), then options.rings rings of
/// neighbours by fan walks. Equal to selectRefineRegion in memory, with its counts in stats.
/// known: the seeds the smoothed evaluation read off this map (used instead of the pass when they
/// are known at options' edge length and threshold). Memory: the region. InputError on a marked
/// face out of range or a bad edge length.
std::vector<FaceId> selectScratchRefineRegion(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map,
                                              const RefineOptions& options, const StreamPassOptions& pass,
                                              RefineStats* stats = nullptr, const ScratchMapSeeds* known = nullptr);

/// refineNearCones and applyRefinement's corners on the out-of-core map: the first region by
/// selectScratchRefineRegion, then the same rounds (core/refine/detail_refine.h) with the regions
/// paged in (a set of page caches per thread) and the map read through page caches. The groups
/// of a round are solved a batch at a time (an eighth of pass.memoryBytes in solved corners), and
/// each batch's free corners go into `map` at once (as applyScratchRefinement applies them). The
/// result has no corners: its translations still go in with applyScratchRefinement. The map,
/// translations and figures equal those of refineNearCones and applyRefinement in memory.
/// Memory: a batch of corners, the solves, the face lists of the region and a flag per vertex
/// (within a sixteenth of pass.memoryBytes, else on disk). mapSeeds: see selectScratchRefineRegion.
/// changedFaces, when given: the faces of every corner the rounds gave a new value (increasing);
/// no other face of the map changes.
RefineResult refineScratchNearCones(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                    const ScratchCut& cut, ScratchMap& map,
                                    const std::vector<std::complex<double>>& seamT, const RefineOptions& options,
                                    const StreamPassOptions& pass, const ScratchMapSeeds* mapSeeds = nullptr,
                                    std::vector<FaceId>* changedFaces = nullptr);

/// applyRefinement on the out-of-core map: the refined corners' wedges take their values in place
/// (a wedge whose corners disagree is split as WedgeMap::assign splits it, the new wedges appended
/// and map.numWedges grown; vertexWedgeStart then no longer lists them), and the re-solved
/// translations go into `translations` when given. InputError on a corner or seam out of range,
/// before anything changes.
void applyScratchRefinement(ScratchFolder& folder, const RefineResult& refinement, ScratchMap& map,
                            std::vector<std::complex<double>>* translations, const StreamPassOptions& pass);

}  // namespace seamvox
