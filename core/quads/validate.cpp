#include "core/quads/validate.h"

#include <algorithm>

namespace seamvox {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

std::uint64_t edgeKey(std::uint32_t from, std::uint32_t to) { return (std::uint64_t(from) << 32) | to; }

}  // namespace

QuadValidation validateQuads(const QuadResult& quads, const ComponentsResult& map) {
  const PolygonMesh& pm = quads.mesh;
  QuadValidation out;
  out.vertices = pm.numVertices();
  out.faces = pm.numFaces();
  // Directed edges, sorted: a repeated one is non-manifold, one without its reverse is boundary.
  std::vector<std::uint64_t> directed;
  directed.reserve(pm.faceVertices.size());
  for (std::uint32_t f = 0; f < pm.numFaces(); ++f) {
    const std::uint32_t n = pm.degree(f), *v = &pm.faceVertices[pm.faceStart[f]];
    (n == 4 ? out.quads : n == 3 ? out.triangles : n == 5 ? out.pentagons : out.otherFaces)++;
    std::vector<std::uint32_t> sorted(v, v + n);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) ++out.degenerateFaces;
    for (std::uint32_t k = 0; k < n; ++k) directed.push_back(edgeKey(v[k], v[(k + 1) % n]));
  }
  out.quadFraction = out.faces ? double(out.quads) / double(out.faces) : 0.0;
  std::sort(directed.begin(), directed.end());
  auto has = [&](std::uint64_t key) { return std::binary_search(directed.begin(), directed.end(), key); };
  std::vector<std::uint32_t> valence(pm.numVertices(), 0), boundaryOut(pm.numVertices(), kNone);
  std::vector<std::uint8_t> onBoundary(pm.numVertices(), 0);
  std::vector<std::uint32_t> boundaryIn(pm.numVertices(), 0);
  std::vector<std::uint64_t> compEdges(map.components.size(), 0);
  for (std::size_t i = 0; i < directed.size(); ++i) {
    if (i > 0 && directed[i] == directed[i - 1]) {
      ++out.nonManifoldEdges;
      continue;
    }
    const std::uint32_t a = std::uint32_t(directed[i] >> 32), b = std::uint32_t(directed[i]);
    const bool twin = has(edgeKey(b, a));
    if (twin && a > b) continue;  // counted from the other side
    ++out.edges;
    ++valence[a];
    ++valence[b];
    ++compEdges[quads.vertexComponent[a]];
    if (twin) continue;
    ++out.boundaryEdges;
    onBoundary[a] = onBoundary[b] = 1;
    if (boundaryOut[a] != kNone) ++out.nonManifoldVertices;
    boundaryOut[a] = b;
    ++boundaryIn[b];
  }
  for (std::uint32_t v = 0; v < pm.numVertices(); ++v) {
    out.nonManifoldVertices += boundaryIn[v] != (boundaryOut[v] != kNone ? 1u : 0u);
  }
  // Boundary loops, per component.
  std::vector<std::uint32_t> compLoops(map.components.size(), 0);
  std::vector<std::uint8_t> seen(pm.numVertices(), 0);
  for (std::uint32_t v = 0; v < pm.numVertices(); ++v) {
    if (boundaryOut[v] == kNone || seen[v]) continue;
    std::uint32_t w = v;
    while (w != kNone && !seen[w]) seen[w] = 1, w = boundaryOut[w];
    if (w != v) continue;  // not a loop: an open chain (counted as non-manifold vertices)
    ++out.boundaryLoops;
    ++compLoops[quads.vertexComponent[v]];
  }
  for (std::uint32_t v = 0; v < pm.numVertices(); ++v) {
    if (onBoundary[v]) continue;
    const int cone = quads.vertexConeIndex[v];
    const bool wrong = std::int64_t(valence[v]) != 4 - cone - quads.vertexLostEdges[v];
    if (cone != 0) {
      ++out.conesOnVertices;
      out.conesWithWrongValence += wrong;
    } else {
      out.irregularVertices += wrong;
    }
  }
  for (std::uint32_t f = 0; f < pm.numFaces(); ++f) {
    const std::uint32_t n = pm.degree(f), *v = &pm.faceVertices[pm.faceStart[f]];
    bool boundary = false;
    for (std::uint32_t k = 0; k < n; ++k) boundary |= !has(edgeKey(v[(k + 1) % n], v[k]));
    out.interiorNonQuads += !boundary && n != 4;
  }
  // Euler characteristic per component of the map.
  std::vector<std::uint64_t> compVertices(map.components.size(), 0), compFaces(map.components.size(), 0);
  for (std::uint32_t v = 0; v < pm.numVertices(); ++v) ++compVertices[quads.vertexComponent[v]];
  for (std::uint32_t f = 0; f < pm.numFaces(); ++f) {
    ++compFaces[quads.vertexComponent[pm.faceVertices[pm.faceStart[f]]]];
  }
  for (std::uint32_t c = 0; c < map.components.size(); ++c) {
    if (compFaces[c] == 0) continue;
    QuadComponentCheck k;
    k.component = c;
    k.vertices = compVertices[c];
    k.edges = compEdges[c];
    k.faces = compFaces[c];
    k.boundaryLoops = compLoops[c];
    k.eulerCharacteristic = std::int64_t(k.vertices) - std::int64_t(k.edges) + std::int64_t(k.faces);
    k.genus = (2 - k.eulerCharacteristic - k.boundaryLoops) / 2;
    const ComponentInfo& info = map.components[c];
    k.mapBoundaryLoops = info.boundaryLoops;
    k.mapEulerCharacteristic = info.eulerCharacteristic;
    k.mapGenus = info.genus;
    out.componentsDiffering += !k.matches();
    out.components.push_back(k);
  }
  return out;
}

}  // namespace seamvox
