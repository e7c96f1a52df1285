#pragma once
/// The voxel basis' per-face steps written once for the in-memory build (voxel_grid,
/// voxel_basis) and the out-of-core one (stream/voxel_stream): clipping faces into voxel
/// fragments, a voxel's elements (its fragments joined through shared non-cut edges) and their
/// integrals. Templates over where a face's corners, neighbours and directions come from (the
/// mesh in memory, or page caches of scratch files).
#include <algorithm>
#include <cmath>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "core/basis/voxel_basis.h"
#include "core/basis/voxel_clip.h"
#include "core/cut/cut.h"
#include "core/mesh/detail_union_find.h"
#include "core/mesh/mesh.h"
#include "core/system/errors.h"

namespace seamvox::detail {

/// Fragments of a range of faces, before their voxels have ids.
struct ClippedChunk {
  FaceId begin = 0, end = 0;
  std::vector<VoxelCoord> voxel;
  std::vector<FaceId> face;
  std::vector<std::uint8_t> edgeMask;
};

/// Clips the chunk's faces but those in `leftOut` (increasing: the islands, islands.h);
/// gridCorners(f): the face's corners in grid coordinates (as faceGridCoords computes them).
template <class GridCorners>
void clipChunk(const VoxelGridGeometry& grid, GridCorners&& gridCorners, ClippedChunk& chunk,
               const std::vector<FaceId>& leftOut = {}) {
  std::vector<VoxelPiece> pieces;
  auto skip = std::lower_bound(leftOut.begin(), leftOut.end(), chunk.begin);
  for (FaceId f = chunk.begin; f < chunk.end; ++f) {
    if (skip != leftOut.end() && *skip == f) {
      ++skip;
      continue;
    }
    const std::array<Vec3d, 3> g = gridCorners(f);
    clipTriangleToVoxels(g, grid.resolution, pieces);
    const std::size_t before = chunk.face.size();
    for (const VoxelPiece& piece : pieces) {
      chunk.voxel.push_back(piece.voxel);
      chunk.face.push_back(f);
      chunk.edgeMask.push_back(voxelEdgeMask(g, piece.voxel));
    }
    if (!pieces.empty()) continue;
    // Zero-area face: no integrals, but its edges still connect its neighbours. It gets a
    // fragment in every voxel its edges run through (a few at most), else one at its centroid.
    const VoxelCoord lo = grid.voxelOf(g[0].cwiseMin(g[1]).cwiseMin(g[2]));
    const VoxelCoord hi = grid.voxelOf(g[0].cwiseMax(g[1]).cwiseMax(g[2]));
    const std::int64_t count = std::int64_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    if (count <= 64) {
      for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
            const std::uint8_t mask = voxelEdgeMask(g, {x, y, z});
            if (mask == 0) continue;
            chunk.voxel.push_back({x, y, z});
            chunk.face.push_back(f);
            chunk.edgeMask.push_back(mask);
          }
    }
    if (chunk.face.size() == before) {
      const VoxelCoord v = grid.voxelOf((g[0] + g[1] + g[2]) / 3.0);
      chunk.voxel.push_back(v);
      chunk.face.push_back(f);
      chunk.edgeMask.push_back(voxelEdgeMask(g, v));
    }
  }
}

/// The chunk's fragments in order, each voxel registered in grid (grid.insert: ids of first
/// appearance); sink(fragment). InputError past VoxelFragment::kMaxVoxels voxels.
template <class Grid, class Sink>
void registerChunk(const ClippedChunk& chunk, Grid& grid, Sink&& sink) {
  for (std::size_t i = 0; i < chunk.face.size(); ++i) {
    const std::uint32_t voxel = grid.insert(chunk.voxel[i]);
    if (voxel >= VoxelFragment::kMaxVoxels) {
      throw InputError("voxel basis: more than 2^29 voxels on the surface; use a coarser grid");
    }
    VoxelFragment fragment;
    fragment.face = chunk.face[i];
    fragment.voxel = voxel;
    fragment.edgeMask = chunk.edgeMask[i];
    sink(fragment);
  }
}

/// Faces [0, numFaces) chunk by chunk (Chunk: begin, end) through a TBB pipeline: work(chunk) in
/// parallel, then finish(chunk) in face order, at most two chunks per thread alive.
template <class Chunk, class Work, class Finish>
void facesInOrder(std::uint64_t numFaces, std::uint32_t chunkFaces, Work&& work, Finish&& finish) {
  const std::uint64_t step = std::max<std::uint32_t>(chunkFaces, 1);
  std::uint64_t nextFace = 0;
  const std::size_t tokens = 2 * std::size_t(tbb::this_task_arena::max_concurrency());
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, std::shared_ptr<Chunk>>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& control) -> std::shared_ptr<Chunk> {
            if (nextFace >= numFaces) {
              control.stop();
              return nullptr;
            }
            auto chunk = std::make_shared<Chunk>();
            chunk->begin = static_cast<FaceId>(nextFace);
            nextFace = std::min(numFaces, nextFace + step);
            chunk->end = static_cast<FaceId>(nextFace);
            return chunk;
          }) &
          tbb::make_filter<std::shared_ptr<Chunk>, std::shared_ptr<Chunk>>(tbb::filter_mode::parallel,
                                                                         [&](std::shared_ptr<Chunk> chunk) {
                                                                           work(*chunk);
                                                                           return chunk;
                                                                         }) &
          tbb::make_filter<std::shared_ptr<Chunk>, void>(tbb::filter_mode::serial_in_order,
                                                         [&](std::shared_ptr<Chunk> chunk) { finish(*chunk); }));
}

/// Clips faces [0, numFaces) chunk by chunk (facesInOrder): clip(chunk) in parallel (clipChunk
/// with the caller's corners), then in face order the chunk's fragments registered in grid and
/// passed to sink, and done(chunk) (progress).
template <class Clip, class Grid, class Sink, class Done>
void clipFacesInOrder(std::uint64_t numFaces, std::uint32_t chunkFaces, Clip&& clip, Grid& grid, Sink&& sink,
                      Done&& done) {
  facesInOrder<ClippedChunk>(numFaces, chunkFaces, clip, [&](ClippedChunk& chunk) {
    registerChunk(chunk, grid, sink);
    done(chunk);
  });
}

/// Dense labels 0.. of the union-find classes, in order of first appearance.
inline std::uint32_t denseLabels(UnionFind& uf, std::vector<std::uint32_t>& label) {
  const std::size_t n = uf.parent.size();
  std::vector<std::uint32_t> rootLabel(n, kInvalidId);
  label.resize(n);
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t r = uf.find(static_cast<std::uint32_t>(i));
    if (rootLabel[r] == kInvalidId) rootLabel[r] = count++;
    label[i] = rootLabel[r];
  }
  return count;
}

/// Position of key in the increasing list, kInvalidId when absent. Branch-free halving (the
/// compiler emits conditional moves): the searches of element labelling hit unpredictable keys.
inline std::uint32_t findSorted(const std::vector<FaceId>& sorted, FaceId key) {
  if (sorted.empty()) return kInvalidId;
  const FaceId* base = sorted.data();
  std::size_t n = sorted.size();
  while (n > 1) {
    const std::size_t half = n / 2;
    base = base[half] <= key ? base + half : base;
    n -= half;
  }
  return *base == key ? static_cast<std::uint32_t>(base - sorted.data()) : kInvalidId;
}

/// Elements of one voxel: its fragments (faces increasing, their edge masks) joined through
/// shared non-cut edges. opposite(c), isCut(c) of the cut surface. label[i]: the element of
/// fragment i, numbered 0.. in order of first appearance; returns their number.
template <class Opposite, class IsCut>
std::uint32_t labelVoxelFragments(const std::vector<FaceId>& faces, const std::vector<std::uint8_t>& masks,
                                  Opposite&& opposite, IsCut&& isCut, std::vector<std::uint32_t>& label) {
  const std::uint32_t m = static_cast<std::uint32_t>(faces.size());
  UnionFind uf(m);
  for (std::uint32_t i = 0; i < m; ++i) {
    for (int j = 0; j < 3; ++j) {
      const CornerId c = 3 * faces[i] + j;
      if (!(masks[i] >> j & 1) || isCut(c)) continue;
      const CornerId o = opposite(c);
      if (o == kInvalidId) continue;
      const std::uint32_t i2 = findSorted(faces, cornerFace(o));
      if (i2 == kInvalidId) continue;
      if (masks[i2] >> (o % 3) & 1) uf.unite(i, i2);
    }
  }
  return denseLabels(uf, label);
}

/// What the integrals need of a face: corners in world and grid coordinates, and the target
/// direction (the combed field, cut.h) with the face's unit normal (zero on a zero-area face).
struct FaceIntegrand {
  std::array<Vec3d, 3> grid;
  Vec3d direction, normal;
};

/// The combed direction rot^rotation(u) about the normal n.
inline Vec3d combedDirection(Vec3d u, const Vec3d& n, std::uint8_t rotation) {
  for (int k = 0; k < rotation % 4; ++k) u = n.cross(u);
  return u;
}

/// Integrals of the elements of one voxel from its fragments (faces[i], element[i], elements
/// first..last, in fragment order); integrand(f) gives a FaceIntegrand. Re-clips each fragment
/// (no polygons are stored). sums: scratch space.
template <class Integrand>
void integrateVoxel(const VoxelCoord& voxel, double voxelSize, double edgeLength, const std::vector<FaceId>& faces,
                    const std::vector<std::uint32_t>& element, std::uint32_t first, std::uint32_t last,
                    Integrand&& integrand, std::vector<FragmentSums>& sums, VoxelIntegrals* records,
                    std::array<double, 36>* normalStiffness) {
  sums.assign(last - first + 1, FragmentSums{});
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceIntegrand face = integrand(faces[i]);
    if (face.normal.squaredNorm() == 0.0) continue;  // zero-area face: nothing to integrate
    const ClipPolygon piece = clipTriangleToVoxel(face.grid, voxel);
    accumulateFragment(piece, voxel, voxelSize, face.normal, face.direction, edgeLength, sums[element[i] - first]);
  }
  for (std::uint32_t e = first; e <= last; ++e) {
    finishElement(sums[e - first], records[e - first], 0.0, normalStiffness[e - first].data());
  }
}

/// A seam link between element-function nodes 8 e + k on either side of a seam.
struct SeamLink {
  std::uint32_t left, right, seam;
};

/// The element functions (nodes 8 e + k) of one grid corner joined into domains, and the seam
/// links between them.
struct DomainLinks {
  UnionFind functions{0};
  std::vector<SeamLink> seamLinks;
};

/// The links of a chunk of faces, found in parallel and applied in face order (applyTo): the seam
/// links keep their order, and the union-find's sets (each rooted at its smallest node) do not
/// depend on the order of the unions.
struct RecordedLinks {
  struct Functions {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    void unite(std::uint32_t a, std::uint32_t b) { pairs.emplace_back(a, b); }
  } functions;
  std::vector<SeamLink> seamLinks;
  void applyTo(DomainLinks& links) const {
    for (const auto& [a, b] : functions.pairs) links.functions.unite(a, b);
    links.seamLinks.insert(links.seamLinks.end(), seamLinks.begin(), seamLinks.end());
  }
};

/// Faces [begin, end) and the links found in them: facesInOrder's chunk for the linking.
struct LinkChunk {
  FaceId begin = 0, end = 0;
  RecordedLinks links;
};

/// A fragment as the linking sees it.
struct FaceFragment {
  VoxelCoord voxel;
  std::uint32_t element = 0;
  std::uint8_t edgeMask = 0;
};

inline VoxelCoord voxelDifference(const VoxelCoord& b, const VoxelCoord& a) {
  return {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
}
inline bool isNeighbourOffset(const VoxelCoord& d) {
  return std::abs(d[0]) <= 1 && std::abs(d[1]) <= 1 && std::abs(d[2]) <= 1;
}

/// Calls f(k, k2) for every grid corner shared by voxels A and B = A + d: local index k in A,
/// k2 in B (corner A + k == B + k2).
template <class F>
void forSharedCorners(const VoxelCoord& d, F&& f) {
  for (int k = 0; k < 8; ++k) {
    const int kx = (k & 1) - d[0], ky = ((k >> 1) & 1) - d[1], kz = ((k >> 2) & 1) - d[2];
    if (kx < 0 || kx > 1 || ky < 0 || ky > 1 || kz < 0 || kz > 1) continue;
    f(k, kx + 2 * ky + 4 * kz);
  }
}

/// (a) One triangle meets a support (a convex box) in a convex, connected piece: its fragments in
/// any two voxels of the support belong to the same domain. `sorted` is scratch space.
template <class Functions>
void joinFacePieces(const std::vector<FaceFragment>& pieces, std::vector<std::pair<VoxelCoord, std::uint32_t>>& sorted,
                    Functions& functions) {
  sorted.clear();
  for (const FaceFragment& piece : pieces) sorted.emplace_back(piece.voxel, piece.element);
  std::sort(sorted.begin(), sorted.end());
  for (const auto& [a, ea] : sorted) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const VoxelCoord b{a[0] + dx, a[1] + dy, a[2] + dz};
          if (b <= a) continue;
          const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(b, std::uint32_t(0)));
          if (it == sorted.end() || it->first != b) continue;
          const std::uint32_t eb = it->second;
          forSharedCorners({dx, dy, dz}, [&](int k, int k2) { functions.unite(8 * ea + k, 8 * eb + k2); });
        }
  }
}

/// Scratch space of linkFaceFragments, one per thread.
struct LinkScratch {
  std::vector<FaceFragment> one, theirs;                    // one neighbour; the three on f's edges
  std::vector<std::pair<VoxelCoord, std::uint32_t>> sorted;  // (voxel, index in theirs)
  std::vector<std::uint32_t> near;                           // theirs' indices near one fragment
};

/// Domains and seam links of face f's fragments (in face order, f after every face before):
/// (a) its pieces joined (joinFacePieces); (b) two triangles across an edge meet in the support
/// along the edge's piece: non-cut edges join their domains, seam edges make a seam link.
/// g: f's corners in grid coordinates; opposite(c), isCut(c), seamSide(c) (SeamIndex::Side);
/// neighbour(h, out) fills the fragments of face h. Links: DomainLinks, or any type with
/// functions.unite(a, b) and seamLinks.push_back(link) (a record of them, applied in face order).
/// A neighbour with many fragments on the edge (a sliver across many voxels) is searched by voxel,
/// so a fan of long faces costs k log k per face, not k^2; the links come in the same order.
template <class Opposite, class IsCut, class SeamSide, class Neighbour, class Links>
void linkFaceFragments(FaceId f, const std::vector<FaceFragment>& mine, const std::array<Vec3d, 3>& g,
                       Opposite&& opposite, IsCut&& isCut, SeamSide&& seamSide, Neighbour&& neighbour,
                       LinkScratch& scratch, Links& links) {
  constexpr std::uint32_t kScan = 8;  // up to this many fragments on an edge: a plain scan
  if (mine.size() >= 2) joinFacePieces(mine, scratch.sorted, links.functions);
  struct Edge {
    bool cut = false;
    SeamIndex::Side side{};
    std::uint32_t begin = 0, end = 0;  // the neighbour's fragments on the edge, in theirs
  };
  std::array<Edge, 3> edges;
  std::uint8_t used = 0;
  for (const FaceFragment& fr : mine) used |= fr.edgeMask;
  scratch.theirs.clear();
  scratch.sorted.clear();
  bool searched = false;
  for (int j = 0; j < 3; ++j) {
    Edge& e = edges[j];
    e.begin = e.end = static_cast<std::uint32_t>(scratch.theirs.size());
    if (!(used >> j & 1)) continue;
    const CornerId c = 3 * f + j;
    const CornerId o = opposite(c);
    if (o == kInvalidId || cornerFace(o) < f) continue;
    e.cut = isCut(c);
    e.side = e.cut ? seamSide(c) : SeamIndex::Side{};
    if (e.cut && e.side.seam == kInvalidId) continue;
    neighbour(cornerFace(o), scratch.one);
    for (const FaceFragment& other : scratch.one) {
      if (other.edgeMask >> (o % 3) & 1) scratch.theirs.push_back(other);
    }
    e.end = static_cast<std::uint32_t>(scratch.theirs.size());
    if (e.end - e.begin > kScan) {
      for (std::uint32_t i = e.begin; i < e.end; ++i) scratch.sorted.emplace_back(scratch.theirs[i].voxel, i);
      searched = true;
    }
  }
  if (searched) std::sort(scratch.sorted.begin(), scratch.sorted.end());
  // The indices in theirs of edge e's fragments that may touch voxel a, in theirs' order.
  const auto nearby = [&](const VoxelCoord& a, const Edge& e) {
    scratch.near.clear();
    if (e.end - e.begin <= kScan) {
      for (std::uint32_t i = e.begin; i < e.end; ++i) scratch.near.push_back(i);
      return;
    }
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const VoxelCoord b{a[0] + dx, a[1] + dy, a[2] + dz};
          auto it = std::lower_bound(scratch.sorted.begin(), scratch.sorted.end(), std::make_pair(b, e.begin));
          for (; it != scratch.sorted.end() && it->first == b && it->second < e.end; ++it) {
            scratch.near.push_back(it->second);
          }
        }
    std::sort(scratch.near.begin(), scratch.near.end());
  };
  for (const FaceFragment& fr : mine) {
    const VoxelCoord& a = fr.voxel;
    for (int j = 0; j < 3; ++j) {
      const Edge& e = edges[j];
      if (!(fr.edgeMask >> j & 1) || e.begin == e.end) continue;
      const Vec3d& p = g[(j + 1) % 3];
      const Vec3d& q = g[(j + 2) % 3];
      nearby(a, e);
      for (const std::uint32_t i : scratch.near) {
        const FaceFragment& other = scratch.theirs[i];
        const VoxelCoord& b = other.voxel;
        const VoxelCoord d = voxelDifference(b, a);
        if (!isNeighbourOffset(d)) continue;
        if (d != VoxelCoord{0, 0, 0}) {
          // The edge must run inside the shared face or line of the two voxels.
          Vec3d lo, hi;
          for (int x = 0; x < 3; ++x) {
            lo[x] = std::max(a[x], b[x]);
            hi[x] = std::min(a[x], b[x]) + 1;
          }
          if (!segmentOverlapsBox(p, q, lo, hi)) continue;
        } else if (!e.cut) {
          continue;  // same voxel, joined into one element already
        }
        const std::uint32_t ea = fr.element, eb = other.element;
        forSharedCorners(d, [&](int k, int k2) {
          if (!e.cut) {
            links.functions.unite(8 * ea + k, 8 * eb + k2);
          } else if (e.side.left) {
            links.seamLinks.push_back({8 * ea + k, 8 * eb + k2, e.side.seam});
          } else {
            links.seamLinks.push_back({8 * eb + k2, 8 * ea + k, e.side.seam});
          }
        });
      }
    }
  }
}

/// What a VoxelBasis is made of, built in memory (buildVoxelBasis) or out of core
/// (stream/voxel_stream): elements by voxel with their integrals, and the links that make the
/// domains. The per-face index (for evaluation and support faces) only in memory.
struct VoxelBasisParts {
  VoxelGridGeometry grid;
  std::vector<VoxelCoord> voxelCoords;           // per voxel id
  std::vector<std::uint32_t> voxelElementStart;  // #voxels + 1
  std::vector<std::uint32_t> elementVoxel;       // #elements
  std::vector<VoxelIntegrals> records;           // #elements, tangential stiffness
  std::vector<std::array<double, 36>> normalStiffness;  // #elements, unweighted
  DomainLinks links;
  std::vector<std::uint32_t> faceFragmentStart;  // #F + 1, or empty (out of core)
  std::vector<std::uint32_t> fragmentElement;    // #fragments, ordered by face, or empty
};

}  // namespace seamvox::detail
