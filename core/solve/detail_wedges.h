#pragma once
/// The wedges of a vertex (corners between consecutive cut edges) walked once for the in-memory
/// buildCutWedges and the out-of-core evaluation (stream/evaluate_stream): a template over the
/// corner table (vertexCorner, cw, ccw) and the cut (isCut).
#include "core/mesh/topology.h"

namespace seamvox::detail {

/// Calls f(corner) for the corners of v counter-clockwise, starting just after a cut edge when v
/// has one (at the fan's start on the boundary), and f(kInvalidId) after every cut edge crossed:
/// the wedge boundaries.
template <class Table, class Cut, class F>
void walkWedges(Table& topology, Cut& corners, VertexId v, F&& f) {
  CornerId start = topology.vertexCorner(v);
  if (start == kInvalidId) return;
  // The edge between corner c and ccw(c) is the edge of next(c) (topology.h).
  if (topology.cw(start) != kInvalidId) {
    const CornerId fanStart = start;
    CornerId c = fanStart;
    do {
      if (corners.isCut(nextCorner(c))) {
        start = topology.ccw(c);
        break;
      }
      c = topology.ccw(c);
    } while (c != fanStart);
  }
  CornerId c = start;
  do {
    f(c);
    if (corners.isCut(nextCorner(c))) f(kInvalidId);
    c = topology.ccw(c);
  } while (c != kInvalidId && c != start);
}

}  // namespace seamvox::detail
