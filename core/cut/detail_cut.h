#pragma once
/// The cut's steps written once for the in-memory cutToDisk and the out-of-core cut
/// (stream/cut_stream): templates over the corner table (opposite, vertex, forEachCornerAround,
/// isBoundaryVertex) and the per-face, per-corner and per-vertex state, each a vector in memory or
/// a page cache of a scratch file. Conventions: cut.h.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "core/cut/cut.h"
#include "core/mesh/topology.h"
#include "core/system/errors.h"

namespace seamvox::detail {

/// A vector seen as the state the steps take: value = a[i], a.set(i, value).
template <class T>
struct VectorArray {
  std::vector<T>& values;
  T operator[](std::size_t i) const { return values[i]; }
  void set(std::size_t i, T value) { values[i] = value; }
};

/// buildDualTree's default: nothing told of the faces as the tree reaches them.
struct IgnoreReached {
  void operator()(FaceId, std::uint32_t) {}
};

/// Dual spanning tree by BFS per component, roots in face order, neighbours in corner order.
/// Rotation: visited(f), rotation[f], set(f, r): the combing r_g = r_f - matching(c). Component:
/// set(f, id). Cut (every edge cut before): the edges the tree crosses set uncut. reached(f, id)
/// as each face joins (a component's faces before the next's). Returns the number of components.
template <class Table, class Matching, class Rotation, class Component, class Cut, class Reached = IgnoreReached>
std::uint32_t buildDualTree(Table& table, std::uint64_t numFaces, Matching&& matching, Rotation& rotation,
                            Component& component, Cut& cut, Reached&& reached = Reached()) {
  std::deque<FaceId> queue;  // the BFS front only (a surface's front is far smaller than it)
  std::uint32_t numComponents = 0;
  for (FaceId root = 0; root < numFaces; ++root) {
    if (rotation.visited(root)) continue;
    rotation.set(root, 0);
    component.set(root, numComponents);
    reached(root, numComponents);
    queue.push_back(root);
    while (!queue.empty()) {
      const FaceId f = queue.front();
      queue.pop_front();
      const std::uint8_t rf = rotation[f];
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        const CornerId o = table.opposite(c);
        if (o == kInvalidId) continue;
        const FaceId g = cornerFace(o);
        if (rotation.visited(g)) continue;
        rotation.set(g, static_cast<std::uint8_t>((rf + 4 - matching(c)) % 4));
        cut.setCut(c, false);
        cut.setCut(o, false);
        component.set(g, numComponents);
        reached(g, numComponents);
        queue.push_back(g);
      }
    }
    ++numComponents;
  }
  return numComponents;
}

/// The cut edge at v (a corner of a face around v whose edge is cut and touches v), or kInvalidId.
template <class Table, class Cut>
CornerId findCutEdgeAt(Table& table, Cut& cut, VertexId v) {
  CornerId found = kInvalidId;
  table.forEachCornerAround(v, [&](CornerId c) {
    if (found != kInvalidId) return;
    if (cut.isCut(prevCorner(c))) found = prevCorner(c);       // edge v -> vertex(next c)
    else if (cut.isCut(nextCorner(c))) found = nextCorner(c);  // edge vertex(prev c) -> v
  });
  return found;
}

/// How pruneCut finds the one cut edge left at a vertex: by a walk around its fan.
struct WalkForCutEdge {
  template <class Table, class Cut>
  CornerId at(Table& table, Cut& cut, VertexId v) {
    return findCutEdgeAt(table, cut, v);
  }
  void toggle(VertexId, CornerId) {}
};

/// Or by per vertex the XOR of its cut edges' smaller corners (Values: zero before, filled by
/// countCutDegrees): with one cut edge left, that edge, without a walk (the out-of-core cut, whose
/// walks go through page caches).
template <class Values>
struct CutEdgeXor {
  Values& values;
  template <class Table, class Cut>
  CornerId at(Table&, Cut&, VertexId v) {
    return values[v];
  }
  void toggle(VertexId v, CornerId c) { values.set(v, values[v] ^ c); }
};

/// Per vertex (Degree: zero before) the number of cut edges at it, boundary edges included;
/// returns per component its number of cut edges. Edges: told each cut edge's smaller corner at
/// both its ends.
template <class Table, class Cut, class Component, class Degree, class Edges = WalkForCutEdge>
std::vector<std::uint64_t> countCutDegrees(Table& table, std::uint64_t numCorners, Cut& cut, Component& component,
                                           std::uint32_t numComponents, Degree& degree, Edges&& edges = Edges()) {
  std::vector<std::uint64_t> remaining(numComponents, 0);
  for (CornerId c = 0; c < numCorners; ++c) {
    if (!cut.isCut(c)) continue;
    const CornerId o = table.opposite(c);
    if (o != kInvalidId && o < c) continue;
    const VertexId a = table.vertex(nextCorner(c)), b = table.vertex(prevCorner(c));
    degree.set(a, degree[a] + 1);
    degree.set(b, degree[b] + 1);
    edges.toggle(a, c);
    edges.toggle(b, c);
    ++remaining[component[cornerFace(c)]];
  }
  return remaining;
}

/// Removes dangling cut edges (an end of cut-degree 1 that is not a cone), the chains from the
/// highest vertex down; boundary edges stay. A component whose cut would vanish (closed genus 0
/// with at most one cone) keeps one edge, so its cut surface is a disk (the sphere slit along it).
/// Edges: as given to countCutDegrees.
template <class Table, class IsCone, class Component, class Cut, class Degree, class Edges = WalkForCutEdge>
void pruneCut(Table& table, std::uint64_t numVertices, IsCone&& isCone, Component& component,
              std::vector<std::uint64_t>& remaining, Cut& cut, Degree& degree, Edges&& edges = Edges()) {
  for (std::uint64_t top = numVertices; top-- > 0;) {
    VertexId v = static_cast<VertexId>(top);
    while (degree[v] == 1 && !isCone(v)) {
      const CornerId e = edges.at(table, cut, v);
      if (e == kInvalidId || !cut.isCut(e)) break;
      const CornerId o = table.opposite(e);
      if (o == kInvalidId) break;  // boundary edges are never pruned
      std::uint64_t& left = remaining[component[cornerFace(e)]];
      if (left == 1) break;
      --left;
      cut.setCut(e, false);
      cut.setCut(o, false);
      const VertexId a = table.vertex(nextCorner(e)), b = table.vertex(prevCorner(e));
      const VertexId w = a == v ? b : a;
      degree.set(v, degree[v] - 1);
      degree.set(w, degree[w] - 1);
      edges.toggle(v, std::min(e, o));
      edges.toggle(w, std::min(e, o));
      v = w;
    }
  }
}

/// Combed matching k + r_g - r_f of every corner, in corner order (field.h, cut.h): zero across
/// every tree edge, 0 on the boundary. out(c, isCut, k). TopologyError when a rotation is left on
/// a pruned edge (a cone missing from the singularities).
template <class Table, class Matching, class Rotation, class Cut, class Out>
void combCorners(Table& table, std::uint64_t numCorners, Matching&& matching, Rotation& rotation, Cut& cut, Out&& out) {
  for (CornerId c = 0; c < numCorners; ++c) {
    const CornerId o = table.opposite(c);
    const bool isCut = cut.isCut(c);
    std::uint8_t k = 0;
    if (o != kInvalidId) {
      k = static_cast<std::uint8_t>((matching(c) + rotation[cornerFace(o)] + 4 - rotation[cornerFace(c)]) % 4);
      if (k != 0 && !isCut) {
        throw TopologyError("cutToDisk: the matchings around vertex " + std::to_string(table.vertex(nextCorner(c))) +
                            " or " + std::to_string(table.vertex(prevCorner(c))) +
                            " do not agree with the singularities (a cone is missing)");
      }
    }
    out(c, isCut, k);
  }
}

/// Traces one seam curve starting with the edge of corner first (its face on the left), along
/// cut interior edges through non-node vertices, until a node or the start vertex again. Marks
/// the corners of the traced edges (both sides): traced[c], traced.set(c, 1).
template <class Table, class IsNode, class Traced, class Cut>
void traceSeam(Table& table, CornerId first, IsNode&& isNode, Traced& traced, Cut& cut, std::vector<SeamCurve>& seams) {
  const std::uint32_t id = static_cast<std::uint32_t>(seams.size());
  SeamCurve seam;
  seam.start = table.vertex(nextCorner(first));
  seam.matching = cut.matching(first);
  CornerId c = first;
  while (true) {
    if (cut.matching(c) != seam.matching) {
      throw TopologyError("cutToDisk: seam " + std::to_string(id) + " changes rotation at vertex " +
                          std::to_string(table.vertex(nextCorner(c))) + " (a cone missing from the singularities?)");
    }
    seam.corners.push_back(c);
    traced.set(c, 1);
    traced.set(table.opposite(c), 1);
    const VertexId w = table.vertex(prevCorner(c));
    if (isNode(w) || w == seam.start) {
      seam.end = w;
      break;
    }
    // w has exactly two cut edges, both interior: continue on the untraced one, leaving w.
    CornerId next = kInvalidId;
    table.forEachCornerAround(w, [&](CornerId k) {
      const CornerId out = prevCorner(k);
      if (next == kInvalidId && cut.isCut(out) && !traced[out]) next = out;
    });
    if (next == kInvalidId || table.opposite(next) == kInvalidId) {
      throw TopologyError("cutToDisk: seam " + std::to_string(id) + " breaks off at vertex " + std::to_string(w));
    }
    c = next;
  }
  seams.push_back(std::move(seam));
}

/// Seam curves: first the chains that start at a node (vertices in order, their fans
/// counter-clockwise), then closed loops without one (corners in order).
template <class Table, class IsNode, class Degree, class Traced, class Cut>
void traceSeams(Table& table, std::uint64_t numVertices, std::uint64_t numCorners, IsNode&& isNode, Degree& degree,
                Traced& traced, Cut& cut, std::vector<SeamCurve>& seams) {
  auto startsSeam = [&](CornerId c) { return cut.isCut(c) && table.opposite(c) != kInvalidId && !traced[c]; };
  for (VertexId v = 0; v < numVertices; ++v) {
    if (degree[v] == 0 || !isNode(v)) continue;
    table.forEachCornerAround(v, [&](CornerId k) {
      const CornerId out = prevCorner(k);  // edge v -> vertex(next k), face(k) on its left
      if (startsSeam(out)) traceSeam(table, out, isNode, traced, cut, seams);
    });
  }
  for (CornerId c = 0; c < numCorners; ++c) {
    if (startsSeam(c)) traceSeam(table, c, isNode, traced, cut, seams);
  }
}

}  // namespace seamvox::detail
