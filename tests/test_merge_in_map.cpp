#include <gtest/gtest.h>
#include <cmath>
#include <string>

#include "core/cut/cut.h"
#include "core/field/cone_merge.h"
#include "core/field/field.h"
#include "core/quality/metrics.h"
#include "core/refine/merge_in_map.h"
#include "core/solve/hat_solver.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

using testing::Surface;

/// A flat n x n grid of unit cells whose field turns by (arg(x - a) + arg(x - b)) sa / 4 around
/// two cones of index4 sa a few edges apart, cut through them and mapped by the hat solver with a
/// grid spacing h much larger than their distance: the rounding puts both on one point.
struct CloseCones {
  Surface s;
  CrossField field;
  VertexId a, b;
  CutResult cut;
  ParamResult map;
};

CloseCones closeCones(int n, int apart, double sign, double h) {
  CloseCones out{testing::makeSurface(testing::gridMesh(n, n)), {}, VertexId((n / 2) * (n + 1) + n / 2),
                 VertexId((n / 2) * (n + 1) + n / 2 + apart), {}, {}};
  const Vec3d pa = out.s.mesh.position(out.a), pb = out.s.mesh.position(out.b);
  for (FaceId f = 0; f < out.s.mesh.numFaces(); ++f) {
    const Triangle& t = out.s.mesh.triangles[f];
    const Vec3d x = (out.s.mesh.position(t[0]) + out.s.mesh.position(t[1]) + out.s.mesh.position(t[2])) / 3.0;
    const double theta =
        sign * (std::atan2(x.y() - pa.y(), x.x() - pa.x()) + std::atan2(x.y() - pb.y(), x.x() - pb.x())) / 4.0;
    out.field.direction.push_back(Vec3f(float(std::cos(theta)), float(std::sin(theta)), 0.f));
  }
  const FieldSingularities sing = computeSingularities(out.s.mesh, out.s.topology, out.field);
  out.cut = cutToDisk(out.s.mesh, out.s.topology, out.field, sing);
  ParamOptions options;
  options.edgeLength = h;
  out.map = parameterizeMesh(out.s.mesh, out.s.topology, out.field, out.cut, options);
  return out;
}

/// Every seam's corners hold its matching, their opposite corners the inverse.
void expectCombedSeams(const Topology& topology, const CutResult& cut) {
  for (const SeamCurve& seam : cut.seams) {
    for (const CornerId c : seam.corners) {
      EXPECT_EQ(cut.corners.matching(c), seam.matching) << c;
      EXPECT_EQ(cut.corners.matching(topology.opposite(c)), (4 - seam.matching) % 4) << c;
    }
  }
}

// Two +1 (and two -1) cones the map put on one point: one seam's end leaves the cut's cones, the
// other takes both indices, and the map is seamless on the changed cut with integer translations
// and the same corners outside the region solved again; no face between them collapses.
TEST(MergeInMap, TwoConesOnOnePointBecomeOneConeOfTheMap) {
  for (const double sign : {1.0, -1.0}) {
    const std::string what = sign > 0 ? "+1 +1" : "-1 -1";
    CloseCones c = closeCones(40, 2, sign, 20.0);
    ASSERT_EQ(c.cut.cones.size(), 2u) << what;
    const auto pairs = coincidentCones(c.s.mesh, c.s.topology, c.cut.cones, c.map.cornerUV, 5.0);
    ASSERT_EQ(pairs.size(), 1u) << what << ": the rounding should put the cones on one point";

    const WedgeMap before = c.map.cornerUV;
    MergeInMapOptions options;
    options.edgeLength = 20.0;
    options.radius = 0.25;
    const MergeInMapResult merged = mergeConesInMap(c.s.mesh, c.s.topology, c.field, c.cut, c.map.cornerUV,
                                                    c.map.translations, c.a, int(sign), c.b, int(sign), options);
    ASSERT_TRUE(merged.merged) << what << ": " << merged.reason;
    EXPECT_EQ(merged.keptIndex4, 2 * int(sign)) << what;
    EXPECT_EQ(c.cut.cones, std::vector<VertexId>{merged.kept}) << what;
    EXPECT_GT(merged.pathEdges, 0u);
    EXPECT_GT(merged.changedSeams, 0u);
    EXPECT_GT(merged.regionFaces, merged.pieceFaces);
    expectCombedSeams(c.s.topology, c.cut);
    const SeamQuality seams = measureSeams(c.s.mesh, c.s.topology, c.cut, c.map.cornerUV);
    EXPECT_TRUE(seams.isSeamless()) << what << ": residual " << seams.maxResidual;
    for (const auto& t : c.map.translations) {
      EXPECT_EQ(t.real(), std::round(t.real())) << what;
      EXPECT_EQ(t.imag(), std::round(t.imag())) << what;
    }
    // Corners farther than the region's reach (0.25 h in rings at the path's edge, 2 rings at
    // least, around the piece, the path and the seams bounding the piece) keep their values.
    std::uint32_t changed = 0;
    for (CornerId k = 0; k < c.s.topology.numCorners(); ++k) changed += (c.map.cornerUV[k] - before[k]).norm() > 0.0;
    EXPECT_GT(changed, 0u);
    EXPECT_LE(changed, 3 * merged.regionFaces) << what;
    EXPECT_EQ(measureMap(c.s.mesh, c.map.cornerUV, &c.field, 20.0).collapsed, 0u) << what;
  }
}

// Cones the map keeps apart are not merged, and nothing changes.
TEST(MergeInMap, ConesOnTwoPointsAreLeftAsTheyAre) {
  CloseCones c = closeCones(40, 6, 1.0, 1.0);
  ASSERT_EQ(c.cut.cones.size(), 2u);
  ASSERT_TRUE(coincidentCones(c.s.mesh, c.s.topology, c.cut.cones, c.map.cornerUV, 10.0).empty());
  const WedgeMap before = c.map.cornerUV;
  const auto translations = c.map.translations;
  const std::vector<std::uint8_t> corners = c.cut.corners.cornerBytes();
  const FaceRotations rotations = c.cut.faceRotation;
  MergeInMapOptions options;
  options.edgeLength = 1.0;
  options.pathLength = 10.0;
  const MergeInMapResult merged =
      mergeConesInMap(c.s.mesh, c.s.topology, c.field, c.cut, c.map.cornerUV, c.map.translations, c.a, 1, c.b, 1, options);
  EXPECT_FALSE(merged.merged);
  EXPECT_EQ(merged.reason, "not on one point");
  EXPECT_EQ(c.cut.corners.cornerBytes(), corners);
  EXPECT_TRUE(c.cut.faceRotation == rotations);
  EXPECT_EQ(c.map.translations, translations);
  EXPECT_EQ(c.cut.cones.size(), 2u);
  for (CornerId k = 0; k < c.s.topology.numCorners(); ++k) EXPECT_EQ(c.map.cornerUV[k], before[k]) << k;
  EXPECT_THROW(mergeConesInMap(c.s.mesh, c.s.topology, c.field, c.cut, c.map.cornerUV, c.map.translations, c.a, 2,
                               c.b, 2, options),
               InputError);
}

}  // namespace
}  // namespace seamvox
