#include "core/mesh/clean.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>

#include "core/mesh/detail_corner_table.h"
#include "core/mesh/detail_union_find.h"
#include "core/mesh/morton.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace {

constexpr std::size_t kGrain = 4096;

void checkInput(const TriangleMesh& mesh) {
  const std::uint32_t nv = mesh.numVertices();
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!mesh.positions[v].allFinite()) {
      throw InputError("vertex " + std::to_string(v) + " has a non-finite coordinate (NaN or inf)");
    }
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (VertexId v : mesh.triangles[f]) {
      if (v >= nv) {
        throw InputError("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                         " but the mesh has " + std::to_string(nv) + " vertices");
      }
    }
  }
  mesh.attributes.checkSize(mesh.positions.size());
  if (!mesh.cornerUV.empty() && mesh.cornerUV.size() != 3 * mesh.triangles.size()) {
    throw InputError("the mesh has " + std::to_string(mesh.cornerUV.size()) +
                     " texture coordinates for " + std::to_string(mesh.triangles.size()) +
                     " faces (expected 3 per face)");
  }
}

/// Representative (smallest index) of each vertex's weld cluster. tolerance 0: equal positions.
std::vector<VertexId> weldMap(const std::vector<Vec3f>& positions, double tolerance) {
  const std::uint32_t nv = static_cast<std::uint32_t>(positions.size());
  std::vector<VertexId> order(nv);
  std::iota(order.begin(), order.end(), 0u);
  detail::UnionFind sets(nv);
  if (tolerance <= 0.0) {
    auto less = [&](VertexId a, VertexId b) {
      const Vec3f &p = positions[a], &q = positions[b];
      if (p.x() != q.x()) return p.x() < q.x();
      if (p.y() != q.y()) return p.y() < q.y();
      if (p.z() != q.z()) return p.z() < q.z();
      return a < b;
    };
    tbb::parallel_sort(order.begin(), order.end(), less);
    for (std::uint32_t i = 1; i < nv; ++i) {
      if (positions[order[i]] == positions[order[i - 1]]) sets.unite(order[i], order[i - 1]);
    }
  } else {
    // Hash vertices into cells of size tolerance; compare against the 27 surrounding cells.
    using Cell = std::array<std::int64_t, 3>;
    auto cellOf = [&](VertexId v) {
      const Vec3d p = positions[v].cast<double>() / tolerance;
      return Cell{std::int64_t(std::floor(p.x())), std::int64_t(std::floor(p.y())),
                  std::int64_t(std::floor(p.z()))};
    };
    std::vector<Cell> cells(nv);
    parallelForEach(nv, 4096, [&](std::uint64_t v) { cells[v] = cellOf(v); });
    tbb::parallel_sort(order.begin(), order.end(), [&](VertexId a, VertexId b) {
      return cells[a] != cells[b] ? cells[a] < cells[b] : a < b;
    });
    const double tol2 = tolerance * tolerance;
    for (std::uint32_t i = 0; i < nv; ++i) {
      const VertexId v = order[i];
      const Cell c = cells[v];
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dz = -1; dz <= 1; ++dz) {
            const Cell n{c[0] + dx, c[1] + dy, c[2] + dz};
            if (n > c) continue;  // each pair of cells once (same cell: below)
            auto lo = std::lower_bound(order.begin(), order.end(), n,
                                       [&](VertexId a, const Cell& key) { return cells[a] < key; });
            for (auto it = lo; it != order.end() && cells[*it] == n; ++it) {
              if (n == c && *it >= v) break;
              if ((positions[*it] - positions[v]).cast<double>().squaredNorm() <= tol2) {
                sets.unite(*it, v);
              }
            }
          }
    }
  }
  std::vector<VertexId> rep(nv);
  for (std::uint32_t v = 0; v < nv; ++v) rep[v] = sets.find(v);
  return rep;
}

/// Keeps the faces for which keep[f] is set (in order), with their UVs and origins.
void compactFaces(TriangleMesh& mesh, std::vector<FaceId>& faceOrigin, const std::vector<std::uint8_t>& keep) {
  std::size_t out = 0;
  const bool uv = mesh.hasUV();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (!keep[f]) continue;
    mesh.triangles[out] = mesh.triangles[f];
    faceOrigin[out] = faceOrigin[f];
    if (uv) {
      for (int k = 0; k < 3; ++k) mesh.cornerUV.copyCorner(3 * out + k, 3 * f + k);
    }
    ++out;
  }
  mesh.triangles.resize(out);
  mesh.triangles.shrink_to_fit();
  faceOrigin.resize(out);
  if (uv) mesh.cornerUV.resizeCorners(3 * out);
}

/// Marks faces with the same vertex set as an earlier face (either orientation).
std::vector<std::uint8_t> findUniqueFaces(const std::vector<Triangle>& tris, std::uint32_t nv,
                                          std::uint64_t& duplicates) {
  // Group faces by their smallest vertex (counting sort), then compare within each group.
  const std::uint32_t nf = static_cast<std::uint32_t>(tris.size());
  auto sorted = [&](FaceId f) {
    Triangle t = tris[f];
    std::sort(t.begin(), t.end());
    return t;
  };
  std::vector<std::uint32_t> offsets(std::size_t(nv) + 1, 0);
  for (const Triangle& t : tris) ++offsets[std::min({t[0], t[1], t[2]}) + 1];
  for (std::uint32_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  std::vector<FaceId> faces(nf);
  {
    std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (FaceId f = 0; f < nf; ++f) faces[cursor[std::min({tris[f][0], tris[f][1], tris[f][2]})]++] = f;
  }
  std::vector<std::uint8_t> keep(nf, 1);
  duplicates = tbb::parallel_reduce(
      tbb::blocked_range<std::uint32_t>(0, nv, kGrain), std::uint64_t(0),
      [&](const tbb::blocked_range<std::uint32_t>& r, std::uint64_t n) {
        for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
          for (std::uint32_t i = offsets[v]; i < offsets[v + 1]; ++i) {
            const Triangle a = sorted(faces[i]);
            for (std::uint32_t j = offsets[v]; j < i; ++j) {  // faces[] is increasing per group
              if (keep[faces[j]] && sorted(faces[j]) == a) {
                keep[faces[i]] = 0;
                ++n;
                break;
              }
            }
          }
        }
        return n;
      },
      std::plus<>());
  return keep;
}

/// Flips faces so each component is consistently oriented where its edges allow it. Per
/// component, keeps the orientation most of its faces already have. The edges of exactly two
/// faces join the faces with their relation (same direction: one of them flips) in the order of
/// their vertex pairs (smaller vertex, larger vertex, then corner), as the out-of-core cleaning
/// (stream/clean_stream) reads them from its sort; in a non-orientable component the edge closing
/// a loop against the orientation stays a clash. Returns the flips made.
std::uint64_t orientFaces(TriangleMesh& mesh, const detail::VertexCorners& vc) {
  const std::uint32_t nf = mesh.numFaces();
  const auto& tris = mesh.triangles;
  auto vertexOf = [&](CornerId x) { return tris[x / 3][x % 3]; };
  detail::ParityUnionFind faces(nf);
  struct Side {
    VertexId hi;
    CornerId corner;
    bool forward;
    bool operator<(const Side& o) const { return hi != o.hi ? hi < o.hi : corner < o.corner; }
  };
  std::vector<Side> sides;
  for (VertexId lo = 0; lo + 1 < vc.offsets.size(); ++lo) {
    // The sides of the edges (lo, hi > lo): corner p's edge runs lo -> vertex(n), corner n's runs
    // vertex(p) -> lo, for the corners d, n, p of each face at lo.
    sides.clear();
    for (std::uint32_t i = vc.offsets[lo]; i < vc.offsets[lo + 1]; ++i) {
      const CornerId d = vc.corners[i], n = nextCorner(d), p = prevCorner(d);
      if (vertexOf(n) > lo) sides.push_back({vertexOf(n), p, true});
      if (vertexOf(p) > lo) sides.push_back({vertexOf(p), n, false});
    }
    std::sort(sides.begin(), sides.end());
    for (std::size_t i = 0; i < sides.size();) {
      std::size_t j = i + 1;
      while (j < sides.size() && sides[j].hi == sides[i].hi) ++j;
      if (j - i == 2) faces.unite(sides[i].corner / 3, sides[i + 1].corner / 3, sides[i].forward == sides[i + 1].forward);
      i = j;
    }
  }
  const std::vector<std::uint8_t> flip = faces.majorityFlips();
  std::uint64_t flips = 0;
  for (FaceId f = 0; f < nf; ++f) {
    if (!flip[f]) continue;
    ++flips;
    std::swap(mesh.triangles[f][1], mesh.triangles[f][2]);
    if (mesh.hasUV()) mesh.cornerUV.swapCorners(3 * f + 1, 3 * f + 2);
  }
  return flips;
}

/// Pieces of at least this many faces count as large when non-manifold edges are paired.
constexpr std::uint32_t kLargePieceFaces = 1024;

/// Per face, the number of faces of its piece (faces joined by glued edges), capped at
/// kLargePieceFaces.
std::vector<std::uint32_t> cappedPieceSizes(std::size_t numFaces, const std::vector<CornerId>& opposite) {
  detail::UnionFind pieces(numFaces);
  for (CornerId c = 0; c < opposite.size(); ++c) {
    if (opposite[c] != kInvalidId && c < opposite[c]) pieces.unite(c / 3, opposite[c] / 3);
  }
  std::vector<std::uint32_t> size(numFaces, 0);
  for (FaceId f = 0; f < numFaces; ++f) ++size[pieces.find(f)];
  for (FaceId f = 0; f < numFaces; ++f) size[f] = std::min(size[pieces.find(f)], kLargePieceFaces);
  return size;
}

/// On every edge shared by more than two faces (all left unglued by glueEdges), glues pairs of
/// oppositely oriented faces: pairs of two large pieces first (faces joined through the glued
/// edges, kLargePieceFaces), then the flattest pair (most aligned normals). A fin or a small flap
/// on a closed surface then leaves the surface closed and only its own edge open, even when it
/// lies flatter against the surface than the surface's own faces meet (a flap folded onto its
/// face: glued to the far side, the surface would open along the edge and the flap would overlap
/// the face in the map). An edge left open with both sides in one fan of each endpoint would stay
/// shared in the written file (the same vertex ids on both sides) while the map treats it as a
/// boundary. Serial: such edges are rare.
void pairNonManifoldEdges(const TriangleMesh& mesh, const detail::VertexCorners& vc,
                          std::vector<CornerId>& opposite) {
  const std::vector<Triangle>& tris = mesh.triangles;
  auto vertexOf = [&](CornerId x) { return tris[x / 3][x % 3]; };
  auto normalOf = [&](FaceId f) {
    return gluingNormal(mesh.position(tris[f][0]), mesh.position(tris[f][1]), mesh.position(tris[f][2]));
  };
  const std::vector<std::uint32_t> pieceFaces = cappedPieceSizes(tris.size(), opposite);
  std::vector<CornerId> same, reverse;
  for (CornerId c = 0; c < 3 * tris.size(); ++c) {
    if (opposite[c] != kInvalidId) continue;
    const detail::EdgeMatch m = detail::matchEdge(tris, vc, c);
    if (m.sameDirection + m.reverseDirection <= 2 || m.smallestCorner != c) continue;
    // Corners naming the edge a -> b (like c) and b -> a, as matchEdge finds them.
    const VertexId a = vertexOf(nextCorner(c)), b = vertexOf(prevCorner(c));
    same.clear();
    reverse.clear();
    for (std::uint32_t i = vc.offsets[a]; i < vc.offsets[a + 1]; ++i) {
      const CornerId d = vc.corners[i];
      if (vertexOf(nextCorner(d)) == b) same.push_back(prevCorner(d));
      if (vertexOf(prevCorner(d)) == b) reverse.push_back(nextCorner(d));
    }
    struct Pair {
      std::uint32_t smallerPiece;
      double alignment;
      CornerId x, y;
    };
    std::vector<Pair> pairs;
    for (CornerId x : same) {
      for (CornerId y : reverse) {
        pairs.push_back({std::min(pieceFaces[x / 3], pieceFaces[y / 3]),
                         gluingAlignment(normalOf(x / 3), normalOf(y / 3)), x, y});
      }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& p, const Pair& q) {
      if (p.smallerPiece != q.smallerPiece) return p.smallerPiece > q.smallerPiece;
      return p.alignment != q.alignment ? p.alignment > q.alignment : p.x != q.x ? p.x < q.x : p.y < q.y;
    });
    for (const Pair& pair : pairs) {
      if (opposite[pair.x] != kInvalidId || opposite[pair.y] != kInvalidId) continue;
      opposite[pair.x] = pair.y;
      opposite[pair.y] = pair.x;
    }
  }
}

/// Boundary vertices at exactly the position of another boundary vertex of another origin.
std::uint64_t countUnweldedBoundaryVertices(const TriangleMesh& mesh, const Topology& topology,
                                            const std::vector<VertexId>& vertexOrigin) {
  struct Entry {
    Vec3f p;
    VertexId origin;
  };
  std::vector<Entry> boundary;
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    if (topology.vertexCorner(v) != kInvalidId && topology.isBoundaryVertex(v)) {
      boundary.push_back({mesh.positions[v], vertexOrigin[v]});
    }
  }
  const auto key = [](const Entry& e) { return std::make_tuple(e.p.x(), e.p.y(), e.p.z(), e.origin); };
  std::sort(boundary.begin(), boundary.end(), [&](const Entry& a, const Entry& b) { return key(a) < key(b); });
  std::uint64_t count = 0;
  for (std::size_t i = 0; i < boundary.size();) {
    std::size_t j = i + 1;
    while (j < boundary.size() && boundary[j].p == boundary[i].p) ++j;
    if (boundary[j - 1].origin != boundary[i].origin) count += j - i;  // two origins at least
    i = j;
  }
  return count;
}

/// Median of a small list (reorders it): the element at size / 2 sorted; 0 for an empty one. A
/// vertex's few values are sorted by insertion (nth_element's set-up costs more at that size).
double median(std::vector<double>& values) {
  if (values.empty()) return 0.0;
  if (values.size() > 16) {
    auto middle = values.begin() + values.size() / 2;
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
  }
  for (std::size_t i = 1; i < values.size(); ++i) {
    const double x = values[i];
    std::size_t j = i;
    for (; j > 0 && values[j - 1] > x; --j) values[j] = values[j - 1];
    values[j] = x;
  }
  return values[values.size() / 2];
}

/// Calls f(squared length) for every edge at v (the two edges of each corner around it).
/// Around an interior vertex every edge is two corners' edge: each is given once, which leaves
/// the least value and the median (the element at size / 2, sorted) as they were.
template <class F>
void forEachSquaredEdgeLength(const TriangleMesh& mesh, const Topology& topology, VertexId v, F&& f) {
  const Vec3d p = mesh.position(v);
  if (!topology.isBoundaryVertex(v)) {
    topology.forEachCornerAround(v, [&](CornerId c) { f((mesh.position(topology.vertex(nextCorner(c))) - p).squaredNorm()); });
    return;
  }
  topology.forEachCornerAround(v, [&](CornerId c) {
    for (CornerId other : {nextCorner(c), prevCorner(c)}) f((mesh.position(topology.vertex(other)) - p).squaredNorm());
  });
}

}  // namespace

std::vector<VertexId> findSpikeVertices(const TriangleMesh& mesh, const Topology& topology) {
  const std::uint32_t nv = topology.numVertices();
  std::vector<double> shortest(nv, 0.0);  // shortest edge at each vertex
  parallelFor(nv, kGrain, [&](const IndexRange& r) {
    for (VertexId v = r.begin(); v != r.end(); ++v) {
      if (topology.isIsolatedVertex(v)) continue;
      double least = std::numeric_limits<double>::infinity();
      forEachSquaredEdgeLength(mesh, topology, v, [&](double squared) { least = std::min(least, squared); });
      shortest[v] = std::sqrt(least);  // the root is monotone and correctly rounded
    }
  });
  // The median edge length at w (its typical length), only where a vertex needs it.
  const auto typicalAt = [&](VertexId w, std::vector<double>& lengths) {
    lengths.clear();
    forEachSquaredEdgeLength(mesh, topology, w, [&](double squared) { lengths.push_back(squared); });
    return std::sqrt(median(lengths));
  };
  std::vector<std::uint8_t> spike(nv, 0);
  parallelFor(nv, kGrain, [&](const IndexRange& r) {
    std::vector<double> around, lengths;
    for (VertexId v = r.begin(); v != r.end(); ++v) {
      if (topology.isIsolatedVertex(v)) continue;
      // Each neighbour once around an interior vertex (as forEachSquaredEdgeLength's edges).
      const bool interior = !topology.isBoundaryVertex(v);
      const auto forEachNeighbour = [&](auto&& f) {
        topology.forEachCornerAround(v, [&](CornerId c) {
          for (CornerId other : {nextCorner(c), prevCorner(c)}) {
            if (!(interior && other == prevCorner(c))) f(topology.vertex(other));
          }
        });
      };
      // A neighbour's typical length is at least its shortest edge: most vertices are decided
      // by the shortest edges alone, without a median.
      double leastShortest = std::numeric_limits<double>::infinity();
      forEachNeighbour([&](VertexId w) { leastShortest = std::min(leastShortest, shortest[w]); });
      if (!(shortest[v] > kSpikeRatio * leastShortest)) continue;
      around.clear();
      double least = std::numeric_limits<double>::infinity();
      forEachNeighbour([&](VertexId w) {
        around.push_back(typicalAt(w, lengths));
        least = std::min(least, around.back());
      });
      // The median is at least the least value.
      if (!(shortest[v] > kSpikeRatio * least)) continue;
      const double scale = median(around);
      spike[v] = scale > 0.0 && shortest[v] > kSpikeRatio * scale;
    }
  });
  std::vector<VertexId> out;
  for (VertexId v = 0; v < nv; ++v) {
    if (spike[v]) out.push_back(v);
  }
  return out;
}

namespace {

/// 1. Welding (optional) and degenerate faces (a repeated vertex) dropped.
void weldAndDropDegenerateFaces(TriangleMesh& mesh, const CleanOptions& options, std::vector<FaceId>& faceOrigin,
                                CleanReport& report) {
  faceOrigin.resize(mesh.numFaces());
  std::iota(faceOrigin.begin(), faceOrigin.end(), 0u);
  if (options.weldVertices) {
    const std::vector<VertexId> rep = weldMap(mesh.positions, options.weldTolerance);
    for (std::uint32_t v = 0; v < rep.size(); ++v) report.weldedVertices += rep[v] != v;
    parallelForEach(mesh.triangles.size(), 4096, [&](std::uint64_t f) {
      for (VertexId& v : mesh.triangles[f]) v = rep[v];
    });
  }
  std::vector<std::uint8_t> keep(mesh.numFaces());
  parallelForEach(mesh.triangles.size(), 4096, [&](std::uint64_t f) {
    const Triangle& t = mesh.triangles[f];
    keep[f] = t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
  });
  report.degenerateFaces = std::count(keep.begin(), keep.end(), std::uint8_t(0));
  if (report.degenerateFaces) compactFaces(mesh, faceOrigin, keep);
}

/// 3. Unreferenced vertices dropped; vertexOrigin gets the input id of every kept vertex.
void dropUnreferencedVertices(TriangleMesh& mesh, std::vector<VertexId>& vertexOrigin, CleanReport& report) {
  std::vector<VertexId> newId(mesh.numVertices(), kInvalidId);
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) newId[v] = 0;
  }
  std::uint32_t n = 0;
  for (VertexId v = 0; v < newId.size(); ++v) {
    if (newId[v] == kInvalidId) continue;
    newId[v] = n;
    mesh.positions[n] = mesh.positions[v];
    vertexOrigin.push_back(v);
    ++n;
  }
  // The vertices welded at read time are not in the mesh; those welded here still are.
  report.unreferencedVertices = mesh.numVertices() - n - (report.weldedVertices - mesh.weldedAtRead);
  mesh.positions.resize(n);
  mesh.positions.shrink_to_fit();
  parallelForEach(mesh.triangles.size(), 4096, [&](std::uint64_t f) {
    for (VertexId& v : mesh.triangles[f]) v = newId[v];
  });
}

/// True when the faces come in a scattered order: more than half of the faces share no vertex
/// with the face before them (a scan in scanner or grid order: well under a fifth; a subdivided
/// mesh, children together: a fifth; a shuffled or naively merged one: nearly all).
bool scatteredOrder(const TriangleMesh& mesh) {
  const std::size_t nf = mesh.triangles.size();
  const std::uint64_t apart = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(1, std::max<std::size_t>(nf, 1), kGrain), std::uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t n) {
        for (std::size_t f = r.begin(); f != r.end(); ++f) {
          const Triangle& a = mesh.triangles[f - 1];
          const Triangle& b = mesh.triangles[f];
          bool shared = false;
          for (VertexId v : a) shared = shared || v == b[0] || v == b[1] || v == b[2];
          n += !shared;
        }
        return n;
      },
      std::plus<>());
  return 2u * apart > nf;
}

/// True when the faces are in order but the vertex ids are not: more than half of the faces span
/// more than a sixteenth of the ids (a subdivided mesh, new vertices appended level by level:
/// three quarters; a scan in scanner or grid order: well under 1%).
bool scatteredVertexIds(const TriangleMesh& mesh) {
  const std::size_t nf = mesh.triangles.size();
  const std::uint32_t far = std::max<std::uint32_t>(mesh.numVertices() / 16, 1);
  const std::uint64_t spread = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nf, kGrain), std::uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t n) {
        for (std::size_t f = r.begin(); f != r.end(); ++f) {
          const Triangle& t = mesh.triangles[f];
          n += std::max({t[0], t[1], t[2]}) - std::min({t[0], t[1], t[2]}) > far;
        }
        return n;
      },
      std::plus<>());
  return 2u * spread > nf;
}

/// Vertices renumbered in the order the faces first use them (unused ones last, in their order);
/// the faces keep theirs. A vertex's neighbours then have nearby ids: the walks around vertices
/// (smoothing, spikes, wound vertices) read nearby memory. vertexOrigin as in reorderForLocality.
void renumberVerticesByFirstUse(TriangleMesh& mesh, std::vector<VertexId>& vertexOrigin) {
  const std::uint32_t nv = mesh.numVertices();
  std::vector<VertexId> newId(nv, kInvalidId);
  VertexId next = 0;
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) {
      if (newId[v] == kInvalidId) newId[v] = next++;
    }
  }
  for (VertexId v = 0; v < nv; ++v) {
    if (newId[v] == kInvalidId) newId[v] = next++;
  }
  std::vector<Vec3f> positions(nv);
  std::vector<VertexId> origin(nv);
  parallelForEach(nv, kGrain, [&](std::uint64_t v) {
    positions[newId[v]] = mesh.positions[v];
    origin[newId[v]] = vertexOrigin.empty() ? VertexId(v) : vertexOrigin[v];
  });
  mesh.positions = std::move(positions);
  vertexOrigin = std::move(origin);
  parallelForEach(mesh.triangles.size(), kGrain, [&](std::uint64_t f) {
    for (VertexId& v : mesh.triangles[f]) v = newId[v];
  });
}

/// 1b. A large mesh whose order is scattered (scatteredOrder) is put in spatial order: vertices by
///     the Morton code of their position, faces by their first vertex in that order. Every later
///     stage walks neighbours through these arrays; a shuffled 5M-face scan ran 3.4 times slower
///     than the same scan in order. Only a scattered face order counts: on a subdivided scan,
///     whose vertex ids are scattered but faces are not, spatial order gained 5% and the map's
///     flips changed several times over with it, so such meshes keep their order. A mesh with
///     (u, v) keeps its order too. vertexOrigin (empty: the identity) follows the vertices.
///     Returns whether it moved.
bool reorderForLocality(TriangleMesh& mesh, std::uint32_t minFaces, std::vector<VertexId>& vertexOrigin,
                        std::vector<FaceId>& faceOrigin) {
  if (mesh.numFaces() < minFaces || mesh.hasUV() || !scatteredOrder(mesh)) return false;
  const std::uint32_t nv = mesh.numVertices(), nf = mesh.numFaces();
  const BoundingBox box = computeBoundingBox(mesh.positions);
  std::vector<std::pair<std::uint64_t, VertexId>> byCode(nv);
  parallelForEach(nv, kGrain, [&](std::uint64_t v) { byCode[v] = {mortonCode(mesh.positions[v].cast<double>(), box), VertexId(v)}; });
  tbb::parallel_sort(byCode.begin(), byCode.end());
  std::vector<VertexId> newId(nv);
  std::vector<Vec3f> positions(nv);
  std::vector<VertexId> origin(nv);
  parallelForEach(nv, kGrain, [&](std::uint64_t i) {
    const VertexId v = byCode[i].second;
    newId[v] = VertexId(i);
    positions[i] = mesh.positions[v];
    origin[i] = vertexOrigin.empty() ? v : vertexOrigin[v];
  });
  std::vector<std::pair<std::uint64_t, VertexId>>().swap(byCode);
  mesh.positions = std::move(positions);
  vertexOrigin = std::move(origin);
  // Faces by their smallest new vertex id, ties in input order (a counting sort).
  parallelForEach(nf, kGrain, [&](std::uint64_t f) {
    for (VertexId& v : mesh.triangles[f]) v = newId[v];
  });
  std::vector<VertexId>().swap(newId);
  std::vector<std::uint32_t> start(std::size_t(nv) + 1, 0);
  for (const Triangle& t : mesh.triangles) ++start[std::min({t[0], t[1], t[2]}) + 1];
  for (std::uint32_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<Triangle> triangles(nf);
  std::vector<FaceId> faces(nf);
  for (FaceId f = 0; f < nf; ++f) {
    const Triangle& t = mesh.triangles[f];
    const std::uint32_t i = start[std::min({t[0], t[1], t[2]})]++;
    triangles[i] = t;
    faces[i] = faceOrigin[f];
  }
  mesh.triangles = std::move(triangles);
  faceOrigin = std::move(faces);
  return true;
}

/// 4. Orientation and edge gluing: every edge shared by exactly two opposite faces is glued,
///    every other edge becomes boundary (this splits non-manifold edges). Returns opposite.
std::vector<CornerId> orientAndGlueEdges(TriangleMesh& mesh, CleanReport& report) {
  std::vector<CornerId> opposite;
  auto vc = std::make_unique<detail::VertexCorners>(detail::VertexCorners::build(mesh.triangles, mesh.numVertices()));
  detail::GlueStats glue = detail::glueEdges(mesh.triangles, *vc, opposite);
  if (glue.orientationClashes) {
    report.flippedFaces = orientFaces(mesh, *vc);
    if (report.flippedFaces) {
      *vc = detail::VertexCorners::build(mesh.triangles, mesh.numVertices());
      glue = detail::glueEdges(mesh.triangles, *vc, opposite);
    }
  }
  report.nonManifoldEdges = glue.nonManifoldEdges + glue.orientationClashes;
  if (glue.nonManifoldEdges) pairNonManifoldEdges(mesh, *vc, opposite);
  return opposite;
}

/// 5. Non-manifold vertices: every fan beyond the first gets its own copy of the vertex.
///    Returns one corner per vertex (copies included).
std::vector<CornerId> splitNonManifoldVertices(TriangleMesh& mesh, const std::vector<CornerId>& opposite,
                                               std::vector<VertexId>& vertexOrigin, CleanReport& report) {
  const detail::FanTable fans = detail::findFans(mesh.triangles, mesh.numVertices(), opposite);
  const std::uint32_t nv = mesh.numVertices();
  std::vector<CornerId> vertexCorner(fans.fanOffsets.back() , kInvalidId);
  std::vector<VertexId> firstExtra(nv);
  std::uint32_t next = nv;
  for (VertexId v = 0; v < nv; ++v) {
    firstExtra[v] = next;
    next += fans.fanOffsets[v + 1] - fans.fanOffsets[v] - 1;  // every vertex is referenced: >= 1 fan
  }
  report.nonManifoldVertices = 0;
  mesh.positions.resize(next);
  vertexOrigin.resize(next);
  parallelFor(nv, kGrain, [&](const IndexRange& r) {
    for (VertexId v = r.begin(); v != r.end(); ++v) {
      const std::uint32_t begin = fans.fanOffsets[v], end = fans.fanOffsets[v + 1];
      vertexCorner[v] = fans.fanStart[begin];
      for (std::uint32_t i = begin + 1; i < end; ++i) {
        const VertexId copy = firstExtra[v] + (i - begin - 1);
        vertexCorner[copy] = fans.fanStart[i];
        mesh.positions[copy] = mesh.positions[v];
        vertexOrigin[copy] = vertexOrigin[v];
        detail::walkFan(opposite, fans.fanStart[i], [&](CornerId c) { mesh.triangles[c / 3][c % 3] = copy; });
      }
    }
  });
  for (VertexId v = 0; v < nv; ++v) report.nonManifoldVertices += fans.fanOffsets[v + 1] - fans.fanOffsets[v] > 1;
  return vertexCorner;
}

/// 6. Zero-area faces are kept (removing them would open holes) but counted.
std::uint64_t countZeroAreaFaces(const TriangleMesh& mesh) {
  const double diag = computeBoundingBox(mesh.positions).diagonal();
  const double tiny = 1e-14 * diag * diag;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), kGrain), std::uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t n) {
        for (std::size_t f = r.begin(); f != r.end(); ++f) n += faceArea(mesh, FaceId(f)) <= tiny;
        return n;
      },
      std::plus<>());
}

/// Bounding-box diagonal of the vertices that are not spikes (spikes: sorted).
double diagonalWithout(const TriangleMesh& mesh, const std::vector<VertexId>& spikes) {
  BoundingBox box;
  std::size_t next = 0;
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    if (next < spikes.size() && spikes[next] == v) {
      ++next;
      continue;
    }
    const Vec3d p = mesh.positions[v].cast<double>();
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box.isEmpty() ? 0.0 : box.diagonal();
}

}  // namespace

CleanResult cleanMesh(TriangleMesh mesh, const CleanOptions& options) {
  CleanResult result;
  CleanReport& report = result.report;
  report.inputVertices = mesh.numVertices() + mesh.weldedAtRead;
  report.weldedVertices = mesh.weldedAtRead;
  report.inputFaces = mesh.numFaces();
  checkInput(mesh);
  reportProgress(options.progress, "cleaning", 0.0);

  std::vector<FaceId>& faceOrigin = result.faceOrigin;
  weldAndDropDegenerateFaces(mesh, options, faceOrigin, report);
  reportProgress(options.progress, "cleaning", 0.15);

  std::vector<VertexId> inputOrder;  // vertex origins through the reorder, if any
  report.reordered = reorderForLocality(mesh, options.reorderMinFaces, inputOrder, faceOrigin);
  // 1c. Faces in order, vertex ids scattered: only the vertices are renumbered.
  if (!report.reordered && mesh.numFaces() >= options.reorderMinFaces && !mesh.hasUV() && scatteredVertexIds(mesh)) {
    renumberVerticesByFirstUse(mesh, inputOrder);
    report.verticesRenumbered = true;
  }

  // 2. Duplicate faces.
  {
    const std::vector<std::uint8_t> keep = findUniqueFaces(mesh.triangles, mesh.numVertices(), report.duplicateFaces);
    if (report.duplicateFaces) compactFaces(mesh, faceOrigin, keep);
  }
  if (mesh.triangles.empty()) {
    throw InputError("the mesh has no valid faces (" + std::to_string(report.inputFaces) +
                     " faces in the input, all degenerate or duplicates)");
  }
  reportProgress(options.progress, "cleaning", 0.3);

  dropUnreferencedVertices(mesh, result.vertexOrigin, report);
  mesh.weldedAtRead = 0;  // counted: the cleaned mesh is its own input
  if (!inputOrder.empty()) {
    for (VertexId& v : result.vertexOrigin) v = inputOrder[v];
    std::vector<VertexId>().swap(inputOrder);
  }
  reportProgress(options.progress, "cleaning", 0.4);
  std::vector<CornerId> opposite = orientAndGlueEdges(mesh, report);
  reportProgress(options.progress, "cleaning", 0.75);
  std::vector<CornerId> vertexCorner = splitNonManifoldVertices(mesh, opposite, result.vertexOrigin, report);
  reportProgress(options.progress, "cleaning", 0.9);
  report.zeroAreaFaces = countZeroAreaFaces(mesh);

  // Vertex properties follow every output vertex to the input vertex it comes from: a weld keeps
  // the values of the vertex whose position it keeps, a split vertex's copies keep the original's.
  if (!mesh.attributes.empty()) mesh.attributes = mesh.attributes.gathered(result.vertexOrigin);

  report.outputVertices = mesh.numVertices();
  report.outputFaces = mesh.numFaces();
  result.mesh = std::move(mesh);
  result.topology = Topology::viewParts(result.mesh.triangles, std::move(opposite), std::move(vertexCorner));
  report.unweldedBoundaryVertices = countUnweldedBoundaryVertices(result.mesh, result.topology, result.vertexOrigin);
  result.spikes = findSpikeVertices(result.mesh, result.topology);
  report.spikeVertices = result.spikes.size();
  report.diagonalWithoutSpikes = diagonalWithout(result.mesh, result.spikes);
  reportProgress(options.progress, "cleaning", 1.0);
  return result;
}

}  // namespace seamvox
