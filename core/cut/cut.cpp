// Cut graph, combing and seam curves (DESIGN section 5). Conventions: core/cut/cut.h.
#include "core/cut/cut.h"

#include <algorithm>
#include <deque>
#include <string>

#include "core/system/errors.h"

namespace seamvox {

namespace {

/// The cut edge at v (a corner of a face around v whose edge is cut and touches v), or kInvalidId.
CornerId findCutEdgeAt(const Topology& topology, const CutCorners& corners, VertexId v) {
  CornerId found = kInvalidId;
  topology.forEachCornerAround(v, [&](CornerId c) {
    if (found != kInvalidId) return;
    if (corners.isCut(prevCorner(c))) found = prevCorner(c);       // edge v -> vertex(next c)
    else if (corners.isCut(nextCorner(c))) found = nextCorner(c);  // edge vertex(prev c) -> v
  });
  return found;
}

/// Dual spanning tree by BFS per component. Fills the cut flags (every edge not crossed by the
/// tree, boundary included), faceRotation (combing: r_g = r_f - matching) and the component of
/// each face; returns the number of components.
std::uint32_t buildDualTree(const Topology& topology, const FieldSingularities& singularities,
                            CutResult& cut, std::vector<std::uint32_t>& faceComponent) {
  const std::uint32_t numFaces = topology.numFaces();
  constexpr std::uint8_t kUnvisited = 0xff;
  cut.corners = CutCorners(3 * std::size_t(numFaces), true);
  cut.faceRotation.assign(numFaces, kUnvisited);
  faceComponent.assign(numFaces, kInvalidId);
  std::deque<FaceId> queue;  // the BFS front only (a surface's front is far smaller than it)
  std::uint32_t numComponents = 0;
  const auto visit = [&](FaceId f) {
    faceComponent[f] = numComponents;
    queue.push_back(f);
  };
  for (FaceId root = 0; root < numFaces; ++root) {
    if (cut.faceRotation[root] != kUnvisited) continue;
    cut.faceRotation[root] = 0;
    visit(root);
    while (!queue.empty()) {
      const FaceId f = queue.front();
      queue.pop_front();
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        const CornerId o = topology.opposite(c);
        if (o == kInvalidId) continue;
        const FaceId g = cornerFace(o);
        if (cut.faceRotation[g] != kUnvisited) continue;
        cut.faceRotation[g] = static_cast<std::uint8_t>((cut.faceRotation[f] + 4 - singularities.matching[c]) % 4);
        cut.corners.setCut(c, false);
        cut.corners.setCut(o, false);
        visit(g);
      }
    }
    ++numComponents;
  }
  return numComponents;
}

/// Removes dangling cut edges (an end of cut-degree 1 that is not a cone); boundary edges stay.
/// A component whose cut would vanish (closed genus 0 with at most one cone) keeps one edge, so
/// its cut surface is a disk (the sphere slit along that edge). Returns the cut-degree per vertex.
std::vector<std::uint32_t> pruneCut(const Topology& topology, const std::vector<std::uint8_t>& isCone,
                                    const std::vector<std::uint32_t>& faceComponent,
                                    std::uint32_t numComponents, CutCorners& corners) {
  const std::uint32_t numVertices = topology.numVertices();
  std::vector<std::uint32_t> degree(numVertices, 0);
  std::vector<std::uint64_t> remaining(numComponents, 0);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (!corners.isCut(c) || (o != kInvalidId && o < c)) continue;
    ++degree[topology.vertex(nextCorner(c))];
    ++degree[topology.vertex(prevCorner(c))];
    ++remaining[faceComponent[cornerFace(c)]];
  }
  std::vector<VertexId> stack;
  for (VertexId v = 0; v < numVertices; ++v) {
    if (degree[v] == 1 && !isCone[v]) stack.push_back(v);
  }
  while (!stack.empty()) {
    const VertexId v = stack.back();
    stack.pop_back();
    if (degree[v] != 1) continue;
    const CornerId e = findCutEdgeAt(topology, corners, v);
    const CornerId o = topology.opposite(e);
    if (e == kInvalidId || o == kInvalidId) continue;  // boundary edges are never pruned
    std::uint64_t& left = remaining[faceComponent[cornerFace(e)]];
    if (left == 1) continue;
    --left;
    corners.setCut(e, false);
    corners.setCut(o, false);
    const VertexId a = topology.vertex(nextCorner(e)), b = topology.vertex(prevCorner(e));
    const VertexId w = a == v ? b : a;
    --degree[v];
    if (--degree[w] == 1 && !isCone[w]) stack.push_back(w);
  }
  return degree;
}

/// Traces one seam curve starting with the edge of corner first (its face on the left), along
/// cut interior edges through non-node vertices, until a node or the start vertex again.
/// Marks the corners of the traced edge (both sides) in traced.
void traceSeam(const Topology& topology, CornerId first, const std::vector<std::uint8_t>& isNode,
               std::vector<bool>& traced, CutResult& cut) {
  const std::uint32_t id = static_cast<std::uint32_t>(cut.seams.size());
  SeamCurve seam;
  seam.start = topology.vertex(nextCorner(first));
  seam.matching = cut.corners.matching(first);
  CornerId c = first;
  while (true) {
    if (cut.corners.matching(c) != seam.matching) {
      throw TopologyError("cutToDisk: seam " + std::to_string(id) + " changes rotation at vertex " +
                          std::to_string(topology.vertex(nextCorner(c))) +
                          " (a cone missing from the singularities?)");
    }
    seam.corners.push_back(c);
    traced[c] = traced[topology.opposite(c)] = true;
    const VertexId w = topology.vertex(prevCorner(c));
    if (isNode[w] || w == seam.start) {
      seam.end = w;
      break;
    }
    // w has exactly two cut edges, both interior: continue on the unvisited one, leaving w.
    CornerId next = kInvalidId;
    topology.forEachCornerAround(w, [&](CornerId k) {
      const CornerId out = prevCorner(k);
      if (next == kInvalidId && cut.corners.isCut(out) && !traced[out]) next = out;
    });
    if (next == kInvalidId || topology.opposite(next) == kInvalidId) {
      throw TopologyError("cutToDisk: seam " + std::to_string(id) + " breaks off at vertex " +
                          std::to_string(w));
    }
    c = next;
  }
  cut.seams.push_back(std::move(seam));
}

}  // namespace

CutResult cutToDisk(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                    const FieldSingularities& singularities, const CutOptions& options) {
  const std::uint32_t numFaces = topology.numFaces(), numVertices = topology.numVertices();
  if (singularities.matching.size() != 3 * std::size_t(numFaces) ||
      singularities.index4.size() != numVertices || field.direction.size() != numFaces) {
    throw InputError("cutToDisk: field/singularities do not match the mesh (" +
                     std::to_string(numFaces) + " faces, " + std::to_string(numVertices) +
                     " vertices)");
  }
  CutResult cut;
  std::vector<std::uint8_t> isCone(numVertices, 0);
  for (VertexId v : singularities.cones) {
    if (v >= numVertices) throw InputError("cutToDisk: cone vertex " + std::to_string(v) + " out of range");
    isCone[v] = 1;
  }
  cut.cones = singularities.cones;

  reportProgress(options.progress, "cut: dual tree", 0.0);
  std::vector<std::uint32_t> faceComponent;
  const std::uint32_t numComponents = buildDualTree(topology, singularities, cut, faceComponent);
  reportProgress(options.progress, "cut: prune", 0.3);
  const std::vector<std::uint32_t> degree =
      pruneCut(topology, isCone, faceComponent, numComponents, cut.corners);

  // Combed matching k + r_g - r_f (field.h, cut.h): zero across every tree edge.
  reportProgress(options.progress, "cut: comb", 0.6);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId) continue;
    const std::uint8_t k = static_cast<std::uint8_t>(
        (singularities.matching[c] + cut.faceRotation[cornerFace(o)] + 4 - cut.faceRotation[cornerFace(c)]) % 4);
    cut.corners.setMatching(c, k);
    if (k != 0 && !cut.corners.isCut(c)) {
      // Only a vertex of nonzero index can leave a rotation on a pruned edge.
      throw TopologyError("cutToDisk: the matchings around vertex " +
                          std::to_string(topology.vertex(nextCorner(c))) + " or " +
                          std::to_string(topology.vertex(prevCorner(c))) +
                          " do not agree with the singularities (a cone is missing)");
    }
  }

  // Seam curves: first the chains that start at a node, then closed loops without one.
  reportProgress(options.progress, "cut: seams", 0.8);
  std::vector<std::uint8_t> isNode(numVertices, 0);
  for (VertexId v = 0; v < numVertices; ++v) {
    isNode[v] = degree[v] != 2 || isCone[v] || topology.isBoundaryVertex(v);
  }
  std::vector<bool> traced(topology.numCorners(), false);
  auto startsSeam = [&](CornerId c) {
    return cut.corners.isCut(c) && topology.opposite(c) != kInvalidId && !traced[c];
  };
  for (VertexId v = 0; v < numVertices; ++v) {
    if (!isNode[v] || degree[v] == 0) continue;
    topology.forEachCornerAround(v, [&](CornerId k) {
      const CornerId out = prevCorner(k);  // edge v -> vertex(next k), face(k) on its left
      if (startsSeam(out)) traceSeam(topology, out, isNode, traced, cut);
    });
  }
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    if (startsSeam(c)) traceSeam(topology, c, isNode, traced, cut);
  }
  reportProgress(options.progress, "cut: seams", 1.0);
  return cut;
}

SeamIndex::SeamIndex(const Topology& topology, const std::vector<SeamCurve>& seams) {
  std::size_t n = 0;
  for (const SeamCurve& seam : seams) n += 2 * seam.corners.size();
  entries_.reserve(n);
  for (std::uint32_t id = 0; id < seams.size(); ++id) {
    for (CornerId c : seams[id].corners) {
      const CornerId o = c < topology.numCorners() ? topology.opposite(c) : kInvalidId;
      if (o == kInvalidId) {
        throw InputError("seam " + std::to_string(id) + ": corner " + std::to_string(c) +
                         " is not on an interior edge");
      }
      entries_.push_back({c, id, true});
      entries_.push_back({o, id, false});
    }
  }
  std::sort(entries_.begin(), entries_.end(),
            [](const Entry& a, const Entry& b) { return a.corner < b.corner; });
}

SeamIndex::Side SeamIndex::find(CornerId c) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), c,
                                   [](const Entry& e, CornerId corner) { return e.corner < corner; });
  if (it == entries_.end() || it->corner != c) return {};
  return {it->seam, it->left};
}

}  // namespace seamvox
