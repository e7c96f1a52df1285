#pragma once
/// The vertex smoothing step of the field's geometry (smoothPositions), written once for the
/// in-memory corner table and the out-of-core one (stream/field_stream). Internal.
#include "core/mesh/topology.h"

namespace seamvox::detail {

/// Halfway from `here` to the mean of `count` neighbours summing to `sum` (here when not finite).
inline Vec3f smoothingTarget(const Vec3d& here, const Vec3d& sum, std::uint32_t count) {
  const Vec3d target = 0.5 * (here + sum / count);
  return target.allFinite() ? Vec3f(target.cast<float>()) : Vec3f(here.cast<float>());
}

/// One smoothing step at vertex v: halfway to the mean of its neighbours in fan order (valueOf(w)
/// gives the current position of w in double); boundary and isolated vertices stay. Table: a
/// corner table with isIsolatedVertex, isBoundaryVertex, forEachCornerAround and vertex.
template <class Table, class ValueOf>
Vec3f smoothingStep(Table& table, VertexId v, ValueOf&& valueOf) {
  const Vec3d here = valueOf(v);
  if (table.isIsolatedVertex(v) || table.isBoundaryVertex(v)) return here.cast<float>();
  Vec3d sum = Vec3d::Zero();
  std::uint32_t count = 0;
  table.forEachCornerAround(v, [&](CornerId c) {
    sum += valueOf(table.vertex(nextCorner(c)));
    ++count;
  });
  return smoothingTarget(here, sum, count);
}

}  // namespace seamvox::detail
