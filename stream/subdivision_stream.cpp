#include "stream/subdivision_stream.h"

#include <string>

#include "core/mesh/subdivide.h"
#include "core/system/errors.h"

namespace seamvox {

/// The points of one input face (lattice (i, j), i + j <= n, corner k of the face at (0, 0),
/// (n, 0), (0, n) for k = 0, 1, 2) or edge (lattice (m, 0)), level by level.
struct SubdivisionStream::Points {
  std::vector<std::uint32_t> local;  ///< (n + 1)^2: lattice point -> index into positions
  std::vector<Vec3f> positions;
  VertexAttributes attributes;
  std::vector<std::array<VertexId, 2>> ends;
  std::uint32_t n = 1;
  std::uint32_t& at(std::uint32_t i, std::uint32_t j) { return local[std::size_t(j) * (n + 1) + i]; }

  void start(std::uint32_t size, const TriangleMesh& mesh, const std::vector<VertexId>& corners) {
    n = size;
    local.assign(std::size_t(n + 1) * (n + 1), 0);
    positions.clear();
    for (VertexId v : corners) positions.push_back(mesh.positions[v]);
    if (!mesh.attributes.empty()) attributes = mesh.attributes.gathered(corners);
  }
  /// New point at (i, j): the midpoint of the points at a and b, as subdivideMesh rounds it.
  void midpoint(std::uint32_t i, std::uint32_t j, std::uint32_t a, std::uint32_t b, bool withAttributes) {
    at(i, j) = static_cast<std::uint32_t>(positions.size());
    positions.push_back(subdivisionMidpoint(positions[a], positions[b]));
    if (withAttributes) ends.push_back({a, b});
  }
  void finishLevel(bool withAttributes) {
    if (withAttributes && !ends.empty()) attributes = attributes.withMidpoints(ends);
    ends.clear();
  }
};

SubdivisionStream::SubdivisionStream(const TriangleMesh& mesh, const Topology& topology, std::uint32_t levels)
    : mesh_(mesh), topology_(topology), levels_(levels) {
  if (topology.numFaces() != mesh.numFaces() || topology.numVertices() != mesh.numVertices()) {
    throw TopologyError("subdivision stream: the corner table does not belong to the mesh");
  }
  if (levels > 15 || (std::uint64_t(mesh.numFaces()) << (2 * levels)) >= kInvalidId) {
    throw TopologyError("subdividing " + std::to_string(mesh.numFaces()) + " faces " + std::to_string(levels) +
                        " times exceeds 32-bit face ids");
  }
  mesh.attributes.checkSize(mesh.numVertices());
  n_ = 1u << levels;
  edgeOf_ = subdivisionEdgeNumbers(topology, numEdges_);
  edgeOwner_.resize(numEdges_);
  for (CornerId c = 0; c < topology.numCorners(); ++c) {
    const CornerId o = topology.opposite(c);
    if (o == kInvalidId || c < o) edgeOwner_[edgeOf_[c]] = c;
  }
  edgeBase_ = mesh.numVertices();
  faceBase_ = edgeBase_ + numEdges_ * (n_ - 1);
  numVertices_ = faceBase_ + std::uint64_t(mesh.numFaces()) * (n_ - 1) * (n_ >= 2 ? n_ - 2 : 0) / 2;
  if (numVertices_ >= kInvalidId) {
    throw TopologyError("subdivision would need " + std::to_string(numVertices_) +
                        " vertices, more than 32-bit ids allow");
  }
}

SubdivisionStream::~SubdivisionStream() = default;

void SubdivisionStream::subdivideEdge(CornerId owner, Points& points) const {
  const VertexId a = topology_.vertex(nextCorner(owner)), b = topology_.vertex(prevCorner(owner));
  points.start(n_, mesh_, {a, b});
  points.at(0, 0) = 0;
  points.at(n_, 0) = 1;
  const bool withAttributes = !mesh_.attributes.empty();
  for (std::uint32_t s = n_; s >= 2; s /= 2) {
    const std::uint32_t h = s / 2;
    for (std::uint32_t m = h; m < n_; m += s) points.midpoint(m, 0, points.at(m - h, 0), points.at(m + h, 0), withAttributes);
    points.finishLevel(withAttributes);
  }
}

void SubdivisionStream::subdivideFace(FaceId f, Points& points) const {
  const Triangle& t = topology_.triangles()[f];
  points.start(n_, mesh_, {t[0], t[1], t[2]});
  points.at(0, 0) = 0;
  points.at(n_, 0) = 1;
  points.at(0, n_) = 2;
  const bool withAttributes = !mesh_.attributes.empty();
  // Level by level: each new point is the midpoint of the one edge of the previous level it lies
  // on (edges run along (1, 0), (0, 1) and (1, -1)).
  for (std::uint32_t s = n_; s >= 2; s /= 2) {
    const std::uint32_t h = s / 2;
    for (std::uint32_t j = 0; j <= n_; j += h) {
      for (std::uint32_t i = 0; i + j <= n_; i += h) {
        const bool oddI = i % s != 0, oddJ = j % s != 0;
        if (!oddI && !oddJ) continue;
        if (oddI && !oddJ) points.midpoint(i, j, points.at(i - h, j), points.at(i + h, j), withAttributes);
        else if (!oddI) points.midpoint(i, j, points.at(i, j - h), points.at(i, j + h), withAttributes);
        else points.midpoint(i, j, points.at(i - h, j + h), points.at(i + h, j - h), withAttributes);
      }
    }
    points.finishLevel(withAttributes);
  }
}

bool SubdivisionStream::nextVertices(std::size_t count, MeshChunk& chunk) {
  chunk.positions.clear();
  chunk.attributes = mesh_.attributes.emptyCopy();
  const std::uint64_t items = edgeBase_ + numEdges_ + mesh_.numFaces();
  if (nextItem_ >= items) return false;
  // Input vertices first, edges' then faces' inner points: the ids count on from there.
  std::uint64_t first = nextItem_ <= edgeBase_ ? nextItem_
                        : nextItem_ <= edgeBase_ + numEdges_
                            ? edgeBase_ + (nextItem_ - edgeBase_) * (n_ - 1)
                            : faceBase_ + (nextItem_ - edgeBase_ - numEdges_) * ((n_ - 1) * (n_ >= 2 ? n_ - 2 : 0) / 2);
  chunk.firstVertex = static_cast<std::uint32_t>(first);
  Points points;
  std::vector<VertexId> picked;
  while (nextItem_ < items && chunk.positions.size() < count) {
    if (nextItem_ < edgeBase_) {
      const std::uint64_t end = std::min<std::uint64_t>(edgeBase_, nextItem_ + (count - chunk.positions.size()));
      picked.clear();
      for (std::uint64_t v = nextItem_; v < end; ++v) picked.push_back(static_cast<VertexId>(v));
      for (VertexId v : picked) chunk.positions.push_back(mesh_.positions[v]);
      if (!mesh_.attributes.empty()) chunk.attributes.append(mesh_.attributes.gathered(picked));
      nextItem_ = end;
      continue;
    }
    picked.clear();
    if (nextItem_ < edgeBase_ + numEdges_) {
      subdivideEdge(edgeOwner_[nextItem_ - edgeBase_], points);
      for (std::uint32_t m = 1; m < n_; ++m) picked.push_back(points.at(m, 0));
    } else {
      subdivideFace(static_cast<FaceId>(nextItem_ - edgeBase_ - numEdges_), points);
      for (std::uint32_t j = 1; j < n_; ++j) {
        for (std::uint32_t i = 1; i + j < n_; ++i) picked.push_back(points.at(i, j));
      }
    }
    for (VertexId v : picked) chunk.positions.push_back(points.positions[v]);
    if (!mesh_.attributes.empty()) chunk.attributes.append(points.attributes.gathered(picked));
    ++nextItem_;
  }
  return true;
}

bool SubdivisionStream::nextTriangles(std::size_t count, MeshChunk& chunk) {
  chunk.triangles.clear();
  if (nextFace_ >= topology_.numFaces()) return false;
  const std::uint32_t n = n_;
  const std::uint64_t inner = std::uint64_t(n - 1) * (n >= 2 ? n - 2 : 0) / 2;
  std::vector<std::uint64_t> rowStart(n + 1, 0);  // inner points before row j
  for (std::uint32_t j = 1; j + 1 <= n; ++j) rowStart[j + 1] = rowStart[j] + (n - 1 - j);
  std::vector<VertexId> id(std::size_t(n + 1) * (n + 1), kInvalidId);
  const auto at = [&](std::uint32_t i, std::uint32_t j) -> VertexId& { return id[std::size_t(j) * (n + 1) + i]; };
  while (nextFace_ < topology_.numFaces() && chunk.triangles.size() < count) {
    const FaceId f = nextFace_++;
    const Triangle& t = topology_.triangles()[f];
    at(0, 0) = t[0];
    at(n, 0) = t[1];
    at(0, n) = t[2];
    // The side opposite corner k runs from `from` (distance 0) to the far corner; its inner points
    // are numbered from the owning corner's start.
    const auto side = [&](int k, VertexId from, auto point) {
      const CornerId c = 3 * f + k;
      const std::uint32_t e = edgeOf_[c];
      const bool forward = topology_.vertex(nextCorner(edgeOwner_[e])) == from;
      for (std::uint32_t d = 1; d < n; ++d) {
        const std::uint32_t m = forward ? d : n - d;
        point(d) = static_cast<VertexId>(edgeBase_ + std::uint64_t(e) * (n - 1) + (m - 1));
      }
    };
    side(2, t[0], [&](std::uint32_t d) -> VertexId& { return at(d, 0); });      // t0 -> t1
    side(1, t[2], [&](std::uint32_t d) -> VertexId& { return at(0, n - d); });  // t2 -> t0
    side(0, t[1], [&](std::uint32_t d) -> VertexId& { return at(n - d, d); });  // t1 -> t2
    for (std::uint32_t j = 1; j < n; ++j) {
      for (std::uint32_t i = 1; i + j < n; ++i) {
        at(i, j) = static_cast<VertexId>(faceBase_ + std::uint64_t(f) * inner + rowStart[j] + (i - 1));
      }
    }
    // Children in subdivideMesh's order: corner triangles at corners 0, 1, 2, then the middle one.
    struct P { std::uint32_t i, j; };
    const auto mid = [](P a, P b) { return P{(a.i + b.i) / 2, (a.j + b.j) / 2}; };
    const auto emit = [&](const auto& self, P a, P b, P c, std::uint32_t depth) -> void {
      if (depth == levels_) {
        chunk.triangles.push_back({at(a.i, a.j), at(b.i, b.j), at(c.i, c.j)});
        return;
      }
      const P ma = mid(b, c), mb = mid(c, a), mc = mid(a, b);
      self(self, a, mc, mb, depth + 1);
      self(self, b, ma, mc, depth + 1);
      self(self, c, mb, ma, depth + 1);
      self(self, ma, mb, mc, depth + 1);
    };
    emit(emit, P{0, 0}, P{n, 0}, P{0, n}, 0);
  }
  return true;
}

}  // namespace seamvox
