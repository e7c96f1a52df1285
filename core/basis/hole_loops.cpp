#include "core/basis/hole_loops.h"

#include <algorithm>

namespace seamvox {

namespace {

// The composed transition q -> i^rotation q + translation . t of a walk so far.
struct Walk {
  int rotation = 0;
  GaussVector translation;
};

// Crossing the edge of corner c from face(c) to face(opposite(c)) (cut.h: left to right is
// q_right = r q_left + t with r = i^(-k)).
void cross(const SeamIndex& seams, const CutResult& cut, CornerId c, Walk& walk) {
  const SeamIndex::Side side = seams.find(c);
  if (side.seam == kInvalidId) return;
  const int k = cut.seams[side.seam].matching;
  const GaussVector unit{{side.seam, GaussInt(1)}};
  if (side.left) {
    const GaussInt r = unitPower(-k);
    walk.translation = scaled(walk.translation, r);
    addScaled(walk.translation, GaussInt(1), unit);
    walk.rotation = (walk.rotation - k + 4) % 4;
  } else {
    const GaussInt rInv = unitPower(k);
    walk.translation = scaled(walk.translation, rInv);
    addScaled(walk.translation, -rInv, unit);
    walk.rotation = (walk.rotation + k) % 4;
  }
}

}  // namespace

HoleLoopConstraints smallHoleConstraints(const TriangleMesh& mesh, const Topology& topology,
                                         const CutResult& cut, double maxExtent,
                                         const std::vector<std::uint8_t>* loopVertices) {
  HoleLoopConstraints out;
  if (cut.seams.empty()) return out;
  const SeamIndex seams(topology, cut.seams);
  std::vector<std::uint8_t> seen(topology.numCorners(), 0);
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (!topology.isBoundaryEdge(start) || seen[start]) continue;
    BoundingBox box;
    bool small = true;
    Walk walk;
    std::vector<CornerId> crossed;
    CornerId c = start;
    do {
      seen[c] = 1;
      const VertexId v = topology.vertex(prevCorner(c));
      if (loopVertices && !(*loopVertices)[v]) small = false;
      if (small) {
        const Vec3d p = mesh.position(v);
        box.min = box.min.cwiseMin(p);
        box.max = box.max.cwiseMax(p);
        small = (box.max - box.min).norm() <= maxExtent;
      }
      crossed.clear();
      c = nextBoundaryCorner(topology, c, small ? &crossed : nullptr);
      for (CornerId edge : crossed) cross(seams, cut, edge, walk);
    } while (c != start);
    if (!small) continue;
    ++out.smallLoops;
    if (walk.rotation != 0) {
      ++out.rotatedLoops;
    } else if (!walk.translation.empty()) {
      out.rows.push_back(std::move(walk.translation));
    }
  }
  return out;
}

}  // namespace seamvox
