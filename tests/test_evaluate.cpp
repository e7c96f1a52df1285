// Evaluation of the map (core/solve/evaluate): the cut's wedges, one evaluation per wedge equal
// to evaluating each corner on its own, constants reproduced (hat and voxel bases), wedges
// outside the basis left unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <complex>
#include <random>
#include <vector>

#include "core/basis/basis.h"
#include "core/basis/reduce.h"
#include "core/basis/voxel_grid.h"
#include "core/cut/cut.h"
#include "core/mesh/clean.h"
#include "core/field/field.h"
#include "core/solve/detail_wedges.h"
#include "core/solve/evaluate.h"
#include "tests/test_meshes.h"

namespace seamvox {
namespace {

using Complex = std::complex<double>;

struct CutTorus : testing::CutSurface {
  CutTorus() : CutSurface(testing::makeCutSurface(testing::torusMesh(12, 8), 5)) {}
};

TEST(Evaluate, WedgesChangeExactlyAcrossCutEdges) {
  const CutTorus t;
  const WedgeMap wedges = buildCutWedges(t.s.topology, t.cut);
  ASSERT_EQ(wedges.size(), t.s.topology.numCorners());
  for (CornerId c = 0; c < t.s.topology.numCorners(); ++c) {
    // The corner turning across the edge of prevCorner(c) (the edge from vertex(c) to vertex(next(c))).
    const CornerId edge = prevCorner(c);
    const CornerId o = t.s.topology.opposite(edge);
    if (o == kInvalidId) continue;
    const CornerId around = prevCorner(o);  // same vertex, other side of that edge (topology.h)
    ASSERT_EQ(t.s.topology.vertex(around), t.s.topology.vertex(c));
    if (!t.cut.corners.isCut(edge)) {
      EXPECT_EQ(wedges.wedge(around), wedges.wedge(c)) << "corner " << c;
    }
  }
  // Wedges never span two vertices. Counting each vertex's cut edges once per corner (the edge
  // of prevCorner, which leaves the vertex): an interior vertex with k >= 1 cut edges has k
  // wedges, a boundary vertex (its incoming boundary edge not counted) one fewer than its cut
  // edges: max(1, count) either way.
  std::vector<VertexId> wedgeVertex(wedges.numWedges(), kInvalidId);
  for (CornerId c = 0; c < t.s.topology.numCorners(); ++c) {
    VertexId& v = wedgeVertex[wedges.wedge(c)];
    if (v == kInvalidId) v = t.s.topology.vertex(c);
    EXPECT_EQ(v, t.s.topology.vertex(c));
  }
  std::vector<std::uint32_t> cutEdges(t.s.topology.numVertices(), 0), wedgeCount(t.s.topology.numVertices(), 0);
  for (CornerId c = 0; c < t.s.topology.numCorners(); ++c) {
    if (t.cut.corners.isCut(prevCorner(c))) ++cutEdges[t.s.topology.vertex(c)];
  }
  for (VertexId v : wedgeVertex) ++wedgeCount[v];
  for (VertexId v = 0; v < t.s.topology.numVertices(); ++v) {
    EXPECT_EQ(wedgeCount[v], std::max(1u, cutEdges[v])) << "vertex " << v;
  }
}

// Over many blocks of vertices (holes, islands, a cut): wedges numbered in vertex order, each
// vertex's in the order its fan is walked, as one serial walk over every vertex numbers them.
TEST(Evaluate, WedgesAreNumberedInVertexOrderOverManyBlocks) {
  const testing::CutSurface t = testing::makeCutSurface(cleanMesh(testing::generatedMesh(MeshKind::Scan, 120000)).mesh, 3);
  const Topology& topology = t.s.topology;
  ASSERT_GT(topology.numVertices(), 3u << 14) << "the test needs several blocks of vertices";
  std::vector<std::uint32_t> expected(topology.numCorners(), 0), firstWedge(topology.numVertices(), 0);
  std::uint32_t w = 0;
  for (VertexId v = 0; v < topology.numVertices(); ++v) {
    firstWedge[v] = w;
    bool open = false;
    detail::walkWedges(topology, t.cut.corners, v, [&](CornerId c) {
      if (c == kInvalidId) {
        if (open) ++w;
        open = false;
      } else {
        open = true;
        expected[c] = w;
      }
    });
    if (open) ++w;
  }
  const WedgeMap wedges = buildCutWedges(topology, t.cut);
  ASSERT_EQ(wedges.numWedges(), w);
  std::size_t differ = 0;
  for (CornerId c = 0; c < topology.numCorners(); ++c) differ += wedges.wedge(c) != expected[c];
  EXPECT_EQ(differ, 0u);
  // Ids per vertex over the triangles where few corners lie off their vertex's first wedge (this
  // random field's cut has too many: ids per corner), the same ids either way.
  std::size_t off = 0;
  for (CornerId c = 0; c < topology.numCorners(); ++c) off += expected[c] != firstWedge[topology.vertex(c)];
  const WedgeMap viewing = buildCutWedges(topology, t.cut, true);
  EXPECT_EQ(viewing.viewsTriangles(), off <= topology.numCorners() / 16 + 1024) << off << " corners off";
  ASSERT_EQ(viewing.size(), wedges.size());
  ASSERT_EQ(viewing.numWedges(), w);
  differ = 0;
  for (CornerId c = 0; c < topology.numCorners(); ++c) differ += viewing.wedge(c) != expected[c];
  EXPECT_EQ(differ, 0u);
}

TEST(Evaluate, PerWedgeEqualsPerCorner) {
  const CutTorus t;
  const HatBasis basis(t.s.mesh, t.s.topology, t.field, t.cut, {});
  const Reduction reduction = reduceBasis(basis);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> value(-3.0, 3.0);
  std::vector<Complex> x(reduction.numUnknowns());
  for (Complex& xi : x) xi = Complex(value(rng), value(rng));
  WedgeMap uv = buildCutWedges(t.s.topology, t.cut);
  evaluateMap(basis, reduction, x, uv);
  // A hat map's value at a corner is the coefficient of the corner's domain.
  const std::vector<Complex> coefficients = expandCoefficients(reduction, x);
  for (CornerId c = 0; c < t.s.topology.numCorners(); ++c) {
    const Complex q = coefficients[basis.cornerDomain()[c]];
    EXPECT_LT((uv[c] - Vec2d(q.real(), q.imag())).norm(), 1e-12) << "corner " << c;
  }
}

TEST(Evaluate, ConstantsAreReproducedByHatAndVoxelBases) {
  const testing::Surface s = testing::makeSurface(testing::gridMesh(9, 7, 0.3));
  const CrossField field = testing::constantField(s.mesh);
  const CutResult cut = testing::boundaryCut(s.topology);
  const Complex constant(2.5, -1.25);
  const HatBasis hat(s.mesh, s.topology, field, cut, {});
  VoxelBasisOptions voxelOptions;
  voxelOptions.gridResolution = 8;
  const VoxelBuildResult voxel = buildVoxelBasis(s.mesh, s.topology, field, cut, voxelOptions);
  for (const Basis* basis : {static_cast<const Basis*>(&hat), static_cast<const Basis*>(voxel.basis.get())}) {
    const Reduction reduction = reduceBasis(*basis);
    ASSERT_TRUE(reduction.map.offset.empty());
    std::vector<Complex> x(reduction.numUnknowns(), 0.0);
    for (std::uint32_t j = 0; j < reduction.numPositional; ++j) x[j] = constant;
    WedgeMap uv = buildCutWedges(s.topology, cut);
    evaluateMap(*basis, reduction, x, uv);
    for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
      EXPECT_LT((uv[c] - Vec2d(constant.real(), constant.imag())).norm(), 1e-12) << "corner " << c;
    }
  }
}

TEST(Evaluate, WedgesOutsideAFaceSubsetKeepTheirValues) {
  const testing::Surface s = testing::makeSurface(testing::gridMesh(4, 4));
  const CrossField field = testing::constantField(s.mesh);
  const CutResult cut = testing::boundaryCut(s.topology);
  HatBasisOptions options;
  for (FaceId f = 0; f < 8; ++f) options.faces.push_back(f);  // the first row of squares
  const HatBasis basis(s.mesh, s.topology, field, cut, options);
  const Reduction reduction = reduceBasis(basis);
  std::vector<Complex> x(reduction.numUnknowns(), Complex(1.0, 1.0));
  WedgeMap uv = buildCutWedges(s.topology, cut);
  for (std::uint32_t w = 0; w < uv.numWedges(); ++w) uv.setWedgeValue(w, Vec2d(-7.0, 7.0));
  evaluateMap(basis, reduction, x, uv);
  // A wedge is covered when one of its corners lies in the subset.
  std::vector<std::uint8_t> covered(uv.numWedges(), 0);
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    if (basis.cornerDomain()[c] != kInvalidId) covered[uv.wedge(c)] = 1;
  }
  ASSERT_GT(std::count(covered.begin(), covered.end(), 0), 0);
  for (CornerId c = 0; c < s.topology.numCorners(); ++c) {
    EXPECT_EQ(uv[c], covered[uv.wedge(c)] ? Vec2d(1.0, 1.0) : Vec2d(-7.0, 7.0)) << "corner " << c;
  }
}

}  // namespace
}  // namespace seamvox
