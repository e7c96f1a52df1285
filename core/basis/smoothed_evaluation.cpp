// The voxel map re-evaluated at the smoothed surface at the vertices of the faces it folds.
#include "core/basis/smoothed_evaluation.h"

#include <algorithm>

#include "core/field/field_proxy.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

std::array<Vec2d, 3> faceValues(const WedgeMap& uv, FaceId f) { return {uv[3 * f], uv[3 * f + 1], uv[3 * f + 2]}; }

std::array<Vec3d, 3> facePoints(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return {mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])};
}

}  // namespace

SmoothedEvaluationStats evaluateFoldsAtSmoothedSurface(const TriangleMesh& mesh, const Topology& topology,
                                                        const CrossField& field, const VoxelBasis& basis,
                                                        const std::vector<std::complex<double>>& coefficients,
                                                        double h, WedgeMap& cornerUV, std::size_t batchVertices) {
  if (batchVertices == 0) throw InputError("smoothed evaluation: a batch needs at least one vertex");
  SmoothedEvaluationStats stats;
  const FaceId nf = topology.numFaces();
  const std::uint32_t steps = field.frameSmoothing > 0 ? field.frameSmoothing : kFieldSmoothingIterations;
  // Round one measures every face (in parallel, listed by blocks of faces rather than flagged per
  // face: this runs at the pipeline's peak), the next ones the fans moved.
  constexpr std::uint64_t kBlock = 1u << 16;
  std::vector<std::vector<FaceId>> foundIn((nf + kBlock - 1) / kBlock);
  parallelForEach(foundIn.size(), 1, [&](std::uint64_t b) {
    const FaceId end = static_cast<FaceId>(std::min<std::uint64_t>(nf, (b + 1) * kBlock));
    for (FaceId f = static_cast<FaceId>(b * kBlock); f < end; ++f) {
      if (foldedForSmoothedEvaluation(facePoints(mesh, f), faceValues(cornerUV, f), h)) foundIn[b].push_back(f);
    }
  });
  std::vector<FaceId> faces;
  for (std::vector<FaceId>& found : foundIn) {
    faces.insert(faces.end(), found.begin(), found.end());
    std::vector<FaceId>().swap(found);
  }
  stats.foldedBefore = faces.size();
  std::vector<VertexId> tried;  // every vertex a round tried, sorted
  for (std::uint32_t round = 0; round < kSmoothedEvaluationRounds && !faces.empty(); ++round) {
    std::vector<VertexId> vertices = detail::smoothedCandidates(
        faces, tried,
        [&](FaceId f) { return foldedForSmoothedEvaluation(facePoints(mesh, f), faceValues(cornerUV, f), h); },
        [&](FaceId f) { return mesh.triangles[f]; });
    // One wedge: every corner around the vertex in it (no seam through it).
    const auto seamOrIsolated = [&](VertexId v) {
      if (topology.isIsolatedVertex(v)) return true;
      const std::uint32_t w = cornerUV.wedge(topology.vertexCorner(v));
      bool several = false;
      topology.forEachCornerAround(v, [&](CornerId c) { several = several || cornerUV.wedge(c) != w; });
      return several;
    };
    vertices.erase(std::remove_if(vertices.begin(), vertices.end(), seamOrIsolated), vertices.end());
    if (vertices.empty()) break;
    const VoxelGridGeometry& grid = basis.grid();
    // A batch of vertices at a time, in increasing order: a noisy scan folds millions of faces,
    // and the smoothed ball around them all (3 rings, two positions per vertex) would sit on the
    // pipeline's peak next to the basis and the map. A vertex's smoothed position and value do
    // not depend on the batch; the decisions below go in increasing order either way.
    // Each batch's smoothed positions and new values (in parallel; they read neither the map nor
    // the decisions), then its decisions: vertex by vertex in increasing order, each set unless
    // it stretches a face of its fan at the values so far (as the out-of-core pass goes). The
    // next batch is prepared while one core decides the current one.
    struct Prepared {
      std::vector<std::uint8_t> keep;
      std::vector<Vec2d> value;
    };
    const auto prepare = [&](std::size_t first) {
      const std::size_t count = std::min(batchVertices, vertices.size() - first);
      const std::vector<VertexId> batch(vertices.begin() + first, vertices.begin() + first + count);
      const std::vector<Vec3f> smoothed = field.frameSmoothing > 0 ? framePositionsAt(mesh, topology, field, batch)
                                                                    : smoothPositionsAt(mesh, topology, steps, batch);
      Prepared p;
      p.keep.assign(count, 0);
      p.value.resize(count);
      parallelFor(count, 1024, [&](const IndexRange& range) {
        for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
          const VertexId v = batch[i];
          // The wedge's value comes from its smallest corner's element (VoxelBasis::evaluateCorners).
          CornerId smallest = kInvalidId;
          topology.forEachCornerAround(v, [&](CornerId c) { smallest = std::min(smallest, c); });
          const std::uint32_t e = basis.cornerElement(smallest);
          p.keep[i] = e == kInvalidId;
          if (p.keep[i]) continue;
          const std::complex<double> q = basis.evaluateAt(e, grid.toGrid(smoothed[i].cast<double>()), coefficients);
          p.value[i] = Vec2d(q.real(), q.imag());
        }
      });
      return p;
    };
    const auto decide = [&](std::size_t first, Prepared& p) {
      for (std::size_t i = 0; i < p.keep.size(); ++i) {
        const VertexId v = vertices[first + i];
        topology.forEachCornerAround(v, [&](CornerId c) {
          const FaceId f = cornerFace(c);
          p.keep[i] = p.keep[i] || movingStretches(facePoints(mesh, f), faceValues(cornerUV, f), c % 3, p.value[i], h);
        });
        if (!p.keep[i]) cornerUV.setWedgeValue(cornerUV.wedge(topology.vertexCorner(v)), p.value[i]);
        stats.keptForStretch += p.keep[i];
      }
    };
    Prepared current = prepare(0);
    for (std::size_t first = 0; first < vertices.size(); first += batchVertices) {
      Prepared next;
      const std::size_t following = first + batchVertices;
      if (following < vertices.size()) {
        parallelForEach(2, 1, [&](std::uint64_t k) {
          if (k == 0) decide(first, current);
          else next = prepare(following);
        });
      } else {
        decide(first, current);
      }
      current = std::move(next);
    }
    detail::finishSmoothedRound(topology, vertices, tried, faces, stats);
  }
  return stats;
}

}  // namespace seamvox
