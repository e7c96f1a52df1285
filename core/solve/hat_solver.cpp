#include "core/solve/hat_solver.h"

#include "core/basis/detail_hat_wedges.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/basis/basis.h"
#include "core/basis/hole_loops.h"
#include "core/solve/evaluate.h"
#include "core/basis/reduce.h"
#include "core/system/stopwatch.h"

namespace seamvox {

ParamResult parameterizeMesh(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const ParamOptions& options) {
  ParamResult out;
  auto start = std::chrono::steady_clock::now();
  HatBasisOptions basisOptions;
  basisOptions.edgeLength = options.edgeLength;
  basisOptions.coneWeightRadius = options.coneWeightRadius;
  const HatBasis basis(mesh, topology, field, cut, basisOptions);
  out.basisFunctions = basis.numBasisFunctions();
  out.domains = basis.numDomains();
  out.seamAdjacencies = static_cast<std::uint32_t>(basis.adjacencies().size());
  out.secondsBasis = secondsSince(start);

  start = std::chrono::steady_clock::now();
  ReduceOptions reduceOptions;
  reduceOptions.progress = options.progress;
  std::vector<std::uint8_t> integerPoints;
  if (options.featureCorners) {
    integerPoints = conesOnFeatures(topology, cut, basis, *options.featureCorners);
    reduceOptions.integerPoints = &integerPoints;
  }
  const std::vector<GaussVector> holes = closeSmallHoles(mesh, topology, cut, options, out);
  reduceOptions.extraConstraints = &holes;
  const Reduction reduction = reduceBasis(basis, reduceOptions);
  out.translationConstraints = static_cast<std::uint32_t>(reduction.cycleConstraints.size());
  out.secondsReduce = secondsSince(start);

  RoundOptions roundOptions;
  std::vector<LineConstraint> lines;
  if (options.featureCorners) {
    lines = featureLineConstraints(mesh, field, cut, basis, *options.featureCorners);
    roundOptions.lines = &lines;
    roundOptions.lineStats = &out.lines;
  }
  roundOptions.greedy = options.greedyRounding;
  roundOptions.progress = options.progress;
  roundOptions.failsToFactor = options.failsToFactor;
  storeSeamlessSolution(basis, reduction, solveSeamless(basis, reduction, roundOptions), topology, cut, out,
                        options.mapViewsTriangles);
  return out;
}

std::vector<std::uint8_t> conesOnFeatures(const Topology& topology, const CutResult& cut, const HatBasis& basis,
                                          const std::vector<CornerId>& sideCorners) {
  std::vector<std::uint8_t> onFeature(topology.numVertices(), 0), isCone(topology.numVertices(), 0);
  for (CornerId c : sideCorners) onFeature[topology.vertex(nextCorner(c))] = onFeature[topology.vertex(prevCorner(c))] = 1;
  for (VertexId v : cut.cones) isCone[v] = 1;
  std::vector<std::uint8_t> flags(basis.numBasisFunctions(), 0);
  for (std::uint32_t b = 0; b < flags.size(); ++b) {
    const VertexId v = basis.basisVertex()[b];
    flags[b] = onFeature[v] && isCone[v];
  }
  return flags;
}

std::vector<LineConstraint> featureLineConstraints(const TriangleMesh& mesh, const CrossField& field,
                                                   const CutResult& cut, const HatBasis& basis,
                                                   const std::vector<CornerId>& sideCorners) {
  const double minCosine = std::cos(kFeatureAxisDegrees * M_PI / 180.0);
  std::vector<LineConstraint> lines;
  for (std::uint32_t g = 0; g < sideCorners.size(); ++g) {
    const CornerId s = sideCorners[g];
    const FaceId f = cornerFace(s);
    const Triangle& t = mesh.triangles[f];
    const Vec3d edge = mesh.position(t[(s + 2) % 3]) - mesh.position(t[(s + 1) % 3]);
    const Vec3d n = faceNormal(mesh, f);
    if (edge.norm() == 0.0 || n.squaredNorm() == 0.0) continue;
    Vec3d u = field.at(f);  // combed direction, as HatBasis::elementIntegrals
    for (int k = 0; k < cut.faceRotation[f] % 4; ++k) u = n.cross(u);
    const double alongU = std::abs(edge.normalized().dot(u));
    const double alongV = std::abs(edge.normalized().dot(n.cross(u)));
    if (std::max(alongU, alongV) < minCosine) continue;
    const std::uint8_t axis = alongU >= alongV ? 1 : 0;  // along u: v is constant on the edge
    for (CornerId end : {nextCorner(s), prevCorner(s)}) {
      const std::uint32_t domain = basis.cornerDomain()[end];
      if (domain != kInvalidId) lines.push_back({domain, axis, g});
    }
  }
  return lines;
}

namespace {

/// The faces of the unsolved and of the anchored components: each of their domains is given the
/// coefficient 1 (unsolved) or i (anchored), every other domain 0, and the basis is evaluated;
/// by the partition of unity a face of such a component evaluates to that tag (a component of the
/// surface lies within one component of the reduction). Costs one evaluation, only when needed.
void findComponentFaces(const Basis& basis, const Reduction& reduction, const SeamlessSolution& solution,
                        const Topology& topology, const CutResult& cut, ParamResult& out) {
  if (solution.unsolvedComponents.empty() && solution.anchoredComponents.empty()) return;
  std::vector<std::complex<double>> tagOfComponent(reduction.numComponents, 0.0);
  for (std::uint32_t c : solution.unsolvedComponents) tagOfComponent[c] = 1.0;
  for (std::uint32_t c : solution.anchoredComponents) tagOfComponent[c] = std::complex<double>(0.0, 1.0);
  const ReducedMap& P = reduction.map;
  std::vector<std::complex<double>> tag(basis.numDomains(), 0.0);
  for (std::size_t d = 0; d + 1 < P.rowStart.size() && d < tag.size(); ++d) {
    if (P.rowStart[d] == P.rowStart[d + 1]) continue;
    const std::uint32_t c = reduction.unknownComponent[P.column[P.rowStart[d]]];
    if (c != kInvalidId) tag[d] = tagOfComponent[c];
  }
  WedgeMap tagged = buildCutWedges(topology, cut);
  basis.evaluateCorners(tag, tagged);
  for (FaceId f = 0; f < topology.numFaces(); ++f) {
    const Vec2d mean = (tagged[3 * f] + tagged[3 * f + 1] + tagged[3 * f + 2]) / 3.0;
    if (mean[0] > 0.5) out.unsolvedFaces.push_back(f);
    if (mean[1] > 0.5) out.anchoredFaces.push_back(f);
  }
}

}  // namespace

void storeSeamlessSolution(const Basis& basis, const Reduction& reduction, SeamlessSolution solution,
                           const Topology& topology, const CutResult& cut, ParamResult& out, bool viewTriangles) {
  findComponentFaces(basis, reduction, solution, topology, cut, out);
  out.stats = solution.stats;
  out.translations = std::move(solution.translations);
  const auto start = std::chrono::steady_clock::now();
  out.cornerUV = buildCutWedges(topology, cut, viewTriangles);
  evaluateMap(basis, reduction, solution.unknowns, out.cornerUV);
  out.secondsEvaluate = secondsSince(start);
}

std::vector<GaussVector> closeSmallHoles(const TriangleMesh& mesh, const Topology& topology,
                                         const CutResult& cut, const ParamOptions& options,
                                         ParamResult& out) {
  if (options.closeHolesWithin <= 0.0) return {};
  HoleLoopConstraints holes = smallHoleConstraints(mesh, topology, cut, options.closeHolesWithin);
  out.smallHoles = holes.smallLoops;
  out.smallHolesRotated = holes.rotatedLoops;
  return std::move(holes.rows);
}

std::vector<GaussVector> seamCycleConstraints(const TriangleMesh&, const Topology& topology, const CrossField&,
                                              const CutResult& cut, double) {
  const std::vector<FaceId> faces = detail::facesAroundSeams(topology, cut.seams);
  if (faces.empty()) return {};  // an empty subset would mean the whole mesh
  const HatDomains domains(detail::buildSubsetWedges(topology, cut.corners, faces, cut.seams), cut.seams);
  return reduceBasis(domains).cycleConstraints;
}

}  // namespace seamvox
