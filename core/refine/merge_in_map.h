#pragma once
/// Merging two cones a solve put on one point in the map itself, instead of another cone pass.
///
/// A pair of cones the rounding put on one point folds the faces between them, and no repair that
/// holds the cones unfolds them. Merged, they are one cone (DESIGN section 8), and when one of
/// them (gone) ends a single seam of the cut, the merge needs no new cut. A shortest path P of
/// uncut edges from gone to the other cone (kept) is a chord of the cut surface: it cuts off a
/// small piece D, bounded by P and by the cut's seams between the two cones. Turning the combing
/// of D by the quarter turns that make gone's seam the identity moves gone's index onto kept
/// along P (the field's matchings change on P alone), changes the rotations of the seams that
/// bound D, and, since both cones were rotations about one point p of D's chart, their new
/// translations follow exactly from rotating D's chart about p: every loop around the pair keeps
/// its holonomy, the map outside a neighbourhood of D stays valid, and that neighbourhood is
/// solved again in the hat basis with every translation fixed.
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/mesh/wedge_map.h"

namespace seamvox {

struct MergeInMapOptions {
  double edgeLength = 1.0;  ///< h, of the map (> 0)
  /// The region solved again: faces within about radius * h of D, P and the seams bounding D
  /// (vertex rings at P's mean edge length, at least 2).
  double radius = 1.0;
  /// Longest path P from gone to kept (mesh units); <= 0: 4 h.
  double pathLength = 0.0;
  double coneWeightRadius = 0.0;  ///< of the local hat solve (HatBasisOptions)
  double closeHolesWithin = 0.0;  ///< the global solve's ParamOptions::closeHolesWithin
  /// A larger side D or region is not solved (the pair is left to another cone pass).
  std::size_t maxFaces = std::size_t(1) << 18;
};

struct MergeInMapResult {
  bool merged = false;
  std::string reason;  ///< why not, when not merged
  VertexId kept = kInvalidId, gone = kInvalidId;
  std::int32_t keptIndex4 = 0;  ///< the kept vertex's index after the merge (0: the pair cancelled)
  std::uint64_t pieceFaces = 0;  ///< faces of D
  std::uint32_t pathEdges = 0, changedSeams = 0;
  std::uint64_t regionFaces = 0, freeVertices = 0;
};

/// Merges cones a and b (index4 ia and ib, both nonzero, |ia + ib| <= 3) that the map puts on one
/// point, as above: gone is b when it ends exactly one seam, else a when it does. P is at most
/// options.pathLength long (mesh units) and its inner vertices touch no cut edge. cut (matchings
/// of the seams bounding D, their corners' matchings, D's face rotations, cones), cornerUV (the
/// free corners of the region: D and the faces within the radius of D, P and those seams) and
/// seamT change only when it merges; the seams' curves stay. Not merged, with the reason and
/// nothing changed: neither cone ends one seam, no such path, no small side of it (more than
/// maxFaces faces), the cones not on one point in D's chart (1e-6 grid units), or a local system
/// that cannot be factored.
MergeInMapResult mergeConesInMap(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                 CutResult& cut, WedgeMap& cornerUV, std::vector<std::complex<double>>& seamT,
                                 VertexId a, std::int32_t ia, VertexId b, std::int32_t ib,
                                 const MergeInMapOptions& options);

}  // namespace seamvox
