#pragma once
/// The voxel map re-evaluated at the field's smoothed surface where it folds. Evaluated at a
/// noisy vertex, the trilinear map repeats the tangential part of the noise: a vertex jittered by
/// a quarter of an edge flips or collapses its faces, which then seed the local refinement with
/// their rings (2.2 of the 8.4 points of vertices refined on a noisy 22M-face armadillo). Moved
/// to the smoothed surface, where the field was computed, the map there is the smooth one.
/// Only the vertices of faces the map folds move, and only those with one wedge (no seam through
/// them), so the map stays seamless whatever point they are evaluated at; each keeps its element
/// (the one holding its own position: evaluateAt clamps the point into that voxel).
/// A vertex keeps its value when the new one would stretch a face of its fan (isStretched) that
/// the old one did not, the rest of the fan as set so far (vertices in increasing order): a noise
/// needle (a face far thinner in 3D than its neighbours) given an image of its neighbours' size.
/// Rounds: first every face is measured, then only the faces around the vertices just moved; a
/// vertex is tried once.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <vector>

#include "core/basis/voxel_basis.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/quality/metrics.h"
#include "core/system/parallel.h"

namespace seamvox {

/// Rounds of evaluateFoldsAtSmoothedSurface (each after the faces it measured).
constexpr std::uint32_t kSmoothedEvaluationRounds = 3;
/// Vertices smoothed and evaluated at once: bounds the smoothed ball's memory (a few tens of MB).
constexpr std::size_t kSmoothedBatchVertices = std::size_t(1) << 18;
/// A face is folded here when its parameterAreaRatio is below this (flipped, or collapsed to
/// under a tenth of its area; a zero-area face, NaN, is not): the refinement's default collapse
/// threshold, so what this leaves folded is what seeds it.
constexpr double kSmoothedEvaluationRatio = 0.1;

inline bool foldedForSmoothedEvaluation(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q, double h) {
  const double ratio = parameterAreaRatio(p, q, h);
  return !std::isnan(ratio) && ratio < kSmoothedEvaluationRatio;
}

/// Whether moving corner k of a face with corners p and values q to `moved` stretches it
/// (isStretched) where q did not.
inline bool movingStretches(const std::array<Vec3d, 3>& p, std::array<Vec2d, 3> q, int k, const Vec2d& moved,
                            double h) {
  if (isStretched(gradientNormSquared(p, q), h)) return false;
  q[k] = moved;
  return isStretched(gradientNormSquared(p, q), h);
}

struct SmoothedEvaluationStats {
  std::uint64_t foldedBefore = 0;  ///< faces folded (foldedForSmoothedEvaluation) by the map as evaluated
  std::uint64_t vertices = 0;      ///< vertices re-evaluated, over all rounds
  std::uint64_t keptForStretch = 0;  ///< of them, kept at their value (movingStretches)
  std::uint32_t rounds = 0;        ///< rounds that tried a vertex
};

namespace detail {

/// A round's candidates: the vertices of the faces still folded (folded(f), triangle(f)) that no
/// round tried yet (`tried`, sorted); sorted, unique.
template <class Folded, class TriangleOf>
std::vector<VertexId> smoothedCandidates(const std::vector<FaceId>& faces, const std::vector<VertexId>& tried,
                                         Folded&& folded, TriangleOf&& triangle) {
  std::vector<VertexId> vertices;
  for (FaceId f : faces) {
    if (!folded(f)) continue;
    for (VertexId v : triangle(f)) {
      if (!std::binary_search(tried.begin(), tried.end(), v)) vertices.push_back(v);
    }
  }
  sortUniqueIds(vertices);
  return vertices;
}

/// After a round on `vertices`: they join `tried`, and `faces` becomes their fans (the faces
/// whose values changed), sorted, unique. table: a Topology or a PagedCornerTable.
template <class Table>
void finishSmoothedRound(Table& table, const std::vector<VertexId>& vertices, std::vector<VertexId>& tried,
                         std::vector<FaceId>& faces, SmoothedEvaluationStats& stats) {
  stats.vertices += vertices.size();
  ++stats.rounds;
  std::vector<VertexId> all;
  all.reserve(tried.size() + vertices.size());
  std::merge(tried.begin(), tried.end(), vertices.begin(), vertices.end(), std::back_inserter(all));
  tried = std::move(all);
  faces.clear();
  for (VertexId v : vertices) table.forEachCornerAround(v, [&](CornerId c) { faces.push_back(cornerFace(c)); });
  sortUniqueIds(faces);
}

}  // namespace detail

/// The in-memory pass on cornerUV (the wedges of buildCutWedges, values of basis.evaluateCorners
/// with these coefficients): the smoothed surface is framePositionsAt (smoothPositionsAt with
/// kFieldSmoothingIterations steps for a field computed on the mesh itself), at the vertices
/// that move. h: the map's edge length. batchVertices: how many vertices are smoothed and
/// evaluated at once (the map does not depend on it).
SmoothedEvaluationStats evaluateFoldsAtSmoothedSurface(const TriangleMesh& mesh, const Topology& topology,
                                                        const CrossField& field, const VoxelBasis& basis,
                                                        const std::vector<std::complex<double>>& coefficients,
                                                        double h, WedgeMap& cornerUV,
                                                        std::size_t batchVertices = kSmoothedBatchVertices);

}  // namespace seamvox
