#pragma once
/// The foldover repair (core/refine/untangle) of an out-of-core map: the faces it flips found by
/// one pass, a window of rings around them paged in (stream/refine_stream's readers) as a mesh of
/// its own, untangleFlips run there with the window's border pinned (its faces outside keep
/// their values, so the map stays seamless), and the moved corners written back in place.
#include <algorithm>
#include <array>
#include <complex>
#include <cstdint>
#include <vector>

#include "core/refine/refine.h"
#include "core/refine/untangle.h"
#include "stream/clean_stream.h"
#include "stream/cut_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/field_stream.h"

namespace seamvox {

/// Window figures besides untangleFlips' own (flips before and after are the whole map's: the
/// window holds every flipped face).
struct ScratchUntangleStats {
  UntangleStats untangle;  ///< leftFaces: mesh face ids (without `only`)
  std::uint64_t windowFaces = 0;
  std::uint32_t windowRings = 0;
  double leftMeanEdge = 0.0;  ///< mean edge length of untangle.leftFaces
};

/// Faces whose centroid lies within `distance` of one of `points`: the repair near a few cones
/// before deciding on another cone pass (UntangleOptions::onlyFaces in memory).
struct FacesNearPoints {
  std::vector<Vec3d> points;
  double distance = 0.0;
  bool holds(const std::array<Vec3d, 3>& p) const {
    const Vec3d c = (p[0] + p[1] + p[2]) / 3.0;
    return std::any_of(points.begin(), points.end(), [&](const Vec3d& q) { return (c - q).norm() <= distance; });
  }
};

/// Repairs the flips of map (seamT per seam of cut, updated where a seam inside a patch
/// re-rounded). options.edgeLength is h; options.onlyFaces and pinnedVertices must be unset: with
/// `only`, only the flipped faces it holds are repaired and counted. The
/// window holds rings enough for every patch round and the joint step, fewer (halved) when it
/// would exceed max(8 minPatchFaces, pass.memoryBytes / 1 KiB) faces. Memory: the window.
/// candidates (increasing, not with `only`): the only faces that may be flipped, read through
/// small pages instead of a pass over every face (a caller that knows the rest of the map).
ScratchUntangleStats untangleScratchFlips(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                          const ScratchCut& cut, ScratchMap& map,
                                          std::vector<std::complex<double>>& seamT, const UntangleOptions& options,
                                          const StreamPassOptions& pass, const FacesNearPoints* only = nullptr,
                                          const std::vector<FaceId>* candidates = nullptr);

/// The hat re-solve of the flips an out-of-core repair left (UntangleOptions::leftoverRadius;
/// refineScratchNearCones with leftoverRefineOptions) and the repair again, as the in-memory
/// pipeline does: `repaired` (the earlier repair's figures) becomes both repairs'. refine: the
/// pipeline's refine options (edgeLength set here from options). Nothing without flips left.
void resolveScratchLeftoverFlips(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                 const ScratchCut& cut, ScratchMap& map, std::vector<std::complex<double>>& seamT,
                                 RefineOptions refine, const UntangleOptions& options, const StreamPassOptions& pass,
                                 ScratchUntangleStats& repaired);

}  // namespace seamvox
