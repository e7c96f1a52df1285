// Cleaning raw meshes (core/mesh/clean): welding, degenerate and duplicate faces, unreferenced
// vertices, orientation, non-manifold edges and vertices. Every output validates, the report
// counts exactly what was injected, and faceOrigin/vertexOrigin lead back to the input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <numeric>
#include <random>
#include <set>

#include "core/mesh/clean.h"
#include "core/mesh/subdivide.h"
#include "core/mesh/topology.h"
#include "core/system/errors.h"
#include "tests/test_meshes.h"

namespace seamvox {
namespace {

using testing::concatMeshes;
using testing::gridMesh;
using testing::torusMesh;

Topology buildOf(const TriangleMesh& mesh) { return Topology::build(mesh.triangles, mesh.numVertices()); }

std::array<Vec3f, 3> sortedCorners(const TriangleMesh& mesh, const Triangle& t) {
  std::array<Vec3f, 3> p{mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
  std::sort(p.begin(), p.end(), [](const Vec3f& a, const Vec3f& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  return p;
}

// Every output vertex has its input vertex's position and every output face lies on its input
// face's positions (in some order: flips and welds may change the indices, not the places).
void expectOriginsLeadBack(const TriangleMesh& input, const CleanResult& r) {
  ASSERT_EQ(r.vertexOrigin.size(), r.mesh.numVertices());
  ASSERT_EQ(r.faceOrigin.size(), r.mesh.numFaces());
  for (VertexId v = 0; v < r.mesh.numVertices(); ++v) {
    ASSERT_LT(r.vertexOrigin[v], input.numVertices());
    EXPECT_EQ(r.mesh.positions[v], input.positions[r.vertexOrigin[v]]) << "vertex " << v;
  }
  std::set<FaceId> used;
  for (FaceId f = 0; f < r.mesh.numFaces(); ++f) {
    ASSERT_LT(r.faceOrigin[f], input.numFaces());
    EXPECT_TRUE(used.insert(r.faceOrigin[f]).second) << "two faces from input face " << r.faceOrigin[f];
    EXPECT_EQ(sortedCorners(r.mesh, r.mesh.triangles[f]), sortedCorners(input, input.triangles[r.faceOrigin[f]]))
        << "face " << f;
  }
}

std::int64_t eulerCharacteristic(const Topology& t) {
  std::int64_t halfEdges = 0, boundary = 0;
  for (CornerId c = 0; c < t.numCorners(); ++c) (t.isBoundaryEdge(c) ? boundary : halfEdges) += 1;
  const std::int64_t edges = halfEdges / 2 + boundary;
  return std::int64_t(t.numVertices()) - edges + t.numFaces();
}

// A torus corrupted the way scans are, with every injected defect counted.
TEST(Clean, RandomCorruptionIsRepairedAndCountedExactly) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 4; ++trial) {
    const TriangleMesh clean = torusMesh(16 + 2 * trial, 9);
    const std::uint32_t nv = clean.numVertices(), nf = clean.numFaces();
    TriangleMesh input = clean;
    std::uniform_int_distribution<std::uint32_t> face(0, nf - 1), corner(0, 2);
    // Split vertices: a corner gets a fresh copy of its vertex (welding must merge it back).
    std::set<std::pair<FaceId, int>> splitCorners;
    for (int k = 0; k < 25; ++k) splitCorners.insert({face(rng), int(corner(rng))});
    for (const auto& [f, k] : splitCorners) {
      input.positions.push_back(input.positions[input.triangles[f][k]]);
      input.triangles[f][k] = input.numVertices() - 1;
    }
    // Flips: a minority of the faces, so the component keeps the majority's orientation.
    std::set<FaceId> flips;
    for (int k = 0; k < 20; ++k) flips.insert(face(rng));
    for (FaceId f : flips) std::swap(input.triangles[f][1], input.triangles[f][2]);
    // Duplicates (either orientation, of the original or of a split copy), degenerates, and
    // unreferenced vertices far away (distinct, so they do not weld).
    const std::uint32_t duplicates = 15, degenerates = 10, unreferenced = 7;
    // sourceOf: the torus face each input face stands for (kInvalidId: degenerate).
    std::vector<FaceId> sourceOf(nf);
    std::iota(sourceOf.begin(), sourceOf.end(), 0u);
    for (std::uint32_t k = 0; k < duplicates; ++k) {
      // Same orientation as the (possibly flipped) face it copies, so either copy may survive
      // with the same flip count; reversed duplicates: RemovesDegenerateDuplicateAndUnreferenced.
      const FaceId f = face(rng);
      Triangle t = input.triangles[f];
      std::rotate(t.begin(), t.begin() + k % 3, t.end());
      input.triangles.push_back(t);
      sourceOf.push_back(f);
    }
    for (std::uint32_t k = 0; k < degenerates; ++k) {
      const Triangle t = clean.triangles[face(rng)];
      input.triangles.push_back({t[0], t[1], t[k % 2 == 0 ? 0 : 1]});
      sourceOf.push_back(kInvalidId);
    }
    for (std::uint32_t k = 0; k < unreferenced; ++k) input.positions.emplace_back(100.f + k, 0.f, 0.f);
    // Shuffle the faces so origins are not the identity.
    std::vector<FaceId> order(input.numFaces());
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<Triangle> shuffled(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) shuffled[i] = input.triangles[order[i]];
    input.triangles = shuffled;

    CleanOptions weld;
    weld.weldVertices = true;
    const CleanResult r = cleanMesh(input, weld);
    EXPECT_NO_THROW(r.topology.validate());
    const CleanReport& report = r.report;
    EXPECT_EQ(report.inputFaces, input.numFaces());
    EXPECT_EQ(report.inputVertices, input.numVertices());
    EXPECT_EQ(report.weldedVertices, splitCorners.size());
    EXPECT_EQ(report.duplicateFaces, duplicates);
    EXPECT_EQ(report.degenerateFaces, degenerates);
    EXPECT_EQ(report.unreferencedVertices, unreferenced);
    EXPECT_EQ(report.flippedFaces, flips.size());
    EXPECT_EQ(report.nonManifoldEdges, 0u);
    EXPECT_EQ(report.nonManifoldVertices, 0u);
    EXPECT_EQ(report.outputFaces, nf);
    EXPECT_EQ(report.outputVertices, nv);
    EXPECT_EQ(r.mesh.numFaces(), nf);
    EXPECT_EQ(eulerCharacteristic(r.topology), 0) << "still a torus";
    for (CornerId c = 0; c < r.topology.numCorners(); ++c) EXPECT_FALSE(r.topology.isBoundaryEdge(c));
    expectOriginsLeadBack(input, r);
    // The surviving faces are the torus' own, one each, oriented as the torus was.
    std::vector<int> survivors(nf, 0);
    for (FaceId f = 0; f < r.mesh.numFaces(); ++f) {
      const FaceId original = sourceOf[order[r.faceOrigin[f]]];
      ASSERT_LT(original, nf) << "a degenerate face survived";
      ++survivors[original];
      const Triangle& t = r.mesh.triangles[f];
      const Vec3d n = (r.mesh.position(t[1]) - r.mesh.position(t[0])).cross(r.mesh.position(t[2]) - r.mesh.position(t[0]));
      const Triangle& o = clean.triangles[original];
      const Vec3d m = (clean.position(o[1]) - clean.position(o[0])).cross(clean.position(o[2]) - clean.position(o[0]));
      EXPECT_GT(n.dot(m), 0.0) << "face " << f << " not oriented like the torus";
    }
    EXPECT_EQ(std::count(survivors.begin(), survivors.end(), 1), std::ptrdiff_t(nf));
  }
}

TEST(Clean, InjectedFinsAndBowtiesAreSplit) {
  const TriangleMesh clean = torusMesh(24, 12);
  const Topology topology = buildOf(clean);
  TriangleMesh input = clean;
  // Fins on edges that share no vertex, bowtie triangles on other vertices (one each).
  std::vector<std::uint8_t> usedVertex(clean.numVertices(), 0);
  std::uint32_t fins = 0, bowties = 0;
  for (CornerId c = 0; c < topology.numCorners() && fins < 6; c += 37) {
    const VertexId a = topology.vertex(nextCorner(c)), b = topology.vertex(prevCorner(c));
    if (usedVertex[a] || usedVertex[b]) continue;
    usedVertex[a] = usedVertex[b] = 1;
    input.positions.push_back(((clean.positions[a] + clean.positions[b]) * 0.5f) + Vec3f(0.f, 0.f, 3.f));
    input.triangles.push_back({a, b, input.numVertices() - 1});
    ++fins;
  }
  for (VertexId v = 5; v < clean.numVertices() && bowties < 5; v += 29) {
    if (usedVertex[v]) continue;
    usedVertex[v] = 1;
    input.positions.push_back(clean.positions[v] + Vec3f(5.f, 0.f, 0.f));
    input.positions.push_back(clean.positions[v] + Vec3f(5.f, 1.f, 0.f));
    input.triangles.push_back({v, input.numVertices() - 2, input.numVertices() - 1});
    ++bowties;
  }
  ASSERT_EQ(fins, 6u);
  ASSERT_EQ(bowties, 5u);
  const CleanResult r = cleanMesh(input);
  EXPECT_NO_THROW(r.topology.validate());
  EXPECT_EQ(r.report.nonManifoldEdges, fins);
  // A fin's two vertices and a bowtie's shared vertex each get one copy per extra fan.
  EXPECT_EQ(r.report.nonManifoldVertices, 2 * fins + bowties);
  EXPECT_EQ(r.mesh.numVertices(), input.numVertices() + 2 * fins + bowties);
  EXPECT_EQ(r.mesh.numFaces(), input.numFaces());
  EXPECT_EQ(computeComponents(r.topology).components.size(), 1u + fins + bowties);
  expectOriginsLeadBack(input, r);
  EXPECT_EQ(r.report.unweldedBoundaryVertices, 0u) << "split copies of one vertex are not a crack";
}

// A grid cut along the line x = 2 with its own copies of that line's vertices on the right: a
// crack of 5 + 5 boundary vertices on each other, counted (and kept); welding joins them. A
// bowtie on a boundary corner: its two copies come from one input vertex, not counted.
TEST(Clean, AnUnweldedCrackIsCountedAndWeldingJoinsIt) {
  TriangleMesh mesh = gridMesh(4, 4, 1.0);
  std::vector<VertexId> copyOf(mesh.numVertices(), kInvalidId);
  for (Triangle& t : mesh.triangles) {
    const float cx = (mesh.positions[t[0]].x() + mesh.positions[t[1]].x() + mesh.positions[t[2]].x()) / 3.0f;
    if (cx < 2.0f) continue;
    for (VertexId& v : t) {
      if (mesh.positions[v].x() != 2.0f) continue;
      if (copyOf[v] == kInvalidId) {
        copyOf[v] = mesh.numVertices();
        mesh.positions.push_back(mesh.positions[v]);
      }
      v = copyOf[v];
    }
  }
  const VertexId corner = 0;
  ASSERT_EQ(mesh.positions[corner], Vec3f(0.f, 0.f, 0.f));
  mesh.positions.push_back(Vec3f(-1.f, -0.5f, 0.f));
  mesh.positions.push_back(Vec3f(-0.5f, -1.f, 0.f));
  mesh.triangles.push_back({corner, mesh.numVertices() - 1, mesh.numVertices() - 2});
  const CleanResult kept = cleanMesh(mesh);
  EXPECT_EQ(kept.report.nonManifoldVertices, 1u);
  EXPECT_EQ(kept.report.unweldedBoundaryVertices, 10u);
  EXPECT_EQ(computeComponents(kept.topology).components.size(), 3u);
  CleanOptions weld;
  weld.weldVertices = true;
  const CleanResult welded = cleanMesh(mesh, weld);
  EXPECT_EQ(welded.report.weldedVertices, 5u);
  EXPECT_EQ(welded.report.unweldedBoundaryVertices, 0u);
  EXPECT_EQ(computeComponents(welded.topology).components.size(), 2u);
}

// A 1280-face icosphere with one more face on one of its edges: after cleaning, the sphere's
// faces are glued to each other and the extra face is on its own.
void expectSphereClosedAndFaceApart(const TriangleMesh& mesh) {
  ASSERT_EQ(mesh.numFaces(), 1281u);
  const CleanResult clean = cleanMesh(mesh);
  EXPECT_EQ(clean.report.nonManifoldEdges, 1u);
  std::uint32_t open = 0;
  for (CornerId k = 0; k < 3 * 1280; ++k) open += clean.topology.opposite(k) == kInvalidId;
  EXPECT_EQ(open, 0u) << "the sphere's faces are glued to each other";
  for (CornerId k = 3 * 1280; k < 3 * 1281; ++k) EXPECT_EQ(clean.topology.opposite(k), kInvalidId);
  EXPECT_EQ(computeComponents(clean.topology).components.size(), 2u);
}

// A flap folded onto one of the edge's faces, lying exactly in the plane of the other one (so it
// matches that face better than the two surface faces match each other, 1280-face icosphere:
// about 10 degrees): the surface's faces are glued, the flap is left on its own, the sphere
// stays closed. Glued to the far face instead, the sphere would open along the edge and the
// flap would cover its face in the map (quads through a vertex twice on fin-damaged scans).
TEST(Clean, AFlapOnAnEdgeLeavesTheSurfaceClosedHoweverFlatItLies) {
  TriangleMesh mesh = testing::icosphereMesh(3);
  const Topology sphere = buildOf(mesh);
  const CornerId c = 0;  // face 0's edge a -> b opposite its corner 0
  const VertexId a = sphere.vertex(nextCorner(c)), b = sphere.vertex(prevCorner(c));
  const VertexId d = sphere.vertex(sphere.opposite(c));  // the far face runs b -> a -> d
  const Vec3d pa = mesh.position(a), pb = mesh.position(b), pd = mesh.position(d);
  const Vec3d along = (pb - pa).normalized();
  const Vec3d toD = (pd - pa) - (pd - pa).dot(along) * along;  // in the far face's plane
  mesh.positions.push_back((0.5 * (pa + pb) - toD).cast<float>());
  mesh.triangles.push_back({a, b, mesh.numVertices() - 1});  // runs a -> b, as face 0 does
  const Vec3d flapNormal = gluingNormal(pa, pb, mesh.position(mesh.numVertices() - 1));
  const Vec3d farNormal = gluingNormal(pb, pa, pd);
  const Triangle t0 = mesh.triangles[0];
  const Vec3d faceNormal = gluingNormal(mesh.position(t0[0]), mesh.position(t0[1]), mesh.position(t0[2]));
  ASSERT_GT(gluingAlignment(flapNormal, farNormal), gluingAlignment(faceNormal, farNormal))
      << "the flap lies flatter against the far face than the sphere's own face";
  expectSphereClosedAndFaceApart(mesh);
}

// A scan's collinear face on an edge of a closed surface, lying in the plane of one of the edge's
// faces (so its rounding-noise normal matches that face better than the two faces match each
// other): the surface's two faces are glued, the sliver is left on its own, the sphere stays closed.
TEST(Clean, ASliverOnAnEdgeIsGluedLast) {
  TriangleMesh mesh = testing::icosphereMesh(3);
  const Triangle t = mesh.triangles[0];
  const Vec3d a = mesh.position(t[0]), b = mesh.position(t[1]), c = mesh.position(t[2]);
  const Vec3d along = (b - a).normalized(), n = (b - a).cross(c - a).normalized();
  const Vec3d away = n.cross(along).dot(c - a) > 0.0 ? Vec3d(-n.cross(along)) : Vec3d(n.cross(along));
  mesh.positions.push_back((0.5 * (a + b) + 1e-5 * (b - a).norm() * away).cast<float>());
  const VertexId tip = mesh.numVertices() - 1;
  mesh.triangles.push_back({t[0], tip, t[1]});  // runs b -> a, as the sphere's other face there
  ASSERT_LT(gluingNormal(a, mesh.position(tip), b).norm(), 0.5) << "a sliver";
  expectSphereClosedAndFaceApart(mesh);
}

TEST(Clean, RemovesDegenerateDuplicateAndUnreferenced) {
  TriangleMesh mesh = gridMesh(3, 3);
  const std::uint32_t faces = mesh.numFaces();
  mesh.triangles.push_back(mesh.triangles[4]);                       // exact duplicate
  const Triangle t = mesh.triangles[7];
  mesh.triangles.push_back({t[0], t[2], t[1]});                      // reversed duplicate
  mesh.triangles.push_back({t[0], t[0], t[1]});                      // degenerate
  mesh.positions.emplace_back(9.f, 9.f, 9.f);                        // unreferenced
  const CleanResult r = cleanMesh(std::move(mesh));
  EXPECT_EQ(r.report.duplicateFaces, 2u);
  EXPECT_EQ(r.report.degenerateFaces, 1u);
  EXPECT_EQ(r.report.unreferencedVertices, 1u);
  EXPECT_EQ(r.mesh.numFaces(), faces);
  EXPECT_EQ(r.mesh.numVertices(), 16u);
  ASSERT_EQ(r.faceOrigin.size(), faces);
  for (FaceId f = 0; f < faces; ++f) EXPECT_EQ(r.faceOrigin[f], f);
  EXPECT_NO_THROW(r.topology.validate());
}

TEST(Clean, WeldsCoincidentVertices) {
  // Two halves of a grid with their shared column duplicated: two components until welded.
  TriangleMesh left = gridMesh(2, 3), right = gridMesh(2, 3);
  for (Vec3f& p : right.positions) p.x() += 2.f;
  const TriangleMesh soup = concatMeshes({left, right});
  EXPECT_EQ(computeComponents(buildOf(soup)).components.size(), 2u);

  CleanOptions weld;
  weld.weldVertices = true;
  CleanResult r = cleanMesh(soup, weld);
  EXPECT_EQ(r.report.weldedVertices, 4u);
  EXPECT_EQ(r.mesh.numVertices(), 5u * 4u);
  const ComponentsResult comps = computeComponents(r.topology);
  ASSERT_EQ(comps.components.size(), 1u);
  EXPECT_EQ(comps.components[0].boundaryLoops, 1u);
  EXPECT_NO_THROW(r.topology.validate());

  // With noise below the tolerance, welding needs the tolerance.
  TriangleMesh noisy = soup;
  for (VertexId v = right.numVertices() - 0; v < noisy.numVertices(); ++v) noisy.positions[v].y() += 1e-6f;
  EXPECT_EQ(cleanMesh(noisy, weld).report.weldedVertices, 0u);
  weld.weldTolerance = 1e-4;
  r = cleanMesh(noisy, weld);
  EXPECT_EQ(r.report.weldedVertices, 4u);
  EXPECT_EQ(computeComponents(r.topology).components.size(), 1u);
}

TEST(Clean, SplitsNonManifoldEdgesAndVertices) {
  TriangleMesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  CleanResult r = cleanMesh(fin);
  EXPECT_EQ(r.report.nonManifoldEdges, 1u);
  EXPECT_NO_THROW(r.topology.validate());
  EXPECT_EQ(r.mesh.numFaces(), 3u);

  TriangleMesh bowtie;
  bowtie.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  bowtie.triangles = {{0, 1, 2}, {0, 3, 4}};
  r = cleanMesh(bowtie);
  EXPECT_EQ(r.report.nonManifoldVertices, 1u);
  EXPECT_EQ(r.mesh.numVertices(), 6u);
  EXPECT_EQ(r.vertexOrigin[5], 0u);
  EXPECT_EQ(r.mesh.positions[5], r.mesh.positions[0]);
  EXPECT_NO_THROW(r.topology.validate());
  EXPECT_EQ(computeComponents(r.topology).components.size(), 2u);
}

TEST(Clean, OrientsFacesConsistently) {
  TriangleMesh torus = torusMesh(12, 8);
  std::vector<Vec2d> values(3 * torus.numFaces());
  for (CornerId c = 0; c < values.size(); ++c) values[c] = Vec2d(torus.triangles[c / 3][c % 3], 0.5);
  torus.cornerUV = WedgeMap::fromCorners(torus.triangles, values);
  EXPECT_EQ(torus.cornerUV.numWedges(), torus.numVertices());
  for (FaceId f : {3u, 40u, 41u, 100u}) {
    std::swap(torus.triangles[f][1], torus.triangles[f][2]);
    torus.cornerUV.swapCorners(3 * f + 1, 3 * f + 2);
  }
  const CleanResult r = cleanMesh(torus);
  EXPECT_EQ(r.report.flippedFaces, 4u);
  EXPECT_EQ(r.report.nonManifoldEdges, 0u);
  EXPECT_NO_THROW(r.topology.validate());
  EXPECT_EQ(computeComponents(r.topology).components.at(0).genus, 1);
  // The UV of each corner still belongs to its vertex.
  for (CornerId c = 0; c < r.topology.numCorners(); ++c) {
    EXPECT_EQ(r.mesh.cornerUV[c].x(), double(r.vertexOrigin[r.topology.vertex(c)]));
  }
}

TEST(Clean, NonOrientableStripBecomesValidTopology) {
  // Moebius strip: a 6 x 1 grid whose last column is glued to the first with a twist.
  TriangleMesh m = gridMesh(6, 1);
  for (Triangle& t : m.triangles)
    for (VertexId& v : t) {
      if (v == 6) v = 7;        // top-right of row 0 -> bottom-left of row 1 (twist)
      else if (v == 13) v = 0;  // top-right -> bottom-left
    }
  const CleanResult r = cleanMesh(m);
  EXPECT_NO_THROW(r.topology.validate());
  EXPECT_GE(r.report.nonManifoldEdges, 1u);
}

TEST(Clean, RejectsBadInput) {
  TriangleMesh nan = gridMesh(1, 1);
  nan.positions[2].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(cleanMesh(nan), InputError);

  TriangleMesh onlyDegenerate;
  onlyDegenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  onlyDegenerate.triangles = {{0, 1, 1}};
  EXPECT_THROW(cleanMesh(onlyDegenerate), InputError);

  TriangleMesh bad = gridMesh(1, 1);
  bad.triangles[0][0] = 17;
  EXPECT_THROW(cleanMesh(bad), InputError);
}

TEST(Clean, CountsZeroAreaFacesAndKeepsThem) {
  TriangleMesh m = gridMesh(2, 1);
  m.positions[1] = Vec3f(0.f, 0.f, 0.f) * 0.5f + Vec3f(1.f, 0.f, 0.f);  // unchanged
  // Collapse face 0 to a segment by moving vertex 4 (1,1) onto the line through 0 and 1? Use a sliver:
  m.positions.push_back({0.5f, 0.f, 0.f});
  m.triangles.push_back({0, 1, m.numVertices() - 1});
  const CleanResult r = cleanMesh(m);
  EXPECT_EQ(r.report.zeroAreaFaces, 1u);
  EXPECT_EQ(r.mesh.numFaces(), 5u);
}

/// Faces whose vertex ids span more than 1% of the vertices.
double scatteredFraction(const TriangleMesh& mesh) {
  std::uint64_t scattered = 0;
  for (const Triangle& t : mesh.triangles) {
    scattered += 100u * std::uint64_t(*std::max_element(t.begin(), t.end()) - *std::min_element(t.begin(), t.end())) >
                 mesh.numVertices();
  }
  return double(scattered) / mesh.numFaces();
}

TEST(Clean, ScatteredMeshIsPutInSpatialOrderWithItsOriginsKept) {
  const TriangleMesh input = testing::shuffledMesh(testing::generatedMesh(MeshKind::Scan, 40000), 7);
  ASSERT_GT(scatteredFraction(input), 0.5);
  CleanOptions options;
  options.reorderMinFaces = 1000;
  const CleanResult r = cleanMesh(input, options);
  EXPECT_TRUE(r.report.reordered);
  EXPECT_LT(scatteredFraction(r.mesh), 0.25);
  options.reorderMinFaces = std::numeric_limits<std::uint32_t>::max();
  const CleanResult kept = cleanMesh(input, options);
  EXPECT_FALSE(kept.report.reordered);
  ASSERT_EQ(r.mesh.numFaces(), kept.mesh.numFaces());
  ASSERT_EQ(r.mesh.numVertices(), kept.mesh.numVertices());
  // Every output vertex and face leads back to the input's, corners in the same order.
  std::vector<std::uint8_t> faceSeen(input.numFaces(), 0);
  for (VertexId v = 0; v < r.mesh.numVertices(); ++v) {
    ASSERT_EQ(r.mesh.positions[v], input.positions[r.vertexOrigin[v]]);
  }
  for (FaceId f = 0; f < r.mesh.numFaces(); ++f) {
    const Triangle& in = input.triangles[r.faceOrigin[f]];
    for (int k = 0; k < 3; ++k) ASSERT_EQ(r.vertexOrigin[r.mesh.triangles[f][k]], in[k]) << "face " << f;
    faceSeen[r.faceOrigin[f]] = 1;
  }
  EXPECT_EQ(std::count(faceSeen.begin(), faceSeen.end(), std::uint8_t(1)), std::ptrdiff_t(r.mesh.numFaces()));
  r.topology.validate();
  // The same counts as cleaning in the input's order.
  EXPECT_EQ(kept.report.duplicateFaces, r.report.duplicateFaces);
  EXPECT_EQ(kept.report.nonManifoldEdges, r.report.nonManifoldEdges);
  EXPECT_EQ(kept.report.spikeVertices, r.report.spikeVertices);
  EXPECT_EQ(kept.report.zeroAreaFaces, r.report.zeroAreaFaces);
}

TEST(Clean, CoherentOrSmallMeshesKeepTheirOrder) {
  // A grid in row order is coherent: nothing moves, whatever the size threshold.
  const TriangleMesh ordered = gridMesh(100, 200);
  CleanOptions options;
  options.reorderMinFaces = 1000;
  const CleanResult a = cleanMesh(ordered, options);
  EXPECT_FALSE(a.report.reordered);
  for (FaceId f = 0; f < a.mesh.numFaces(); ++f) ASSERT_EQ(a.faceOrigin[f], f);
  // Below the default size a shuffled mesh keeps its order too.
  const CleanResult b = cleanMesh(testing::shuffledMesh(ordered, 3));
  EXPECT_FALSE(b.report.reordered);
}

// A subdivided mesh keeps its faces together but appends each level's vertices after the last:
// most faces span far apart ids. Only its vertices are renumbered, in the order the faces first
// use them; faces, geometry and the cleaning's counts stay those of the input order.
TEST(Clean, ScatteredVertexIdsAreRenumberedInFaceOrder) {
  const testing::Surface coarse = testing::makeSurface(testing::generatedMesh(MeshKind::Sphere, 2000));
  SubdivideOptions levels;
  levels.levels = 3;
  TriangleMesh input = subdivideMesh(coarse.mesh, coarse.topology, levels).mesh;
  input.positions.push_back({9.f, 9.f, 9.f});  // an unreferenced vertex, dropped wherever it goes
  ASSERT_GT(scatteredFraction(input), 0.5);
  CleanOptions options;
  options.reorderMinFaces = 1000;
  const CleanResult r = cleanMesh(input, options);
  EXPECT_TRUE(r.report.verticesRenumbered);
  EXPECT_FALSE(r.report.reordered);
  EXPECT_LT(scatteredFraction(r.mesh), 0.25);
  options.reorderMinFaces = std::numeric_limits<std::uint32_t>::max();
  const CleanResult kept = cleanMesh(input, options);
  EXPECT_FALSE(kept.report.verticesRenumbered);
  ASSERT_EQ(r.mesh.numFaces(), input.numFaces());
  ASSERT_EQ(r.mesh.numVertices(), kept.mesh.numVertices());
  VertexId next = 0;
  for (FaceId f = 0; f < r.mesh.numFaces(); ++f) {
    ASSERT_EQ(r.faceOrigin[f], f);
    for (int k = 0; k < 3; ++k) {
      const VertexId v = r.mesh.triangles[f][k];
      ASSERT_LE(v, next) << "face " << f << " uses a vertex before its turn";
      if (v == next) ++next;
      ASSERT_EQ(r.vertexOrigin[v], input.triangles[f][k]);
      ASSERT_EQ(r.mesh.positions[v], input.positions[input.triangles[f][k]]);
    }
  }
  EXPECT_EQ(next, r.mesh.numVertices());
  r.topology.validate();
  EXPECT_EQ(kept.report.unreferencedVertices, 1u);
  EXPECT_EQ(r.report.unreferencedVertices, 1u);
  EXPECT_EQ(kept.report.spikeVertices, r.report.spikeVertices);
  EXPECT_EQ(kept.report.zeroAreaFaces, r.report.zeroAreaFaces);
  // Ids that already follow the faces stay as they are.
  options.reorderMinFaces = 1000;
  const CleanResult again = cleanMesh(r.mesh, options);
  EXPECT_FALSE(again.report.verticesRenumbered);
  EXPECT_FALSE(again.report.reordered);
}

// The spike test by its definition: per vertex the two edges of every corner around it (an
// interior edge twice), their least and median length, then the median of the neighbours' medians
// over the same corners. findSpikeVertices lists each interior edge once; on a scan with holes,
// islands and vertices pulled far out, its spikes must be these.
TEST(CleanSpikes, SameAsTheDefinitionWithEveryCornersTwoEdges) {
  TriangleMesh mesh = testing::generatedMesh(MeshKind::Scan, 20000);
  std::mt19937 random(5);
  for (int k = 0; k < 40; ++k) {
    const VertexId v = random() % mesh.numVertices();
    mesh.positions[v] += Vec3f(0.0f, 0.0f, 0.5f * float(1 + k % 3));
  }
  const CleanResult cleaned = cleanMesh(std::move(mesh));
  TriangleMesh m = cleaned.mesh;
  const Topology& topology = cleaned.topology;
  const std::uint32_t nv = m.numVertices();
  // Boundary vertices pulled out by varying amounts too: there the two edges of every corner are
  // not every edge twice.
  for (VertexId v = 0, pulled = 0; v < nv && pulled < 60; v += 7) {
    if (topology.isIsolatedVertex(v) || !topology.isBoundaryVertex(v)) continue;
    m.positions[v] += Vec3f(0.0f, 0.0f, 0.02f * float(1 + pulled++));
  }
  const auto medianOf = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
  };
  std::vector<double> typical(nv, 0.0), shortest(nv, 0.0);
  std::size_t boundary = 0;
  for (VertexId v = 0; v < nv; ++v) {
    if (topology.isIsolatedVertex(v)) continue;
    boundary += topology.isBoundaryVertex(v);
    std::vector<double> lengths;
    topology.forEachCornerAround(v, [&](CornerId c) {
      for (CornerId o : {nextCorner(c), prevCorner(c)}) lengths.push_back((m.position(topology.vertex(o)) - m.position(v)).norm());
    });
    shortest[v] = *std::min_element(lengths.begin(), lengths.end());
    typical[v] = medianOf(lengths);
  }
  std::vector<VertexId> expected;
  for (VertexId v = 0; v < nv; ++v) {
    if (topology.isIsolatedVertex(v)) continue;
    std::vector<double> around;
    topology.forEachCornerAround(v, [&](CornerId c) {
      for (CornerId o : {nextCorner(c), prevCorner(c)}) around.push_back(typical[topology.vertex(o)]);
    });
    const double scale = medianOf(around);
    if (scale > 0.0 && shortest[v] > kSpikeRatio * scale) expected.push_back(v);
  }
  ASSERT_GT(boundary, 0u) << "no boundary: the test needs holes";
  ASSERT_GE(expected.size(), 10u) << "too few spikes to compare";
  EXPECT_EQ(findSpikeVertices(m, topology), expected);
}

}  // namespace
}  // namespace seamvox
