#include "core/refine.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "core/basis.h"
#include "core/errors.h"
#include "core/evaluate.h"
#include "core/gaussian_int.h"
#include "core/reduce.h"
#include "core/round.h"

namespace seamvox {

namespace {

using Complex = std::complex<double>;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Why a face is in the region (before the rings are added).
enum FaceFlag : std::uint8_t { kOutside = 0, kMarked = 1, kCollapsed = 2, kFlipped = 3 };

// Signed parameter-space area of face f against its expected area A_T / h^2: kCollapsed below
// threshold times the expected area (non-finite values included), kFlipped when negative.
FaceFlag classifyFace(const TriangleMesh& mesh, const std::vector<Vec2d>& uv, FaceId f,
                      double threshold, double inverseH2) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d p0 = mesh.position(t[0]);
  const double expected = 0.5 * (mesh.position(t[1]) - p0).cross(mesh.position(t[2]) - p0).norm() *
                          inverseH2;
  if (!(expected > 0.0)) return kOutside;  // zero-area face: no energy, nothing to repair
  const Vec2d a = uv[3 * f + 1] - uv[3 * f], b = uv[3 * f + 2] - uv[3 * f];
  const double area = 0.5 * (a.x() * b.y() - a.y() * b.x());
  if (area >= threshold * expected) return kOutside;
  return area < 0.0 ? kFlipped : kCollapsed;
}

bool isSortedUnique(const std::vector<FaceId>& faces) {
  for (std::size_t i = 1; i < faces.size(); ++i) {
    if (faces[i] <= faces[i - 1]) return false;
  }
  return true;
}

}  // namespace

std::vector<FaceId> selectRefineRegion(const TriangleMesh& mesh, const Topology& topology,
                                       const std::vector<Vec2d>& cornerUV,
                                       const RefineOptions& options, RefineStats* stats) {
  const FaceId nf = topology.numFaces();
  if (cornerUV.size() != 3u * static_cast<std::size_t>(nf) || mesh.numFaces() != nf) {
    throw InputError("refine: " + std::to_string(cornerUV.size()) + " corner UVs for " +
                     std::to_string(nf) + " faces (need 3 per face)");
  }
  if (!(options.edgeLength > 0.0) || !std::isfinite(options.edgeLength)) {
    throw InputError("refine: edge length must be positive and finite");
  }
  std::vector<std::uint8_t> flag(nf, kOutside);
  for (FaceId f : options.markedFaces) {
    if (f >= nf) {
      throw InputError("refine: marked face " + std::to_string(f) + " out of range (" +
                       std::to_string(nf) + " faces)");
    }
    flag[f] = kMarked;
  }
  const double inverseH2 = 1.0 / (options.edgeLength * options.edgeLength);
  tbb::parallel_for(tbb::blocked_range<FaceId>(0, nf, 1u << 14), [&](const auto& range) {
    for (FaceId f = range.begin(); f != range.end(); ++f) {
      if (flag[f] != kOutside) continue;
      flag[f] = classifyFace(mesh, cornerUV, f, options.collapseThreshold, inverseH2);
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

  // Rings: every face sharing a vertex with the region joins it, options.rings times.
  std::vector<std::uint8_t> vertexSeen(topology.numVertices(), 0);
  std::vector<FaceId> frontier = region;
  for (std::uint32_t ring = 0; ring < options.rings && !frontier.empty(); ++ring) {
    std::vector<FaceId> added;
    for (FaceId f : frontier) {
      for (int k = 0; k < 3; ++k) {
        const VertexId v = topology.vertex(3 * f + k);
        if (vertexSeen[v]) continue;
        vertexSeen[v] = 1;
        topology.forEachCornerAround(v, [&](CornerId c) {
          const FaceId g = cornerFace(c);
          if (flag[g] == kOutside) {
            flag[g] = kMarked;  // any value but kOutside
            added.push_back(g);
          }
        });
      }
    }
    region.insert(region.end(), added.begin(), added.end());
    frontier = std::move(added);
  }
  std::sort(region.begin(), region.end());
  counts.regionFaces = region.size();
  if (stats) {
    stats->markedFaces = counts.markedFaces;
    stats->collapsedFaces = counts.collapsedFaces;
    stats->flippedFaces = counts.flippedFaces;
    stats->regionFaces = counts.regionFaces;
  }
  reportProgress(options.progress, "refine region", 1.0);
  return region;
}

RegionMesh extractRegion(const TriangleMesh& mesh, const Topology& topology,
                         const CrossField& field, const CutResult& cut,
                         const std::vector<FaceId>& regionFaces) {
  const FaceId nf = topology.numFaces();
  if (field.direction.size() != nf || cut.isCut.size() != 3u * nf ||
      cut.faceRotation.size() != nf || cut.cornerSeam.size() != 3u * nf ||
      cut.combedMatching.size() != 3u * nf || mesh.numFaces() != nf) {
    throw InputError("refine: field or cut sizes do not match the mesh (" + std::to_string(nf) +
                     " faces)");
  }
  if (!isSortedUnique(regionFaces) || (!regionFaces.empty() && regionFaces.back() >= nf)) {
    throw InputError("refine: region faces must be increasing face ids below " +
                     std::to_string(nf));
  }
  RegionMesh out;
  out.faceOrigin = regionFaces;
  const std::uint32_t rf = static_cast<std::uint32_t>(regionFaces.size());
  auto subFace = [&](FaceId f) -> std::uint32_t {
    const auto it = std::lower_bound(regionFaces.begin(), regionFaces.end(), f);
    return it != regionFaces.end() && *it == f ? static_cast<std::uint32_t>(it - regionFaces.begin())
                                               : kInvalidId;
  };
  auto subCorner = [&](CornerId c) -> CornerId {
    if (c == kInvalidId) return kInvalidId;
    const std::uint32_t i = subFace(cornerFace(c));
    return i == kInvalidId ? kInvalidId : 3 * i + c % 3;
  };

  // Sub vertices: one per fan piece of region corners around each whole-mesh vertex.
  std::vector<VertexId> cornerVertex(3u * rf, kInvalidId);
  std::vector<CornerId> vertexCorner;
  for (CornerId sc = 0; sc < 3u * rf; ++sc) {
    if (cornerVertex[sc] != kInvalidId) continue;
    const CornerId start = 3 * regionFaces[sc / 3] + sc % 3;
    // Most clockwise corner of the piece; a piece reaching a face outside the region is locked.
    CornerId first = start;
    bool free = true;
    for (;;) {
      const CornerId before = topology.cw(first);
      if (before == kInvalidId) break;
      if (before == start) break;  // closed fan, all in the region
      if (subFace(cornerFace(before)) == kInvalidId) {
        free = false;
        break;
      }
      first = before;
    }
    const VertexId id = static_cast<VertexId>(out.vertexOrigin.size());
    CornerId c = first;
    for (;;) {
      const CornerId sc2 = subCorner(c);  // in the region by construction
      if (sc2 == kInvalidId) break;
      cornerVertex[sc2] = id;
      const CornerId after = topology.ccw(c);
      if (after == kInvalidId || after == first) break;
      if (subFace(cornerFace(after)) == kInvalidId) {
        free = false;
        break;
      }
      c = after;
    }
    out.vertexOrigin.push_back(topology.vertex(start));
    out.vertexFree.push_back(free ? 1 : 0);
    vertexCorner.push_back(subCorner(first));
  }

  const std::uint32_t nv = static_cast<std::uint32_t>(out.vertexOrigin.size());
  TriangleMesh& sub = out.mesh;
  sub.positions.resize(nv);
  for (VertexId v = 0; v < nv; ++v) sub.positions[v] = mesh.positions[out.vertexOrigin[v]];
  sub.triangles.resize(rf);
  std::vector<CornerId> opposite(3u * rf);
  out.field.direction.resize(rf);
  CutResult& subCut = out.cut;
  subCut.isCut.resize(3u * rf);
  subCut.faceRotation.resize(rf);
  subCut.combedMatching.resize(3u * rf);
  subCut.cornerSeam.assign(3u * rf, kInvalidId);
  for (std::uint32_t i = 0; i < rf; ++i) {
    const FaceId f = regionFaces[i];
    out.field.direction[i] = field.direction[f];
    subCut.faceRotation[i] = cut.faceRotation[f];
    for (int k = 0; k < 3; ++k) {
      const CornerId c = 3 * f + k, sc = 3 * i + k;
      sub.triangles[i][k] = cornerVertex[sc];
      opposite[sc] = subCorner(topology.opposite(c));
      subCut.isCut[sc] = cut.isCut[c] || opposite[sc] == kInvalidId ? 1 : 0;
      subCut.combedMatching[sc] = cut.combedMatching[c];
    }
  }
  // Seams: the edges with both faces in the region, in curve order, under local ids.
  for (std::uint32_t s = 0; s < cut.seams.size(); ++s) {
    SeamCurve local;
    local.matching = cut.seams[s].matching;
    for (CornerId c : cut.seams[s].corners) {
      const CornerId sc = subCorner(c), so = subCorner(topology.opposite(c));
      if (sc == kInvalidId || so == kInvalidId) continue;
      local.corners.push_back(sc);
    }
    if (local.corners.empty()) continue;
    const std::uint32_t id = static_cast<std::uint32_t>(subCut.seams.size());
    for (CornerId sc : local.corners) subCut.cornerSeam[sc] = subCut.cornerSeam[opposite[sc]] = id;
    local.start = sub.triangles[local.corners.front() / 3][nextCorner(local.corners.front()) % 3];
    local.end = sub.triangles[local.corners.back() / 3][prevCorner(local.corners.back()) % 3];
    subCut.seams.push_back(std::move(local));
    out.seamOrigin.push_back(s);
  }
  for (VertexId v = 0; v < nv; ++v) {
    if (std::binary_search(cut.cones.begin(), cut.cones.end(), out.vertexOrigin[v])) {
      subCut.cones.push_back(v);
    }
  }
  out.topology = Topology::fromParts(sub.triangles, std::move(opposite), std::move(vertexCorner));
  return out;
}

RegionSolution solveRegion(const RegionMesh& region, const std::vector<Vec2d>& cornerUV,
                           const std::vector<Complex>& seamT, double edgeLength,
                           RefineStats* stats) {
  const std::uint32_t rf = region.topology.numFaces();
  const std::uint32_t ns = static_cast<std::uint32_t>(region.cut.seams.size());
  if (cornerUV.size() != 3u * static_cast<std::size_t>(rf) || seamT.size() != ns) {
    throw InputError("refine: region has " + std::to_string(rf) + " faces and " +
                     std::to_string(ns) + " seams but got " + std::to_string(cornerUV.size()) +
                     " corner UVs and " + std::to_string(seamT.size()) + " translations");
  }
  HatBasisOptions basisOptions;
  basisOptions.edgeLength = edgeLength;
  const HatBasis basis(region.mesh, region.topology, region.field, region.cut, basisOptions);
  // No translation constraints: then column np + j of P is t_j itself (t = s).
  const std::vector<GaussVector> noConstraints;
  ReduceOptions reduceOptions;
  reduceOptions.translationConstraints = &noConstraints;
  const Reduction reduction = reduceBasis(basis, reduceOptions);
  const ReducedMap& P = reduction.map;
  const std::uint32_t nd = basis.numDomains();
  const std::uint32_t np = reduction.numPositional;
  const auto& cornerDomain = basis.cornerDomain();
  auto isLockedVertex = [&](VertexId v) { return !region.vertexFree[v]; };
  auto isLocked = [&](std::uint32_t d) {
    return isLockedVertex(basis.basisVertex()[basis.domainBasis()[d]]);
  };
  std::vector<CornerId> domainCorner(nd, kInvalidId);
  for (CornerId c = 0; c < 3u * rf; ++c) {
    if (domainCorner[cornerDomain[c]] == kInvalidId) domainCorner[cornerDomain[c]] = c;
  }
  auto input = [&](std::uint32_t d) {
    const Vec2d& q = cornerUV[domainCorner[d]];
    return Complex(q.x(), q.y());
  };

  // Translations: a seam touching a locked vertex keeps the input's t (the locked values on its
  // two sides obey it). The other seams lie among free vertices only (e.g. between a cone and a
  // seam node): the input map says little about their t (the Vox solve barely sees them), so
  // t = seamT + U s is solved, rounded and solved again, where U spans the Gaussian-integer
  // solutions of the cycle constraints restricted to these seams (seamT obeys the constraints,
  // so every t of this form does too).
  std::vector<std::uint8_t> freeSeam(ns, 1);
  for (std::uint32_t j = 0; j < ns; ++j) {
    for (CornerId c : region.cut.seams[j].corners) {
      const Triangle& t = region.mesh.triangles[c / 3];
      if (isLockedVertex(t[(c + 1) % 3]) || isLockedVertex(t[(c + 2) % 3])) freeSeam[j] = 0;
    }
  }
  LatticeEliminator lattice(ns);
  for (const GaussVector& row : reduction.cycleConstraints) {
    GaussVector restricted;
    for (const auto& entry : row) {
      if (freeSeam[entry.first]) restricted.push_back(entry);
    }
    if (!restricted.empty()) lattice.addConstraint(restricted);
  }
  lattice.finish();
  std::vector<std::uint32_t> sIndex(lattice.numFree(), kInvalidId);
  std::uint32_t numS = 0;
  for (std::uint32_t j = 0; j < ns; ++j) {
    if (!freeSeam[j]) continue;
    for (const auto& [k, u] : lattice.row(j)) {
      if (sIndex[k] == kInvalidId) sIndex[k] = numS++;
    }
  }

  // Fixed part of every domain's coefficient: the translations seamT.
  std::vector<Complex> fixedPart(nd, 0.0);
  for (std::uint32_t d = 0; d < nd; ++d) {
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (j >= np) fixedPart[d] += P.value[k] * seamT[j - np];
    }
  }

  // Kernel: a region component without a locked vertex and without a fixed seam of rotation
  // r != 1 can shift freely; pin one positional unknown there to its input value (kept in both
  // solves: such a component is the whole surface component, not a repair).
  const ComponentsResult components = computeComponents(region.topology);
  std::vector<std::uint8_t> anchored(components.components.size(), 0);
  for (CornerId c = 0; c < 3u * rf; ++c) {
    if (isLocked(cornerDomain[c])) anchored[components.faceComponent[c / 3]] = 1;
  }
  for (std::uint32_t j = 0; j < ns; ++j) {
    const SeamCurve& seam = region.cut.seams[j];
    if (seam.matching % 4 != 0 && !freeSeam[j]) {
      anchored[components.faceComponent[seam.corners.front() / 3]] = 1;
    }
  }
  std::vector<std::uint8_t> pinned(np, 0);
  std::vector<Complex> pinValue(np, 0.0);
  RefineStats local;
  for (CornerId c = 0; c < 3u * rf; ++c) {
    const std::uint32_t comp = components.faceComponent[c / 3];
    const std::uint32_t d = cornerDomain[c];
    if (anchored[comp]) continue;
    // A domain whose row is value c_0 + fixed translations only.
    std::uint32_t column = kInvalidId;
    Complex value;
    bool onlyFixed = true;
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      if (P.column[k] < np) {
        column = P.column[k];
        value = P.value[k];
      } else if (freeSeam[P.column[k] - np]) {
        onlyFixed = false;
      }
    }
    if (column == kInvalidId || !onlyFixed) continue;
    pinned[column] = 1;
    pinValue[column] = (input(d) - fixedPart[d]) / value;
    anchored[comp] = 1;
    ++local.pinned;
  }

  // The local map: free domains keep their positional column (compacted) and the free
  // translations (through U); fixed translations, pins and locked wedges go to the offset.
  std::vector<std::uint32_t> newIndex(np, kInvalidId);
  Reduction system;
  std::uint32_t numPositional = 0;
  for (std::uint32_t d = 0; d < nd; ++d) {
    if (isLocked(d)) continue;
    for (std::uint64_t k = P.rowStart[d]; k < P.rowStart[d + 1]; ++k) {
      const std::uint32_t j = P.column[k];
      if (j < np && !pinned[j] && newIndex[j] == kInvalidId) newIndex[j] = numPositional++;
    }
  }
  system.numPositional = numPositional;
  system.numTranslational = numS;
  ReducedMap& Q = system.map;
  Q.rowStart.assign(nd + 1, 0);
  Q.offset.resize(nd);
  std::vector<std::pair<std::uint32_t, Complex>> row;
  for (std::uint32_t d = 0; d < nd; ++d) {
    row.clear();
    if (isLocked(d)) {
      Q.offset[d] = input(d);
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
  // No component bookkeeping: solveSeamless then pins nothing (the pins above are offsets).
  system.unknownComponent.assign(system.numUnknowns(), kInvalidId);
  local.unknowns = system.numUnknowns();
  local.freeTranslations = numS;

  RegionSolution out;
  std::vector<Complex> x;
  if (system.numUnknowns() > 0) {
    const SeamlessSolution solution = solveSeamless(basis, system);
    x = solution.unknowns;
    local.systemNonzeros = solution.stats.systemNonzeros;
    local.factorNonzeros = solution.stats.factorNonzeros;
    local.factorBytes = solution.stats.factorBytes;
    local.factorPeakBytes = solution.stats.factorPeakBytes;
  }
  out.seamT = seamT;
  if (numS > 0) {
    const std::vector<Complex> s(x.begin() + numPositional, x.end());
    const std::vector<Complex> t = seamTranslations(system, s);
    for (std::uint32_t j = 0; j < ns; ++j) out.seamT[j] += t[j];
  }
  out.cornerUV.assign(3u * rf, Vec2d::Zero());
  evaluateMap(basis, system, x, out.cornerUV);
  for (CornerId c = 0; c < 3u * rf; ++c) {
    if (isLocked(cornerDomain[c])) out.cornerUV[c] = cornerUV[c];  // exactly the input
  }
  if (stats) {
    stats->unknowns = local.unknowns;
    stats->freeTranslations = local.freeTranslations;
    stats->pinned = local.pinned;
    stats->systemNonzeros = local.systemNonzeros;
    stats->factorNonzeros = local.factorNonzeros;
    stats->factorBytes = local.factorBytes;
    stats->factorPeakBytes = local.factorPeakBytes;
  }
  return out;
}

RefineResult refineNearCones(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const std::vector<Vec2d>& cornerUV, const std::vector<Complex>& seamT,
                             const RefineOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (seamT.size() != cut.seams.size()) {
    throw InputError("refine: " + std::to_string(seamT.size()) + " translations for " +
                     std::to_string(cut.seams.size()) + " seams");
  }
  RefineResult out;
  RefineStats& stats = out.stats;
  auto lap = std::chrono::steady_clock::now();
  const std::vector<FaceId> faces = selectRefineRegion(mesh, topology, cornerUV, options, &stats);
  stats.secondsRegion = secondsSince(lap);
  if (faces.empty()) {
    stats.secondsTotal = secondsSince(start);
    return out;
  }

  lap = std::chrono::steady_clock::now();
  const RegionMesh region = extractRegion(mesh, topology, field, cut, faces);
  const std::uint32_t rf = region.topology.numFaces();
  std::vector<Vec2d> regionUV(3u * rf);
  for (std::uint32_t i = 0; i < rf; ++i) {
    for (int k = 0; k < 3; ++k) regionUV[3 * i + k] = cornerUV[3 * region.faceOrigin[i] + k];
  }
  std::vector<Complex> regionT(region.seamOrigin.size());
  for (std::size_t s = 0; s < regionT.size(); ++s) regionT[s] = seamT[region.seamOrigin[s]];
  for (std::uint8_t free : region.vertexFree) {
    if (free) {
      ++stats.freeVertices;
    } else {
      ++stats.lockedVertices;
    }
  }
  stats.refinedVertexFraction =
      mesh.numVertices() ? double(stats.freeVertices) / mesh.numVertices() : 0.0;
  stats.secondsExtract = secondsSince(lap);
  reportProgress(options.progress, "refine", 0.3);
  if (stats.freeVertices == 0) {
    stats.secondsTotal = secondsSince(start);
    return out;
  }

  lap = std::chrono::steady_clock::now();
  const RegionSolution solved = solveRegion(region, regionUV, regionT, options.edgeLength, &stats);
  stats.secondsSolve = secondsSince(lap);
  for (CornerId c = 0; c < 3u * rf; ++c) {
    if (!region.vertexFree[region.mesh.triangles[c / 3][c % 3]]) continue;
    out.corners.push_back(3 * region.faceOrigin[c / 3] + c % 3);
    out.cornerUV.push_back(solved.cornerUV[c]);
  }
  for (std::uint32_t j = 0; j < regionT.size(); ++j) {
    if (solved.seamT[j] == regionT[j]) continue;
    out.seams.push_back(region.seamOrigin[j]);
    out.seamT.push_back(solved.seamT[j]);
  }
  reportProgress(options.progress, "refine", 1.0);
  stats.secondsTotal = secondsSince(start);
  return out;
}

void applyRefinement(const RefineResult& refinement, std::vector<Vec2d>& cornerUV,
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
  for (std::size_t k = 0; k < refinement.corners.size(); ++k) {
    if (refinement.corners[k] >= cornerUV.size()) {
      throw InputError("refine: corner " + std::to_string(refinement.corners[k]) +
                       " out of range (" + std::to_string(cornerUV.size()) + " corners)");
    }
    cornerUV[refinement.corners[k]] = refinement.cornerUV[k];
  }
}

}  // namespace seamvox
