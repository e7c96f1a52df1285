// Feature curves (boundaries and creases): found and split at corners, followed by the field
// (Poincare-Hopf with the boundary's turning), held on integer iso-lines by the map (every aligned
// curve's normal coordinate one integer), the map still seamless without flips; a box with its
// creases aligned gives a valid all-quad mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/field/features.h"
#include "core/field/field.h"
#include "core/field/field_proxy.h"
#include "core/pipeline/parameterize.h"
#include "core/quads/extract.h"
#include "core/quads/validate.h"
#include "core/system/errors.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

/// Surface of the cube [0, size]^3 with n x n squares per side, two triangles each, welded.
TriangleMesh boxMesh(int n, double size = 1.0) {
  TriangleMesh mesh;
  std::map<std::array<int, 3>, VertexId> index;
  auto vertex = [&](std::array<int, 3> p) {
    const auto [it, added] = index.emplace(p, mesh.numVertices());
    if (added) mesh.positions.push_back(Vec3f(p[0], p[1], p[2]) * float(size / n));
    return it->second;
  };
  // Per side: the fixed axis and its value, then two in-plane axes ordered so the normal points out.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      int a = (axis + 1) % 3, b = (axis + 2) % 3;
      if (side == 0) std::swap(a, b);
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> p{};
            p[axis] = side * n;
            p[a] = i + di;
            p[b] = j + dj;
            return vertex(p);
          };
          const VertexId v00 = at(0, 0), v10 = at(1, 0), v11 = at(1, 1), v01 = at(0, 1);
          mesh.triangles.push_back({v00, v10, v11});
          mesh.triangles.push_back({v00, v11, v01});
        }
      }
    }
  }
  return mesh;
}

std::int64_t eulerCharacteristic(const Topology& topology) {
  std::int64_t chi = 0;
  for (const ComponentInfo& c : computeComponents(topology).components) chi += c.eulerCharacteristic;
  return chi;
}

/// Sum of interior and boundary indices (quarter turns).
std::int64_t indexSumWithBoundary(const FieldSingularities& s) {
  std::int64_t sum = s.indexSum4();
  for (std::int32_t i : s.boundaryIndex4) sum += i;
  return sum;
}

FeatureOptions boundaryFeatures() {
  FeatureOptions options;
  options.alignBoundary = true;
  return options;
}

PipelineOptions featureOptions(double cells, double featureAngle = 0.0) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.spacing.cells = cells;
  options.features.alignBoundary = true;
  options.features.featureAngle = featureAngle;
  return options;
}

/// Every feature edge's normal coordinate in the map: constant and an integer at both ends in each
/// face along it (the check measureFeatureAlignment makes, recomputed here from the field's axis).
double largestNormalResidual(const PipelineResult& r) {
  double worst = 0.0;
  for (CornerId c : featureSideCorners(r.topology, r.features)) {
    const Vec2d p = r.mesh.cornerUV[nextCorner(c)], q = r.mesh.cornerUV[prevCorner(c)];
    const Vec2d d = q - p;
    const int normal = std::abs(d[0]) > std::abs(d[1]) ? 1 : 0;  // the edge runs along the other axis
    worst = std::max({worst, std::abs(d[normal]), std::abs(p[normal] - std::round(p[normal]))});
  }
  return worst;
}

TEST(Features, BoundaryCurvesSplitAtCorners) {
  const testing::Surface plate = testing::makeSurface(testing::gridMesh(6, 4));
  FeatureOptions boundary;
  boundary.alignBoundary = true;
  const FeatureSet f = findFeatures(plate.mesh, plate.topology, boundary);
  EXPECT_EQ(f.boundaryEdges, 20u);
  EXPECT_EQ(f.creaseEdges, 0u);
  ASSERT_EQ(f.numCurves(), 4u);  // the four sides
  std::vector<std::uint32_t> lengths;
  for (std::uint32_t k = 0; k < 4; ++k) lengths.push_back(f.curveStart[k + 1] - f.curveStart[k]);
  std::sort(lengths.begin(), lengths.end());
  EXPECT_EQ(lengths, (std::vector<std::uint32_t>{4, 4, 6, 6}));
  // Consecutive edges of a curve share a vertex.
  for (std::uint32_t k = 0; k < f.numCurves(); ++k) {
    for (std::uint32_t i = f.curveStart[k] + 1; i < f.curveStart[k + 1]; ++i) {
      const CornerId a = f.curveEdges[i - 1], b = f.curveEdges[i];
      const VertexId a0 = plate.topology.vertex(nextCorner(a)), a1 = plate.topology.vertex(prevCorner(a));
      const VertexId b0 = plate.topology.vertex(nextCorner(b)), b1 = plate.topology.vertex(prevCorner(b));
      EXPECT_TRUE(a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1);
    }
  }
  EXPECT_TRUE(findFeatures(plate.mesh, plate.topology, {}).empty());  // the default: none
  // A cylinder's two rims are loops without a corner.
  const testing::Surface tube = testing::makeSurface(testing::cylinderMesh(24, 6));
  const FeatureSet rims = findFeatures(tube.mesh, tube.topology, boundary);
  EXPECT_EQ(rims.numCurves(), 2u);
  EXPECT_EQ(rims.curveEdges.size(), 48u);
}

TEST(Features, CreasesOfABoxAboveTheFeatureAngle) {
  const testing::Surface box = testing::makeSurface(boxMesh(4));
  EXPECT_TRUE(findFeatures(box.mesh, box.topology, {}).empty());  // closed, no feature angle
  FeatureOptions options;
  options.featureAngle = 30.0;
  const FeatureSet f = findFeatures(box.mesh, box.topology, options);
  EXPECT_EQ(f.creaseEdges, 12u * 4u);
  EXPECT_EQ(f.numCurves(), 12u);  // split at the 8 corners, where three creases meet
  options.featureAngle = 95.0;    // the creases turn by 90 degrees
  EXPECT_TRUE(findFeatures(box.mesh, box.topology, options).empty());
  options.featureAngle = -1.0;
  EXPECT_THROW(findFeatures(box.mesh, box.topology, options), InputError);
}

TEST(Features, FieldFollowsTheBoundaryAndPoincareHopfCountsItsTurning) {
  for (TriangleMesh mesh : {testing::gridMesh(12, 9), testing::cylinderMesh(32, 8)}) {
    const testing::Surface s = testing::makeSurface(std::move(mesh));
    FeatureOptions boundary;
    boundary.alignBoundary = true;
    const FeatureSet features = findFeatures(s.mesh, s.topology, boundary);
    SmoothFieldOptions smooth;
    smooth.alignCorners = featureSideCorners(s.topology, features);
    const CrossField field = computeCrossField(s.mesh, s.topology, FieldMethod::Direct, smooth);
    for (CornerId c : smooth.alignCorners) {
      const Triangle& t = s.mesh.triangles[cornerFace(c)];
      const Vec3d edge = (s.mesh.position(t[(c + 2) % 3]) - s.mesh.position(t[(c + 1) % 3])).normalized();
      // sin 2 theta / 2 of the angle theta between the edge and the field: 0 when parallel or
      // perpendicular (float directions: 1e-7).
      const Vec3d u = field.at(cornerFace(c));
      EXPECT_NEAR(edge.dot(u) * edge.cross(u).norm(), 0.0, 1e-6) << "face " << cornerFace(c);
    }
    const FieldSingularities sing = computeSingularities(s.mesh, s.topology, field);
    EXPECT_EQ(indexSumWithBoundary(sing), 4 * eulerCharacteristic(s.topology));
  }
  // The plate's aligned field is constant: four corners of +1, nothing else.
  const testing::Surface plate = testing::makeSurface(testing::gridMesh(12, 9));
  SmoothFieldOptions smooth;
  smooth.alignCorners = featureSideCorners(plate.topology, findFeatures(plate.mesh, plate.topology, boundaryFeatures()));
  const FieldSingularities sing =
      computeSingularities(plate.mesh, plate.topology, computeCrossField(plate.mesh, plate.topology, FieldMethod::Direct, smooth));
  EXPECT_TRUE(sing.cones.empty());
  std::int32_t corners = 0;
  for (std::int32_t i : sing.boundaryIndex4) {
    EXPECT_TRUE(i == 0 || i == 1) << i;
    corners += i;
  }
  EXPECT_EQ(corners, 4);
}

TEST(Features, PoincareHopfWithBoundaryHoldsForAFreeField) {
  // The boundary index corrects for the field's angle to the boundary: the sum holds for any field.
  for (TriangleMesh mesh : {testing::gridMesh(10, 7), testing::cylinderMesh(20, 6)}) {
    const testing::Surface s = testing::makeSurface(std::move(mesh));
    for (std::uint32_t seed : {1u, 2u, 3u}) {
      const FieldSingularities sing = computeSingularities(s.mesh, s.topology, testing::randomField(s.mesh, seed));
      EXPECT_EQ(indexSumWithBoundary(sing), 4 * eulerCharacteristic(s.topology)) << "seed " << seed;
    }
  }
}

TEST(Features, ProxyFieldRefusesAlignment) {
  const testing::Surface plate = testing::makeSurface(testing::gridMesh(4, 4));
  SmoothFieldOptions smooth;
  smooth.alignCorners = featureSideCorners(plate.topology, findFeatures(plate.mesh, plate.topology, boundaryFeatures()));
  EXPECT_THROW(computeCrossField(plate.mesh, plate.topology, FieldMethod::Proxy, smooth), InputError);
}

void expectAlignedSeamlessWithoutFlips(const PipelineResult& r) {
  EXPECT_GT(r.featureCurves.total, 0u);
  EXPECT_EQ(r.featureCurves.aligned, r.featureCurves.total);
  EXPECT_EQ(r.featureCurves.notAligned, 0u);
  EXPECT_LT(r.featureCurves.largestResidual, 1e-9);
  EXPECT_LT(largestNormalResidual(r), 1e-9);
  EXPECT_TRUE(r.isSeamless()) << r.seamQuality.maxResidual << " " << r.seamQuality.maxIntegerDistance;
  EXPECT_EQ(r.mapQuality.flipped, 0u);
  EXPECT_EQ(r.featureLines.conflicting, 0u);
  EXPECT_EQ(r.featureLines.unsupported, 0u);
  EXPECT_EQ(r.featureLines.applied, r.featureLines.constraints);
}

TEST(Features, PlateBoundaryOnIntegerIsoLines) {
  // 7.3 cells on the diagonal: the sides are not whole multiples of h, the map must stretch.
  const PipelineResult r = parameterize(testing::gridMesh(16, 11), featureOptions(7.3));
  EXPECT_TRUE(r.featureFieldAligned);
  EXPECT_EQ(r.featureCurves.total, 4u);
  expectAlignedSeamlessWithoutFlips(r);
  // The sides are iso-lines: the quad mesh is valid, every iso-line traces, inner cells are quads.
  // (Extraction still puts a boundary point at every mesh vertex of a side, as where an iso-line
  // crosses the boundary, so the cells along the sides are polygons with extra vertices.)
  const QuadResult quads = extractQuads(r.mesh, r.topology);
  const QuadValidation v = validateQuads(quads, computeComponents(r.topology));
  EXPECT_TRUE(v.isValid());
  EXPECT_EQ(v.interiorNonQuads, 0u);
  EXPECT_GT(v.quads, 0u);
  EXPECT_EQ(quads.stats.untracedEdges + quads.stats.unpairedEdges + quads.stats.openFaces, 0u);
}

TEST(Features, CylinderRimsOnIntegerIsoLines) {
  const PipelineResult r = parameterize(testing::cylinderMesh(40, 12, 1.0, 2.5), featureOptions(11.0));
  EXPECT_EQ(r.featureCurves.total, 2u);
  expectAlignedSeamlessWithoutFlips(r);
}

TEST(Features, WithoutAlignmentTheBoundaryIsFree) {
  PipelineOptions options = featureOptions(7.3);
  options.features.alignBoundary = false;
  const PipelineResult r = parameterize(testing::gridMesh(16, 11), options);
  EXPECT_EQ(r.featureCurves.total, 0u);
  EXPECT_FALSE(r.featureFieldAligned);
  EXPECT_EQ(r.featureLines.constraints, 0u);
  EXPECT_TRUE(r.isSeamless());
}

TEST(Features, ClosedMeshKeepsItsCones) {
  // No boundary and no feature angle: the same field, cones and map as with features off.
  PipelineOptions on = featureOptions(12.0), off = on;
  off.features.alignBoundary = false;
  const TriangleMesh mesh = testing::concatMeshes({testing::icosphereMesh(3), testing::torusMesh(30, 12)});
  const PipelineResult a = parameterize(mesh, on), b = parameterize(mesh, off);
  EXPECT_EQ(a.cones, b.cones);
  EXPECT_EQ(a.coneIndex4, b.coneIndex4);
  EXPECT_EQ(a.mapQuality.relativeGradientError, b.mapQuality.relativeGradientError);
  EXPECT_EQ(a.featureCurves.total, 0u);
}

TEST(Features, BoxCornersOnIntegerPointsAndCreasesOnIntegerLines) {
  // The corners are cones on creases: the map puts them on integer points, so the quad mesh has
  // a vertex of valence 3 at each. The seam translations are rounded before the creases' integers
  // (line_constraints.h), so a crease whose two corners were rounded to different lines cannot be
  // held: it is counted as not aligned, and every curve counted aligned is exactly on its line.
  const PipelineResult r = parameterize(boxMesh(8, 1.0), featureOptions(std::sqrt(3.0) * 4.0, 30.0));
  EXPECT_EQ(r.featureCurves.total, 12u);
  EXPECT_EQ(r.cones.size(), 8u);
  EXPECT_GT(r.featureCurves.aligned, 0u);
  EXPECT_EQ(r.featureCurves.aligned + r.featureCurves.notAligned, r.featureCurves.total);
  EXPECT_LT(r.featureCurves.largestResidual, 1e-9);
  EXPECT_TRUE(r.isSeamless()) << r.seamQuality.maxResidual << " " << r.seamQuality.maxIntegerDistance;
  EXPECT_EQ(r.mapQuality.flipped, 0u);
  EXPECT_EQ(r.featureLines.unsupported, 0u);
  EXPECT_EQ(r.featureLines.applied + r.featureLines.conflicting, r.featureLines.constraints);
  const QuadResult quads = extractQuads(r.mesh, r.topology);
  const QuadValidation v = validateQuads(quads, computeComponents(r.topology));
  EXPECT_TRUE(v.isValid());
  EXPECT_EQ(v.quads, v.faces);
  EXPECT_GT(v.faces, 0u);
  EXPECT_EQ(quads.conesOnGridVertices, 8u);  // the box's corners are quad vertices
}

TEST(Features, CreasesCloserThanACellAreReleasedInsteadOfCollapsingTheFacesBetween) {
  // A plate with a narrow ridge: three parallel creases two rows apart, about a fifth of a cell.
  // Held on integer lines they round onto one line and squeeze the ridge flat; the pipeline
  // releases curves at the collapsed faces and solves again until nothing collapses.
  TriangleMesh mesh = testing::gridMesh(30, 30);
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    if (mesh.positions[v].y() == 15.0f) mesh.positions[v].z() = 1.0f;
  }
  PipelineOptions options = featureOptions(4.0, 30.0);
  const PipelineResult r = parameterize(mesh, options);
  EXPECT_EQ(r.features.creaseEdges, 3u * 30u);
  EXPECT_GT(r.featureCurvesReleased, 0u);
  EXPECT_LE(r.featureCurvesReleased, r.featureCurves.notAligned);
  EXPECT_GT(r.featureCurves.aligned, 0u) << "the plate's sides stay aligned";
  EXPECT_EQ(r.mapQuality.collapsed, 0u);
  EXPECT_EQ(r.mapQuality.flipped, 0u);
  EXPECT_TRUE(r.isSeamless());
  EXPECT_LT(r.featureCurves.largestResidual, 1e-9);
  const QuadResult quads = extractQuads(r.mesh, r.topology);
  EXPECT_TRUE(validateQuads(quads, computeComponents(r.topology)).isValid());

  // Without the release the same constraints collapse the ridge (what the test guards against).
  options.features.featureAngle = 30.0;
  options.maxFeatureReleaseRounds = 0;
  const PipelineResult held = parameterize(mesh, options);
  EXPECT_EQ(held.featureCurvesReleased, 0u);
  EXPECT_GT(held.mapQuality.collapsed, 0u);
}

TEST(Features, AutoFeatureAngleTurnsCreasesOnForACadModelOnly) {
  // A box: creases in long straight curves, so the automatic choice aligns them; a scan's folds
  // and a smooth sphere give no such curves and nothing is chosen.
  PipelineOptions options = featureOptions(std::sqrt(3.0) * 4.0, 0.0);
  options.features.alignBoundary = false;
  options.features.autoFeatureAngle = true;
  const PipelineResult box = parameterize(boxMesh(8, 1.0), options);
  EXPECT_TRUE(box.featureAngleAuto);
  EXPECT_EQ(box.featureAngle, kAutoFeatureAngle);
  EXPECT_EQ(box.featureCurves.total, 12u);
  EXPECT_GT(box.featureCurves.aligned, 0u);
  EXPECT_TRUE(box.isSeamless());
  for (const MeshKind kind : {MeshKind::Scan, MeshKind::Sphere}) {
    const PipelineResult r = parameterize(testing::generatedMesh(kind, 20000), options);
    EXPECT_FALSE(r.featureAngleAuto);
    EXPECT_EQ(r.featureAngle, 0.0);
    EXPECT_EQ(r.features.creaseEdges, 0u);
  }
  // Only where the solver aligns curves: at grid 16 the automatic solver takes hat for a
  // feature-aligned map up to 400K / 64 / 5 = 1250 faces, for a plain one up to 6250; a
  // 4800-face box gets the plain hat map without looking for creases, unless hat is asked for.
  {
    PipelineOptions coarse = options;
    coarse.solver.solver = ParamSolver::Auto;
    coarse.solver.gridResolution = 16;
    const TriangleMesh bigBox = boxMesh(20, 1.0);
    ASSERT_GT(bigBox.numFaces(), kAutoHatMaxFacesGrid128 / 64 / kAutoFeatureSolves);
    const PipelineResult automatic = parameterize(bigBox, coarse);
    EXPECT_FALSE(automatic.featureAngleAuto);
    EXPECT_EQ(automatic.features.creaseEdges, 0u);
    EXPECT_EQ(automatic.solved.solver, ParamSolver::Hat);
    EXPECT_EQ(automatic.featureCurves.aligned, 0u);
    EXPECT_TRUE(automatic.isSeamless());
    coarse.solver.solver = ParamSolver::Hat;
    const PipelineResult hat = parameterize(bigBox, coarse);
    EXPECT_TRUE(hat.featureAngleAuto);
    EXPECT_EQ(hat.featureCurves.total, 12u);
    EXPECT_GT(hat.featureCurves.aligned, 0u);
  }
  // Given explicitly (even 0), the angle is used as it is.
  options.features.autoFeatureAngle = false;
  const PipelineResult off = parameterize(boxMesh(8, 1.0), options);
  EXPECT_FALSE(off.featureAngleAuto);
  EXPECT_EQ(off.features.creaseEdges, 0u);
  // The rule itself: long curves are CAD, curves of one or two edges are a scan's folds.
  FeatureSet creases;
  creases.creaseEdges = 96;
  creases.curveStart = {0, 48, 96};
  EXPECT_TRUE(looksLikeCad(creases));
  creases.curveStart.assign(49, 0);
  for (std::uint32_t k = 0; k < 49; ++k) creases.curveStart[k] = 2 * k;
  EXPECT_FALSE(looksLikeCad(creases));
}

TEST(Features, ParamPrintsAndReportsTheCurves) {
  testing::TempDir dir;
  writeMesh(dir.path("plate.obj"), testing::gridMesh(10, 7));
  std::string out;
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("plate.obj") + " -o " + dir.path("out.obj") +
                                    " --cells 6 --align-boundary --report " + dir.path("r.json") + " --quiet",
                                &out),
            0)
      << out;
  EXPECT_NE(out.find("feature curves: 4"), std::string::npos) << out;
  const JsonValue report = parseJson(testing::readFile(dir.path("r.json")));
  EXPECT_EQ(report.numberAt("featureCurves.total"), 4.0);
  EXPECT_EQ(report.numberAt("featureCurves.aligned"), 4.0);
  EXPECT_EQ(report.numberAt("featureCurves.notAligned"), 0.0);
  EXPECT_EQ(report.numberAt("featureCurves.featureAngle"), 0.0);
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("plate.obj") + " -o " + dir.path("free.obj") +
                                    " --cells 6 --feature-angle 30 --quiet --report " +
                                    dir.path("f.json"),
                                &out),
            0)
      << out;
  const JsonValue free = parseJson(testing::readFile(dir.path("f.json")));
  EXPECT_EQ(free.numberAt("featureCurves.total"), 0.0);
  EXPECT_EQ(free.numberAt("featureCurves.featureAngle"), 30.0);
  EXPECT_EQ(testing::runSeamvox("param " + dir.path("plate.obj") + " -o " + dir.path("bad.obj") +
                                    " --feature-angle 200 --quiet",
                                &out),
            2)
      << out;
  // Without --feature-angle a box's creases are chosen (and said so); --feature-angle 0 keeps none.
  writeMesh(dir.path("box.obj"), boxMesh(8, 1.0));
  for (const bool given : {false, true}) {
    ASSERT_EQ(testing::runSeamvox("param " + dir.path("box.obj") + " -o " + dir.path("box_uv.obj") + " --cells 7 --quiet" +
                                      (given ? " --feature-angle 0" : "") + " --report " + dir.path("b.json"),
                                  &out),
              0)
        << out;
    const JsonValue box = parseJson(testing::readFile(dir.path("b.json")));
    EXPECT_EQ(box.numberAt("featureCurves.featureAngleAuto"), given ? 0.0 : 1.0);
    EXPECT_EQ(box.numberAt("featureCurves.featureAngle"), given ? 0.0 : kAutoFeatureAngle);
    EXPECT_EQ(out.find("look like a CAD model") != std::string::npos, !given) << out;
  }
}

}  // namespace
}  // namespace seamvox
