#include "core/refine/refine.h"

#include "core/refine/detail_refine.h"
#include "core/refine/detail_region.h"
#include "core/refine/spline_space.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>

#include "core/basis/basis.h"
#include "core/system/errors.h"
#include "core/solve/evaluate.h"
#include "core/basis/gaussian_int.h"
#include "core/basis/hole_loops.h"
#include "core/quality/metrics.h"
#include "core/basis/reduce.h"
#include "core/solve/assemble.h"
#include "core/solve/cholmod_solver.h"
#include "core/solve/seamless_solve.h"
#include "core/system/memory.h"
#include "core/system/parallel.h"
#include "core/system/stopwatch.h"
#include "core/mesh/detail_union_find.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;


// Why a face is in the region (kOutside: it is not).
enum FaceFlag : std::uint8_t { kOutside = 0, kMarked = 1, kCollapsed = 2, kFlipped = 3, kRing = 4 };

// kCollapsed when the parameter area of face f is below threshold times its expected area
// (non-finite values included), kFlipped when negative.
FaceFlag classifyFace(const TriangleMesh& mesh, const WedgeMap& uv, FaceId f,
                      double threshold, double edgeLength) {
  switch (classifyRefineSeed(parameterAreaRatio(mesh, uv, f, edgeLength), threshold)) {
    case RefineSeed::Collapsed: return kCollapsed;
    case RefineSeed::Flipped: return kFlipped;
    default: return kOutside;
  }
}

using detail::isSortedUnique;

// Every face sharing a vertex with the frontier joins the region (flag kRing), rings times.
void addRings(const Topology& topology, std::vector<FaceId> frontier, std::uint32_t rings,
              std::vector<std::uint8_t>& flag, std::vector<FaceId>& region) {
  std::vector<std::uint8_t> vertexSeen(topology.numVertices(), 0);
  for (std::uint32_t ring = 0; ring < rings && !frontier.empty(); ++ring) {
    std::vector<FaceId> added;
    for (FaceId f : frontier) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = topology.vertex(3 * f + k);
        if (vertexSeen[v]) continue;
        vertexSeen[v] = 1;
        topology.forEachCornerAround(v, [&](CornerId c) {
          const FaceId g = cornerFace(c);
          if (flag[g] == kOutside) {
            flag[g] = kRing;
            added.push_back(g);
          }
        });
      }
    }
    region.insert(region.end(), added.begin(), added.end());
    frontier = std::move(added);
  }
  std::sort(region.begin(), region.end());
}

// selectRefineRegion with the per-face flags kept for later rounds.
std::vector<FaceId> selectFlagged(const TriangleMesh& mesh, const Topology& topology,
                                  const WedgeMap& cornerUV, const RefineOptions& options,
                                  std::vector<std::uint8_t>& flag, RefineStats* stats) {
  const FaceId nf = topology.numFaces();
  if (cornerUV.size() != 3u * static_cast<std::size_t>(nf) || mesh.numFaces() != nf) {
    throw InputError("refine: " + std::to_string(cornerUV.size()) + " corner UVs for " +
                     std::to_string(nf) + " faces (need 3 per face)");
  }
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength)) {
    throw InputError("refine: edge length must be positive and finite");
  }
  flag.assign(nf, kOutside);
  for (FaceId f : options.markedFaces) {
    if (f >= nf) {
      throw InputError("refine: marked face " + std::to_string(f) + " out of range (" +
                       std::to_string(nf) + " faces)");
    }
    flag[f] = kMarked;
  }
  if (options.seedFromMap) parallelFor(nf, 1u << 14, [&](const IndexRange& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      if (flag[f] != kOutside) continue;
      flag[f] = classifyFace(mesh, cornerUV, f, options.collapseThreshold, options.edgeLength);
    }
  });
  RefineStats counts;
  std::vector<FaceId> region;
  for (FaceId f = 0; f < nf; ++f) {
    if (flag[f] == kOutside) continue;
    region.push_back(f);
    counts.markedFaces += flag[f] == kMarked;
    counts.collapsedFaces += flag[f] == kCollapsed;
    counts.flippedFaces += flag[f] == kFlipped;
  }
  reportProgress(options.progress, "refine region", 0.5);
  addRings(topology, region, options.rings, flag, region);
  counts.regionFaces = region.size();
  copyRegionCounts(counts, stats);
  reportProgress(options.progress, "refine region", 1.0);
  return region;
}

}  // namespace

WedgeMap regionCornerValues(const RegionMesh& region, const WedgeMap& cornerUV) {
  std::vector<Vec2d> values(3 * region.faceOrigin.size());
  for (std::size_t i = 0; i < region.faceOrigin.size(); ++i) {
    for (int k = 0; k < 3; ++k) values[3 * i + k] = cornerUV[3 * region.faceOrigin[i] + k];
  }
  return WedgeMap::fromCorners(region.mesh.triangles, values);
}

std::vector<std::complex<double>> regionTranslations(const RegionMesh& region,
                                                     const std::vector<std::complex<double>>& seamT) {
  std::vector<std::complex<double>> out(region.seamOrigin.size());
  for (std::size_t j = 0; j < out.size(); ++j) out[j] = seamT[region.seamOrigin[j]];
  return out;
}

RefineOptions leftoverRefineOptions(const RefineOptions& base, std::vector<FaceId> flipped, double meanEdge,
                                    double radius) {
  RefineOptions out = base;
  out.markedFaces = std::move(flipped);
  out.islandFaces.clear();
  out.seedFromMap = false;
  out.maxRounds = 1;
  out.splineSpacing = 0.0;
  out.splineCells = 0;
  const double rings = meanEdge > 0.0 ? std::ceil(radius * base.edgeLength / meanEdge) : 1.0;
  out.rings = static_cast<std::uint32_t>(std::clamp(rings, 1.0, 256.0));
  return out;
}

std::vector<FaceId> growFaces(const Topology& topology, std::vector<FaceId> frontier, std::uint32_t rings,
                              std::size_t maxFaces) {
  return detail::growFacesIn(topology, std::move(frontier), rings, maxFaces);
}

std::vector<std::vector<FaceId>> splitRegion(const Topology& topology, const std::vector<FaceId>& faces,
                                             std::size_t groupFaces) {
  if (!isSortedUnique(faces)) throw InputError("refine: region faces must be sorted and unique");
  return detail::splitRegionIn(topology, faces, groupFaces);
}

void copyRegionCounts(const RefineStats& counts, RefineStats* stats) {
  if (!stats) return;
  stats->markedFaces = counts.markedFaces;
  stats->collapsedFaces = counts.collapsedFaces;
  stats->flippedFaces = counts.flippedFaces;
  stats->regionFaces = counts.regionFaces;
}

bool regionHoldsEveryFlip(const RefineOptions& options) {
  return options.seedFromMap && options.collapseThreshold >= kCollapsedAreaFraction;
}

RefineSeed classifyRefineSeed(double ratio, double threshold) {
  if (std::isnan(ratio) || ratio >= threshold) return RefineSeed::None;  // NaN: zero-area face, no energy
  return ratio < 0.0 ? RefineSeed::Flipped : RefineSeed::Collapsed;
}

std::vector<FaceId> selectRefineRegion(const TriangleMesh& mesh, const Topology& topology,
                                       const WedgeMap& cornerUV,
                                       const RefineOptions& options, RefineStats* stats) {
  std::vector<std::uint8_t> flag;
  return selectFlagged(mesh, topology, cornerUV, options, flag, stats);
}

namespace {

void checkRegionInput(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                      const CutResult& cut, const std::vector<FaceId>& regionFaces) {
  const FaceId nf = topology.numFaces();
  if (field.direction.size() != nf || cut.corners.size() != 3u * nf ||
      cut.faceRotation.size() != nf || mesh.numFaces() != nf) {
    throw InputError("refine: field or cut sizes do not match the mesh (" + std::to_string(nf) +
                     " faces)");
  }
  if (!isSortedUnique(regionFaces) || (!regionFaces.empty() && regionFaces.back() >= nf)) {
    throw InputError("refine: region faces must be increasing face ids below " +
                     std::to_string(nf));
  }
}

}  // namespace

RegionMesh extractRegion(const TriangleMesh& mesh, const Topology& topology,
                         const CrossField& field, const CutResult& cut,
                         const std::vector<FaceId>& regionFaces) {
  checkRegionInput(mesh, topology, field, cut, regionFaces);
  return detail::extractRegionFrom(
      topology, [&](VertexId v) { return mesh.positions[v]; }, [&](FaceId f) { return field.direction[f]; },
      [&](FaceId f) { return cut.faceRotation[f]; }, cut.corners, cut.seams, cut.cones, regionFaces);
}

RegionMesh extractRegionOnFieldSurface(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                                       const CutResult& cut, const std::vector<FaceId>& regionFaces) {
  RegionMesh out = extractRegion(mesh, topology, field, cut, regionFaces);
  if (field.framePositions.size() == mesh.numVertices()) {
    detail::placeRegionOnSurfaceOf(out, [&](VertexId v) { return field.framePositions[v]; });
  } else if (field.frameSmoothing > 0) {
    placeRegionOnSurface(out, framePositionsAt(mesh, topology, field, out.vertexOrigin));
  }
  return out;
}

void placeRegionOnSurface(RegionMesh& region, std::vector<Vec3f> surface) {
  if (surface.size() != region.mesh.numVertices()) {
    throw InputError("refine: " + std::to_string(surface.size()) + " surface positions for a region of " +
                     std::to_string(region.mesh.numVertices()) + " vertices");
  }
  const auto normal = [](const std::vector<Vec3f>& points, const Triangle& t) {
    const Vec3d a = points[t[0]].cast<double>();
    return Vec3d((points[t[1]].cast<double>() - a).cross(points[t[2]].cast<double>() - a));
  };
  for (FaceId f = 0; f < region.mesh.numFaces(); ++f) {
    const Triangle& t = region.mesh.triangles[f];
    const Vec3d own = normal(region.mesh.positions, t), there = normal(surface, t);
    const double a = own.norm(), b = there.norm();
    if (!(a > 0.0) || !(b > 0.0) || !std::isfinite(a) || !std::isfinite(b)) continue;
    region.field.set(f, rotateBetween(own / a, there / b, region.field.at(f)));
  }
  region.mesh.positions = std::move(surface);
}

namespace {

/// A region's hat basis and reduction with what every phase of solveRegion reads: the locked
/// vertices and domains and the input value of a domain.
struct RegionProblem {
  const RegionMesh& region;
  const WedgeMap& cornerUV;
  const HatBasis& basis;
  const Reduction& reduction;
  std::uint32_t rf = 0, ns = 0, nd = 0, np = 0;
  std::vector<CornerId> domainCorner;  ///< a corner of each domain

  RegionProblem(const RegionMesh& r, const WedgeMap& uv, const HatBasis& b, const Reduction& red)
      : region(r), cornerUV(uv), basis(b), reduction(red) {
    rf = region.topology.numFaces();
    ns = static_cast<std::uint32_t>(region.cut.seams.size());
    nd = basis.numDomains();
    np = reduction.numPositional;
    const auto& cornerDomain = basis.cornerDomain();
    domainCorner.assign(nd, kInvalidId);
    for (CornerId c = 0; c < 3u * rf; ++c) {
      if (domainCorner[cornerDomain[c]] == kInvalidId) domainCorner[cornerDomain[c]] = c;
    }
  }
  bool isLockedVertex(VertexId v) const { return !region.vertexFree[v]; }
  bool isLocked(std::uint32_t d) const { return isLockedVertex(basis.basisVertex()[basis.domainBasis()[d]]); }
  Complex input(std::uint32_t d) const {
    const Vec2d q = cornerUV[domainCorner[d]];
    return Complex(q.x(), q.y());
  }
};

/// Region vertices on a boundary loop of the region that has a locked vertex: a hole of the
/// mesh the region holds only in part lies on such a loop, and a seam at it keeps its t (the
/// hole's translation, ParamOptions::closeHolesWithin, is not a constraint of the region).
std::vector<std::uint8_t> verticesOnLockedLoops(const RegionProblem& p) {
  const Topology& topology = p.region.topology;
  std::vector<std::uint8_t> onLoop(topology.numVertices(), 0), seen(topology.numCorners(), 0);
  std::vector<CornerId> loop;
  for (CornerId start = 0; start < topology.numCorners(); ++start) {
    if (!topology.isBoundaryEdge(start) || seen[start]) continue;
    loop.clear();
    bool locked = false;
    for (CornerId c = start; loop.empty() || c != start; c = nextBoundaryCorner(topology, c)) {
      seen[c] = 1;
      loop.push_back(c);
      locked = locked || p.isLockedVertex(topology.vertex(prevCorner(c)));
    }
    if (!locked) continue;
    for (CornerId c : loop) onLoop[topology.vertex(prevCorner(c))] = 1;
  }
  return onLoop;
}

/// Translations: a seam touching a locked vertex keeps the input's t (the locked values on its
/// two sides obey it), as does a seam at a hole the region holds in part. The other seams lie
/// among free vertices only (e.g. between a cone and a seam node): the input map says little
/// about their t (the Vox solve barely sees them), so t = seamT + U s is solved, rounded and
/// solved again, where U spans the Gaussian-integer solutions of the cycle constraints (and of
/// the small holes the region holds whole) restricted to these seams (seamT obeys the
/// constraints, so every t of this form does too). Returns 1 for the free seams.
std::vector<std::uint8_t> findFreeSeams(const RegionProblem& p) {
  std::vector<std::uint8_t> freeSeam(p.ns, 1);
  const std::vector<std::uint8_t> onLockedLoop = verticesOnLockedLoops(p);
  const auto keepsT = [&](VertexId v) { return p.isLockedVertex(v) || onLockedLoop[v]; };
  for (std::uint32_t j = 0; j < p.ns; ++j) {
    for (CornerId c : p.region.cut.seams[j].corners) {
      const Triangle& t = p.region.mesh.triangles[c / 3];
      if (keepsT(t[(c + 1) % 3]) || keepsT(t[(c + 2) % 3])) freeSeam[j] = 0;
    }
  }
  return freeSeam;
}

/// Kernel: a region component without a locked vertex and without a fixed seam of rotation
/// r != 1 can shift freely (anchored stays 0 for it); hasPositional: the component has a
/// positional unknown.
struct RegionComponents {
  ComponentsResult components;
  std::vector<std::uint8_t> anchored, hasPositional;
};

RegionComponents findRegionComponents(const RegionProblem& p, const std::vector<std::uint8_t>& freeSeam) {
  const auto& cornerDomain = p.basis.cornerDomain();
  const ReducedMap& P = p.reduction.map;
  RegionComponents rc;
  rc.components = computeComponents(p.region.topology);
  const ComponentsResult& components = rc.components;
  rc.anchored.assign(components.components.size(), 0);
  for (CornerId c = 0; c < 3u * p.rf; ++c) {
    if (p.isLocked(cornerDomain[c])) rc.anchored[components.faceComponent[c / 3]] = 1;
  }
  for (std::uint32_t j = 0; j < p.ns; ++j) {
    const SeamCurve& seam = p.region.cut.seams[j];
    if (seam.matching % 4 != 0 && !freeSeam[j]) {
      rc.anchored[components.faceComponent[seam.corners.front() / 3]] = 1;
    }
  }
  rc.hasPositional.assign(components.components.size(), 0);
  for (CornerId c = 0; c < 3u * p.rf; ++c) {
    const std::uint32_t d = cornerDomain[c];
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      if (P.column[k] < p.np) rc.hasPositional[components.faceComponent[c / 3]] = 1;
    }
  }
  return rc;
}

/// U: the Gaussian-integer solutions of the cycle constraints restricted to the free seams, and
/// the local index of each of its columns that a free seam uses (numS of them).
struct FreeTranslations {
  LatticeEliminator lattice;
  std::vector<std::uint32_t> sIndex;
  std::uint32_t numS = 0;
  explicit FreeTranslations(std::uint32_t ns) : lattice(ns) {}
};

FreeTranslations findFreeTranslations(const RegionProblem& p, const std::vector<std::uint8_t>& freeSeam,
                                      double closeHolesWithin) {
  FreeTranslations ft(p.ns);
  // The holes the region holds whole stay closed when the global solve closed them
  // (ParamOptions::closeHolesWithin, the same extent). Held regardless, they froze the loop
  // translations the voxel map gave one-triangle cracks: on a scan with thousands of them the
  // re-solve flipped 110 faces and stretched 23 up to 170-fold.
  std::vector<GaussVector> rows;
  if (closeHolesWithin > 0.0) {
    rows = smallHoleConstraints(p.region.mesh, p.region.topology, p.region.cut, closeHolesWithin, &p.region.vertexFree)
               .rows;
  }
  rows.insert(rows.begin(), p.reduction.cycleConstraints.begin(), p.reduction.cycleConstraints.end());
  for (const GaussVector& row : rows) {
    GaussVector restricted;
    for (const auto& entry : row) {
      if (freeSeam[entry.first]) restricted.push_back(entry);
    }
    if (!restricted.empty()) ft.lattice.addConstraint(restricted);
  }
  ft.lattice.finish();
  ft.sIndex.assign(ft.lattice.numFree(), kInvalidId);
  for (std::uint32_t j = 0; j < p.ns; ++j) {
    if (!freeSeam[j]) continue;
    for (const auto& [k, u] : ft.lattice.row(j)) {
      if (ft.sIndex[k] == kInvalidId) ft.sIndex[k] = ft.numS++;
    }
  }
  return ft;
}

/// Fixed part of every domain's coefficient: the translations seamT.
std::vector<Complex> fixedTranslationPart(const RegionProblem& p, const std::vector<Complex>& seamT) {
  const ReducedMap& P = p.reduction.map;
  std::vector<Complex> fixedPart(p.nd, 0.0);
  for (std::uint32_t d = 0; d < p.nd; ++d) {
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (j >= p.np) fixedPart[d] += P.value[k] * seamT[j - p.np];
    }
  }
  return fixedPart;
}

/// Pins one positional unknown to its input value in every component still free to shift (kept
/// in both solves: such a component is the whole surface component, not a repair). A component
/// without any positional unknown (every vertex a cone, e.g. a tetrahedron) is left to
/// solveSeamless, which anchors its shift through a translation. Returns the number of pins.
std::uint32_t pinFreeComponents(const RegionProblem& p, const std::vector<std::uint8_t>& freeSeam,
                                const std::vector<Complex>& fixedPart, RegionComponents& rc,
                                std::vector<std::uint8_t>& pinned, std::vector<Complex>& pinValue) {
  const auto& cornerDomain = p.basis.cornerDomain();
  const ReducedMap& P = p.reduction.map;
  pinned.assign(p.np, 0);
  pinValue.assign(p.np, 0.0);
  std::uint32_t count = 0;
  for (CornerId c = 0; c < 3u * p.rf; ++c) {
    const std::uint32_t comp = rc.components.faceComponent[c / 3];
    const std::uint32_t d = cornerDomain[c];
    if (rc.anchored[comp]) continue;
    // A domain whose row is value c_0 + fixed translations only.
    std::uint32_t column = kInvalidId;
    Complex value;
    bool onlyFixed = true;
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      if (P.column[k] < p.np) {
        column = P.column[k];
        value = P.value[k];
      } else if (freeSeam[P.column[k] - p.np]) {
        onlyFixed = false;
      }
    }
    if (column == kInvalidId || !onlyFixed) continue;
    pinned[column] = 1;
    pinValue[column] = (p.input(d) - fixedPart[d]) / value;
    rc.anchored[comp] = 1;
    ++count;
  }
  return count;
}

/// The local map: free domains keep their positional column (compacted) and the free
/// translations (through U); fixed translations, pins and locked wedges go to the offset. With
/// the translations per seam in terms of the local s, and the component bookkeeping only for the
/// components without a positional unknown (solveSeamless anchors them); elsewhere it pins
/// nothing (the pins are offsets).
Reduction buildRegionSystem(const RegionProblem& p, const std::vector<std::uint8_t>& freeSeam,
                            const FreeTranslations& ft, const std::vector<Complex>& fixedPart,
                            const std::vector<std::uint8_t>& pinned, const std::vector<Complex>& pinValue,
                            const RegionComponents& rc) {
  const ReducedMap& P = p.reduction.map;
  const std::uint32_t nd = p.nd, np = p.np, ns = p.ns;
  const LatticeEliminator& lattice = ft.lattice;
  const std::vector<std::uint32_t>& sIndex = ft.sIndex;
  std::vector<std::uint32_t> newIndex(np, kInvalidId);
  Reduction system;
  std::uint32_t numPositional = 0;
  for (std::uint32_t d = 0; d < nd; ++d) {
    if (p.isLocked(d)) continue;
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (j < np && !pinned[j] && newIndex[j] == kInvalidId) newIndex[j] = numPositional++;
    }
  }
  system.numPositional = numPositional;
  system.numTranslational = ft.numS;
  ReducedMap& Q = system.map;
  Q.rowStart.assign(nd + 1, 0);
  Q.offset.resize(nd);
  std::vector<std::pair<std::uint32_t, Complex>> row;
  for (std::uint32_t d = 0; d < nd; ++d) {
    row.clear();
    if (p.isLocked(d)) {
      Q.offset[d] = p.input(d);
    } else {
      Q.offset[d] = fixedPart[d];
      for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
        const std::uint32_t j = P.column[k];
        if (j < np) {
          if (pinned[j]) {
            Q.offset[d] += P.value[k] * pinValue[j];
          } else {
            row.emplace_back(newIndex[j], P.value[k]);
          }
        } else if (freeSeam[j - np]) {
          for (const auto& [col, u] : lattice.row(j - np)) {
            row.emplace_back(numPositional + sIndex[col], P.value[k] * u.toComplex());
          }
        }
      }
      std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    }
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (k > 0 && row[k].first == row[k - 1].first) {
        Q.value.back() += row[k].second;
      } else {
        Q.column.push_back(row[k].first);
        Q.value.push_back(row[k].second);
      }
    }
    Q.rowStart[d + 1] = Q.column.size();
  }
  // Translations per seam in terms of the local s (for seamTranslations).
  system.seamTranslation.resize(ns);
  for (std::uint32_t j = 0; j < ns; ++j) {
    if (!freeSeam[j]) continue;
    for (const auto& [col, u] : lattice.row(j)) system.seamTranslation[j].emplace_back(sIndex[col], u);
  }
  const ComponentsResult& components = rc.components;
  system.unknownComponent.assign(system.numUnknowns(), kInvalidId);
  system.numComponents = static_cast<std::uint32_t>(components.components.size());
  system.componentHasRotation.assign(system.numComponents, 0);
  for (std::uint32_t j = 0; j < ns; ++j) {
    const SeamCurve& seam = p.region.cut.seams[j];
    const std::uint32_t comp = components.faceComponent[seam.corners.front() / 3];
    if (rc.anchored[comp] || rc.hasPositional[comp] || !freeSeam[j]) continue;
    if (seam.matching % 4 != 0) system.componentHasRotation[comp] = 1;
    for (const auto& [col, u] : lattice.row(j)) system.unknownComponent[numPositional + sIndex[col]] = comp;
  }
  return system;
}

void evaluateRegion(const RegionProblem& p, const Reduction& system, const std::vector<Complex>& x,
                    RegionSolution& out);

/// The local system with the given seams' translations free (the rest fixed to seamT, whose part
/// is fixedPart); its counts go to local.
Reduction buildLocalSystem(const RegionProblem& p, const std::vector<std::uint8_t>& freeSeam,
                           const std::vector<Complex>& fixedPart, double closeHolesWithin, RefineStats& local) {
  RegionComponents components = findRegionComponents(p, freeSeam);
  const FreeTranslations translations = findFreeTranslations(p, freeSeam, closeHolesWithin);
  std::vector<std::uint8_t> pinned;
  std::vector<Complex> pinValue;
  local.pinned = pinFreeComponents(p, freeSeam, fixedPart, components, pinned, pinValue);
  Reduction system = buildRegionSystem(p, freeSeam, translations, fixedPart, pinned, pinValue, components);
  local.unknowns = system.numUnknowns();
  local.freeTranslations = translations.numS;
  return system;
}

/// Elements of a basis, each with its integrals times a scale: assembled over the faces whose
/// weight w is not 1 with scale w - 1, the part a re-weighted system adds to the basis' own
/// (the assembly is linear in the integrals). Their area counts 0 (the system's area is the
/// basis' own).
class ScaledElements final : public Basis {
 public:
  ScaledElements(const Basis& base, std::vector<std::uint64_t> elements, std::vector<double> scale)
      : base_(base), elements_(std::move(elements)), scale_(std::move(scale)) {}
  std::uint64_t numElements() const override { return elements_.size(); }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override {
    return base_.elementDomains(elements_[e], out);
  }
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override {
    base_.elementIntegrals(elements_[e], out);
    const double s = scale_[e];
    for (std::uint32_t k = 0; k < out.count * out.count; ++k) out.stiffness[k] *= s;
    for (std::uint32_t k = 0; k < out.count; ++k) out.rhs[k] *= s;
    out.area = 0.0;
  }
  void evaluateCorners(const std::vector<Complex>&, WedgeMap&) const override {
    throw InputError("scaled elements: not a basis to evaluate");
  }

 private:
  const Basis& base_;
  std::vector<std::uint64_t> elements_;
  std::vector<double> scale_;
};

/// Solves the local system (when it has unknowns), evaluates the map on the region's wedges and
/// puts the locked corners back exactly as in the input.
RegionSolution solveRegionSystem(const RegionProblem& p, const Reduction& system, const std::vector<Complex>& seamT,
                                 RefineStats& local, std::vector<std::uint32_t>* firstOrder = nullptr,
                                 const LinearSystem* assembled = nullptr) {
  RegionSolution out;
  std::vector<Complex> x;
  if (system.numUnknowns() > 0) {
    RoundOptions roundOptions;
    roundOptions.dropUnsolvable = false;  // a region's failure is the refinement's, reported whole
    roundOptions.firstOrder = firstOrder;
    const SeamlessSolution solution = assembled ? solveSeamlessSystem(*assembled, system, roundOptions)
                                                : solveSeamless(p.basis, system, roundOptions);
    x = solution.unknowns;
    local.systemNonzeros = solution.stats.systemNonzeros;
    local.factorNonzeros = solution.stats.factorNonzeros;
    local.factorBytes = solution.stats.factorBytes;
    local.factorPeakBytes = solution.stats.factorPeakBytes;
  }
  out.seamT = seamT;
  if (system.numTranslational > 0) {
    const std::vector<Complex> s(x.begin() + system.numPositional, x.end());
    const std::vector<Complex> t = seamTranslations(system, s);
    for (std::uint32_t j = 0; j < p.ns; ++j) out.seamT[j] += t[j];
  }
  evaluateRegion(p, system, x, out);
  return out;
}

/// The map of unknowns x on the region's wedges, with the locked corners put back exactly as in
/// the input.
void evaluateRegion(const RegionProblem& p, const Reduction& system, const std::vector<Complex>& x,
                    RegionSolution& out) {
  out.cornerUV = buildCutWedges(p.region.topology, p.region.cut);
  evaluateMap(p.basis, system, x, out.cornerUV);
  const auto& cornerDomain = p.basis.cornerDomain();
  std::vector<CornerId> locked;
  std::vector<Vec2d> lockedUV;
  for (CornerId c = 0; c < 3u * p.rf; ++c) {
    if (!p.isLocked(cornerDomain[c])) continue;
    locked.push_back(c);
    lockedUV.push_back(p.cornerUV[c]);  // exactly the input
  }
  out.cornerUV.assign(locked, lockedUV);
}

/// The positional unknowns of the map as it is: x0_j from the input at a free domain of unknown j
/// (row: value x_j + offset; the free translations at s = 0).
std::vector<Complex> inputUnknowns(const RegionProblem& p, const Reduction& system) {
  const ReducedMap& Q = system.map;
  std::vector<Complex> x(system.numUnknowns(), 0.0);
  std::vector<std::uint8_t> seen(system.numPositional, 0);
  for (std::uint32_t d = 0; d < p.nd; ++d) {
    if (p.isLocked(d)) continue;
    for (std::uint64_t k = Q.rowStart[d]; k < Q.rowStart[d + 1]; ++k) {
      const std::uint32_t j = Q.column[k];
      if (j >= system.numPositional || seen[j]) continue;
      seen[j] = 1;
      x[j] = (p.input(d) - Q.offset[d]) / Q.value[k];
    }
  }
  return x;
}

/// The spline round's solve (spline_space.h): x = x0 + P c with c minimising the region's hat
/// energy, P^H K P c = P^H (rhs - K x0). Restricted B-splines can be linearly dependent (a flat
/// patch inside a cell), so the diagonal gets a relative 1e-9: it picks one of equal-energy
/// combinations and changes nothing else measurable.
RegionSolution solveInSplines(const RegionProblem& p, const Reduction& system, detail::SplineSpace& space,
                              const std::vector<Complex>& seamT, RefineStats& local) {
  std::vector<Complex> x = inputUnknowns(p, system);
  const std::uint32_t np = system.numPositional, m = space.numColumns;
  if (m > 0) {
    // Only P, the reduced lower triangle and b outlive their block into the factorization: the
    // largest groups' solves run at the in-memory pipeline's peak, two at a time.
    ComplexSparse P(static_cast<int>(np), static_cast<int>(m));
    {
      std::vector<ComplexTriplet> triplets;
      triplets.reserve(space.column.size());
      for (std::uint32_t j = 0; j < np; ++j) {
        for (std::uint64_t k = space.rowStart[j]; k < space.rowStart[j + 1]; ++k) {
          triplets.emplace_back(static_cast<int>(j), static_cast<int>(space.column[k]), space.value[k]);
        }
      }
      P.setFromTriplets(triplets.begin(), triplets.end());
    }
    // P holds the space's rows from here on (its ownUnknown flags stay for the caller).
    std::vector<std::uint64_t>().swap(space.rowStart);
    std::vector<std::uint32_t>().swap(space.column);
    std::vector<Complex>().swap(space.value);
    ComplexSparse lower;
    ComplexVector b;
    {
      // A = P^H K P as P^H (K P), each operand freed once used: the hat system's lower half, its
      // full copy and K P are the group's largest blocks (a 454K-face piece of a noisy scan's
      // region runs at the pipeline's peak).
      ComplexSparse KP;
      ComplexVector residual;
      {
        LinearSystem ls = assembleSystem(p.basis, system);
        const ComplexSparse K = ls.lower.selfadjointView<Eigen::Lower>();
        ls.lower = ComplexSparse();
        ComplexVector x0(np);
        for (std::uint32_t j = 0; j < np; ++j) x0[j] = x[j];
        residual = ls.rhs - K * x0;
        KP = K * P;
      }
      const ComplexSparse PH = P.adjoint();
      b = PH * residual;
      const ComplexSparse A = PH * KP;
      KP = ComplexSparse();
      lower = A.triangularView<Eigen::Lower>();
    }
    for (int i = 0; i < static_cast<int>(m); ++i) {
      Complex& diagonal = lower.coeffRef(i, i);
      diagonal = diagonal.real() > 0.0 ? Complex(diagonal.real() * (1.0 + 1e-9), 0.0) : Complex(1.0, 0.0);
    }
    lower.makeCompressed();
    CholmodFactor factor;
    factor.factor(lower);
    const ComplexVector c = factor.solve(b);
    const ComplexVector dx = P * c;
    for (std::uint32_t j = 0; j < np; ++j) x[j] += dx[j];
    local.unknowns = m;
    local.systemNonzeros = static_cast<std::uint64_t>(lower.nonZeros());
    local.factorNonzeros = factor.factorNonzeros();
    local.factorBytes = factor.factorBytes();
    local.factorPeakBytes = factor.peakBytes();
  }
  RegionSolution out;
  out.seamT = seamT;
  evaluateRegion(p, system, x, out);
  return out;
}

/// A local solve's figures into the caller's stats (when given).
void copySolveStats(const RefineStats& local, RefineStats* stats) {
  if (!stats) return;
  stats->unknowns = local.unknowns;
  stats->freeTranslations = local.freeTranslations;
  stats->pinned = local.pinned;
  stats->systemNonzeros = local.systemNonzeros;
  stats->factorNonzeros = local.factorNonzeros;
  stats->factorBytes = local.factorBytes;
  stats->factorPeakBytes = local.factorPeakBytes;
}

/// Throws InputError unless cornerUV and seamT fit the region.
void checkRegionMap(const RegionMesh& region, const WedgeMap& cornerUV, const std::vector<Complex>& seamT) {
  const std::uint32_t rf = region.topology.numFaces();
  const std::uint32_t ns = static_cast<std::uint32_t>(region.cut.seams.size());
  if (cornerUV.size() != 3u * static_cast<std::size_t>(rf) || seamT.size() != ns) {
    throw InputError("refine: region has " + std::to_string(rf) + " faces and " +
                     std::to_string(ns) + " seams but got " + std::to_string(cornerUV.size()) +
                     " corner UVs and " + std::to_string(seamT.size()) + " translations");
  }
}

/// The region's hat basis (weights only around cones) and its reduction without translation
/// constraints (column np + j of P is t_j itself).
HatBasisOptions regionBasisOptions(double edgeLength, const std::vector<double>& faceWeight, double coneWeightRadius) {
  HatBasisOptions basisOptions;
  basisOptions.edgeLength = edgeLength;
  basisOptions.faceWeight = faceWeight;
  basisOptions.coneWeightRadius = coneWeightRadius;
  return basisOptions;
}

Reduction reduceRegionBasis(const HatBasis& basis) {
  const std::vector<GaussVector> noConstraints;
  ReduceOptions reduceOptions;
  reduceOptions.translationConstraints = &noConstraints;
  return reduceBasis(basis, reduceOptions);
}

/// solveRegion, and with spacing > 0 the spline round's solve (solveRegionInSplines).
RegionSolution solveRegionWith(const RegionMesh& region, const WedgeMap& cornerUV, const std::vector<Complex>& seamT,
                               double edgeLength, RefineStats* stats, const std::vector<double>& faceWeight,
                               double coneWeightRadius, bool keepTranslations, double spacing,
                               std::vector<std::uint8_t>* ownUnknown, double maxColumnFraction,
                               double closeHolesWithin, std::vector<std::uint32_t>* firstOrder = nullptr) {
  checkRegionMap(region, cornerUV, seamT);
  const std::uint32_t ns = static_cast<std::uint32_t>(region.cut.seams.size());
  const HatBasis basis(region.mesh, region.topology, region.field, region.cut,
                       regionBasisOptions(edgeLength, faceWeight, coneWeightRadius));
  const Reduction reduction = reduceRegionBasis(basis);
  const RegionProblem problem(region, cornerUV, basis, reduction);

  const std::vector<Complex> fixedPart = fixedTranslationPart(problem, seamT);
  RefineStats local;
  const auto buildSystem = [&](const std::vector<std::uint8_t>& freeSeam) {
    return buildLocalSystem(problem, freeSeam, fixedPart, closeHolesWithin, local);
  };
  const auto freeSeams = [&] { return keepTranslations ? std::vector<std::uint8_t>(ns, 0) : findFreeSeams(problem); };

  RegionSolution out;
  if (spacing > 0.0) {
    const Reduction system = buildSystem(std::vector<std::uint8_t>(ns, 0));
    std::vector<std::uint8_t> locked(region.mesh.numVertices());
    for (VertexId v = 0; v < locked.size(); ++v) locked[v] = !region.vertexFree[v];
    detail::SplineSpace space = detail::buildSplineSpace(region.mesh, basis.cornerDomain(), system, locked, spacing);
    if (double(space.numColumns) >= maxColumnFraction * system.numPositional) {
      // Cells finer than the mesh: the hat solve, as the round would be without B-splines.
      out = solveRegionSystem(problem, buildSystem(freeSeams()), seamT, local);
    } else {
      out = solveInSplines(problem, system, space, seamT, local);
      out.inSplines = true;
      if (ownUnknown) *ownUnknown = std::move(space.ownUnknown);
    }
  } else {
    out = solveRegionSystem(problem, buildSystem(freeSeams()), seamT, local, firstOrder);
  }
  copySolveStats(local, stats);
  return out;
}

}  // namespace

RegionSolution solveRegion(const RegionMesh& region, const WedgeMap& cornerUV,
                           const std::vector<Complex>& seamT, double edgeLength,
                           RefineStats* stats, const std::vector<double>& faceWeight,
                           double coneWeightRadius, bool keepTranslations, double closeHolesWithin,
                           std::vector<std::uint32_t>* firstOrder) {
  return solveRegionWith(region, cornerUV, seamT, edgeLength, stats, faceWeight, coneWeightRadius, keepTranslations,
                         0.0, nullptr, 0.0, closeHolesWithin, firstOrder);
}

RegionSolution solveRegionInSplines(const RegionMesh& region, const WedgeMap& cornerUV,
                                    const std::vector<Complex>& seamT, double edgeLength, double spacing,
                                    double coneWeightRadius, std::vector<std::uint8_t>& ownUnknown,
                                    RefineStats* stats, double maxColumnFraction, double closeHolesWithin) {
  if (!(spacing > 0.0)) throw InputError("refine: spline spacing must be positive");
  return solveRegionWith(region, cornerUV, seamT, edgeLength, stats, {}, coneWeightRadius, false, spacing,
                         &ownUnknown, maxColumnFraction, closeHolesWithin);
}

struct RegionStiffener::Impl {
  /// One kind of local system (translations solved or kept): built, assembled at weight 1 and
  /// ordered at its first solve.
  struct Kind {
    bool built = false;
    Reduction system;
    LinearSystem assembled;
    std::vector<std::uint32_t> order;
    RefineStats local;
  };
  const RegionMesh& region;
  std::vector<Complex> seamT;
  double closeHolesWithin;
  HatBasis basis;
  Reduction reduction;
  RegionProblem problem;
  std::vector<Complex> fixedPart;
  Kind kinds[2];

  Impl(const RegionMesh& r, const WedgeMap& cornerUV, const std::vector<Complex>& t, double edgeLength,
       double coneWeightRadius, double holes)
      : region(r),
        seamT(t),
        closeHolesWithin(holes),
        basis(r.mesh, r.topology, r.field, r.cut, regionBasisOptions(edgeLength, {}, coneWeightRadius)),
        reduction(reduceRegionBasis(basis)),
        problem(r, cornerUV, basis, reduction),
        fixedPart(fixedTranslationPart(problem, seamT)) {}
};

RegionStiffener::RegionStiffener(const RegionMesh& region, const WedgeMap& cornerUV, const std::vector<Complex>& seamT,
                                 double edgeLength, double coneWeightRadius, double closeHolesWithin) {
  checkRegionMap(region, cornerUV, seamT);
  impl_ = std::make_unique<Impl>(region, cornerUV, seamT, edgeLength, coneWeightRadius, closeHolesWithin);
}

RegionStiffener::~RegionStiffener() = default;

RegionSolution RegionStiffener::solve(const std::vector<double>& faceWeight, bool keepTranslations, RefineStats* stats) {
  Impl& m = *impl_;
  const std::uint32_t rf = m.region.topology.numFaces();
  if (!faceWeight.empty() && faceWeight.size() != rf) {
    throw InputError("refine: " + std::to_string(faceWeight.size()) + " face weights for a region of " +
                     std::to_string(rf) + " faces");
  }
  Impl::Kind& kind = m.kinds[keepTranslations ? 1 : 0];
  if (!kind.built) {
    const std::vector<std::uint8_t> freeSeam =
        keepTranslations ? std::vector<std::uint8_t>(m.region.cut.seams.size(), 0) : findFreeSeams(m.problem);
    kind.system = buildLocalSystem(m.problem, freeSeam, m.fixedPart, m.closeHolesWithin, kind.local);
    kind.assembled = assembleSystem(m.basis, kind.system);
    kind.built = true;
  }
  std::vector<std::uint64_t> elements;
  std::vector<double> scale;
  for (std::uint64_t e = 0; e < m.basis.numElements() && !faceWeight.empty(); ++e) {
    const double w = faceWeight[m.basis.elementFace(e)];
    if (!std::isfinite(w) || w < 0.0) throw InputError("refine: face weights must be finite and not negative");
    if (w == 1.0) continue;
    elements.push_back(e);
    scale.push_back(w - 1.0);
  }
  RefineStats local = kind.local;
  RegionSolution out;
  if (elements.empty()) {
    out = solveRegionSystem(m.problem, kind.system, m.seamT, local, &kind.order, &kind.assembled);
  } else {
    const LinearSystem added = assembleSystem(ScaledElements(m.basis, std::move(elements), std::move(scale)), kind.system);
    LinearSystem weighted;
    weighted.lower = kind.assembled.lower + added.lower;
    weighted.rhs = kind.assembled.rhs + added.rhs;
    weighted.totalArea = kind.assembled.totalArea;
    out = solveRegionSystem(m.problem, kind.system, m.seamT, local, &kind.order, &weighted);
  }
  copySolveStats(local, stats);
  return out;
}

namespace detail {

/// A region's solved corners under whole-mesh ids, in increasing corner order (sub faces follow
/// the whole mesh's order), written from `out` on.
void writeSolvedCorners(const RegionMesh& region, const RegionSolution& solved, SolvedCorner* out,
                        const std::vector<std::uint8_t>* ownUnknown) {
  for (CornerId c = 0; c < solved.cornerUV.size(); ++c) {
    const VertexId v = region.mesh.triangles[c / 3][c % 3];
    const bool free = region.vertexFree[v] != 0;
    out[c] = {solved.cornerUV[c], 3 * region.faceOrigin[c / 3] + c % 3, free,
              free && ownUnknown && !(*ownUnknown)[v]};
  }
}

/// Records solved corners (sorted by corner) in `current` (sorted by corner; these values replace
/// older ones, a corner stays free once freed, and hat-freed once a hat round freed it). Corners seen before are updated in place and new
/// ones merged in within the spare capacity where it suffices: no second copy of `current`,
/// which holds every corner of a region of millions of faces.
void mergeSolved(std::vector<SolvedCorner> fresh, std::vector<SolvedCorner>& current) {
  if (current.empty()) {
    current = std::move(fresh);
    return;
  }
  const auto byCorner = [](const SolvedCorner& a, const SolvedCorner& b) { return a.corner < b.corner; };
  std::vector<SolvedCorner> added;
  for (const SolvedCorner& s : fresh) {
    const auto it = std::lower_bound(current.begin(), current.end(), s, byCorner);
    if (it != current.end() && it->corner == s.corner) {
      const bool hatFreed = (s.free && !s.spline) || (it->free && !it->spline);
      *it = {s.uv, s.corner, s.free || it->free, (s.free || it->free) && !hatFreed};
    } else {
      added.push_back(s);
    }
  }
  const std::size_t old = current.size();
  current.insert(current.end(), added.begin(), added.end());
  std::inplace_merge(current.begin(), current.begin() + old, current.end(), byCorner);
}

/// Measures a solved region into figures; returns its bad faces touching a locked vertex (whole-
/// mesh ids: they seed the next round). collapsedAtBorder: one of them is below the threshold
/// but not flipped.
std::vector<FaceId> measureSolvedRegion(const RegionMesh& region, const RegionSolution& solved, double h,
                                        double collapseThreshold, RefineRound& figures, bool& collapsedAtBorder,
                                        bool everyBadFace, bool collapsedOnly) {
  std::vector<std::uint8_t> subCone(region.mesh.numVertices(), 0);
  for (VertexId v : region.cut.cones) subCone[v] = 1;
  FaceCounts inRegion;
  std::vector<FaceId> border;
  collapsedAtBorder = false;
  const std::uint32_t rf = region.topology.numFaces();
  for (std::uint32_t i = 0; i < rf; ++i) {
    const double ratio = parameterAreaRatio(region.mesh, solved.cornerUV, i, h);
    inRegion.add(ratio, [&] { return collapsesBetweenCones(region.mesh, solved.cornerUV, i, subCone); });
    const Triangle& t = region.mesh.triangles[i];
    if (std::isnan(ratio) || ratio >= collapseThreshold) continue;
    if (everyBadFace) {
      if (collapsedOnly && !(std::abs(ratio) < kCollapsedAreaFraction)) continue;
      if (!collapsesBetweenCones(region.mesh, solved.cornerUV, i, subCone)) border.push_back(region.faceOrigin[i]);
      continue;
    }
    const bool locked = !region.vertexFree[t[0]] || !region.vertexFree[t[1]] || !region.vertexFree[t[2]];
    if (locked && !collapsesBetweenCones(region.mesh, solved.cornerUV, i, subCone)) {
      border.push_back(region.faceOrigin[i]);
      collapsedAtBorder = collapsedAtBorder || ratio >= 0.0;
    }
  }
  figures.collapsed = inRegion.collapsed;
  figures.collapsedAtCones = inRegion.collapsedAtCones;
  figures.flipped = inRegion.flipped;
  figures.borderFaces = border.size();
  return border;
}

void keepLargestSolve(const RefineStats& largest, RefineStats& stats) {
  stats.unknowns = largest.unknowns;
  stats.freeTranslations = largest.freeTranslations;
  stats.pinned = largest.pinned;
  stats.systemNonzeros = largest.systemNonzeros;
  stats.factorNonzeros = largest.factorNonzeros;
  stats.factorBytes = largest.factorBytes;
  stats.factorPeakBytes = largest.factorPeakBytes;
}

void collectChangedSeams(const std::vector<Complex>& currentT, const std::vector<Complex>& seamT, RefineResult& out) {
  for (std::uint32_t j = 0; j < currentT.size(); ++j) {
    if (currentT[j] == seamT[j]) continue;
    out.seams.push_back(j);
    out.seamT.push_back(currentT[j]);
  }
}

}  // namespace detail

namespace {

/// Every corner of a free vertex is in a refinement (all its faces were solved), with one value
/// per wedge (the region's cut keeps every seam around a free vertex): each wedge changes whole
/// and keeps its id, so the values go in place, without WedgeMap::assign's pass over the whole
/// map. Should two corners of a wedge disagree, assign splits it.
void applyRefinedCorners(const std::vector<RefinedCorner>& refined, WedgeMap& cornerUV) {
  for (const RefinedCorner& r : refined) {
    if (r.corner >= cornerUV.size()) {
      throw InputError("refine: corner " + std::to_string(r.corner) + " out of range (" +
                       std::to_string(cornerUV.size()) + " corners)");
    }
    cornerUV.setWedgeValue(cornerUV.wedge(r.corner), r.uv);
  }
  for (const RefinedCorner& r : refined) {
    if (cornerUV[r.corner] == r.uv) continue;
    std::vector<CornerId> corners;
    std::vector<Vec2d> values;
    for (const RefinedCorner& x : refined) corners.push_back(x.corner), values.push_back(x.uv);
    cornerUV.assign(corners, values);
    return;
  }
}

/// The whole mesh and its map in memory as detail::refineRounds reads them: the reads both
/// in-memory sources share.
class MeshReads {
 public:
  MeshReads(const TriangleMesh& mesh, const Topology& topology, const CrossField& field, const CutResult& cut,
            const WedgeMap& cornerUV)
      : mesh_(mesh), topology_(topology), field_(field), cut_(cut), cornerUV_(cornerUV) {}
  /// What one thread of a round reads: here the source itself.
  struct Readers {
    const MeshReads* source;
    Readers* operator->() { return this; }
    Readers& operator*() { return *this; }
    RegionMesh extract(const std::vector<FaceId>& faces) const {
      return extractRegionOnFieldSurface(source->mesh_, source->topology_, source->field_, source->cut_, faces);
    }
    Vec2d value(CornerId c) const { return source->cornerUV_[c]; }
  };
  Readers groupReaders() const { return {this}; }
  const Topology& table() const { return topology_; }
  std::uint32_t numVertices() const { return mesh_.numVertices(); }
  const Triangle& triangle(FaceId f) const { return mesh_.triangles[f]; }
  std::array<Vec3d, 3> points(FaceId f) const {
    const Triangle& t = mesh_.triangles[f];
    return {mesh_.position(t[0]), mesh_.position(t[1]), mesh_.position(t[2])};
  }
  Vec2d value(CornerId c) const { return cornerUV_[c]; }

  detail::FaceCounts countOutside(const std::vector<FaceId>& touched, const std::vector<VertexId>& cones,
                                  double h) const {
    return tbb::parallel_reduce(
        tbb::blocked_range<FaceId>(0, mesh_.numFaces(), 1u << 14), detail::FaceCounts(),
        [&](const tbb::blocked_range<FaceId>& range, detail::FaceCounts counts) {
          auto next = std::lower_bound(touched.begin(), touched.end(), range.begin());
          for (FaceId f = range.begin(); f != range.end(); ++f) {
            if (next != touched.end() && *next == f) {
              ++next;
              continue;
            }
            const std::array<Vec2d, 3> q{cornerUV_[3 * f], cornerUV_[3 * f + 1], cornerUV_[3 * f + 2]};
            counts.add(parameterAreaRatio(points(f), q, h),
                       [&] { return detail::collapsesBetweenListedCones(mesh_.triangles[f], q, cones); });
          }
          return counts;
        },
        [](detail::FaceCounts a, const detail::FaceCounts& b) { return a += b; });
  }

 protected:
  const TriangleMesh& mesh_;
  const Topology& topology_;
  const CrossField& field_;
  const CutResult& cut_;
  const WedgeMap& cornerUV_;
};

/// The input map kept as it is: the solved corners held whole and sorted by corner, one batch
/// per round, returned in the result.
class MeshSource : public MeshReads {
 public:
  using MeshReads::MeshReads;
  Vec2d latest(const Readers&, CornerId c) const {
    return detail::solvedOr(current_, c, [this](CornerId x) { return cornerUV_[x]; });
  }
  std::size_t batchCorners() const { return std::numeric_limits<std::size_t>::max(); }
  void record(std::vector<detail::SolvedCorner> fresh) { detail::mergeSolved(std::move(fresh), current_); }
  detail::FaceCounts countTouched(const std::vector<FaceId>& touched, const std::vector<VertexId>& cones,
                                  double h) const {
    return detail::countSolvedFaces(*this, touched, current_, cones, h);
  }
  void collect(const std::vector<FaceId>& touched, RefineResult& out) {
    detail::collectRefinement(topology_, mesh_.numVertices(), std::move(current_), touched, out);
  }

 private:
  std::vector<detail::SolvedCorner> current_;
};

/// One byte per vertex in memory, as VertexTally reads it.
struct VertexFlags {
  std::vector<std::uint8_t> bytes;
  std::uint8_t get(VertexId v) const { return bytes[v]; }
  void set(VertexId v, std::uint8_t flag) { bytes[v] = flag; }
};

/// The map written in place a batch at a time (refineNearConesInPlace): later batches and rounds
/// read it, and one flag byte per vertex counts the freed and the locked vertices.
class InPlaceSource : public MeshReads {
 public:
  InPlaceSource(const TriangleMesh& mesh, const Topology& topology, const CrossField& field, const CutResult& cut,
                WedgeMap& cornerUV, std::size_t batchCorners)
      : MeshReads(mesh, topology, field, cut, cornerUV), map_(cornerUV), batch_(batchCorners),
        flags_{std::vector<std::uint8_t>(mesh.numVertices(), 0)}, tally_(flags_) {}
  InPlaceSource(const InPlaceSource&) = delete;  // the tally refers to flags_
  Vec2d latest(const Readers&, CornerId c) const { return cornerUV_[c]; }
  std::size_t batchCorners() const { return batch_; }
  void record(std::vector<detail::SolvedCorner> fresh) {
    fresh.erase(std::remove_if(fresh.begin(), fresh.end(), [](const detail::SolvedCorner& s) { return !s.free; }),
                fresh.end());
    tally_.addFreed(topology_, fresh);
    applyRefinedCorners(fresh, map_);
  }
  detail::FaceCounts countTouched(const std::vector<FaceId>& touched, const std::vector<VertexId>& cones,
                                  double h) const {
    return detail::countFaces(*this, touched, cones, h, [this](CornerId c) { return cornerUV_[c]; });
  }
  void collect(const std::vector<FaceId>& touched, RefineResult& out) {
    tally_.collect(topology_, touched, mesh_.numVertices(), out);
  }

 private:
  WedgeMap& map_;
  std::size_t batch_;
  VertexFlags flags_;
  detail::VertexTally<VertexFlags> tally_;
};

}  // namespace

std::vector<VertexId> listedCones(const std::vector<VertexId>& cones, std::uint64_t numVertices) {
  std::vector<VertexId> out = cones;
  for (VertexId v : out) {
    if (v >= numVertices) {
      throw InputError("refine: cone " + std::to_string(v) + " out of range (" + std::to_string(numVertices) +
                       " vertices)");
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

/// refineNearCones' steps around the rounds, with the source makeSource(cornerUV) gives.
template <class MakeSource>
RefineResult refineWith(const TriangleMesh& mesh, const Topology& topology, const CutResult& cut,
                        const WedgeMap& cornerUV, const std::vector<Complex>& seamT, const RefineOptions& options,
                        MakeSource&& makeSource) {
  const auto start = std::chrono::steady_clock::now();
  if (seamT.size() != cut.seams.size()) {
    throw InputError("refine: " + std::to_string(seamT.size()) + " translations for " +
                     std::to_string(cut.seams.size()) + " seams");
  }
  RefineResult out;
  std::vector<FaceId> faces = selectRefineRegion(mesh, topology, cornerUV, options, &out.stats);
  out.stats.secondsRegion = secondsSince(start);
  const std::vector<VertexId> cones = listedCones(cut.cones, mesh.numVertices());
  {
    auto source = makeSource();
    detail::refineRounds(source, cones, seamT, options, std::move(faces), out);
  }
  reportProgress(options.progress, "refine", 1.0);
  out.stats.secondsTotal = secondsSince(start);
  return out;
}

}  // namespace

RefineResult refineNearCones(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const WedgeMap& cornerUV, const std::vector<Complex>& seamT,
                             const RefineOptions& options) {
  return refineWith(mesh, topology, cut, cornerUV, seamT, options,
                    [&] { return MeshSource(mesh, topology, field, cut, cornerUV); });
}

RefineResult refineNearConesInPlace(const TriangleMesh& mesh, const Topology& topology,
                                    const CrossField& field, const CutResult& cut, WedgeMap& cornerUV,
                                    std::vector<Complex>& seamT, const RefineOptions& options,
                                    std::size_t batchCorners) {
  RefineResult out = refineWith(mesh, topology, cut, cornerUV, seamT, options, [&] {
    return InPlaceSource(mesh, topology, field, cut, cornerUV, std::max<std::size_t>(1, batchCorners));
  });
  for (std::size_t k = 0; k < out.seams.size(); ++k) seamT[out.seams[k]] = out.seamT[k];
  return out;
}

void applyRefinement(const RefineResult& refinement, WedgeMap& cornerUV,
                     std::vector<Complex>* translations) {
  if (translations) {
    for (std::size_t k = 0; k < refinement.seams.size(); ++k) {
      if (refinement.seams[k] >= translations->size()) {
        throw InputError("refine: seam " + std::to_string(refinement.seams[k]) +
                         " out of range (" + std::to_string(translations->size()) + " seams)");
      }
      (*translations)[refinement.seams[k]] = refinement.seamT[k];
    }
  }
  applyRefinedCorners(refinement.corners, cornerUV);
}

}  // namespace seamvox
