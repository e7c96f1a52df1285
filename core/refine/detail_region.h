#pragma once
/// A refinement region cut out of the whole mesh (RegionMesh, refine.h) written once for the
/// in-memory extractRegion and the out-of-core one (stream/refine_stream): templates over the
/// corner table, the positions, the field and the cut.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/cut/cut.h"
#include "core/mesh/topology.h"
#include "core/refine/refine.h"

namespace seamvox::detail {

/// Whole-mesh faces and corners to their ids in a region (regionFaces sorted); kInvalidId outside.
/// A region's faces are looked up for every corner of their fans: a bit per id of their span with
/// the count of faces before each 64-bit word answers in one cache line (a face's id is its rank),
/// where those words take at most 1 KiB per region face (a group of a round's patch spans the
/// whole mesh) and 8 MiB in all (an out-of-core window's ids span a billion-face mesh); a wider
/// span is searched.
struct RegionIndex {
  explicit RegionIndex(const std::vector<FaceId>& faces) : regionFaces(faces) {
    if (faces.empty()) return;
    first_ = faces.front();
    const std::uint64_t words = (std::uint64_t(faces.back()) - first_) / 64 + 1;
    if (words > 64 * std::uint64_t(faces.size()) || words > kMaxWords) return;
    words_.assign(words, Word{});
    for (FaceId f : faces) words_[(f - first_) / 64].bits |= std::uint64_t(1) << ((f - first_) % 64);
    std::uint32_t before = 0;
    for (Word& w : words_) {
      w.before = before;
      before += static_cast<std::uint32_t>(__builtin_popcountll(w.bits));
    }
  }
  const std::vector<FaceId>& regionFaces;
  std::uint32_t subFace(FaceId f) const {
    if (!words_.empty()) {
      const std::uint64_t off = std::uint64_t(f) - first_;  // wraps for f < first_
      if (f < first_ || off / 64 >= words_.size()) return kInvalidId;
      const Word& w = words_[off / 64];
      const std::uint64_t below = w.bits & ((std::uint64_t(1) << (off % 64)) - 1);
      return (w.bits >> (off % 64)) & 1 ? w.before + static_cast<std::uint32_t>(__builtin_popcountll(below))
                                        : kInvalidId;
    }
    const auto it = std::lower_bound(regionFaces.begin(), regionFaces.end(), f);
    return it != regionFaces.end() && *it == f ? static_cast<std::uint32_t>(it - regionFaces.begin())
                                               : kInvalidId;
  }
  CornerId subCorner(CornerId c) const {
    if (c == kInvalidId) return kInvalidId;
    const std::uint32_t i = subFace(cornerFace(c));
    return i == kInvalidId ? kInvalidId : 3 * i + c % 3;
  }

 private:
  struct Word {
    std::uint64_t bits = 0;
    std::uint32_t before = 0;  // region faces in the words before
  };
  static constexpr std::uint64_t kMaxWords = std::uint64_t(1) << 19;  // 16 bytes each
  FaceId first_ = 0;
  std::vector<Word> words_;  // empty: binary search
};

/// Sub vertices: one per fan piece of region corners around each whole-mesh vertex (filling
/// out.vertexOrigin and out.vertexFree); a piece reaching a face outside the region is locked.
/// Returns the sub vertex of every region corner; vertexCorner gets one corner per sub vertex.
template <class Table>
std::vector<VertexId> regionVertices(Table& topology, const RegionIndex& index, RegionMesh& out,
                                     std::vector<CornerId>& vertexCorner) {
  const std::vector<FaceId>& regionFaces = index.regionFaces;
  const std::uint32_t rf = static_cast<std::uint32_t>(regionFaces.size());
  std::vector<VertexId> cornerVertex(3u * rf, kInvalidId);
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
      if (index.subFace(cornerFace(before)) == kInvalidId) {
        free = false;
        break;
      }
      first = before;
    }
    const VertexId id = static_cast<VertexId>(out.vertexOrigin.size());
    CornerId c = first;
    for (;;) {
      const CornerId sc2 = index.subCorner(c);  // in the region by construction
      if (sc2 == kInvalidId) break;
      cornerVertex[sc2] = id;
      const CornerId after = topology.ccw(c);
      if (after == kInvalidId || after == first) break;
      if (index.subFace(cornerFace(after)) == kInvalidId) {
        free = false;
        break;
      }
      c = after;
    }
    out.vertexOrigin.push_back(topology.vertex(start));
    out.vertexFree.push_back(free ? 1 : 0);
    vertexCorner.push_back(index.subCorner(first));
  }
  return cornerVertex;
}

/// Seams: the edges with both faces in the region, in curve order, under local ids; and the
/// region's cones.
template <class Table>
void regionSeamsAndCones(Table& topology, const std::vector<SeamCurve>& seams, const std::vector<VertexId>& cones,
                         const RegionIndex& index, RegionMesh& out) {
  const TriangleMesh& sub = out.mesh;
  CutResult& subCut = out.cut;
  for (std::uint32_t s = 0; s < seams.size(); ++s) {
    SeamCurve local;
    local.matching = seams[s].matching;
    for (CornerId c : seams[s].corners) {
      const CornerId sc = index.subCorner(c), so = index.subCorner(topology.opposite(c));
      if (sc == kInvalidId || so == kInvalidId) continue;
      local.corners.push_back(sc);
    }
    if (local.corners.empty()) continue;
    local.start = sub.triangles[local.corners.front() / 3][nextCorner(local.corners.front()) % 3];
    local.end = sub.triangles[local.corners.back() / 3][prevCorner(local.corners.back()) % 3];
    subCut.seams.push_back(std::move(local));
    out.seamOrigin.push_back(s);
  }
  const std::uint32_t nv = static_cast<std::uint32_t>(out.vertexOrigin.size());
  for (VertexId v = 0; v < nv; ++v) {
    if (std::binary_search(cones.begin(), cones.end(), out.vertexOrigin[v])) {
      subCut.cones.push_back(v);
    }
  }
}

/// extractRegion from any source of the whole mesh: the corner table (cw, ccw, opposite,
/// vertex), position(v) and direction(f) (Vec3f), rotation(f) (the combing's quarter turns),
/// the cut's corners (isCut, matching), seams and cones (increasing). regionFaces: sorted, unique.
template <class Table, class Position, class Direction, class Rotation, class Cut>
RegionMesh extractRegionFrom(Table& topology, Position&& position, Direction&& direction, Rotation&& rotation,
                             Cut& cut, const std::vector<SeamCurve>& seams, const std::vector<VertexId>& cones,
                             const std::vector<FaceId>& regionFaces) {
  RegionMesh out;
  out.faceOrigin = regionFaces;
  const std::uint32_t rf = static_cast<std::uint32_t>(regionFaces.size());
  const RegionIndex index{regionFaces};
  std::vector<CornerId> vertexCorner;
  const std::vector<VertexId> cornerVertex = regionVertices(topology, index, out, vertexCorner);

  // Faces, field and cut corners copied under local ids.
  const std::uint32_t nv = static_cast<std::uint32_t>(out.vertexOrigin.size());
  TriangleMesh& sub = out.mesh;
  sub.positions.resize(nv);
  for (VertexId v = 0; v < nv; ++v) sub.positions[v] = position(out.vertexOrigin[v]);
  sub.triangles.resize(rf);
  std::vector<CornerId> opposite(3u * rf);
  out.field.direction.resize(rf);
  CutResult& subCut = out.cut;
  subCut.corners = CutCorners(3u * rf, false);
  subCut.faceRotation = FaceRotations(rf);
  for (std::uint32_t i = 0; i < rf; ++i) {
    const FaceId f = regionFaces[i];
    out.field.direction[i] = direction(f);
    subCut.faceRotation.set(i, rotation(f));
    for (int k = 0; k < 3; ++k) {
      const CornerId c = 3 * f + k, sc = 3 * i + k;
      sub.triangles[i][k] = cornerVertex[sc];
      opposite[sc] = index.subCorner(topology.opposite(c));
      subCut.corners.setCut(sc, cut.isCut(c) || opposite[sc] == kInvalidId);
      subCut.corners.setMatching(sc, cut.matching(c));
    }
  }
  regionSeamsAndCones(topology, seams, cones, index, out);
  out.topology = Topology::fromParts(sub.triangles, std::move(opposite), std::move(vertexCorner));
  return out;
}

/// placeRegionOnSurface with the surface point of each sub vertex read at its whole-mesh vertex:
/// surfaceOf(v) (Vec3f) for v in vertexOrigin.
template <class SurfaceOf>
void placeRegionOnSurfaceOf(RegionMesh& region, SurfaceOf&& surfaceOf) {
  std::vector<Vec3f> surface(region.vertexOrigin.size());
  for (std::size_t i = 0; i < surface.size(); ++i) surface[i] = surfaceOf(region.vertexOrigin[i]);
  placeRegionOnSurface(region, std::move(surface));
}

}  // namespace seamvox::detail
