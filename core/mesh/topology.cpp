#include "core/mesh/topology.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <string>

#include "core/mesh/detail_corner_table.h"
#include "core/mesh/detail_union_find.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace detail {

VertexCorners VertexCorners::build(const std::vector<Triangle>& triangles, std::uint32_t numVertices) {
  VertexCorners vc;
  vc.offsets.assign(std::size_t(numVertices) + 1, 0);
  for (const Triangle& t : triangles) {
    for (VertexId v : t) ++vc.offsets[v + 1];
  }
  for (std::size_t v = 0; v < numVertices; ++v) vc.offsets[v + 1] += vc.offsets[v];
  vc.corners.resize(triangles.size() * 3);
  std::vector<std::uint32_t> cursor(vc.offsets.begin(), vc.offsets.end() - 1);
  const std::size_t numCorners = triangles.size() * 3;
  for (std::size_t c = 0; c < numCorners; ++c) {
    vc.corners[cursor[triangles[c / 3][c % 3]]++] = static_cast<CornerId>(c);
  }
  return vc;
}

EdgeMatch matchEdge(const std::vector<Triangle>& tris, const VertexCorners& vc, CornerId c) {
  auto vertexOf = [&](CornerId x) { return tris[x / 3][x % 3]; };
  const VertexId a = vertexOf(nextCorner(c)), b = vertexOf(prevCorner(c));
  EdgeMatch m;
  m.smallestCorner = c;
  for (std::uint32_t i = vc.offsets[a], end = vc.offsets[a + 1]; i < end; ++i) {
    const CornerId d = vc.corners[i];
    if (vertexOf(nextCorner(d)) == b) {  // face of d traverses a -> b: edge named by prev(d)
      ++m.sameDirection;
      const CornerId named = prevCorner(d);
      if (named != c) m.sameCorner = named;
      m.smallestCorner = std::min(m.smallestCorner, named);
    }
    if (vertexOf(prevCorner(d)) == b) {  // face of d traverses b -> a: edge named by next(d)
      ++m.reverseDirection;
      m.reverseCorner = nextCorner(d);
      m.smallestCorner = std::min(m.smallestCorner, m.reverseCorner);
    }
  }
  return m;
}

GlueStats glueEdges(const std::vector<Triangle>& tris, const VertexCorners& vc,
                    std::vector<CornerId>& opposite) {
  const std::size_t numCorners = tris.size() * 3;
  opposite.assign(numCorners, kInvalidId);
  auto vertexOf = [&](CornerId x) { return tris[x / 3][x % 3]; };
  struct Acc {
    std::uint64_t nonManifold = 0, clashes = 0;
    CornerId first = kInvalidId;
  };
  auto countProblem = [](const EdgeMatch& m, CornerId c, Acc& acc) {
    const std::uint32_t faces = m.sameDirection + m.reverseDirection;
    if (faces <= 1 || m.smallestCorner != c) return;  // boundary, or counted at another corner
    if (faces > 2) {
      ++acc.nonManifold;
    } else {
      ++acc.clashes;
    }
    acc.first = std::min(acc.first, c);
  };
  auto join = [](Acc x, const Acc& y) {
    x.nonManifold += y.nonManifold;
    x.clashes += y.clashes;
    x.first = std::min(x.first, y.first);
    return x;
  };
  // Pass 1: corners whose edge runs from a smaller to a larger vertex id scan the edge and glue
  // both sides, so each manifold edge is looked up once and no two threads write one entry.
  Acc total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, numCorners, 4096), Acc{},
      [&](const tbb::blocked_range<std::size_t>& r, Acc acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const CornerId c = static_cast<CornerId>(i);
          if (vertexOf(nextCorner(c)) > vertexOf(prevCorner(c))) continue;
          const EdgeMatch m = matchEdge(tris, vc, c);
          if (m.isManifold()) {
            opposite[c] = m.reverseCorner;
            opposite[m.reverseCorner] = c;
          } else {
            countProblem(m, c, acc);
          }
        }
        return acc;
      },
      join);
  // Pass 2: the other corners that pass 1 left unglued (boundary or non-manifold edges: rare).
  total = join(total, tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, numCorners, 4096), Acc{},
      [&](const tbb::blocked_range<std::size_t>& r, Acc acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const CornerId c = static_cast<CornerId>(i);
          if (opposite[c] != kInvalidId || vertexOf(nextCorner(c)) < vertexOf(prevCorner(c))) continue;
          countProblem(matchEdge(tris, vc, c), c, acc);
        }
        return acc;
      },
      join));
  return {total.nonManifold, total.clashes, total.first};
}

FanTable findFans(const std::vector<Triangle>& tris, std::uint32_t numVertices,
                  const std::vector<CornerId>& opposite) {
  const std::size_t numCorners = tris.size() * 3;
  auto vertexOf = [&](CornerId x) { return tris[x / 3][x % 3]; };
  // Most clockwise corner of the fan through d (d itself when the fan is closed).
  auto mostClockwise = [&](CornerId d) {
    CornerId s = d;
    for (;;) {
      const CornerId o = opposite[prevCorner(s)];
      if (o == kInvalidId) return s;
      const CornerId cwCorner = prevCorner(o);
      if (cwCorner == d) return d;
      s = cwCorner;
    }
  };
  std::vector<std::uint32_t> count(numVertices, 0);
  std::vector<CornerId> start(numVertices, kInvalidId);
  for (std::size_t c = 0; c < numCorners; ++c) {
    const VertexId v = vertexOf(CornerId(c));
    ++count[v];
    start[v] = CornerId(c);
  }
  // One walk per vertex; a fan that reaches all corners of its vertex is the only one.
  std::vector<std::uint8_t> several(numVertices, 0);
  parallelFor(numVertices, 2048, [&](const IndexRange& r) {
                      for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
                        if (!count[v]) continue;
                        const CornerId s = mostClockwise(start[v]);
                        std::uint32_t n = 0;
                        walkFan(opposite, s, [&](CornerId) { ++n; });
                        start[v] = s;
                        several[v] = n != count[v];
                      }
                    });
  // Vertices with several fans: gather their corners and walk every fan.
  std::vector<VertexId> multi;
  for (VertexId v = 0; v < numVertices; ++v) {
    if (several[v]) multi.push_back(v);
  }
  std::vector<std::vector<CornerId>> multiStarts(multi.size());
  if (!multi.empty()) {
    std::vector<std::uint32_t> slot(numVertices, kInvalidId);
    for (std::uint32_t i = 0; i < multi.size(); ++i) slot[multi[i]] = i;
    std::vector<std::vector<CornerId>> corners(multi.size());
    for (std::size_t c = 0; c < numCorners; ++c) {
      const std::uint32_t i = slot[vertexOf(CornerId(c))];
      if (i != kInvalidId) corners[i].push_back(CornerId(c));
    }
    for (std::uint32_t i = 0; i < multi.size(); ++i) {
      std::vector<CornerId>& mine = corners[i];
      std::vector<std::uint8_t> seen(mine.size(), 0);
      auto indexOf = [&](CornerId c) {
        return std::size_t(std::lower_bound(mine.begin(), mine.end(), c) - mine.begin());
      };
      for (std::size_t k = 0; k < mine.size(); ++k) {
        if (seen[k]) continue;
        const CornerId s = mostClockwise(mine[k]);
        walkFan(opposite, s, [&](CornerId c) { seen[indexOf(c)] = 1; });
        multiStarts[i].push_back(s);
      }
    }
  }
  FanTable fans;
  fans.fanOffsets.assign(std::size_t(numVertices) + 1, 0);
  for (std::uint32_t v = 0; v < numVertices; ++v) fans.fanOffsets[v + 1] = count[v] ? 1 : 0;
  for (std::uint32_t i = 0; i < multi.size(); ++i) {
    fans.fanOffsets[multi[i] + 1] = static_cast<std::uint32_t>(multiStarts[i].size());
  }
  for (std::uint32_t v = 0; v < numVertices; ++v) fans.fanOffsets[v + 1] += fans.fanOffsets[v];
  fans.fanStart.resize(fans.fanOffsets[numVertices]);
  for (std::uint32_t v = 0; v < numVertices; ++v) {
    if (count[v]) fans.fanStart[fans.fanOffsets[v]] = start[v];
  }
  for (std::uint32_t i = 0; i < multi.size(); ++i) {
    std::copy(multiStarts[i].begin(), multiStarts[i].end(), fans.fanStart.begin() + fans.fanOffsets[multi[i]]);
  }
  return fans;
}

}  // namespace detail

namespace {

std::string faceText(CornerId c) {
  return "face " + std::to_string(c / 3) + " (corner " + std::to_string(c % 3) + ")";
}

}  // namespace

Topology Topology::build(std::vector<Triangle> triangles, std::uint32_t numVertices) {
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    for (VertexId v : t) {
      if (v >= numVertices) {
        throw TopologyError("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                            " but the mesh has " + std::to_string(numVertices) + " vertices");
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw TopologyError("face " + std::to_string(f) +
                          " is degenerate (repeats a vertex); clean the mesh first");
    }
  }
  const detail::VertexCorners vc = detail::VertexCorners::build(triangles, numVertices);
  std::vector<CornerId> opposite;
  const detail::GlueStats glue = detail::glueEdges(triangles, vc, opposite);
  if (glue.nonManifoldEdges || glue.orientationClashes) {
    throw TopologyError("the mesh is not an oriented manifold: " +
                        std::to_string(glue.nonManifoldEdges) + " edges shared by more than two faces, " +
                        std::to_string(glue.orientationClashes) +
                        " edges traversed twice in the same direction (first at " +
                        faceText(glue.firstProblem) + "); clean the mesh first");
  }
  const detail::FanTable fans = detail::findFans(triangles, numVertices, opposite);
  std::vector<CornerId> vertexCorner(numVertices, kInvalidId);
  for (std::uint32_t v = 0; v < numVertices; ++v) {
    const std::uint32_t n = fans.fanOffsets[v + 1] - fans.fanOffsets[v];
    if (n > 1) {
      throw TopologyError("vertex " + std::to_string(v) + " is non-manifold (its faces form " +
                          std::to_string(n) + " separate fans); clean the mesh first");
    }
    if (n == 1) vertexCorner[v] = fans.fanStart[fans.fanOffsets[v]];
  }
  return fromParts(std::move(triangles), std::move(opposite), std::move(vertexCorner));
}

Topology Topology::fromParts(std::vector<Triangle> triangles, std::vector<CornerId> opposite,
                             std::vector<CornerId> vertexCorner) {
  Topology t = viewParts(triangles, std::move(opposite), std::move(vertexCorner));
  t.owned_ = std::move(triangles);  // the buffer moves with the vector: the view stays valid
  return t;
}

Topology Topology::viewParts(const std::vector<Triangle>& triangles, std::vector<CornerId> opposite,
                             std::vector<CornerId> vertexCorner) {
  if (opposite.size() != triangles.size() * 3) {
    throw TopologyError("corner table: opposite has " + std::to_string(opposite.size()) +
                        " entries for " + std::to_string(triangles.size()) + " faces");
  }
  Topology t;
  t.tris_ = triangles.data();
  t.numFaces_ = static_cast<std::uint32_t>(triangles.size());
  t.opposite_ = std::move(opposite);
  t.vertexCorner_ = std::move(vertexCorner);
  return t;
}

Topology::Topology(const Topology& other)
    : owned_(other.owned_),
      tris_(other.owned_.empty() ? other.tris_ : owned_.data()),
      numFaces_(other.numFaces_),
      opposite_(other.opposite_),
      vertexCorner_(other.vertexCorner_) {}

Topology& Topology::operator=(const Topology& other) {
  if (this != &other) *this = Topology(other);
  return *this;
}

namespace {

/// Grows a vector to n elements with an exact allocation (resize would double a large array).
template <class T>
void growExactly(std::vector<T>& v, std::size_t n, const T& fill) {
  if (n > v.capacity()) v.reserve(n);
  v.resize(n, fill);
}

}  // namespace

std::vector<std::pair<VertexId, CornerId>> Topology::extend(const std::vector<Triangle>& triangles,
                                                            std::uint32_t numVertices,
                                                            const std::vector<std::pair<CornerId, CornerId>>& glued) {
  const CornerId oldCorners = numCorners();
  const VertexId oldVertices = this->numVertices();
  if (owned_.empty()) {
    tris_ = triangles.data();
  } else {
    owned_ = triangles;
    tris_ = owned_.data();
  }
  numFaces_ = static_cast<std::uint32_t>(triangles.size());
  growExactly(opposite_, std::size_t(numCorners()), kInvalidId);
  growExactly(vertexCorner_, std::size_t(numVertices), kInvalidId);
  for (const auto& [a, b] : glued) {
    opposite_[a] = b;
    opposite_[b] = a;
  }
  // One corner per vertex of the new faces; its fan start as build() picks it: the most clockwise
  // corner of an open fan, the largest corner of a closed one.
  std::vector<std::pair<VertexId, CornerId>> at;
  for (CornerId c = oldCorners; c < numCorners(); ++c) at.push_back({vertex(c), c});
  std::sort(at.begin(), at.end());
  at.erase(std::unique(at.begin(), at.end(), [](const auto& x, const auto& y) { return x.first == y.first; }), at.end());
  std::vector<std::pair<VertexId, CornerId>> before;
  for (const auto& [v, c0] : at) {
    if (v < oldVertices) before.push_back({v, vertexCorner_[v]});
    CornerId s = c0;
    bool closed = false;
    for (;;) {
      const CornerId o = opposite_[prevCorner(s)];
      if (o == kInvalidId) break;
      if (prevCorner(o) == c0) {
        closed = true;
        break;
      }
      s = prevCorner(o);
    }
    if (closed) {
      CornerId c = c0;
      do {
        s = std::max(s, c);
        c = ccw(c);
      } while (c != c0);
    }
    vertexCorner_[v] = s;
  }
  return before;
}

void Topology::shrink(const std::vector<Triangle>& triangles, std::uint32_t faces, std::uint32_t vertices,
                      const std::vector<std::pair<VertexId, CornerId>>& starts) {
  const CornerId kept = 3 * faces;
  for (CornerId c = kept; c < numCorners(); ++c) {
    if (opposite_[c] != kInvalidId && opposite_[c] < kept) opposite_[opposite_[c]] = kInvalidId;
  }
  opposite_.resize(kept);
  vertexCorner_.resize(vertices);
  for (const auto& [v, c] : starts) vertexCorner_[v] = c;
  if (owned_.empty()) {
    tris_ = triangles.data();
  } else {
    owned_.resize(faces);
    tris_ = owned_.data();
  }
  numFaces_ = faces;
}

CornerId nextBoundaryCorner(const Topology& topology, CornerId c, std::vector<CornerId>* crossed) {
  CornerId around = prevCorner(c);  // at vertex(prev c) in the current face
  while (!topology.isBoundaryEdge(prevCorner(around))) {
    const CornerId edge = prevCorner(around);
    if (crossed) crossed->push_back(edge);
    around = prevCorner(topology.opposite(edge));
  }
  return prevCorner(around);
}

std::uint32_t Topology::valence(VertexId v) const {
  std::uint32_t n = 0;
  forEachCornerAround(v, [&](CornerId) { ++n; });
  return n;
}

std::size_t Topology::memoryBytes() const {
  return owned_.capacity() * sizeof(Triangle) + opposite_.capacity() * sizeof(CornerId) +
         vertexCorner_.capacity() * sizeof(CornerId);
}

void Topology::validate() const {
  const std::uint32_t nv = numVertices(), nc = numCorners();
  auto fail = [](const std::string& what) { throw TopologyError("corner table invalid: " + what); };
  std::vector<std::uint32_t> cornersAt(nv, 0);
  for (CornerId c = 0; c < nc; ++c) {
    const VertexId v = vertex(c);
    if (v >= nv) fail(faceText(c) + " refers to vertex " + std::to_string(v) + " >= #V");
    ++cornersAt[v];
    if (v == vertex(nextCorner(c))) fail(faceText(c) + " is degenerate");
    const CornerId o = opposite_[c];
    if (o == kInvalidId) continue;
    if (o >= nc) fail(faceText(c) + " has opposite corner " + std::to_string(o) + " out of range");
    if (o / 3 == c / 3) fail(faceText(c) + " is opposite to a corner of its own face");
    if (opposite_[o] != c) fail(faceText(c) + ": opposite(opposite(c)) != c");
    if (vertex(nextCorner(c)) != vertex(prevCorner(o)) || vertex(prevCorner(c)) != vertex(nextCorner(o))) {
      fail(faceText(c) + " and its opposite corner do not share the edge reversed");
    }
  }
  for (VertexId v = 0; v < nv; ++v) {
    const CornerId start = vertexCorner_[v];
    if (start == kInvalidId) {
      if (cornersAt[v]) fail("vertex " + std::to_string(v) + " has faces but no start corner");
      continue;
    }
    if (start >= nc || vertex(start) != v) fail("vertexCorner of vertex " + std::to_string(v) + " is not at it");
    std::uint32_t n = 0;
    forEachCornerAround(v, [&](CornerId c) {
      if (vertex(c) != v) fail("fan walk around vertex " + std::to_string(v) + " left the vertex");
      if (++n > cornersAt[v]) fail("fan walk around vertex " + std::to_string(v) + " does not close");
    });
    if (n != cornersAt[v]) {
      fail("vertex " + std::to_string(v) + " has " + std::to_string(cornersAt[v]) +
           " corners but its fan reaches " + std::to_string(n) + " (non-manifold or bad start)");
    }
  }
}

namespace {

/// Per face, the smallest face of its component (faces joined across interior edges).
std::vector<FaceId> smallestFaceOfComponents(const Topology& topology) {
  return detail::smallestFaceOfSets(topology, [](FaceId, FaceId) { return true; });
}

}  // namespace

ComponentsResult computeComponents(const Topology& topology) {
  const std::uint32_t nf = topology.numFaces(), nv = topology.numVertices();
  ComponentsResult result;
  // Components numbered in the order of their smallest face (as a search seeded at the first
  // face not reached yet numbers them), then sorted by size below.
  result.faceComponent = smallestFaceOfComponents(topology);
  std::vector<FaceId>& component = result.faceComponent;
  std::vector<ComponentInfo> comps;
  // In face order a face's root (a smaller face, or itself) is reached first: its entry holds
  // the component's id by then.
  for (FaceId f = 0; f < nf; ++f) {
    if (component[f] == f) {
      component[f] = static_cast<std::uint32_t>(comps.size());
      comps.emplace_back();
    } else {
      component[f] = component[component[f]];
    }
  }
  // Faces, vertices and edges counted by both cores; a block adds runs of one component at once
  // (ids vary slowly along a mesh in locality order; one big component would serialise adds).
  const auto addRuns = [&](std::uint64_t begin, std::uint64_t end, auto&& componentOf, auto&& field) {
    std::uint32_t current = kInvalidId;
    std::uint64_t run = 0;
    const auto flush = [&] {
      if (run) __atomic_fetch_add(&field(comps[current]), decltype(field(comps[current]))(run), __ATOMIC_RELAXED);
      run = 0;
    };
    for (std::uint64_t i = begin; i < end; ++i) {
      const std::uint32_t k = componentOf(i);
      if (k == kInvalidId) continue;
      if (k != current) flush(), current = k;
      ++run;
    }
    flush();
  };
  parallelFor(nf, 1u << 16, [&](const IndexRange& r) {
    addRuns(r.begin(), r.end(), [&](std::uint64_t f) { return component[f]; },
            [](ComponentInfo& info) -> std::uint32_t& { return info.faces; });
  });
  parallelFor(nv, 1u << 16, [&](const IndexRange& r) {
    addRuns(r.begin(), r.end(), [&](std::uint64_t v) {
              const CornerId c = topology.vertexCorner(static_cast<VertexId>(v));
              return c == kInvalidId ? kInvalidId : component[c / 3];
            },
            [](ComponentInfo& info) -> std::uint32_t& { return info.vertices; });
  });
  // Each interior edge at its smaller corner, each boundary edge at its corner; the boundary
  // corners listed in increasing order (blocks in order) for the loops below.
  std::vector<std::vector<CornerId>> boundaryOfBlock((topology.numCorners() + (1u << 16) - 1) >> 16);
  parallelForEach(boundaryOfBlock.size(), 1, [&](std::uint64_t block) {
    const std::uint64_t begin = block << 16, end = std::min<std::uint64_t>(topology.numCorners(), (block + 1) << 16);
    addRuns(begin, end, [&](std::uint64_t i) {
              const CornerId c = static_cast<CornerId>(i), o = topology.opposite(c);
              if (o == kInvalidId) boundaryOfBlock[block].push_back(c);
              return o == kInvalidId || c < o ? component[c / 3] : kInvalidId;
            },
            [](ComponentInfo& info) -> std::uint64_t& { return info.edges; });
  });
  std::vector<std::uint8_t> seen;
  for (const std::vector<CornerId>& boundary : boundaryOfBlock) {
    if (!boundary.empty() && seen.empty()) seen.assign(topology.numCorners(), 0);
    for (const CornerId c : boundary) {
      if (seen[c]) continue;
      // Trace the boundary loop through c: the next boundary edge starts where this one ends.
      ++comps[component[c / 3]].boundaryLoops;
      CornerId b = c;
      do {
        seen[b] = 1;
        const VertexId end = topology.vertex(prevCorner(b));
        b = prevCorner(topology.vertexCorner(end));
      } while (b != c && !seen[b]);
    }
  }
  for (ComponentInfo& info : comps) {
    info.eulerCharacteristic = std::int64_t(info.vertices) - std::int64_t(info.edges) + info.faces;
    info.genus = (2 - info.eulerCharacteristic - info.boundaryLoops) / 2;
    result.boundaryLoops += info.boundaryLoops;
  }
  // Sort by decreasing size and renumber faceComponent accordingly.
  std::vector<std::uint32_t> order(comps.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return comps[a].faces > comps[b].faces; });
  std::vector<std::uint32_t> rank(comps.size());
  result.components.resize(comps.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = i;
    result.components[i] = comps[order[i]];
  }
  for (auto& id : result.faceComponent) id = rank[id];
  return result;
}

}  // namespace seamvox
