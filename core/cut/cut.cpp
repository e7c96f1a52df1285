// Cut graph, combing and seam curves (DESIGN section 5). Conventions: core/cut/cut.h.
#include "core/cut/cut.h"

#include <algorithm>
#include <string>

#include "core/cut/detail_cut.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {

namespace {

/// faceRotation with kUnvisited before the tree reaches a face.
struct RotationState {
  static constexpr std::uint8_t kUnvisited = 0xff;
  std::vector<std::uint8_t>& values;
  bool visited(FaceId f) const { return values[f] != kUnvisited; }
  std::uint8_t operator[](FaceId f) const { return values[f]; }
  void set(FaceId f, std::uint8_t r) { values[f] = r; }
};

/// CutCorners' traced edges while the seams are traced.
struct TracedCorners {
  std::vector<bool> values;
  bool operator[](CornerId c) const { return values[c]; }
  void set(CornerId c, bool traced) { values[c] = traced; }
};

/// detail::pruneCut with both cores: every vertex's dangling chains peeled in parallel, each edge
/// claimed once by an atomic flag on its smaller corner. What stays is the cut's 2-core with the
/// cones kept, the same whatever the order, so the same cut as the serial peel; except a component
/// whose cut would vanish (a closed genus-0 surface with at most one cone), where the serial peel
/// keeps the edge its order reaches last: such components get their edges back and the serial
/// peel. degree: the cut degrees, edgeXor: per vertex the XOR of its cut edges' smaller corners
/// (countCutDegrees with CutEdgeXor), remaining: cut edges per component.
void pruneCutInParallel(const Topology& topology, const std::vector<std::uint8_t>& isCone,
                        detail::VectorArray<std::uint32_t>& component, std::vector<std::uint64_t>& remaining,
                        CutCorners& cut, std::vector<std::uint32_t>& degree, std::vector<CornerId>& edgeXor) {
  const std::uint64_t numCorners = topology.numCorners();
  const auto canonical = [&](CornerId c) {
    const CornerId o = topology.opposite(c);
    return o != kInvalidId && o < c ? o : c;
  };
  std::vector<std::uint8_t> flag(numCorners);  // per edge, at its smaller corner
  parallelForEach(numCorners, 1u << 16, [&](std::uint64_t c) { flag[c] = cut.isCut(static_cast<CornerId>(c)); });
  const auto load = [](const std::uint32_t& x) { return __atomic_load_n(&x, __ATOMIC_ACQUIRE); };
  parallelFor(topology.numVertices(), 1u << 12, [&](const IndexRange& range) {
    // Edges taken per component, added to `remaining` a run at a time (one shared counter per
    // edge would pass its cache line between the cores at every step).
    std::uint32_t runComponent = kInvalidId;
    std::uint64_t run = 0;
    const auto flush = [&] {
      if (run) __atomic_fetch_sub(&remaining[runComponent], run, __ATOMIC_RELAXED);
      run = 0;
    };
    for (VertexId v = range.begin(); v != range.end(); ++v) {
      VertexId u = v;
      while (!isCone[u] && load(degree[u]) == 1) {
        // With one cut edge left at u, the XOR is that edge; read after the degree, it is that
        // edge or, once another thread has taken it, nothing that touches u as a cut edge.
        const CornerId e = load(edgeXor[u]);
        if (e >= numCorners) break;
        const VertexId a = topology.vertex(nextCorner(e)), b = topology.vertex(prevCorner(e));
        if (a != u && b != u) break;
        const CornerId o = topology.opposite(e);
        if (o == kInvalidId || o < e) break;  // boundary edges are never pruned; e is canonical
        std::uint8_t expected = 1;
        if (!__atomic_compare_exchange_n(&flag[e], &expected, std::uint8_t(0), false, __ATOMIC_ACQ_REL,
                                         __ATOMIC_RELAXED)) {
          break;  // another thread took it from its other end
        }
        const VertexId w = a == u ? b : a;
        // The XORs before the degrees: a degree read as 1 comes with its vertex's XOR.
        __atomic_fetch_xor(&edgeXor[u], e, __ATOMIC_RELEASE);
        __atomic_fetch_xor(&edgeXor[w], e, __ATOMIC_RELEASE);
        __atomic_fetch_sub(&degree[u], 1u, __ATOMIC_RELEASE);
        __atomic_fetch_sub(&degree[w], 1u, __ATOMIC_RELEASE);
        const std::uint32_t k = component[cornerFace(e)];
        if (k != runComponent) flush(), runComponent = k;
        ++run;
        u = w;
      }
    }
    flush();
  });
  std::vector<std::uint8_t> vanished(remaining.size(), 0);
  bool anyVanished = false;
  for (std::size_t k = 0; k < remaining.size(); ++k) anyVanished |= (vanished[k] = remaining[k] == 0) != 0;
  // Whole bytes per task: two corners share one (CutCorners).
  parallelForEach(cut.numBytes(), 1u << 15, [&](std::uint64_t b) {
    for (std::uint64_t c = 2 * b; c < std::min<std::uint64_t>(2 * b + 2, numCorners); ++c) {
      if (!vanished[component[cornerFace(static_cast<CornerId>(c))]]) cut.setCut(static_cast<CornerId>(c), flag[canonical(static_cast<CornerId>(c))]);
    }
  });
  if (!anyVanished) return;
  // The vanished components have their whole cut back: degrees and counts again, then the serial
  // peel (which finds nothing to do elsewhere).
  std::fill(degree.begin(), degree.end(), 0u);
  detail::VectorArray<std::uint32_t> degreeArray{degree};
  remaining = detail::countCutDegrees(topology, numCorners, cut, component, static_cast<std::uint32_t>(remaining.size()),
                                      degreeArray);
  const auto coneAt = [&](VertexId v) { return isCone[v] != 0; };
  detail::pruneCut(topology, topology.numVertices(), coneAt, component, remaining, cut, degreeArray);
}

}  // namespace

std::vector<std::uint8_t> FaceRotations::faceBytes() const {
  std::vector<std::uint8_t> out(size_);
  for (std::size_t f = 0; f < size_; ++f) out[f] = (*this)[static_cast<FaceId>(f)];
  return out;
}

std::vector<std::uint8_t> CutCorners::cornerBytes() const {
  std::vector<std::uint8_t> out(size_);
  for (std::size_t c = 0; c < size_; ++c) out[c] = byteOfCorner(static_cast<CornerId>(c));
  return out;
}

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
  const auto matching = [&](CornerId c) { return singularities.matching[c]; };

  reportProgress(options.progress, "cut: dual tree", 0.0);
  cut.corners = CutCorners(topology.numCorners(), true);
  // A byte per face while the tree is built (it marks faces not reached yet); packed after combing.
  std::vector<std::uint8_t> rotationValues(numFaces, RotationState::kUnvisited);
  std::vector<std::uint32_t> faceComponent(numFaces, kInvalidId);
  RotationState rotation{rotationValues};
  detail::VectorArray<std::uint32_t> component{faceComponent};
  const std::uint32_t numComponents =
      detail::buildDualTree(topology, numFaces, matching, rotation, component, cut.corners);

  reportProgress(options.progress, "cut: prune", 0.3);
  std::vector<std::uint32_t> degreeValues(numVertices, 0);
  detail::VectorArray<std::uint32_t> degree{degreeValues};
  std::vector<CornerId> edgeXorValues(numVertices, 0);
  detail::VectorArray<CornerId> edgeXorArray{edgeXorValues};
  std::vector<std::uint64_t> remaining =
      detail::countCutDegrees(topology, topology.numCorners(), cut.corners, component, numComponents, degree,
                              detail::CutEdgeXor<detail::VectorArray<CornerId>>{edgeXorArray});
  pruneCutInParallel(topology, isCone, component, remaining, cut.corners, degreeValues, edgeXorValues);
  std::vector<CornerId>().swap(edgeXorValues);

  reportProgress(options.progress, "cut: comb", 0.6);
  detail::combCorners(topology, topology.numCorners(), matching, rotation, cut.corners,
                      [&](CornerId c, bool, std::uint8_t k) { cut.corners.setMatching(c, k); });
  cut.faceRotation = FaceRotations(numFaces);
  for (FaceId f = 0; f < numFaces; ++f) cut.faceRotation.set(f, rotationValues[f]);
  std::vector<std::uint8_t>().swap(rotationValues);

  reportProgress(options.progress, "cut: seams", 0.8);
  const auto isNode = [&](VertexId v) {
    return degreeValues[v] != 2 || isCone[v] || topology.isBoundaryVertex(v);
  };
  TracedCorners traced{std::vector<bool>(topology.numCorners(), false)};
  detail::traceSeams(topology, numVertices, topology.numCorners(), isNode, degree, traced, cut.corners, cut.seams);
  reportProgress(options.progress, "cut: seams", 1.0);
  return cut;
}

SeamIndex::SeamIndex(const Topology& topology, const std::vector<SeamCurve>& seams)
    : SeamIndex(seams, topology.numCorners(), [&](CornerId c) { return topology.opposite(c); }) {}

SeamIndex::SeamIndex(const std::vector<SeamCurve>& seams, std::uint64_t numCorners,
                     const std::function<CornerId(CornerId)>& opposite) {
  std::size_t n = 0;
  for (const SeamCurve& seam : seams) n += 2 * seam.corners.size();
  entries_.reserve(n);
  for (std::uint32_t id = 0; id < seams.size(); ++id) {
    for (CornerId c : seams[id].corners) {
      const CornerId o = c < numCorners ? opposite(c) : kInvalidId;
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
