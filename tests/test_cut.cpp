// Cut graph, combing and seams: the cut surface of every component is a disk, every cone is on
// the cut, combed matchings vanish off the cut and are constant along each seam.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <string>

#include "core/mesh/clean.h"
#include "core/cut/cut.h"
#include "core/cut/detail_cut.h"
#include "core/system/errors.h"
#include "core/field/field.h"
#include "core/synth/generate.h"
#include "core/mesh/topology.h"
#include "io/field_io.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

using testing::loadShared;
using testing::makeSurface;
using testing::Surface;

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) { parent[find(a)] = find(b); }
};

/// Builds the cut mesh independently of cutToDisk's own bookkeeping: corners at a vertex are
/// glued across non-cut edges into wedges (the cut mesh's vertices); then per component counts
/// V - E + F and the boundary loops (cut edges, each side once, chained wedge to wedge).
void expectCutIsDiskPerComponent(const Surface& s, const CutResult& cut, const std::string& what) {
  const Topology& t = s.topology;
  const std::uint32_t numCorners = t.numCorners();
  UnionFind wedges(numCorners), faces(t.numFaces());
  for (CornerId c = 0; c < numCorners; ++c) {
    const CornerId o = t.opposite(c);
    if (o == kInvalidId) continue;
    ASSERT_EQ(cut.corners.isCut(c), cut.corners.isCut(o)) << what;
    faces.unite(cornerFace(c), cornerFace(o));
    if (cut.corners.isCut(c)) continue;
    // The edge of c joins vertex(next c) and vertex(prev c) in both faces.
    wedges.unite(nextCorner(c), prevCorner(o));
    wedges.unite(prevCorner(c), nextCorner(o));
  }
  std::map<std::uint32_t, std::int64_t> chi;         // component root -> V - E + F
  std::map<std::uint32_t, std::uint32_t> loops;      // component root -> boundary loops
  std::vector<std::uint8_t> wedgeCounted(numCorners, 0);
  std::map<std::uint32_t, std::uint32_t> boundaryNext;  // wedge -> next wedge along the boundary
  for (CornerId c = 0; c < numCorners; ++c) {
    const std::uint32_t comp = faces.find(cornerFace(c));
    const std::uint32_t w = wedges.find(c);
    if (!wedgeCounted[w]) {
      wedgeCounted[w] = 1;
      chi[comp] += 1;
    }
    if (c % 3 == 0) chi[comp] += 1;
    const CornerId o = t.opposite(c);
    if (o == kInvalidId || cut.corners.isCut(c)) {
      chi[comp] -= 1;  // each side of a cut edge is an edge of the cut mesh
      const std::uint32_t from = wedges.find(nextCorner(c)), to = wedges.find(prevCorner(c));
      ASSERT_EQ(boundaryNext.count(from), 0u) << what << ": cut mesh not a manifold at a wedge";
      boundaryNext[from] = to;
    } else if (c < o) {
      chi[comp] -= 1;
    }
  }
  std::map<std::uint32_t, std::uint32_t> wedgeComp;
  for (CornerId c = 0; c < numCorners; ++c) wedgeComp[wedges.find(c)] = faces.find(cornerFace(c));
  std::map<std::uint32_t, bool> visited;
  for (const auto& [start, next] : boundaryNext) {
    if (visited[start]) continue;
    ++loops[wedgeComp[start]];
    std::uint32_t w = start;
    do {
      visited[w] = true;
      ASSERT_TRUE(boundaryNext.count(w)) << what << ": open boundary chain";
      w = boundaryNext[w];
    } while (w != start);
  }
  for (const auto& [comp, value] : chi) {
    EXPECT_EQ(value, 1) << what << ": component of face " << comp;
    EXPECT_EQ(loops[comp], 1u) << what << ": component of face " << comp;
  }
}

/// Every cone on the cut; combed matchings are zero off the cut and equal to the matchings of
/// the combed field recomputed from scratch; seams are consistent chains covering the cut.
void expectCombedSeams(const Surface& s, const CrossField& field, const FieldSingularities& sing,
                       const CutResult& cut, const std::string& what) {
  const Topology& t = s.topology;
  std::vector<std::uint32_t> cutDegree(t.numVertices(), 0);
  for (CornerId c = 0; c < t.numCorners(); ++c) {
    if (cut.corners.isCut(c)) ++cutDegree[t.vertex(nextCorner(c))];
  }
  for (VertexId v : sing.cones) EXPECT_GT(cutDegree[v], 0u) << what << ": cone " << v << " off the cut";
  EXPECT_EQ(cut.cones, sing.cones);

  CrossField combed = field;
  for (FaceId f = 0; f < t.numFaces(); ++f) {
    ASSERT_LT(cut.faceRotation[f], 4);
    Vec3d u = field.at(f);
    for (int k = 0; k < cut.faceRotation[f]; ++k) u = faceNormal(s.mesh, f).cross(u);
    combed.set(f, u);
  }
  const FieldSingularities recomputed = computeSingularities(s.mesh, t, combed);
  const SeamIndex seamIndex(t, cut.seams);
  for (CornerId c = 0; c < t.numCorners(); ++c) {
    const CornerId o = t.opposite(c);
    if (o == kInvalidId) {
      EXPECT_TRUE(cut.corners.isCut(c)) << what;
      EXPECT_EQ(seamIndex.seamOf(c), kInvalidId) << what;
      continue;
    }
    ASSERT_EQ(cut.corners.matching(c), recomputed.matching[c]) << what << ": corner " << c;
    if (!cut.corners.isCut(c)) {
      ASSERT_EQ(cut.corners.matching(c), 0) << what << ": corner " << c;
      EXPECT_EQ(seamIndex.seamOf(c), kInvalidId) << what;
    } else {
      const SeamIndex::Side side = seamIndex.find(c), other = seamIndex.find(o);
      ASSERT_NE(side.seam, kInvalidId) << what << ": cut edge of corner " << c << " in no seam";
      EXPECT_EQ(side.seam, other.seam);
      EXPECT_NE(side.left, other.left) << what << ": corner " << c;
    }
  }
  std::size_t seamCorners = 0;
  for (std::uint32_t id = 0; id < cut.seams.size(); ++id) {
    const SeamCurve& seam = cut.seams[id];
    ASSERT_FALSE(seam.corners.empty());
    EXPECT_EQ(t.vertex(nextCorner(seam.corners.front())), seam.start);
    EXPECT_EQ(t.vertex(prevCorner(seam.corners.back())), seam.end);
    for (std::size_t j = 0; j < seam.corners.size(); ++j) {
      const CornerId c = seam.corners[j];
      EXPECT_EQ(seamIndex.seamOf(c), id);
      EXPECT_TRUE(seamIndex.find(c).left);
      EXPECT_EQ(cut.corners.matching(c), seam.matching) << what << ": seam " << id;
      if (j > 0) EXPECT_EQ(t.vertex(nextCorner(c)), t.vertex(prevCorner(seam.corners[j - 1])));
      if (j + 1 < seam.corners.size()) {  // inner vertices: plain path points
        const VertexId v = t.vertex(prevCorner(c));
        EXPECT_EQ(cutDegree[v], 2u);
        EXPECT_FALSE(t.isBoundaryVertex(v));
        EXPECT_EQ(sing.index4[v], 0);
      }
    }
    seamCorners += seam.corners.size();
  }
  std::size_t cutInterior = 0;
  for (CornerId c = 0; c < t.numCorners(); ++c) cutInterior += cut.corners.isCut(c) && t.opposite(c) != kInvalidId;
  EXPECT_EQ(2 * seamCorners, cutInterior) << what << ": seams must cover each cut edge once";
}

void checkAll(const Surface& s, const CrossField& field, const std::string& what) {
  const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
  const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);
  expectCutIsDiskPerComponent(s, cut, what);
  expectCombedSeams(s, field, sing, cut, what);
}

using testing::randomField;

TEST(Cut, GeneratedClosedAndOpenMeshes) {
  GenerateOptions genus2;
  genus2.kind = MeshKind::Genus2;
  genus2.faces = 5000;
  const std::pair<std::string, TriangleMesh> cases[] = {
      {"icosphere", testing::icosphereMesh(3)},
      {"thin torus", testing::torusMesh(96, 16, 3.0, 0.5)},
      {"thick torus", testing::torusMesh(40, 20, 2.0, 1.0)},
      {"genus 2", generateMesh(genus2).mesh},
      {"grid", testing::gridMesh(12, 9)},
      {"cylinder", testing::cylinderMesh(24, 8)},
  };
  for (const auto& [name, mesh] : cases) {
    const Surface s = makeSurface(mesh);
    checkAll(s, computeSmoothestField(s.mesh, s.topology), name + " smoothest");
    checkAll(s, randomField(s.mesh, 5), name + " random");
  }
}

TEST(Cut, SeveralComponents) {
  const Surface s = makeSurface(testing::concatMeshes({testing::icosphereMesh(2), testing::torusMesh(30, 12),
                                                       testing::gridMesh(5, 4), testing::cylinderMesh(12, 3),
                                                       testing::icosphereMesh(1)}));
  checkAll(s, computeSmoothestField(s.mesh, s.topology), "components smoothest");
  checkAll(s, randomField(s.mesh, 9), "components random");
}

/// The serial steps of cutToDisk up to the prune (the last cut edge at a vertex found by walks or
/// by byXor): per corner its cut flag, per vertex its cut degree.
std::pair<std::vector<bool>, std::vector<std::uint32_t>> serialPrune(const Surface& s, const FieldSingularities& sing,
                                                                   bool byXor) {
  const std::uint32_t nf = s.topology.numFaces(), nv = s.topology.numVertices();
  CutCorners cut(s.topology.numCorners(), true);
  std::vector<std::uint8_t> rotationValues(nf, 0xff);
  struct Rotation {
    std::vector<std::uint8_t>& values;
    bool visited(FaceId f) const { return values[f] != 0xff; }
    std::uint8_t operator[](FaceId f) const { return values[f]; }
    void set(FaceId f, std::uint8_t r) { values[f] = r; }
  } rotation{rotationValues};
  std::vector<std::uint32_t> componentValues(nf), degreeValues(nv, 0), xorValues(nv, 0);
  detail::VectorArray<std::uint32_t> component{componentValues}, degree{degreeValues}, xorArray{xorValues};
  const std::uint32_t components = detail::buildDualTree(
      s.topology, nf, [&](CornerId c) { return sing.matching[c]; }, rotation, component, cut);
  std::vector<std::uint8_t> isCone(nv, 0);
  for (VertexId v : sing.cones) isCone[v] = 1;
  const auto coneAt = [&](VertexId v) { return isCone[v] != 0; };
  if (byXor) {
    detail::CutEdgeXor<detail::VectorArray<std::uint32_t>> edges{xorArray};
    std::vector<std::uint64_t> remaining =
        detail::countCutDegrees(s.topology, s.topology.numCorners(), cut, component, components, degree, edges);
    detail::pruneCut(s.topology, nv, coneAt, component, remaining, cut, degree, edges);
  } else {
    std::vector<std::uint64_t> remaining =
        detail::countCutDegrees(s.topology, s.topology.numCorners(), cut, component, components, degree);
    detail::pruneCut(s.topology, nv, coneAt, component, remaining, cut, degree);
  }
  std::vector<bool> out(s.topology.numCorners());
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) out[c] = cut.isCut(c);
  return std::make_pair(out, degreeValues);
}

// cutToDisk peels the dangling cut edges on every core: the cut is the serial peel's, on a mesh
// large enough for many blocks, with a random field's many cones.
TEST(Cut, TheParallelPruneIsTheSerialOne) {
  // A scan, and shuffled islands: flat specks (boundaries), a ball whose cut may vanish and a torus.
  for (const TriangleMesh& mesh : {testing::generatedMesh(MeshKind::Scan, 200000),
                                   testing::shuffledMesh(testing::torusWithIslands(400, 100, 300, 0.05, 3, 0.3f, 7), 5)}) {
    const Surface s = makeSurface(cleanMesh(TriangleMesh(mesh), CleanOptions{}).mesh);
    ASSERT_GT(s.topology.numVertices(), 5u * 4096u);
    const CrossField field = randomField(s.mesh, 3);
    const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
    ASSERT_GT(sing.cones.size(), 100u);
    const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);

    const std::vector<bool> serial = serialPrune(s, sing, false).first;
    std::uint64_t cutEdges = 0;
    for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
      ASSERT_EQ(cut.corners.isCut(c), serial[c]) << "corner " << c;
      cutEdges += serial[c];
    }
    EXPECT_GT(cutEdges, 2 * sing.cones.size());
  }
}

// The out-of-core cut finds a vertex's last cut edge from the XOR of its edges' corners: the same
// edges pruned as by the walks around the fans, with boundaries, several components and closed
// spheres whose cut would vanish (one edge kept, the same one).
TEST(Cut, PruneByEdgeXorIsPruneByWalks) {
  const Surface scan = makeSurface(cleanMesh(testing::generatedMesh(MeshKind::Scan, 20000), CleanOptions{}).mesh);
  const Surface parts = makeSurface(testing::concatMeshes({testing::icosphereMesh(2), testing::torusMesh(30, 12),
                                                           testing::gridMesh(5, 4), testing::cylinderMesh(12, 3),
                                                           testing::icosphereMesh(1)}));
  int compared = 0;
  for (const Surface* s : {&scan, &parts}) {
    for (const std::uint32_t seed : {3u, 9u}) {
      const CrossField field = randomField(s->mesh, seed);
      const FieldSingularities sing = computeSingularities(s->mesh, s->topology, field);
      const auto walks = serialPrune(*s, sing, false), xors = serialPrune(*s, sing, true);
      ASSERT_EQ(walks.first, xors.first) << "seed " << seed;
      ASSERT_EQ(walks.second, xors.second) << "seed " << seed;
      ++compared;
    }
    // No cones: the spheres' cuts would vanish and keep one edge each.
    FieldSingularities none;
    none.matching.assign(s->topology.numCorners(), 0);
    none.index4.assign(s->topology.numVertices(), 0);
    const auto walks = serialPrune(*s, none, false), xors = serialPrune(*s, none, true);
    ASSERT_EQ(walks.first, xors.first);
    std::uint64_t left = 0;
    for (const bool c : xors.first) left += c;
    EXPECT_GT(left, 0u);
    ++compared;
  }
  EXPECT_EQ(compared, 6);
}

TEST(Cut, ClosedSphereWithAtMostOneConeKeepsOneEdge) {
  // Not a valid field on a sphere (Poincare-Hopf wants 8 quarter turns), but the cut must still
  // leave a disk: the pruned cut would vanish, so one edge (at the cone, if any) stays.
  const Surface s = makeSurface(testing::icosphereMesh(2));
  CrossField field;
  field.direction.assign(s.mesh.numFaces(), Vec3f::Zero());
  FieldSingularities sing;
  sing.matching.assign(s.topology.numCorners(), 0);
  sing.index4.assign(s.topology.numVertices(), 0);
  for (int cones = 0; cones <= 1; ++cones) {
    if (cones) {
      sing.index4[7] = 8;
      sing.cones = {7};
    }
    const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);
    expectCutIsDiskPerComponent(s, cut, "sphere cones=" + std::to_string(cones));
    ASSERT_EQ(cut.seams.size(), 1u);
    ASSERT_EQ(cut.seams[0].corners.size(), 1u);
    if (cones) EXPECT_TRUE(cut.seams[0].start == 7 || cut.seams[0].end == 7);
    for (CornerId c = 0; c < cut.corners.size(); ++c) EXPECT_EQ(cut.corners.matching(c), 0);
  }
}

TEST(Cut, PackedCornerFlagsKeepCutAndMatchingApart) {
  // Four bits per corner, two corners to a byte, hold both: every sequence of edits reads back like
  // two separate arrays, and an edit never touches the corner that shares its byte. An odd count
  // leaves the last byte half used.
  constexpr CornerId n = 65;
  CutCorners packed(n, true);
  std::vector<bool> cut(n, true);
  std::vector<std::uint8_t> matching(n, 0);
  std::uint32_t state = 12345;
  for (int step = 0; step < 2000; ++step) {
    state = state * 1664525u + 1013904223u;
    const CornerId c = (state >> 8) % n;
    if ((state >> 20) & 1) {
      cut[c] = (state >> 21) & 1;
      packed.setCut(c, cut[c]);
    } else {
      matching[c] = (state >> 21) & 3;
      packed.setMatching(c, static_cast<std::uint8_t>((state >> 21) & 7));  // taken mod 4
    }
    for (CornerId k = 0; k < n; ++k) {
      ASSERT_EQ(packed.isCut(k), cut[k]) << "step " << step;
      ASSERT_EQ(packed.matching(k), matching[k]) << "step " << step;
    }
  }
  const std::vector<std::uint8_t> bytes = packed.cornerBytes();
  ASSERT_EQ(bytes.size(), n);
  for (CornerId k = 0; k < n; ++k) EXPECT_EQ(bytes[k], CutCorners::byteOf(cut[k], matching[k])) << "corner " << k;
  EXPECT_EQ(packed.size(), n);
  EXPECT_EQ(packed.numBytes(), 33u);
  EXPECT_EQ(packed.memoryBytes(), 33u);  // half a byte per corner
  EXPECT_EQ(CutCorners(n, false).cornerBytes(), std::vector<std::uint8_t>(n, 0));
}

TEST(Cut, PackedFaceRotationsReadBackAsABytePerFace) {
  // Two bits per face, four faces to a byte: random edits read back like a plain array, an edit
  // never touches the faces that share its byte, and a count not a multiple of 4 is whole.
  constexpr FaceId n = 37;
  FaceRotations packed(n);
  std::vector<std::uint8_t> plain(n, 0);
  std::uint32_t state = 777;
  for (int step = 0; step < 1000; ++step) {
    state = state * 1664525u + 1013904223u;
    const FaceId f = (state >> 8) % n;
    plain[f] = (state >> 20) & 3;
    packed.set(f, static_cast<std::uint8_t>((state >> 20) & 7));  // taken mod 4
    for (FaceId g = 0; g < n; ++g) ASSERT_EQ(packed[g], plain[g]) << "step " << step;
  }
  EXPECT_EQ(packed.faceBytes(), plain);
  EXPECT_EQ(packed.size(), n);
  EXPECT_EQ(packed.memoryBytes(), 10u);  // a quarter byte per face
  FaceRotations copy = packed;
  EXPECT_TRUE(copy == packed);
  copy.set(n - 1, static_cast<std::uint8_t>(packed[n - 1] + 1));
  EXPECT_TRUE(copy != packed);
  EXPECT_EQ(FaceRotations(5).faceBytes(), std::vector<std::uint8_t>(5, 0));
}

TEST(Cut, SeamIndexRejectsCornersOffInteriorEdges) {
  const Surface s = makeSurface(testing::gridMesh(3, 3));
  CornerId boundary = 0;
  while (!s.topology.isBoundaryEdge(boundary)) ++boundary;
  SeamCurve seam;
  seam.corners = {boundary};
  EXPECT_THROW(SeamIndex(s.topology, {seam}), InputError);
  seam.corners = {s.topology.numCorners()};
  EXPECT_THROW(SeamIndex(s.topology, {seam}), InputError);
}

TEST(Cut, InconsistentMatchingsThrow) {
  // Matchings that turn around vertices not marked as cones cannot be combed to 0 off the cut
  // and constant along seams: cutToDisk must say so rather than return wrong seams.
  const Surface s = makeSurface(testing::torusMesh(12, 8));
  CrossField field;
  field.direction.assign(s.mesh.numFaces(), Vec3f::Zero());
  FieldSingularities sing;
  sing.matching.assign(s.topology.numCorners(), 0);
  sing.index4.assign(s.topology.numVertices(), 0);
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    const CornerId o = s.topology.opposite(c);
    if (c < o && std::hash<CornerId>()(c * 2654435761u) % 3 == 0) {
      sing.matching[c] = 1;
      sing.matching[o] = 3;
    }
  }
  EXPECT_THROW(cutToDisk(s.mesh, s.topology, field, sing), TopologyError);
  sing.matching.pop_back();
  EXPECT_THROW(cutToDisk(s.mesh, s.topology, field, sing), InputError);
}

TEST(Cut, SharedMeshes) {
  for (const char* name : {"camelhead.off", "fertility.off", "bumpy.off"}) {
    const std::string path = testing::sharedMesh(name);
    if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage(name);
    const Surface s = loadShared(path);
    const CrossField field = computeSmoothestField(s.mesh, s.topology);
    checkAll(s, field, name);
    const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
    const CutResult cut = cutToDisk(s.mesh, s.topology, field, sing);
    std::printf("[ info ] %s: %zu cones, %zu seams\n", name, sing.cones.size(), cut.seams.size());
  }
  const std::string lilium = testing::sharedMesh("lilium.obj");
  const std::string liliumField = testing::sharedMesh("lilium.crossfield");
  if (lilium.empty() || liliumField.empty()) GTEST_SKIP() << testing::missingSharedMessage("lilium.*");
  const Surface s = makeSurface(readMesh(lilium));
  checkAll(s, importField(liliumField, s.mesh), "lilium imported field");
}

}  // namespace
}  // namespace seamvox
