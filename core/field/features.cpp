// Feature edges and curves, and their alignment in a map (features.h).
#include "core/field/features.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/system/errors.h"

namespace seamvox {

namespace {

constexpr double kDegree = M_PI / 180.0;

/// Angle (radians) between the normals of the two faces of an interior edge; 0 when one of them
/// has no normal (zero area).
double dihedralTurn(const TriangleMesh& mesh, FaceId f, FaceId g) {
  const Vec3d a = faceNormal(mesh, f), b = faceNormal(mesh, g);
  if (a.squaredNorm() == 0.0 || b.squaredNorm() == 0.0) return 0.0;
  return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
}

/// The feature edges at each vertex, compressed (start[v] .. start[v + 1] into edge).
struct VertexEdges {
  std::vector<std::uint32_t> start, edge;
};

VertexEdges edgesAtVertices(const Topology& topology, const std::vector<CornerId>& edges) {
  VertexEdges out;
  out.start.assign(topology.numVertices() + 1, 0);
  for (CornerId c : edges) {
    ++out.start[topology.vertex(nextCorner(c)) + 1];
    ++out.start[topology.vertex(prevCorner(c)) + 1];
  }
  for (std::uint32_t v = 0; v < topology.numVertices(); ++v) out.start[v + 1] += out.start[v];
  out.edge.resize(out.start.back());
  std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::uint32_t e = 0; e < edges.size(); ++e) {
    out.edge[fill[topology.vertex(nextCorner(edges[e]))]++] = e;
    out.edge[fill[topology.vertex(prevCorner(edges[e]))]++] = e;
  }
  return out;
}

}  // namespace

FeatureSet findFeatures(const TriangleMesh& mesh, const Topology& topology, const FeatureOptions& options) {
  if (options.featureAngle < 0.0 || !(options.featureAngle < 180.0) || !(options.cornerAngle >= 0.0)) {
    throw InputError("feature angle must be in [0, 180) degrees (got " + std::to_string(options.featureAngle) +
                     "), corner angle >= 0");
  }
  FeatureSet out;
  std::vector<CornerId> edges;
  const double crease = options.featureAngle * kDegree;
  for (CornerId c = 0; c < 3u * topology.numFaces(); ++c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId) {
      if (options.alignBoundary) {
        edges.push_back(c);
        ++out.boundaryEdges;
      }
    } else if (crease > 0.0 && c < o && dihedralTurn(mesh, cornerFace(c), cornerFace(o)) > crease) {
      edges.push_back(c);
      ++out.creaseEdges;
    }
  }
  const VertexEdges at = edgesAtVertices(topology, edges);
  auto otherEnd = [&](std::uint32_t e, VertexId v) {
    const VertexId a = topology.vertex(nextCorner(edges[e]));
    return a == v ? topology.vertex(prevCorner(edges[e])) : a;
  };
  // A vertex splits curves unless exactly two feature edges meet there and turn by at most
  // cornerAngle.
  const double cornerTurn = options.cornerAngle * kDegree;
  auto isCorner = [&](VertexId v) {
    if (at.start[v + 1] - at.start[v] != 2) return true;
    const std::uint32_t e1 = at.edge[at.start[v]], e2 = at.edge[at.start[v] + 1];
    const Vec3d d1 = mesh.position(v) - mesh.position(otherEnd(e1, v));
    const Vec3d d2 = mesh.position(otherEnd(e2, v)) - mesh.position(v);
    const double n = d1.norm() * d2.norm();
    return n > 0.0 && std::acos(std::clamp(d1.dot(d2) / n, -1.0, 1.0)) > cornerTurn;
  };
  std::vector<std::uint8_t> used(edges.size(), 0);
  // Walks from v along edge e until a corner (or back to the start of a loop).
  auto walk = [&](VertexId v, std::uint32_t e) {
    out.curveStart.push_back(static_cast<std::uint32_t>(out.curveEdges.size()));
    for (;;) {
      used[e] = 1;
      out.curveEdges.push_back(edges[e]);
      v = otherEnd(e, v);
      if (isCorner(v)) return;
      const std::uint32_t a = at.edge[at.start[v]], b = at.edge[at.start[v] + 1];
      e = a == e ? b : a;
      if (used[e]) return;  // a closed loop
    }
  };
  for (VertexId v = 0; v < topology.numVertices(); ++v) {
    if (at.start[v] == at.start[v + 1] || !isCorner(v)) continue;
    for (std::uint32_t k = at.start[v]; k < at.start[v + 1]; ++k) {
      if (!used[at.edge[k]]) walk(v, at.edge[k]);
    }
  }
  for (std::uint32_t e = 0; e < edges.size(); ++e) {
    if (!used[e]) walk(topology.vertex(nextCorner(edges[e])), e);  // loops without a corner
  }
  out.curveStart.push_back(static_cast<std::uint32_t>(out.curveEdges.size()));
  return out;
}

std::vector<CornerId> featureSideCorners(const Topology& topology, const FeatureSet& features) {
  std::vector<CornerId> out;
  out.reserve(2 * features.curveEdges.size());
  for (CornerId c : features.curveEdges) {
    out.push_back(c);
    if (topology.opposite(c) != kInvalidId) out.push_back(topology.opposite(c));
  }
  std::sort(out.begin(), out.end());
  return out;
}

FeatureAlignment measureFeatureAlignment(const Topology& topology, const FeatureSet& features,
                                         const WedgeMap& cornerUV, double tolerance) {
  checkCorners(cornerUV, 3u * std::size_t(topology.numFaces()), "feature alignment");
  FeatureAlignment out;
  out.total = features.numCurves();
  for (std::uint32_t k = 0; k < out.total; ++k) {
    bool aligned = true;
    double residual = 0.0;
    for (std::uint32_t i = features.curveStart[k]; i < features.curveStart[k + 1] && aligned; ++i) {
      const CornerId c = features.curveEdges[i];
      for (CornerId side : {c, topology.opposite(c)}) {
        if (side == kInvalidId) continue;
        const Vec2d p = cornerUV[nextCorner(side)], q = cornerUV[prevCorner(side)];
        double best = 1e300;
        for (int axis = 0; axis < 2; ++axis) {
          best = std::min(best, std::max(std::abs(p[axis] - q[axis]), std::abs(p[axis] - std::round(p[axis]))));
        }
        if (!(best <= tolerance)) aligned = false;
        residual = std::max(residual, best);
      }
    }
    if (aligned) {
      ++out.aligned;
      out.largestResidual = std::max(out.largestResidual, residual);
    }
  }
  out.notAligned = out.total - out.aligned;
  return out;
}

bool looksLikeCad(const FeatureSet& creases) {
  return creases.creaseEdges >= 24 && creases.numCurves() > 0 && creases.creaseEdges >= 6u * creases.numCurves();
}

FeatureOptions resolveFeatureAngle(const TriangleMesh& mesh, const Topology& topology, FeatureOptions options,
                                   bool& chosen) {
  chosen = false;
  if (!options.autoFeatureAngle || options.featureAngle > 0.0) return options;
  FeatureOptions probe;
  probe.featureAngle = kAutoFeatureAngle;
  probe.cornerAngle = options.cornerAngle;
  chosen = looksLikeCad(findFeatures(mesh, topology, probe));
  if (chosen) options.featureAngle = kAutoFeatureAngle;
  return options;
}

}  // namespace seamvox
