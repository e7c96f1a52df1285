#include "core/mesh/subdivide.h"


#include <string>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace {

/// One level: fills out (positions and triangles) and returns the number of edges.
std::uint64_t subdivideOnce(const TriangleMesh& mesh, const Topology& topology, TriangleMesh& out) {
  const std::uint64_t numCorners = topology.numCorners();
  std::uint64_t edges = 0;
  const std::vector<std::uint32_t> edgeOf = subdivisionEdgeNumbers(topology, edges);
  const std::uint64_t numVertices = mesh.numVertices();
  if (numVertices + edges >= kInvalidId) {
    throw TopologyError("subdivision would need " + std::to_string(numVertices + edges) +
                        " vertices, more than 32-bit ids allow");
  }

  out.positions.resize(numVertices + edges);
  std::copy(mesh.positions.begin(), mesh.positions.end(), out.positions.begin());
  const bool withAttributes = !mesh.attributes.empty();
  std::vector<std::array<VertexId, 2>> ends(withAttributes ? edges : 0);
  parallelForEach(numCorners, 16384, [&](std::uint64_t c) {
    const auto cc = static_cast<CornerId>(c);
    const CornerId o = topology.opposite(cc);
    if (o != kInvalidId && o < cc) return;
    const VertexId a = topology.vertex(nextCorner(cc)), b = topology.vertex(prevCorner(cc));
    out.positions[numVertices + edgeOf[c]] = subdivisionMidpoint(mesh.positions[a], mesh.positions[b]);
    if (withAttributes) ends[edgeOf[c]] = {a, b};
  });
  if (withAttributes) out.attributes = mesh.attributes.withMidpoints(ends);

  const std::uint64_t numFaces = topology.numFaces();
  out.triangles.resize(4 * numFaces);
  parallelForEach(numFaces, 16384, [&](std::uint64_t f) {
    const Triangle& t = topology.triangles()[f];
    // m_k: midpoint of the edge opposite corner k.
    const auto m0 = static_cast<VertexId>(numVertices + edgeOf[3 * f]);
    const auto m1 = static_cast<VertexId>(numVertices + edgeOf[3 * f + 1]);
    const auto m2 = static_cast<VertexId>(numVertices + edgeOf[3 * f + 2]);
    out.triangles[4 * f + 0] = {t[0], m2, m1};
    out.triangles[4 * f + 1] = {t[1], m0, m2};
    out.triangles[4 * f + 2] = {t[2], m1, m0};
    out.triangles[4 * f + 3] = {m0, m1, m2};
  });
  return edges;
}

}  // namespace

std::vector<std::uint32_t> subdivisionEdgeNumbers(const Topology& topology, std::uint64_t& edges) {
  const std::uint64_t numCorners = topology.numCorners();
  std::vector<std::uint32_t> edgeOf(numCorners);
  edges = 0;
  for (CornerId c = 0; c < numCorners; ++c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId || c < o) edgeOf[c] = static_cast<std::uint32_t>(edges++);
  }
  parallelForEach(numCorners, 16384, [&](std::uint64_t c) {
    const CornerId o = topology.opposite(static_cast<CornerId>(c));
    if (o != kInvalidId && o < c) edgeOf[c] = edgeOf[o];
  });
  return edgeOf;
}

SubdivideResult subdivideMesh(const TriangleMesh& mesh, const Topology& topology,
                              const SubdivideOptions& options) {
  if (topology.numFaces() != mesh.numFaces() || topology.numVertices() != mesh.numVertices()) {
    throw TopologyError("subdivideMesh: the corner table (" + std::to_string(topology.numFaces()) +
                        " faces, " + std::to_string(topology.numVertices()) +
                        " vertices) does not belong to the mesh (" + std::to_string(mesh.numFaces()) +
                        " faces, " + std::to_string(mesh.numVertices()) + " vertices)");
  }
  if (std::uint64_t(mesh.numFaces()) << (2 * options.levels) >= kInvalidId) {
    throw TopologyError("subdividing " + std::to_string(mesh.numFaces()) + " faces " +
                        std::to_string(options.levels) + " times exceeds 32-bit face ids");
  }
  mesh.attributes.checkSize(mesh.numVertices());
  SubdivideResult result;
  result.mesh.positions = mesh.positions;
  result.mesh.triangles = mesh.triangles;
  result.mesh.origin = mesh.origin;
  result.mesh.attributes = mesh.attributes;
  Topology next;
  const Topology* current = &topology;
  for (std::uint32_t level = 0; level < options.levels; ++level) {
    reportProgress(options.progress, "subdivide", static_cast<double>(level) / options.levels);
    TriangleMesh finer;
    finer.origin = result.mesh.origin;
    const std::uint64_t edges = subdivideOnce(result.mesh, *current, finer);
    if (level == 0) result.edges = edges;
    result.mesh = std::move(finer);
    if (level + 1 < options.levels) {
      next = Topology::build(result.mesh.triangles, result.mesh.numVertices());
      current = &next;
    }
  }
  // Child 4 f + k of every level: the original face is the index shifted by 2 bits per level.
  result.parentFace.resize(result.mesh.numFaces());
  parallelForEach(result.parentFace.size(), 16384, [&](std::uint64_t f) {
    result.parentFace[f] = static_cast<FaceId>(f >> (2 * options.levels));
  });
  reportProgress(options.progress, "subdivide", 1.0);
  return result;
}

std::vector<Vec3d> inheritFaceVectors(const std::vector<Vec3d>& values,
                                      const std::vector<FaceId>& parentFace) {
  std::vector<Vec3d> out(parentFace.size());
  for (std::size_t f = 0; f < parentFace.size(); ++f) out[f] = values[parentFace[f]];
  return out;
}

}  // namespace seamvox
