#include "stream/untangle_stream.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "core/quality/metrics.h"
#include "core/refine/detail_refine.h"
#include "core/refine/detail_region.h"
#include "core/system/errors.h"
#include "core/system/stopwatch.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"
#include "stream/refine_stream.h"

namespace seamvox {

namespace {

/// The faces the map flips (collapsed ones apart, as untangleFlips counts them) and the mean
/// length of their edges, by one pass over the faces and their corners' wedges.
std::vector<FaceId> flippedFaces(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map, double h,
                                 std::size_t cacheBytes, const FacesNearPoints* only, double& meanEdge) {
  ScratchMapFaces faces(folder, scratch, map, "untangle", cacheBytes);
  std::vector<FaceId> flipped;
  double edges = 0.0;
  faces.forEach([&](const MapFace& x) { return isFlippedRatio(parameterAreaRatio(x.p, x.q, h)) && (!only || only->holds(x.p)); },
                [&](const MapFace& x, bool isFlipped) {
                  if (!isFlipped) return;
                  flipped.push_back(x.f);
                  for (int k = 0; k < 3; ++k) edges += (x.p[(k + 1) % 3] - x.p[k]).norm();
                });
  meanEdge = flipped.empty() ? 0.0 : edges / (3.0 * flipped.size());
  folder.countRead("untangle", faces.cacheBytesRead());
  return flipped;
}

/// The same of the candidate faces only (increasing), read through small pages.
std::vector<FaceId> flippedAmong(ScratchFolder& folder, const CleanScratch& scratch, const ScratchMap& map, double h,
                                 std::size_t cacheBytes, const std::vector<FaceId>& candidates, double& meanEdge) {
  PagedFacePoints points(scratch, scratch.positions, cacheBytes, kWindowPageBytes);
  PagedReader<std::uint32_t> cornerWedge(map.cornerWedge, cacheBytes, kWindowPageBytes);
  PagedReader<Vec2d> wedgeValues(map.wedgeValues, cacheBytes, kWindowPageBytes);
  std::vector<FaceId> flipped;
  double edges = 0.0;
  for (FaceId f : candidates) {
    const std::array<Vec3d, 3> p = points.points(f);
    const std::array<Vec2d, 3> q = {wedgeValues[cornerWedge[3 * f]], wedgeValues[cornerWedge[3 * f + 1]],
                                    wedgeValues[cornerWedge[3 * f + 2]]};
    if (!isFlippedRatio(parameterAreaRatio(p, q, h))) continue;
    flipped.push_back(f);
    for (int k = 0; k < 3; ++k) edges += (p[(k + 1) % 3] - p[k]).norm();
  }
  meanEdge = flipped.empty() ? 0.0 : edges / (3.0 * flipped.size());
  folder.countRead("untangle", points.bytesRead() + cornerWedge.bytesRead() + wedgeValues.bytesRead());
  return flipped;
}

/// The window as untangleFlips sees the whole mesh: sub vertices in the order of their mesh ids
/// (the repair's Gauss-Seidel passes and joint patches go in vertex order) and every free
/// vertex's fan starting at the mesh's own start corner (the order its fan is summed in).
void alignWindowWithMesh(RegionMesh& w, PagedCornerTable& table) {
  const std::uint32_t nv = static_cast<std::uint32_t>(w.vertexOrigin.size());
  std::vector<VertexId> order(nv);
  for (VertexId v = 0; v < nv; ++v) order[v] = v;
  std::stable_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) { return w.vertexOrigin[a] < w.vertexOrigin[b]; });
  std::vector<VertexId> renamed(nv);
  for (VertexId v = 0; v < nv; ++v) renamed[order[v]] = v;
  const detail::RegionIndex index{w.faceOrigin};
  std::vector<Vec3f> positions(nv);
  std::vector<VertexId> origin(nv);
  std::vector<std::uint8_t> free(nv);
  std::vector<CornerId> vertexCorner(nv);
  for (VertexId v = 0; v < nv; ++v) {
    const VertexId old = order[v];
    positions[v] = w.mesh.positions[old];
    origin[v] = w.vertexOrigin[old];
    free[v] = w.vertexFree[old];
    vertexCorner[v] = w.topology.vertexCorner(old);
    if (free[v]) {  // its whole fan is in the window: start where the mesh starts it
      const CornerId own = index.subCorner(table.vertexCorner(origin[v]));
      if (own != kInvalidId) vertexCorner[v] = own;
    }
  }
  std::vector<CornerId> opposite(w.topology.numCorners());
  for (CornerId c = 0; c < opposite.size(); ++c) opposite[c] = w.topology.opposite(c);
  for (Triangle& t : w.mesh.triangles) {
    for (VertexId& v : t) v = renamed[v];
  }
  for (VertexId& c : w.cut.cones) c = renamed[c];
  std::sort(w.cut.cones.begin(), w.cut.cones.end());
  for (SeamCurve& seam : w.cut.seams) {
    if (seam.start != kInvalidId) seam.start = renamed[seam.start];
    if (seam.end != kInvalidId) seam.end = renamed[seam.end];
  }
  w.mesh.positions = std::move(positions);
  w.vertexOrigin = std::move(origin);
  w.vertexFree = std::move(free);
  w.topology = Topology::fromParts(w.mesh.triangles, std::move(opposite), std::move(vertexCorner));
}

}  // namespace

ScratchUntangleStats untangleScratchFlips(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                          const ScratchCut& cut, ScratchMap& map,
                                          std::vector<std::complex<double>>& seamT, const UntangleOptions& options,
                                          const StreamPassOptions& pass, const FacesNearPoints* only,
                                          const std::vector<FaceId>* candidates) {
  const double h = options.edgeLength;
  if (!(h > 0.0) || !std::isfinite(h) || options.onlyFaces || options.pinnedVertices || options.candidateFaces ||
      (only && candidates)) {
    throw InputError("untangle: the out-of-core repair needs a positive edge length and no face or vertex flags");
  }
  if (seamT.size() != cut.seams.size()) {
    throw InputError("untangle: " + std::to_string(seamT.size()) + " translations for " +
                     std::to_string(cut.seams.size()) + " seams");
  }
  const std::size_t cacheBytes = pageCacheBytes(pass.memoryBytes);
  ScratchUntangleStats out;
  double meanEdge = 0.0;
  const std::vector<FaceId> flipped =
      candidates ? flippedAmong(folder, scratch, map, h, windowCacheBytes(pass.memoryBytes), *candidates, meanEdge)
                 : flippedFaces(folder, scratch, map, h, cacheBytes, only, meanEdge);
  if (flipped.empty()) return out;

  // The window: the rings of every patch round (as untangleFlips sizes them: a round's seeds lie
  // in the patches before it) and of the joint step, halved while the window is too large.
  std::uint32_t rings = (options.jointRings >= 2 ? options.jointRings : 0) + 1;
  const auto ringsFor = [&](double radius) {
    return static_cast<std::uint32_t>(std::clamp(meanEdge > 0.0 ? std::ceil(radius * h / meanEdge) : 2.0, 2.0, 64.0));
  };
  for (std::uint32_t round = 0; round < std::min(options.maxRounds, 8u); ++round) {
    rings += ringsFor(options.patchRadius * double(1u << round));
  }
  // The cones' own re-solves: a cone within coneRepairRadius of a flip, its patch grown twice
  // from it (the second time from the flips the first reached).
  if (options.coneRepairRadius > 0.0) rings += ringsFor(options.coneRepairRadius) + 2 * ringsFor(4.0 * options.coneRepairRadius);
  // The flips lie far apart over the mesh: the window's walks read small pages, and a growth
  // stops as soon as it passes the cap (that many rings would be halved anyway).
  const std::uint64_t cap = std::max<std::uint64_t>(8 * options.minPatchFaces, pass.memoryBytes >> 10);
  const std::size_t windowBytes = windowCacheBytes(pass.memoryBytes);
  std::vector<FaceId> window;
  RegionMesh w;
  std::uint64_t bytesRead = 0;
  {
    PagedCornerTable table(scratch, windowBytes, kWindowPageBytes);
    const auto grow = [&] {
      return detail::growFacesIn(table, flipped, rings, rings > 2 ? cap : std::numeric_limits<std::size_t>::max());
    };
    window = grow();
    while (window.size() > cap && rings > 2) {
      rings = std::max(2u, rings / 2);
      window = grow();
    }
    out.windowFaces = window.size();
    out.windowRings = rings;
    w = extractScratchRegion(scratch, field, cut, window, pass, &bytesRead);
    alignWindowWithMesh(w, table);
    bytesRead += table.bytesRead();
  }
  folder.countRead("untangle", bytesRead);
  // The window's wedges are the map's (per sub vertex), not corners of equal values: corners of
  // two wedges can hold one value (a seam whose transition fixes that point), and the repair
  // moves wedges.
  std::vector<Vec2d> values(3 * window.size());
  std::vector<std::uint32_t> localWedge(values.size());
  std::vector<Vec2d> localValues;
  {
    PagedReader<std::uint32_t> cornerWedge(map.cornerWedge, windowBytes, kWindowPageBytes);
    PagedReader<Vec2d> wedgeValues(map.wedgeValues, windowBytes, kWindowPageBytes);
    // Local ids in the order of the map's (wedge, sub vertex) keys.
    std::vector<std::uint64_t> key(values.size());
    for (std::size_t c = 0; c < values.size(); ++c) {
      const std::uint32_t wedge = cornerWedge[3 * window[c / 3] + c % 3];
      values[c] = wedgeValues[wedge];
      key[c] = (std::uint64_t(wedge) << 32) | w.mesh.triangles[c / 3][c % 3];
    }
    std::vector<std::uint64_t> keys = key;
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    localValues.resize(keys.size());
    for (std::size_t c = 0; c < values.size(); ++c) {
      localWedge[c] = static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key[c]) - keys.begin());
      localValues[localWedge[c]] = values[c];
    }
    if (field.framePositions.bytes > 0) {  // the smoothed surface tells faces folded in 3D
      PagedReader<Vec3f> smooth(field.framePositions, windowBytes, kWindowPageBytes);
      for (VertexId v : w.vertexOrigin) w.field.framePositions.push_back(smooth[v]);
      folder.countRead("untangle", smooth.bytesRead());
    }
    folder.countRead("untangle", cornerWedge.bytesRead() + wedgeValues.bytesRead());
  }
  WedgeMap uv(std::move(localWedge), std::move(localValues));
  std::vector<std::complex<double>> windowT(w.seamOrigin.size());
  for (std::size_t j = 0; j < windowT.size(); ++j) windowT[j] = seamT[w.seamOrigin[j]];
  // The border keeps its values: its faces outside the window hold them too.
  std::vector<std::uint8_t> pinned(w.vertexFree.size());
  for (std::size_t v = 0; v < pinned.size(); ++v) pinned[v] = !w.vertexFree[v];
  UntangleOptions local = options;
  local.pinnedVertices = &pinned;
  // Cones by mesh id to the window's ids (both increasing: the window keeps the mesh's order).
  std::vector<VertexId> notRetried;
  if (options.conesNotRetried) {
    for (VertexId v = 0; v < w.vertexOrigin.size(); ++v) {
      if (std::binary_search(options.conesNotRetried->begin(), options.conesNotRetried->end(), w.vertexOrigin[v])) {
        notRetried.push_back(v);
      }
    }
    local.conesNotRetried = &notRetried;
  }
  std::vector<std::uint8_t> onlyFaces;
  if (only) {
    onlyFaces.resize(w.mesh.numFaces());
    for (FaceId f = 0; f < w.mesh.numFaces(); ++f) {
      const Triangle& t = w.mesh.triangles[f];
      onlyFaces[f] = only->holds({w.mesh.position(t[0]), w.mesh.position(t[1]), w.mesh.position(t[2])});
    }
    local.onlyFaces = &onlyFaces;
  }
  local.maxPatchFraction = options.maxPatchFraction * double(scratch.numFaces) / double(window.size());
  out.untangle = untangleFlips(w.mesh, w.topology, w.field, w.cut, uv, windowT, local);
  for (VertexId& v : out.untangle.conesLeftShort) v = w.vertexOrigin[v];
  // The window holds every flipped face: the faces it leaves are the map's, by mesh id.
  double leftEdges = 0.0;
  for (FaceId& f : out.untangle.leftFaces) {
    const Triangle& t = w.mesh.triangles[f];
    for (int k = 0; k < 3; ++k) leftEdges += (w.mesh.position(t[(k + 1) % 3]) - w.mesh.position(t[k])).norm();
    f = window[f];
  }
  if (!out.untangle.leftFaces.empty()) out.leftMeanEdge = leftEdges / (3.0 * out.untangle.leftFaces.size());

  // The moved corners (free vertices only) and re-rounded translations back into the map.
  RefineResult moved;
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (uv[c] != values[c]) moved.corners.push_back({uv[c], CornerId(3 * window[c / 3] + c % 3), true});
  }
  for (std::size_t j = 0; j < windowT.size(); ++j) {
    if (windowT[j] == seamT[w.seamOrigin[j]]) continue;
    moved.seams.push_back(w.seamOrigin[j]);
    moved.seamT.push_back(windowT[j]);
  }
  applyScratchRefinement(folder, moved, map, &seamT, pass);
  return out;
}

void resolveScratchLeftoverFlips(ScratchFolder& folder, const CleanScratch& scratch, const ScratchField& field,
                                 const ScratchCut& cut, ScratchMap& map, std::vector<std::complex<double>>& seamT,
                                 RefineOptions refine, const UntangleOptions& options, const StreamPassOptions& pass,
                                 ScratchUntangleStats& repaired) {
  if (repaired.untangle.flippedAfter == 0 || !(options.leftoverRadius > 0.0)) return;
  const auto start = SteadyClock::now();
  // The repair's leftover faces are every flip of the map (its window held them all); after the
  // re-solve only those and the re-solved faces are read again.
  const std::vector<FaceId>& flipped = repaired.untangle.leftFaces;
  refine.edgeLength = options.edgeLength;
  RefineOptions local = leftoverRefineOptions(refine, flipped, repaired.leftMeanEdge, options.leftoverRadius);
  local.regionOnly = true;
  const RefineResult resolved = refineScratchNearCones(folder, scratch, field, cut, map, seamT, local, pass);
  applyScratchRefinement(folder, resolved, map, &seamT, pass);
  const double seconds = secondsSince(start);
  std::vector<FaceId> candidates;
  std::set_union(flipped.begin(), flipped.end(), resolved.regionFaces.begin(), resolved.regionFaces.end(),
                 std::back_inserter(candidates));
  UntangleOptions retry = options;
  retry.conesNotRetried = &repaired.untangle.conesLeftShort;
  ScratchUntangleStats again =
      untangleScratchFlips(folder, scratch, field, cut, map, seamT, retry, pass, nullptr, &candidates);
  addLeftoverRepair(again.untangle, repaired.untangle, resolved.stats.regionFaces, resolved.stats.freeVertices, seconds);
  again.windowFaces = std::max(again.windowFaces, repaired.windowFaces);
  repaired = again;
}

}  // namespace seamvox
