#include "core/quality/metrics.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>

#include "core/field/fast_atan2.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "core/basis/gaussian_int.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;
Complex toComplex(const Vec2d& q) { return {q.x(), q.y()}; }

void checkSizes(const TriangleMesh& mesh, const WedgeMap& cornerUV) {
  checkCorners(cornerUV, 3 * static_cast<std::size_t>(mesh.numFaces()), "metrics");
}

double edgeLength3d(const TriangleMesh& mesh, const Topology& topology, CornerId c) {
  return (mesh.position(topology.vertex(nextCorner(c))) - mesh.position(topology.vertex(prevCorner(c))))
      .norm();
}

// The two endpoint pairs (left, right) of the edge of corner c: at vertex(next c) and vertex(prev c).
struct EdgeSides {
  Complex leftA, rightA, leftB, rightB;
};
EdgeSides edgeSides(const WedgeMap& uv, CornerId c, CornerId o) {
  return {toComplex(uv[nextCorner(c)]), toComplex(uv[prevCorner(o)]), toComplex(uv[prevCorner(c)]),
          toComplex(uv[nextCorner(o)])};
}

}  // namespace

double parameterAreaRatio(const TriangleMesh& mesh, FaceId f, const std::array<Vec2d, 3>& q, double edgeLength) {
  const Triangle& t = mesh.triangles[f];
  return parameterAreaRatio({mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])}, q, edgeLength);
}

double parameterAreaRatio(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q, double edgeLength) {
  const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
  const Vec2d a = q[1] - q[0], b = q[2] - q[0];
  const double uvArea = 0.5 * (a.x() * b.y() - a.y() * b.x());
  return uvArea * (edgeLength * edgeLength) / area;
}

double parameterAreaRatio(const TriangleMesh& mesh, const WedgeMap& cornerUV, FaceId f,
                          double edgeLength) {
  return parameterAreaRatio(mesh, f, {cornerUV[3 * f], cornerUV[3 * f + 1], cornerUV[3 * f + 2]}, edgeLength);
}

bool collapsesBetweenCones(const TriangleMesh& mesh, FaceId f, const std::array<Vec2d, 3>& q,
                           const std::vector<std::uint8_t>& isCone) {
  const Triangle& t = mesh.triangles[f];
  for (int k = 0; k < 3; ++k) {
    const int l = (k + 1) % 3;
    if (isCone[t[k]] && isCone[t[l]] && (q[k] - q[l]).norm() <= kCoincidentConeDistance) return true;
  }
  return false;
}

bool collapsesBetweenCones(const TriangleMesh& mesh, const WedgeMap& cornerUV, FaceId f,
                           const std::vector<std::uint8_t>& isCone) {
  return collapsesBetweenCones(mesh, f, {cornerUV[3 * f], cornerUV[3 * f + 1], cornerUV[3 * f + 2]}, isCone);
}

SeamQuality measureSeams(const std::vector<SeamCurve>& seams, const SeamCornerValue& value,
                         const std::function<CornerId(CornerId)>& opposite,
                         const std::function<double(CornerId)>& edgeLength) {
  SeamQuality out;
  out.seams = static_cast<std::uint32_t>(seams.size());
  const auto sides = [&](CornerId c) {
    const CornerId o = opposite(c);
    return EdgeSides{toComplex(value(nextCorner(c))), toComplex(value(prevCorner(o))), toComplex(value(prevCorner(c))),
                     toComplex(value(nextCorner(o)))};
  };
  for (const SeamCurve& seam : seams) {
    if (seam.corners.empty()) continue;
    const Complex r = unitPower(-static_cast<int>(seam.matching)).toComplex();
    const EdgeSides s0 = sides(seam.corners.front());
    const Complex t = s0.rightA - r * s0.leftA;
    out.maxIntegerDistance = std::max(out.maxIntegerDistance, gaussianIntegerDistance(t));
    for (CornerId c : seam.corners) {
      const EdgeSides s = sides(c);
      const double res = std::max(std::abs(s.rightA - (r * s.leftA + t)),
                                  std::abs(s.rightB - (r * s.leftB + t)));
      if (res > out.maxResidual || out.worstEdgeCorner == kInvalidId) {
        out.worstEdgeCorner = c;
        out.maxResidual = res;
      }
      ++out.seamEdges;
      out.seamLength += edgeLength(c);
    }
  }
  return out;
}

SeamQuality measureSeams(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                         const WedgeMap& cornerUV) {
  checkSizes(mesh, cornerUV);
  return measureSeams(
      cut.seams, [&](CornerId c) { return cornerUV[c]; }, [&](CornerId c) { return topology.opposite(c); },
      [&](CornerId c) { return edgeLength3d(mesh, topology, c); });
}

namespace {

SeamEdgeFit fitSeamEdge(const EdgeSides& s) {
  SeamEdgeFit best{std::numeric_limits<double>::infinity(), 0.0};
  for (int k = 0; k < 4; ++k) {
    const Complex r = unitPower(k).toComplex();
    const Complex t = s.rightA - r * s.leftA;
    const double res = std::abs(s.rightB - (r * s.leftB + t));
    const double dist = gaussianIntegerDistance(t);
    if (res < best.residual - 1e-12 || (res <= best.residual + 1e-12 && dist < best.integerDistance)) {
      best.residual = std::min(res, best.residual);
      best.integerDistance = dist;
    }
  }
  return best;
}

}  // namespace

SeamEdgeFit fitSeamEdge(const Vec2d& leftA, const Vec2d& rightA, const Vec2d& leftB, const Vec2d& rightB) {
  return fitSeamEdge(EdgeSides{toComplex(leftA), toComplex(rightA), toComplex(leftB), toComplex(rightB)});
}

SeamQuality measureSeamsFromUV(const TriangleMesh& mesh, const Topology& topology,
                               const WedgeMap& cornerUV) {
  checkSizes(mesh, cornerUV);
  SeamQuality out;
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId || o < c) continue;
    const EdgeSides s = edgeSides(cornerUV, c, o);
    if (s.leftA == s.rightA && s.leftB == s.rightB) continue;
    const SeamEdgeFit fit = fitSeamEdge(s);
    const double bestResidual = fit.residual, bestDistance = fit.integerDistance;
    if (bestResidual > out.maxResidual) out.worstEdgeCorner = c;
    out.maxResidual = std::max(out.maxResidual, bestResidual);
    out.maxIntegerDistance = std::max(out.maxIntegerDistance, bestDistance);
    ++out.seamEdges;
    out.seamLength += edgeLength3d(mesh, topology, c);
  }
  return out;
}

namespace {

// Per face: gradient G = gu + i gv of q and the cross direction u nearest to it (w = u + i n x u).
struct FaceFigures {
  double area = 0.0;
  Vec3d gu = Vec3d::Zero(), gv = Vec3d::Zero(), u = Vec3d::Zero(), v = Vec3d::Zero();
  double gw() const { return gu.dot(u) + gv.dot(v); }  // Re<G, w>
};

// Area, gradient and nearest cross direction of a face from its corners' positions p and values
// q (zero gradient on a zero-area face; no direction without one).
FaceFigures measureFace(const Vec3d p[3], const Complex q[3], const Vec3d* direction) {
  FaceFigures out;
  const Vec3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
  const double twiceArea = normal.norm();
  out.area = 0.5 * twiceArea;
  if (!(twiceArea > 0.0)) return out;
  const Vec3d n = normal / twiceArea;
  for (int k = 0; k < 3; ++k) {
    const Vec3d g = n.cross(p[(k + 2) % 3] - p[(k + 1) % 3]) / twiceArea;
    out.gu += q[k].real() * g;
    out.gv += q[k].imag() * g;
  }
  if (direction) {
    Vec3d u = *direction;
    u -= n * n.dot(u);
    const double len = u.norm();
    if (len > 0.0) {
      u /= len;
      double best = -std::numeric_limits<double>::infinity();
      for (int m = 0; m < 4; ++m) {  // the four cross directions
        const double score = out.gu.dot(u) + out.gv.dot(n.cross(u));
        if (score > best) best = score, out.u = u, out.v = n.cross(u);
        u = n.cross(u);
      }
    }
  }
  return out;
}

FaceFigures measureFace(const TriangleMesh& mesh, const WedgeMap& cornerUV, const CrossField* field,
                        FaceId f) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d p[3] = {mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])};
  const Complex q[3] = {toComplex(cornerUV[3 * f]), toComplex(cornerUV[3 * f + 1]),
                        toComplex(cornerUV[3 * f + 2])};
  if (!field) return measureFace(p, q, nullptr);
  const Vec3d direction = field->at(f);
  return measureFace(p, q, &direction);
}

struct MapSums {
  double area = 0.0, uvArea = 0.0, gw = 0.0, error = 0.0, target = 0.0;
};

}  // namespace

double gradientNormSquared(const FaceFigures& x);  // below: one formula for every stretched count

namespace {

// Per vertex: is it one of the cones (InputError naming an out-of-range one)?
std::vector<std::uint8_t> markCones(const TriangleMesh& mesh, const std::vector<VertexId>& cones) {
  std::vector<std::uint8_t> isCone(mesh.numVertices(), 0);
  for (VertexId v : cones) {
    if (v >= mesh.numVertices()) {
      throw InputError("metrics: cone " + std::to_string(v) + " out of range (" +
                       std::to_string(mesh.numVertices()) + " vertices)");
    }
    isCone[v] = 1;
  }
  return isCone;
}

// What a face is under the map at spacing h.
enum FaceKind : std::uint8_t { kFine, kStretched, kFlippedFace, kCollapsed, kCollapsedAtCones };

// The kind of face f with corners p, values q and measureFace's figures x (isCone: per vertex,
// empty without cones).
std::uint8_t faceKind(const TriangleMesh& mesh, const WedgeMap& cornerUV, FaceId f, const std::array<Vec3d, 3>& p,
                      const std::array<Vec2d, 3>& q, const FaceFigures& x, double h,
                      const std::vector<std::uint8_t>& isCone) {
  const double ratio = parameterAreaRatio(p, q, h);
  if (std::abs(ratio) < kCollapsedAreaFraction) {
    return !isCone.empty() && collapsesBetweenCones(mesh, cornerUV, f, isCone) ? kCollapsedAtCones : kCollapsed;
  }
  if (ratio < 0.0) return kFlippedFace;
  return isStretched(gradientNormSquared(x), h) ? kStretched : kFine;
}

// Area-weighted sums over all faces (in parallel); the error terms only for a spacing h > 0.
// With kind (h > 0), each face's kind too, in the same pass.
MapSums sumFaces(const TriangleMesh& mesh, const WedgeMap& cornerUV, const CrossField* field,
                 double h, std::vector<std::uint8_t>* kind = nullptr,
                 const std::vector<std::uint8_t>& isCone = {}) {
  return tbb::parallel_reduce(
      tbb::blocked_range<FaceId>(0, mesh.numFaces(), 8192), MapSums{},
      [&](const tbb::blocked_range<FaceId>& range, MapSums s) {
        for (FaceId f = range.begin(); f != range.end(); ++f) {
          const FaceFigures x = measureFace(mesh, cornerUV, field, f);
          if (kind) {
            const Triangle& t = mesh.triangles[f];
            (*kind)[f] = faceKind(mesh, cornerUV, f, {mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])},
                                  {cornerUV[3 * f], cornerUV[3 * f + 1], cornerUV[3 * f + 2]}, x, h, isCone);
          }
          const Complex q0 = toComplex(cornerUV[3 * f]);
          s.area += x.area;
          s.uvArea += 0.5 * std::abs(std::imag(std::conj(toComplex(cornerUV[3 * f + 1]) - q0) *
                                               (toComplex(cornerUV[3 * f + 2]) - q0)));
          s.gw += x.area * x.gw();
          if (h > 0.0) {
            s.error += x.area * ((x.gu - x.u / h).squaredNorm() + (x.gv - x.v / h).squaredNorm());
            s.target += x.area * (x.u.squaredNorm() + x.v.squaredNorm()) / (h * h);
          }
        }
        return s;
      },
      [](MapSums a, const MapSums& b) {
        a.area += b.area, a.uvArea += b.uvArea, a.gw += b.gw, a.error += b.error,
            a.target += b.target;
        return a;
      });
}

// Least squares scale 1/h of the target (|w|^2 = 2); without a field, from the areas.
double fitEdgeLength(const TriangleMesh& mesh, const WedgeMap& cornerUV, const CrossField* field) {
  const MapSums fit = sumFaces(mesh, cornerUV, field, 0.0);
  return field && fit.gw > 0.0 ? 2.0 * fit.area / fit.gw
                               : (fit.uvArea > 0.0 ? std::sqrt(fit.area / fit.uvArea) : 1.0);
}

// Counts the faces by kind (faceKind) into out; the flipped ones folded in 3D against the field's
// smoothed surface; flippedFaces (when given) receives the flipped faces.
void countFaceKinds(const TriangleMesh& mesh, std::vector<std::uint8_t>& kind, const CrossField* field,
                    const Topology* topology, MapQuality& out, std::vector<FaceId>* flippedFaces) {
  std::vector<FaceId> flippedList;
  std::vector<FaceId>& flipped = flippedFaces ? *flippedFaces : flippedList;
  flipped.clear();
  std::uint64_t collapsed = 0, collapsedAtCones = 0;
  for (FaceId f = 0; f < kind.size(); ++f) {
    if (kind[f] == kFine) continue;
    out.stretched += kind[f] == kStretched;
    collapsed += kind[f] >= kCollapsed;
    collapsedAtCones += kind[f] == kCollapsedAtCones;
    if (kind[f] == kFlippedFace) flipped.push_back(f);
  }
  std::vector<std::uint8_t>().swap(kind);
  for (std::uint8_t folded : facesFoldedIn3D(mesh, topology, field, flipped)) out.flippedFolded += folded;
  const FaceId nf = mesh.numFaces();
  out.flipped = flipped.size();
  out.collapsed = collapsed;
  out.collapsedAtCones = collapsedAtCones;
  out.flippedFraction = nf ? static_cast<double>(flipped.size()) / nf : 0.0;
}

}  // namespace

namespace {

// faceFoldedIn3D with the smoothed corners given.
bool foldedAgainst(const TriangleMesh& mesh, FaceId f, const Vec3f& sa, const Vec3f& sb, const Vec3f& sc) {
  const Triangle& t = mesh.triangles[f];
  return faceFoldedIn3D({mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2])}, sa, sb, sc);
}

}  // namespace

bool faceFoldedIn3D(const std::array<Vec3d, 3>& p, const Vec3f& sa, const Vec3f& sb, const Vec3f& sc) {
  const Vec3d n = (p[1] - p[0]).cross(p[2] - p[0]);
  const Vec3d a = sa.cast<double>(), b = sb.cast<double>(), c = sc.cast<double>();
  return n.dot((b - a).cross(c - a)) < 0.0;
}

bool faceFoldedIn3D(const TriangleMesh& mesh, const std::vector<Vec3f>& smooth, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return foldedAgainst(mesh, f, smooth[t[0]], smooth[t[1]], smooth[t[2]]);
}

std::vector<std::uint8_t> facesFoldedIn3D(const TriangleMesh& mesh, const Topology* topology,
                                          const CrossField* field, const std::vector<FaceId>& faces) {
  std::vector<std::uint8_t> folded(faces.size(), 0);
  if (!field || faces.empty()) return folded;
  if (field->framePositions.size() == mesh.numVertices()) {
    for (std::size_t i = 0; i < faces.size(); ++i) folded[i] = faceFoldedIn3D(mesh, field->framePositions, faces[i]);
    return folded;
  }
  if (field->frameSmoothing == 0) return folded;
  if (!topology) throw InputError("metrics: the field's smoothed positions were released and no topology was given");
  std::vector<VertexId> corners;
  corners.reserve(3 * faces.size());
  for (FaceId f : faces) corners.insert(corners.end(), mesh.triangles[f].begin(), mesh.triangles[f].end());
  const std::vector<Vec3f> smooth = framePositionsAt(mesh, *topology, *field, corners);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    folded[i] = foldedAgainst(mesh, faces[i], smooth[3 * i], smooth[3 * i + 1], smooth[3 * i + 2]);
  }
  return folded;
}

// The squared gradient of measureFace's figures (NaN for a zero-area face): one formula for
// every path that counts stretched faces.
double gradientNormSquared(const FaceFigures& x) {
  return x.area > 0.0 ? x.gu.squaredNorm() + x.gv.squaredNorm() : std::numeric_limits<double>::quiet_NaN();
}

double gradientNormSquared(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q) {
  const Complex c[3] = {toComplex(q[0]), toComplex(q[1]), toComplex(q[2])};
  return gradientNormSquared(measureFace(p.data(), c, nullptr));
}

double cornerUVAngle(const Vec2d& q, const Vec2d& next, const Vec2d& prev) {
  const Vec2d a = next - q, b = prev - q;
  // A corner on a collapsed edge has no angle (atan2 of signed zeros would give +-pi).
  if (a == Vec2d::Zero() || b == Vec2d::Zero()) return 0.0;
  return detail::fastAtan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
}

double cornerAngleSum(const Topology& topology, const WedgeMap& cornerUV, VertexId v) {
  double sum = 0.0;
  topology.forEachCornerAround(v, [&](CornerId c) {
    sum += cornerUVAngle(cornerUV[c], cornerUV[nextCorner(c)], cornerUV[prevCorner(c)]);
  });
  return sum;
}

namespace {

/// The sixteenths of a turn that bound cornerUVAngle from above (cornerUVAngleBound): a corner's
/// bound is kAngleBound[k] for the k its angle lies below.
constexpr double kEighth = 0.125 * M_PI, kMargin = 1e-5;
constexpr double kAngleBound[9] = {kMargin,          kEighth + kMargin,     2 * kEighth + kMargin,
                                   3 * kEighth + kMargin, 4 * kEighth + kMargin, 5 * kEighth + kMargin,
                                   6 * kEighth + kMargin, 7 * kEighth + kMargin, M_PI + kMargin};

/// The k of kAngleBound[k] >= cornerUVAngle(q, next, prev) (by over 1e-5 rad, more than
/// fastAtan2's error): the upper end of the eighth of a half turn the angle lies in, from
/// comparisons only (0: a negative angle or a collapsed edge).
std::uint8_t cornerUVAngleBound(const Vec2d& q, const Vec2d& next, const Vec2d& prev) {
  const Vec2d a = next - q, b = prev - q;
  if (a == Vec2d::Zero() || b == Vec2d::Zero()) return 0;
  const double y = a.x() * b.y() - a.y() * b.x(), x = a.dot(b);
  constexpr double t = 0.41421356237309503;  // tan(pi / 8), rounded up
  if (y < 0.0) return 0;  // below the axis: a negative angle
  if (x > 0.0) {
    if (y <= t * x) return 1;
    if (y <= x) return 2;
    if (t * y <= x) return 3;
    return 4;
  }
  if (-x <= t * y) return 5;
  if (-x <= y) return 6;
  if (t * -x <= y) return 7;
  return 8;
}

}  // namespace

std::vector<VertexId> woundVertices(const Topology& topology, const WedgeMap& cornerUV) {
  checkCorners(cornerUV, 3 * static_cast<std::size_t>(topology.numFaces()), "metrics");
  const std::uint32_t nv = topology.numVertices();
  // Each corner's bound once, by faces (three lookups of the map a face instead of three a corner
  // around every vertex).
  std::vector<std::uint8_t> bound(3 * std::size_t(topology.numFaces()));
  parallelFor(topology.numFaces(), 4096, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      const Vec2d q[3] = {cornerUV[3 * f], cornerUV[3 * f + 1], cornerUV[3 * f + 2]};
      for (int k = 0; k < 3; ++k) bound[3 * f + k] = cornerUVAngleBound(q[k], q[(k + 1) % 3], q[(k + 2) % 3]);
    }
  });
  constexpr std::uint32_t kBlock = 1u << 16;  // fixed blocks: the list comes out in vertex order
  std::vector<std::vector<VertexId>> found((std::uint64_t(nv) + kBlock - 1) / kBlock);
  parallelForEach(found.size(), 1, [&](std::uint64_t b) {
    const VertexId end = static_cast<VertexId>(std::min<std::uint64_t>(nv, (b + 1) * kBlock));
    for (VertexId v = static_cast<VertexId>(b * kBlock); v != end; ++v) {
      if (topology.isIsolatedVertex(v)) continue;
      // A sum of upper bounds decides most vertices without an arctangent. The walk from
      // vertexCorner covers a boundary fan too: its sum is tested first (cheaper).
      double sum = 0.0;
      topology.forEachCornerAround(v, [&](CornerId c) { sum += kAngleBound[bound[c]]; });
      if (sum < kWoundAngleSum) continue;
      if (cornerAngleSum(topology, cornerUV, v) >= kWoundAngleSum && !topology.isBoundaryVertex(v)) {
        found[b].push_back(v);
      }
    }
  });
  std::vector<VertexId> out;
  for (const std::vector<VertexId>& block : found) out.insert(out.end(), block.begin(), block.end());
  return out;
}

MapQuality measureMap(const TriangleMesh& mesh, const WedgeMap& cornerUV,
                      const CrossField* field, double edgeLength,
                      const std::vector<VertexId>* cones, const Topology* topology,
                      std::vector<FaceId>* flippedFaces) {
  checkSizes(mesh, cornerUV);
  if (field && field->direction.size() != mesh.numFaces()) {
    throw InputError("metrics: field has " + std::to_string(field->direction.size()) +
                     " directions for " + std::to_string(mesh.numFaces()) + " faces");
  }
  MapQuality out;
  out.faces = mesh.numFaces();
  const double h = edgeLength > 0.0 ? edgeLength : fitEdgeLength(mesh, cornerUV, field);
  out.edgeLength = h;
  // One pass: the sums and each face's kind (a byte per face), counted in face order after.
  std::vector<std::uint8_t> kind(mesh.numFaces());
  const MapSums sums = sumFaces(mesh, cornerUV, field, h, &kind, cones ? markCones(mesh, *cones) : std::vector<std::uint8_t>());
  out.relativeGradientError = field && sums.target > 0.0
                                  ? std::sqrt(sums.error / sums.target)
                                  : std::numeric_limits<double>::quiet_NaN();
  countFaceKinds(mesh, kind, field, topology, out, flippedFaces);
  if (topology) {
    out.wound = woundVertices(*topology, cornerUV).size();
    out.woundCounted = true;
  }
  return out;
}

MapQualitySums::Kind MapQualitySums::add(const std::array<Vec3d, 3>& p, const std::array<Vec2d, 3>& q,
                                         const Vec3d* direction) {
  const Complex c[3] = {toComplex(q[0]), toComplex(q[1]), toComplex(q[2])};
  const FaceFigures x = measureFace(p.data(), c, direction);
  error_ += x.area * ((x.gu - x.u / h_).squaredNorm() + (x.gv - x.v / h_).squaredNorm());
  target_ += x.area * (x.u.squaredNorm() + x.v.squaredNorm()) / (h_ * h_);
  hasField_ = hasField_ || direction;
  ++out_.faces;
  const double ratio = parameterAreaRatio(p, q, h_);
  if (std::abs(ratio) < kCollapsedAreaFraction) {
    ++out_.collapsed;
    return Kind::Collapsed;
  }
  if (ratio < 0.0) {
    ++out_.flipped;
    return Kind::Flipped;
  }
  out_.stretched += isStretched(gradientNormSquared(x), h_);
  return Kind::Fine;
}

void MapQualitySums::merge(const MapQualitySums& other) {
  error_ += other.error_;
  target_ += other.target_;
  hasField_ = hasField_ || other.hasField_;
  out_.faces += other.out_.faces;
  out_.collapsed += other.out_.collapsed;
  out_.collapsedAtCones += other.out_.collapsedAtCones;
  out_.flipped += other.out_.flipped;
  out_.flippedFolded += other.out_.flippedFolded;
  out_.stretched += other.out_.stretched;
}

MapQuality MapQualitySums::finish() const {
  MapQuality out = out_;
  out.edgeLength = h_;
  out.relativeGradientError =
      hasField_ && target_ > 0.0 ? std::sqrt(error_ / target_) : std::numeric_limits<double>::quiet_NaN();
  out.flippedFraction = out.faces ? static_cast<double>(out.flipped) / out.faces : 0.0;
  return out;
}

}  // namespace seamvox
