// Per-component figures of a parameterized mesh and the removal of unsolved components.
#include "core/pipeline/components.h"

#include <algorithm>
#include <cmath>

#include "core/quality/metrics.h"
#include "core/system/parallel.h"

namespace seamvox {

const char* componentMappingName(ComponentMapping mapping) {
  switch (mapping) {
    case ComponentMapping::Unsolved: return "unsolved";
    case ComponentMapping::Point: return "point";
    case ComponentMapping::Anchored: return "anchored";
    case ComponentMapping::Solved: return "solved";
  }
  return "solved";
}

namespace {

/// Marks the sorted faces in a per-face flag array.
std::vector<std::uint8_t> faceMask(std::uint32_t numFaces, const std::vector<FaceId>& faces) {
  std::vector<std::uint8_t> mask(numFaces, 0);
  for (FaceId f : faces) mask[f] = 1;
  return mask;
}

/// Per component (computeComponents numbering): whether a corner moves away from the component's
/// first corner (else it maps to a point), whether a face is in the given sets, flipped faces
/// and area.
struct ComponentMapFacts {
  std::vector<std::uint8_t> moved, unsolved, anchored;
  std::vector<std::uint64_t> flipped;
  std::vector<double> area;
};

ComponentMapFacts gatherMapFacts(const TriangleMesh& mesh, const ComponentsResult& components,
                                 const std::vector<FaceId>& unsolvedFaces,
                                 const std::vector<FaceId>& anchoredFaces, double edgeLength,
                                 const std::vector<FaceId>* flippedFaces) {
  const std::size_t n = components.components.size();
  const std::vector<std::uint32_t>& faceComponent = components.faceComponent;
  ComponentMapFacts facts;
  facts.moved.assign(n, 0);
  facts.unsolved.assign(n, 0);
  facts.anchored.assign(n, 0);
  facts.flipped.assign(n, 0);
  facts.area.assign(n, 0.0);
  for (FaceId f : unsolvedFaces) facts.unsolved[faceComponent[f]] = 1;
  for (FaceId f : anchoredFaces) facts.anchored[faceComponent[f]] = 1;
  std::vector<Vec2d> first(n, Vec2d::Zero());
  if (mesh.hasUV()) {
    std::vector<std::uint8_t> seen(n, 0);
    for (FaceId f = 0; f < mesh.numFaces(); ++f) {
      if (!seen[faceComponent[f]]++) first[faceComponent[f]] = mesh.cornerUV[3 * f];
    }
  }
  // Per face in parallel (the map's corners are scattered in memory), summed per component after:
  // area, and bit 0 flipped, bit 1 a corner away from the component's first corner.
  std::vector<float> area(mesh.numFaces());
  std::vector<std::uint8_t> bits(mesh.numFaces(), 0);
  parallelForEach(mesh.numFaces(), 4096, [&](std::uint64_t i) {
    const auto f = static_cast<FaceId>(i);
    area[f] = static_cast<float>(faceArea(mesh, f));
    if (!mesh.hasUV()) return;
    std::uint8_t b = !flippedFaces && isFlippedRatio(parameterAreaRatio(mesh, mesh.cornerUV, f, edgeLength));
    for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
      if ((mesh.cornerUV[c] - first[faceComponent[f]]).cwiseAbs().maxCoeff() > kCoincidentConeDistance) b |= 2;
    }
    bits[f] = b;
  });
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const std::uint32_t k = faceComponent[f];
    facts.area[k] += area[f];
    facts.flipped[k] += bits[f] & 1;
    facts.moved[k] |= bits[f] >> 1;
  }
  if (flippedFaces && mesh.hasUV()) {
    for (FaceId f : *flippedFaces) ++facts.flipped[faceComponent[f]];
  }
  return facts;
}

ComponentMapping mappingOf(const ComponentMapFacts& facts, std::uint32_t k, bool hasUV) {
  const bool point = hasUV && !facts.moved[k];
  if (facts.unsolved[k] && point) return ComponentMapping::Unsolved;
  if (point) return ComponentMapping::Point;
  if (facts.anchored[k]) return ComponentMapping::Anchored;
  return ComponentMapping::Solved;
}

}  // namespace

ComponentSummary summarizeComponents(const TriangleMesh& mesh, const Topology& topology,
                                     const std::vector<VertexId>& cones,
                                     const std::vector<FaceId>& unsolvedFaces,
                                     const std::vector<FaceId>& anchoredFaces, double edgeLength,
                                     std::uint32_t limit,
                                     std::vector<FaceId>* unsolvedComponentFaces,
                                     const std::vector<FaceId>* flippedFaces) {
  const ComponentsResult components = computeComponents(topology);
  const auto n = static_cast<std::uint32_t>(components.components.size());
  const ComponentMapFacts facts =
      gatherMapFacts(mesh, components, unsolvedFaces, anchoredFaces, edgeLength, flippedFaces);
  // Ids in the order of each component's lowest face.
  std::vector<std::uint32_t> idOf(n, kInvalidId);
  std::uint32_t next = 0;
  for (FaceId f = 0; f < mesh.numFaces() && next < n; ++f) {
    std::uint32_t& id = idOf[components.faceComponent[f]];
    if (id == kInvalidId) id = next++;
  }
  std::vector<std::uint32_t> coneCount(n, 0);
  for (VertexId v : cones) {
    if (!topology.isIsolatedVertex(v)) ++coneCount[components.faceComponent[topology.vertexCorner(v) / 3]];
  }
  ComponentSummary out;
  out.count = n;
  out.limit = limit;
  std::vector<ComponentFigures> all(n);
  std::vector<ComponentMapping> mapping(n);
  for (std::uint32_t k = 0; k < n; ++k) {
    const ComponentInfo& info = components.components[k];
    ComponentFigures& c = all[k];
    c.id = idOf[k];
    c.faces = info.faces;
    c.vertices = info.vertices;
    c.boundaryLoops = info.boundaryLoops;
    c.eulerCharacteristic = info.eulerCharacteristic;
    c.genus = info.genus;
    c.area = facts.area[k];
    c.mapping = mapping[k] = mappingOf(facts, k, mesh.hasUV());
    c.cones = coneCount[k];
    c.flippedFaces = facts.flipped[k];
    ++out.mapped[static_cast<int>(c.mapping)];
    if (c.mapping == ComponentMapping::Unsolved) out.unsolvedIds.push_back(c.id);
  }
  std::sort(out.unsolvedIds.begin(), out.unsolvedIds.end());
  if (unsolvedComponentFaces) {
    unsolvedComponentFaces->clear();
    for (FaceId f : unsolvedFaces) {
      if (mapping[components.faceComponent[f]] == ComponentMapping::Unsolved) unsolvedComponentFaces->push_back(f);
    }
  }
  // computeComponents sorts by decreasing faces; ties by id keep the list deterministic.
  std::stable_sort(all.begin(), all.end(), [](const ComponentFigures& a, const ComponentFigures& b) {
    return a.faces != b.faces ? a.faces > b.faces : a.id < b.id;
  });
  const std::uint32_t shown = std::min(n, limit);
  for (std::uint32_t k = shown; k < n; ++k) out.unlistedFaces += all[k].faces;
  out.unlisted = n - shown;
  all.resize(shown);
  out.listed = std::move(all);
  return out;
}

TriangleMesh removeFaces(const TriangleMesh& mesh, const std::vector<FaceId>& faces,
                         std::vector<VertexId>* vertexMap) {
  const std::vector<std::uint8_t> removed = faceMask(mesh.numFaces(), faces);
  TriangleMesh out;
  out.origin = mesh.origin;
  std::vector<VertexId> newVertex(mesh.numVertices(), kInvalidId);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (!removed[f]) for (VertexId v : mesh.triangles[f]) newVertex[v] = 0;
  }
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    if (newVertex[v] == kInvalidId) continue;
    newVertex[v] = out.numVertices();
    out.positions.push_back(mesh.positions[v]);
  }
  const bool withUV = mesh.hasUV();
  std::vector<std::uint32_t> newWedge(withUV ? mesh.cornerUV.numWedges() : 0, kInvalidId);
  std::vector<std::uint32_t> cornerWedge;
  std::vector<Vec2d> wedgeValues;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (removed[f]) continue;
    Triangle t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      t[k] = newVertex[t[k]];
      if (!withUV) continue;
      const std::uint32_t w = mesh.cornerUV.wedge(3 * f + k);
      if (newWedge[w] == kInvalidId) {
        newWedge[w] = static_cast<std::uint32_t>(wedgeValues.size());
        wedgeValues.push_back(mesh.cornerUV.wedgeValue(w));
      }
      cornerWedge.push_back(newWedge[w]);
    }
    out.triangles.push_back(t);
  }
  if (withUV) out.cornerUV = WedgeMap(std::move(cornerWedge), std::move(wedgeValues));
  if (vertexMap) *vertexMap = std::move(newVertex);
  return out;
}

}  // namespace seamvox
