#pragma once
/// The steps of computeSingularities (field.cpp) on one face, one edge or one vertex, shared by the
/// in-memory function and the out-of-core field stage (stream/field_stream), so both read the
/// same matchings and indices. Internal.
#include <array>
#include <cmath>
#include <cstdint>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox::detail {

/// a wrapped into (-pi, pi].
inline double wrapAngle(double a) {
  constexpr double kTwoPi = 2.0 * M_PI;
  if (!(a > -3.0 * M_PI && a <= 3.0 * M_PI)) a = std::fmod(a, kTwoPi);  // rare: far out
  if (a > M_PI) a -= kTwoPi;
  if (a <= -M_PI) a += kTwoPi;
  return a;
}

/// std::lround(x), without the library call where |x| < 4 (x - trunc(x) is exact there).
inline long roundHalfAway(double x) {
  if (!(std::abs(x) < 4.0)) return std::lround(x);
  const double t = std::trunc(x), f = x - t;
  return static_cast<long>(t) + (f >= 0.5) - (f <= -0.5);
}

/// Interior angles at the three corners from the frame angles of their edges. Turning angle at
/// corner k: from the incoming edge (corner k+1) to the outgoing one (corner k+2). The third is
/// set so the turns sum to exactly 2 pi, hence the corner angles to pi, also for degenerate
/// faces; every value agrees with the frame angles modulo 2 pi.
template <class T>
void cornerAngles(const T edge[3], double corner[3]) {
  const double turn0 = wrapAngle(double(edge[2]) - double(edge[1]));
  const double turn1 = wrapAngle(double(edge[0]) - double(edge[2]));
  const double turn2 = 2.0 * M_PI - turn0 - turn1;
  corner[0] = M_PI - turn0;
  corner[1] = M_PI - turn1;
  corner[2] = M_PI - turn2;
}

/// Per face: the field's angle and its edges' angles in the face's frame on the surface the
/// indices are read on (16 bytes; float is ample for rounding to quarter turns).
struct FaceAngleData {
  float theta, edge[3];
};
/// surface: the face's corners there; direction: the field on the face, tangent to the face's
/// own plane of normal *ownNormal, turned onto the surface's plane (null: the surface is the face).
FaceAngleData faceAngleData(const std::array<Vec3d, 3>& surface, const Vec3d* ownNormal, const Vec3d& direction);

/// Matching and residual rotation across the edge of corner c (slot c % 3 of face data f) to its
/// opposite corner o (slot o % 3 of g); read from the smaller corner, so both sides are opposite.
struct Crossing {
  std::uint8_t matching;
  float eps;
};
inline Crossing crossingOf(const FaceAngleData& f, unsigned cSlot, const FaceAngleData& g, unsigned oSlot) {
  // kappa: the edge's angle in g's frame (traversed reversed: plus pi) minus its angle in f's.
  const double kappa = wrapAngle(double(g.edge[oSlot]) + M_PI - double(f.edge[cSlot]));
  const double d = wrapAngle(double(g.theta) - double(f.theta) - kappa);
  const long k = roundHalfAway(d / (0.5 * M_PI));  // in [-2, 2]
  return Crossing{static_cast<std::uint8_t>(((k % 4) + 4) % 4), static_cast<float>(d - k * (0.5 * M_PI))};
}

/// A vertex's index in quarter turns from its turn (radians): the rounding vertexIndices applies.
inline std::int32_t quarterTurns(double turn) { return static_cast<std::int32_t>(std::lround(4.0 * turn / (2.0 * M_PI))); }

/// Index (and boundary index, field.h) of a vertex that is not isolated, walking its fan
/// counter-clockwise; dataOf(face) gives a face's angles, residualOf(corner) the residual
/// rotation across the edge of a corner (0 on a boundary edge).
template <class Table, class DataOf, class ResidualOf>
void vertexIndices(Table& table, VertexId v, DataOf&& dataOf, ResidualOf&& residualOf, std::int32_t& index4,
                   std::int32_t& boundaryIndex4) {
  const auto offQuarterTurn = [](double a) { return a - std::round(a / (0.5 * M_PI)) * (0.5 * M_PI); };
  const bool boundary = table.isBoundaryVertex(v);
  double sum = boundary ? M_PI : 2.0 * M_PI;
  CornerId first = kInvalidId, last = kInvalidId;
  table.forEachCornerAround(v, [&](CornerId c) {
    double corner[3];
    const FaceAngleData data = dataOf(cornerFace(c));
    cornerAngles(data.edge, corner);
    sum += residualOf(nextCorner(c)) - corner[c % 3];
    if (first == kInvalidId) first = c;
    last = c;
  });
  if (!boundary) {
    index4 = quarterTurns(sum);
    return;
  }
  const FaceAngleData a = dataOf(cornerFace(first));
  const FaceAngleData b = dataOf(cornerFace(last));
  const double deltaFirst = offQuarterTurn(double(a.theta) - a.edge[prevCorner(first) % 3]);
  const double deltaLast = offQuarterTurn(double(b.theta) - b.edge[nextCorner(last) % 3]);
  boundaryIndex4 = quarterTurns(sum + deltaFirst - deltaLast);
}

}  // namespace seamvox::detail
