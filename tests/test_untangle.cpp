// Foldover repair (core/refine/untangle) and the cone-neighbourhood weights of the hat energy:
// flips repaired, the map stays seamless with integer translations, only patches around the
// flips move, and the weights are what they say.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include <tbb/global_control.h>

#include "core/basis/basis.h"
#include "core/mesh/clean.h"
#include "core/pipeline/components.h"
#include "core/pipeline/parameterize.h"
#include "core/quality/metrics.h"
#include "core/refine/detail_untangle.h"
#include "core/refine/untangle.h"
#include "core/solve/hat_solver.h"
#include "core/synth/generate.h"
#include "core/system/errors.h"
#include "test_meshes.h"
#include "tests/testing.h"
#include "io/mesh_io.h"
#include "io/json_reader.h"

namespace seamvox {
namespace {

// The joint patches' Newton steps use the untangling energy's gradient and Hessian in one corner:
// they match central differences of the energy and of the gradient, on folded faces too and at
// every eps the schedule reaches.
TEST(Untangle, EnergyGradientAndHessianMatchDifferences) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  TriangleMesh mesh;
  std::size_t folded = 0;
  for (int trial = 0; trial < 200; ++trial) {
    mesh.positions = {Vec3f(0, 0, 0), Vec3f(1.0f + 0.3f * float(unit(random)), 0.2f * float(unit(random)), 0.1f),
                      Vec3f(0.5f * float(unit(random)), 1.0f + 0.3f * float(unit(random)), 0.2f * float(unit(random)))};
    mesh.triangles = {Triangle{0, 1, 2}};
    const detail::ReferenceShape shape = detail::referenceShape(mesh, 0, 0.5);
    ASSERT_GT(shape.area, 0.0);
    Vec2d q[3];
    for (Vec2d& x : q) x = Vec2d(2.0 * unit(random), 2.0 * unit(random));
    const double eps = std::pow(10.0, -3.0 * (trial % 4) / 3.0);  // 1 down to 1e-3
    Eigen::Matrix2d edges;
    edges.col(0) = q[1] - q[0];
    edges.col(1) = q[2] - q[0];
    const double det = (edges * shape.inverse).determinant();
    folded += det < 0.0;
    // Steps well inside the scale on which the energy turns (near a fold, the regularised det),
    // central differences with Richardson's extrapolation.
    const double step = 1e-3 * std::min(1.0, std::abs(det) + eps) / (1.0 + shape.inverse.norm());
    for (int k = 0; k < 3; ++k) {
      const detail::UntanglingTerms t = detail::untanglingTerms(shape, q[0], q[1], q[2], k, eps);
      EXPECT_NEAR(t.energy, detail::untanglingEnergy(shape, q[0], q[1], q[2], eps), 1e-12 * t.energy);
      const auto moved = [&](const Vec2d& d) {
        Vec2d m[3] = {q[0], q[1], q[2]};
        m[k] += d;
        return detail::untanglingTerms(shape, m[0], m[1], m[2], k, eps);
      };
      for (int axis = 0; axis < 2; ++axis) {
        const auto central = [&](double s) {
          const detail::UntanglingTerms plus = moved(s * Vec2d::Unit(axis)), minus = moved(-s * Vec2d::Unit(axis));
          return std::make_pair((plus.energy - minus.energy) / (2.0 * s), Vec2d((plus.gradient - minus.gradient) / (2.0 * s)));
        };
        const auto [slopeH, columnH] = central(step);
        const auto [slopeHalf, columnHalf] = central(0.5 * step);
        const double slope = (4.0 * slopeHalf - slopeH) / 3.0;
        const Vec2d column = (4.0 * columnHalf - columnH) / 3.0;
        EXPECT_NEAR(t.gradient[axis], slope, 1e-6 * (1.0 + t.gradient.norm())) << trial << " " << k;
        EXPECT_NEAR(t.hessian(0, axis), column[0], 1e-5 * (1.0 + t.hessian.norm())) << trial << " " << k;
        EXPECT_NEAR(t.hessian(1, axis), column[1], 1e-5 * (1.0 + t.hessian.norm())) << trial << " " << k;
      }
    }
  }
  EXPECT_GT(folded, 50u);  // folded faces were among the trials
}

using testing::generatedMesh;

TriangleMesh sphere(std::uint64_t faces) { return generatedMesh(MeshKind::Sphere, faces); }

// The relocation's kernel centre against the plain enumeration of every vertex of the linear
// programme (each feasibility tested in constraint order): the same margin and centre bit for bit,
// on fans with a kernel, fans without one (Gain's halved, unweighted positives), regular fans
// whose vertices tie, and random half-planes that are mostly infeasible.
double enumeratedKernelCentre(const std::vector<Vec2d>& normal, const std::vector<double>& offset,
                              const std::vector<double>& weight, Vec2d& centre) {
  const std::size_t n = normal.size();
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      for (std::size_t c = b + 1; c < n; ++c) {
        Eigen::Matrix3d m;
        Eigen::Vector3d r;
        const std::size_t ids[3] = {a, b, c};
        for (int k = 0; k < 3; ++k) {
          m.row(k) << normal[ids[k]].x(), normal[ids[k]].y(), -weight[ids[k]];
          r[k] = -offset[ids[k]];
        }
        const Eigen::Vector3d c01 = m.col(1).cross(m.col(2)), c12 = m.col(2).cross(m.col(0)),
                              c20 = m.col(0).cross(m.col(1));
        const double det = m.col(0).dot(c01);
        if (std::abs(det) < 1e-300) continue;
        const Eigen::Vector3d x(c01.dot(r) / det, c12.dot(r) / det, c20.dot(r) / det);
        if (!x.allFinite() || x[2] <= best) continue;
        bool feasible = true;
        for (std::size_t i = 0; i < n; ++i) {
          const double need = x[2] * weight[i];
          feasible = feasible &&
                     normal[i].dot(x.head<2>()) + offset[i] >= need - 1e-9 * (std::abs(need) + normal[i].norm()) - 1e-300;
        }
        if (feasible) best = x[2], centre = x.head<2>();
      }
    }
  }
  return best;
}

TEST(Untangle, KernelCentreIsTheEnumeratedOptimumBitForBit) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t withKernel = 0, without = 0, none = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int kind = trial % 4;
    const int fan = 3 + trial % 9;
    std::vector<Vec2d> normal;
    std::vector<double> offset, weight;
    // The fan's triangles (0, a, b) around the vertex at the origin, as relocateVertex writes
    // them: ring points at random radii and angles, some pulled across the vertex (folded).
    std::vector<Vec2d> ring;
    for (int k = 0; k < fan; ++k) {
      const double angle = 2.0 * M_PI * (k + (kind == 2 ? 0.0 : 0.4 * unit(random))) / fan;
      double radius = kind == 2 ? 1.0 : 1.0 + 0.5 * unit(random);
      if (kind == 1 && k == 0) radius = -0.3;
      ring.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
    }
    Vec2d lo = Vec2d::Constant(1e300), hi = -lo;
    for (int k = 0; k < fan; ++k) {
      const Vec2d a = ring[k], b = ring[(k + 1) % fan];
      if (kind == 3) {
        normal.emplace_back(unit(random), unit(random));
        offset.push_back(unit(random));
        weight.push_back(normal.back().norm());
      } else {
        const Vec2d nk(a.y() - b.y(), b.x() - a.x());
        normal.push_back(nk);
        offset.push_back(a.x() * b.y() - a.y() * b.x());
        weight.push_back(nk.norm());
      }
      lo = lo.cwiseMin(a).cwiseMin(b), hi = hi.cwiseMax(a).cwiseMax(b);
    }
    for (int axis = 0; axis < 2; ++axis) {
      for (const double sign : {1.0, -1.0}) {
        normal.push_back(axis == 0 ? Vec2d(sign, 0.0) : Vec2d(0.0, sign));
        offset.push_back(sign > 0 ? -lo[axis] : hi[axis]);
        weight.push_back(0.0);
      }
    }
    for (int pass = 0; pass < 2; ++pass) {
      Vec2d expected(7.0, 7.0), got(7.0, 7.0);
      const double want = enumeratedKernelCentre(normal, offset, weight, expected);
      const double have = detail::kernelCentre(normal, offset, weight, got);
      EXPECT_EQ(std::memcmp(&want, &have, sizeof(double)), 0) << "trial " << trial << " pass " << pass;
      EXPECT_EQ(std::memcmp(expected.data(), got.data(), sizeof(Vec2d)), 0) << "trial " << trial << " pass " << pass;
      if (pass == 1) break;
      if (want > 0.0) {
        ++withKernel;
        break;
      }
      (std::isfinite(want) ? without : none) += 1;
      // No kernel: as the Gain move asks again, the positive fan triangles halved and unweighted.
      for (int k = 0; k < fan; ++k) {
        if (offset[k] > 0.0) offset[k] *= 0.5, weight[k] = 0.0;
      }
    }
  }
  // Every kind of programme was met.
  EXPECT_GT(withKernel, 500u);
  EXPECT_GT(without, 100u);
  EXPECT_GT(none + without, 300u);
}

TEST(ConeWeights, SquareRootOfRadiusOverDistanceInsideOneOutside) {
  const TriangleMesh mesh = sphere(4000);
  std::mt19937 random(7);
  // A few cones (each tested) and many (looked up by cell): both against every cone.
  for (const auto& [count, radius] : {std::pair<int, double>{12, 0.3}, {60, 0.12}}) {
    std::vector<VertexId> cones;
    for (int k = 0; k < count; ++k) cones.push_back(random() % mesh.numVertices());
    const std::vector<double> weight = coneNeighbourhoodWeights(mesh, cones, radius);
    ASSERT_EQ(weight.size(), mesh.numFaces());
    std::size_t inside = 0, outside = 0;
    for (FaceId f = 0; f < mesh.numFaces(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const Vec3d c = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
      double nearest = 1e300;
      for (VertexId v : cones) nearest = std::min(nearest, (mesh.position(v) - c).norm());
      const double expected = nearest < radius ? std::sqrt(radius / nearest) : 1.0;
      EXPECT_NEAR(weight[f], expected, 1e-9 * expected) << count << " cones, face " << f;
      inside += nearest < radius;
      outside += nearest >= radius;
    }
    // the checks above covered the weighted part and the ones
    EXPECT_GT(inside, 100u) << count << " cones";
    EXPECT_GT(outside, 100u) << count << " cones";
  }
  EXPECT_EQ(coneNeighbourhoodWeights(mesh, {}, 0.3), std::vector<double>(mesh.numFaces(), 1.0));
}

TEST(FoldedIn3D, AgainstTheSmoothedCopy) {
  TriangleMesh mesh = testing::gridMesh(1, 1);
  std::vector<Vec3f> smooth = mesh.positions;
  EXPECT_FALSE(faceFoldedIn3D(mesh, smooth, 0));
  for (Vec3f& p : smooth) p.x() = -p.x();  // mirrored: every face points the other way
  EXPECT_TRUE(faceFoldedIn3D(mesh, smooth, 0));
}

/// A generated scan with scan noise of the given amplitude (edge lengths) and seed.
TriangleMesh noisyScan(std::uint64_t faces, double amplitude, std::uint64_t seed) {
  ScanNoiseOptions noise;
  noise.amplitude = amplitude;
  noise.seed = seed;
  TriangleMesh raw = generatedMesh(MeshKind::Scan, faces);
  addScanNoise(raw, noise);
  return raw;
}

TEST(FoldedIn3D, SmoothedPositionsAtSomeVerticesAreTheWholeSurfaces) {
  // smoothPositionsAt against smoothPositions: a few vertices (hashed local ids), many (per
  // vertex; on the scan, rings of more than 16384 vertices, grown on both cores), the boundary's
  // vertices and their neighbours, on a noisy scan and a plane with a boundary, from no step to
  // five (the ball stops a ring short of what the steps read).
  for (const bool plane : {false, true}) {
    CleanResult clean = cleanMesh(plane ? testing::denseSpotPlane(8, 2, 8, 0.3, 3) : noisyScan(200000, 0.6, 5));
    const TriangleMesh& mesh = clean.mesh;
    const Topology& topology = clean.topology;
    std::vector<std::vector<VertexId>> sets(3);
    for (VertexId v = 0; v < mesh.numVertices(); ++v) {
      if (v % 7 == 0) sets[0].push_back(v);  // on the scan, rings wide enough to grow on both cores
      if (v % 2003 == 5) sets[1].push_back(v);
      if (topology.isBoundaryVertex(v)) {
        sets[2].push_back(v);
        topology.forEachCornerAround(v, [&](CornerId c) { sets[2].push_back(topology.vertex(nextCorner(c))); });
      }
    }
    sets[1].resize(std::min<std::size_t>(sets[1].size(), std::max<std::size_t>(1, mesh.numVertices() / 1024)));
    if (!plane) ASSERT_LE(sets[1].size(), mesh.numVertices() / 1024) << "the few are hashed";
    ASSERT_FALSE(sets[1].empty());
    ASSERT_GT(sets[0].size(), mesh.numVertices() / 1024) << "the many are per vertex";
    if (plane) ASSERT_FALSE(sets[2].empty()) << "the plane has a boundary";
    for (std::uint32_t steps : {0u, 1u, 2u, 3u, 5u}) {
      const std::vector<Vec3f> whole = smoothPositions(mesh, topology, steps);
      for (const std::vector<VertexId>& vertices : sets) {
        const std::vector<Vec3f> local = smoothPositionsAt(mesh, topology, steps, vertices);
        ASSERT_EQ(local.size(), vertices.size());
        for (std::size_t i = 0; i < vertices.size(); ++i) {
          ASSERT_EQ(local[i], whole[vertices[i]]) << "vertex " << vertices[i] << ", " << steps << " steps, plane " << plane;
        }
      }
    }
  }
}

TEST(FoldedIn3D, ReleasedFramePositionsGiveTheSameFacesAndPositions) {
  // A noisy generated scan folds faces in 3D; the fold test on a field whose smoothed surface was
  // released (recomputed around the asked faces) must equal the test on the whole surface.
  CleanResult clean = cleanMesh(noisyScan(20000, 0.6, 4));
  const TriangleMesh& mesh = clean.mesh;
  const Topology& topology = clean.topology;
  for (std::uint32_t steps : {1u, 3u, 5u}) {
    CrossField field;
    field.framePositions = smoothPositions(mesh, topology, steps);
    field.frameSmoothing = steps;
    std::vector<VertexId> vertices;
    for (VertexId v = 0; v < mesh.numVertices(); v += 37) vertices.push_back(v);
    const std::vector<Vec3f> local = smoothPositionsAt(mesh, topology, steps, vertices);
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      ASSERT_EQ(local[i], field.framePositions[vertices[i]]) << "vertex " << vertices[i] << ", " << steps << " steps";
    }
    std::vector<FaceId> faces(mesh.numFaces());
    for (FaceId f = 0; f < mesh.numFaces(); ++f) faces[f] = f;
    const std::vector<std::uint8_t> whole = facesFoldedIn3D(mesh, &topology, &field, faces);
    std::size_t folded = 0;
    for (std::uint8_t x : whole) folded += x;
    if (steps == 3) EXPECT_GT(folded, 0u) << "the noise folds no face: the comparison below tests nothing";
    releaseFramePositions(field);
    EXPECT_TRUE(field.framePositions.empty());
    EXPECT_EQ(facesFoldedIn3D(mesh, &topology, &field, faces), whole) << steps << " steps";
    EXPECT_THROW(facesFoldedIn3D(mesh, nullptr, &field, faces), InputError);
    restoreFramePositions(mesh, topology, field);
    EXPECT_EQ(field.framePositions, smoothPositions(mesh, topology, steps));
  }
}

/// A seamless hat map of a sphere with its cut, then damaged: a few vertices away from seams and
/// cones are moved far in (u, v), which folds their fans over.
struct DamagedMap {
  testing::CutSurface cs;
  ParamResult map;
  std::vector<VertexId> damaged;
};

DamagedMap damagedSphereMap() {
  DamagedMap d;
  d.cs = testing::makeCutSurface(sphere(6000));
  ParamOptions options;
  options.edgeLength = 0.15;
  d.map = parameterizeMesh(d.cs.s.mesh, d.cs.s.topology, d.cs.field, d.cs.cut, options);
  const Topology& topology = d.cs.s.topology;
  std::vector<std::uint8_t> nearCut(d.cs.s.mesh.numVertices(), 0);
  for (VertexId v : d.cs.cut.cones) nearCut[v] = 1;
  for (const SeamCurve& seam : d.cs.cut.seams) {
    for (CornerId c : seam.corners) {
      nearCut[topology.vertex(c)] = 1;
      nearCut[topology.vertex(3 * (c / 3) + (c + 1) % 3)] = 1;
    }
  }
  std::mt19937 random(3);
  while (d.damaged.size() < 6) {
    const VertexId v = random() % d.cs.s.mesh.numVertices();
    if (nearCut[v]) continue;
    bool clear = true;  // one wedge around v, and no other damaged vertex near
    topology.forEachCornerAround(v, [&](CornerId c) {
      for (int k = 0; k < 3; ++k) clear = clear && !nearCut[topology.vertex(3 * (c / 3) + k)];
    });
    for (VertexId w : d.damaged) {
      clear = clear && (d.cs.s.mesh.position(v) - d.cs.s.mesh.position(w)).norm() > 0.5;
    }
    if (!clear) continue;
    CornerId any = kInvalidId;
    topology.forEachCornerAround(v, [&](CornerId c) { any = c; });
    d.map.cornerUV.setWedgeValue(d.map.cornerUV.wedge(any), d.map.cornerUV[any] + Vec2d(2.5, -1.5));
    d.damaged.push_back(v);
  }
  return d;
}

TEST(Untangle, RepairsFlipsKeepsSeamlessAndMovesOnlyPatches) {
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const double h = 0.15;
  const WedgeMap before = d.map.cornerUV;
  const MapQuality damaged = measureMap(mesh, before, &d.cs.field, h);
  ASSERT_GE(damaged.flipped, d.damaged.size());  // each moved vertex folds part of its fan
  ASSERT_TRUE(measureSeams(mesh, d.cs.s.topology, d.cs.cut, before).isSeamless());

  UntangleOptions options;
  options.edgeLength = h;
  std::vector<std::complex<double>> t = d.map.translations;
  const UntangleStats stats = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options);
  EXPECT_EQ(stats.flippedBefore, damaged.flipped);
  EXPECT_EQ(stats.flippedAfter, 0u);
  EXPECT_EQ(measureMap(mesh, d.map.cornerUV, &d.cs.field, h).flipped, 0u);
  EXPECT_GE(stats.solves, 1u);
  const SeamQuality seams = measureSeams(mesh, d.cs.s.topology, d.cs.cut, d.map.cornerUV);
  EXPECT_TRUE(seams.isSeamless()) << seams.maxResidual << " " << seams.maxIntegerDistance;
  for (const auto& z : t) {
    EXPECT_EQ(z.real(), std::round(z.real()));
    EXPECT_EQ(z.imag(), std::round(z.imag()));
  }
  // Only vertices near a damaged one moved: the patches reach at most a few h.
  std::size_t moved = 0;
  for (CornerId c = 0; c < 3u * mesh.numFaces(); ++c) {
    if (d.map.cornerUV[c] == before[c]) continue;
    ++moved;
    const Vec3d p = mesh.position(d.cs.s.topology.vertex(c));
    double nearest = 1e300;
    for (VertexId v : d.damaged) nearest = std::min(nearest, (p - mesh.position(v)).norm());
    EXPECT_LT(nearest, 4.0 * h) << "corner " << c;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_EQ(stats.freeVertices > 0, true);
}

// Restricted to marked faces (the repair near a few cones before deciding on another pass): the
// flips among them are repaired and counted, the others are left exactly as they were.
TEST(Untangle, OnlyTheMarkedFacesFlipsAreRepaired) {
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const double h = 0.15;
  const WedgeMap before = d.map.cornerUV;
  // Faces within h of the first three damaged vertices.
  const auto nearOf = [&](const Vec3d& p, std::size_t first, std::size_t last) {
    double nearest = 1e300;
    for (std::size_t k = first; k < last; ++k) nearest = std::min(nearest, (p - mesh.position(d.damaged[k])).norm());
    return nearest;
  };
  std::vector<std::uint8_t> marked(mesh.numFaces(), 0);
  std::uint64_t flippedMarked = 0, flippedElsewhere = 0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const Triangle& tri = mesh.triangles[f];
    const Vec3d c = (mesh.position(tri[0]) + mesh.position(tri[1]) + mesh.position(tri[2])) / 3.0;
    marked[f] = nearOf(c, 0, 3) < h;
    const bool flipped = isFlippedRatio(parameterAreaRatio(mesh, before, f, h));
    (marked[f] ? flippedMarked : flippedElsewhere) += flipped;
  }
  ASSERT_GT(flippedMarked, 0u);
  ASSERT_GT(flippedElsewhere, 0u);
  UntangleOptions options;
  options.edgeLength = h;
  options.onlyFaces = &marked;
  std::vector<std::complex<double>> t = d.map.translations;
  const UntangleStats stats = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options);
  EXPECT_EQ(stats.flippedBefore, flippedMarked);
  EXPECT_EQ(stats.flippedAfter, 0u);
  EXPECT_EQ(measureMap(mesh, d.map.cornerUV, &d.cs.field, h).flipped, flippedElsewhere);
  EXPECT_TRUE(measureSeams(mesh, d.cs.s.topology, d.cs.cut, d.map.cornerUV).isSeamless());
  for (CornerId c = 0; c < 3u * mesh.numFaces(); ++c) {
    if (d.map.cornerUV[c] == before[c]) continue;
    EXPECT_LT(nearOf(mesh.position(d.cs.s.topology.vertex(c)), 0, 3), nearOf(mesh.position(d.cs.s.topology.vertex(c)), 3, 6))
        << "corner " << c << " moved nearer an unmarked damaged vertex";
  }
  std::vector<std::uint8_t> wrongSize(3, 1);
  options.onlyFaces = &wrongSize;
  EXPECT_THROW(untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options), InputError);
}

TEST(Untangle, FoldedClosedSpecksSmallerThanACellGoOnOnePoint) {
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const Topology& topology = d.cs.s.topology;
  const double diagonal = computeBoundingBox(mesh.positions).diagonal();
  const WedgeMap damaged = d.map.cornerUV;
  ASSERT_GT(measureMap(mesh, damaged, &d.cs.field, 0.15).flipped, 0u);
  const auto sameMap = [&](const WedgeMap& a, const WedgeMap& b) {
    for (CornerId c = 0; c < 3u * mesh.numFaces(); ++c) {
      if (a[c] != b[c]) return false;
    }
    return true;
  };
  // Larger than a cell: left as it is.
  std::vector<std::complex<double>> t = d.map.translations;
  WedgeMap map = damaged;
  for (std::uint32_t faces : collapseSpecks(mesh, topology, d.cs.cut, map, t, 0.5 * diagonal)) EXPECT_EQ(faces, 0u);
  EXPECT_TRUE(sameMap(map, damaged));
  EXPECT_EQ(t, d.map.translations);
  // Smaller than a cell but not folded: left as it is.
  ParamOptions options;
  options.edgeLength = 0.15;
  const ParamResult clean = parameterizeMesh(mesh, topology, d.cs.field, d.cs.cut, options);
  ASSERT_EQ(measureMap(mesh, clean.cornerUV, &d.cs.field, 0.15).flipped, 0u);
  map = clean.cornerUV;
  t = clean.translations;
  for (std::uint32_t faces : collapseSpecks(mesh, topology, d.cs.cut, map, t, 2.0 * diagonal)) EXPECT_EQ(faces, 0u);
  EXPECT_TRUE(sameMap(map, clean.cornerUV));
  // Smaller than a cell and folded: every corner on (0, 0), seamless, collapsed, not flipped.
  map = damaged;
  t = d.map.translations;
  const std::vector<std::uint32_t> faces = collapseSpecks(mesh, topology, d.cs.cut, map, t, 2.0 * diagonal);
  ASSERT_EQ(faces.size(), 1u);
  EXPECT_EQ(faces[0], mesh.numFaces());
  for (CornerId c = 0; c < 3u * mesh.numFaces(); ++c) EXPECT_EQ(map[c], Vec2d::Zero()) << c;
  for (const auto& z : t) EXPECT_EQ(z, std::complex<double>(0.0, 0.0));
  EXPECT_TRUE(measureSeams(mesh, topology, d.cs.cut, map).isSeamless());
  const MapQuality onePoint = measureMap(mesh, map, &d.cs.field, 2.0 * diagonal);
  EXPECT_EQ(onePoint.flipped, 0u);
  EXPECT_EQ(onePoint.collapsed, mesh.numFaces());
  // The repair's last step, counted in its figures: over the whole map, and restricted to one
  // flipped face (the speck holding it still goes on one point).
  UntangleOptions nothingElse;
  nothingElse.edgeLength = 2.0 * diagonal;
  nothingElse.maxRounds = 0;
  nothingElse.relocationPasses = 0;
  nothingElse.jointRings = 0;
  std::vector<std::uint8_t> marked(mesh.numFaces(), 0);
  for (FaceId f = 0; f < mesh.numFaces() && !std::count(marked.begin(), marked.end(), 1); ++f) {
    marked[f] = isFlippedRatio(parameterAreaRatio(mesh, damaged, f, nothingElse.edgeLength));
  }
  const std::vector<std::uint8_t>* const restrictions[] = {nullptr, &marked};
  for (const std::vector<std::uint8_t>* only : restrictions) {
    nothingElse.onlyFaces = only;
    map = damaged;
    t = d.map.translations;
    const UntangleStats stats = untangleFlips(mesh, topology, d.cs.field, d.cs.cut, map, t, nothingElse);
    if (only) EXPECT_EQ(stats.flippedBefore, 1u);
    EXPECT_GT(stats.flippedBefore, 0u);
    EXPECT_EQ(stats.flippedAfter, 0u);
    EXPECT_EQ(stats.specks, 1u);
    EXPECT_EQ(stats.speckFaces, mesh.numFaces());
    EXPECT_EQ(measureMap(mesh, map, &d.cs.field, nothingElse.edgeLength).flipped, 0u);
  }
}

// Every face flipped (a map mirrored) on one component larger than a cell: the walks from the
// flipped faces are given up one after another, and a later walk hemmed in by earlier walks' faces
// must not take its pocket for a closed speck (it once did, and the written map was not seamless
// where the pocket went to one point).
TEST(Untangle, PocketsBetweenGivenUpWalksAreNotSpecks) {
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const Topology& topology = d.cs.s.topology;
  const double diagonal = computeBoundingBox(mesh.positions).diagonal();
  ParamOptions options;
  options.edgeLength = 0.15;
  const ParamResult clean = parameterizeMesh(mesh, topology, d.cs.field, d.cs.cut, options);
  std::vector<CornerId> corners(3u * mesh.numFaces());
  std::vector<Vec2d> mirrored(corners.size());
  for (CornerId c = 0; c < corners.size(); ++c) {
    corners[c] = c;
    mirrored[c] = Vec2d(clean.cornerUV[c].x(), -clean.cornerUV[c].y());
  }
  WedgeMap map = clean.cornerUV;
  map.assign(corners, mirrored);
  std::vector<std::complex<double>> t = clean.translations;
  for (auto& z : t) z = std::conj(z);
  const WedgeMap before = map;
  for (const double cell : {0.03, 0.06, 0.1, 0.2}) {
    SCOPED_TRACE(cell);
    ASSERT_EQ(measureMap(mesh, map, &d.cs.field, cell * diagonal).flipped, mesh.numFaces());
    EXPECT_TRUE(collapseSpecks(mesh, topology, d.cs.cut, map, t, cell * diagonal).empty());
    for (CornerId c = 0; c < corners.size(); ++c) ASSERT_EQ(map[c], before[c]) << c;
  }
}

TEST(Untangle, AFloatingCrumbIsMappedToOnePointAndEveryToolAgrees) {
  // A closed crumb a tenth of a cell across beside a sphere (a scan's floating speck): its cones
  // blow its map up to a cell and fold it. param maps it to one point instead: no flips, its
  // faces collapsed, the component reported as a point; check calls the file seamless with the
  // same counts, and quads reports the crumb as an island.
  TriangleMesh crumb = testing::icosphereMesh(2);
  for (Vec3f& p : crumb.positions) p = p * 0.003f + Vec3f(3.0f, 0.0f, 0.0f);
  const std::uint32_t crumbFaces = crumb.numFaces();
  const TriangleMesh mesh = testing::concatMeshes({sphere(20000), crumb});
  testing::TempDir dir;
  writeMesh(dir.path("in.obj"), mesh);
  std::string out;
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("in.obj") + " -o " + dir.path("raw.ply") +
                                    " --no-untangle --quiet --report " + dir.path("raw.json"), &out), 0) << out;
  const JsonValue raw = parseJson(testing::readFile(dir.path("raw.json")));
  ASSERT_GT(raw.numberAt("quality.flipped"), 0.0) << "the crumb's map should fold without the repair";
  ASSERT_EQ(testing::runSeamvox("param " + dir.path("in.obj") + " -o " + dir.path("map.ply") +
                                    " --quiet --report " + dir.path("map.json"), &out), 0) << out;
  const JsonValue r = parseJson(testing::readFile(dir.path("map.json")));
  EXPECT_EQ(r.numberAt("quality.flipped"), 0.0);
  EXPECT_EQ(r.numberAt("quality.collapsed"), double(crumbFaces));
  EXPECT_EQ(r.numberAt("untangle.specks"), 1.0);
  EXPECT_EQ(r.numberAt("untangle.speckFaces"), double(crumbFaces));
  EXPECT_EQ(r.numberAt("componentList.mapped.point"), 1.0);
  EXPECT_EQ(r.numberAt("quality.seamless"), 1.0);
  std::string checked;
  EXPECT_EQ(testing::runSeamvox("check " + dir.path("map.ply"), &checked), 0) << checked;
  EXPECT_NE(checked.find("flipped 0 "), std::string::npos) << checked;
  EXPECT_NE(checked.find("collapsed " + std::to_string(crumbFaces)), std::string::npos) << checked;
  std::string quads;
  ASSERT_EQ(testing::runSeamvox("quads " + dir.path("map.ply") + " -o " + dir.path("q.obj") + " --quiet --report " +
                                    dir.path("q.json"), &quads), 0) << quads;
  const JsonValue q = parseJson(testing::readFile(dir.path("q.json")));
  EXPECT_EQ(q.numberAt("extraction.islands"), 1.0);
  EXPECT_EQ(q.numberAt("extraction.islandFaces"), double(crumbFaces));
  EXPECT_EQ(q.numberAt("validation.valid"), 1.0);
}

TEST(Untangle, RelocationAloneUnfoldsMovedVerticesAndMovesNothingElse) {
  // Without re-solves, each damaged vertex (one wedge, off the cut) moves into the kernel of its
  // fan: no flip left, seams untouched, and no other corner changes.
  for (std::uint32_t passes : {0u, 8u}) {
    DamagedMap d = damagedSphereMap();
    const TriangleMesh& mesh = d.cs.s.mesh;
    const double h = 0.15;
    const WedgeMap before = d.map.cornerUV;
    const std::uint64_t flipped = measureMap(mesh, before, &d.cs.field, h).flipped;
    UntangleOptions options;
    options.edgeLength = h;
    options.maxRounds = 0;
    options.relocationPasses = passes;
    options.jointRings = 0;  // the relocation alone
    std::vector<std::complex<double>> t = d.map.translations;
    const UntangleStats stats = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options);
    EXPECT_EQ(stats.solves, 0u);
    EXPECT_EQ(stats.flippedBefore, flipped);
    const MapQuality after = measureMap(mesh, d.map.cornerUV, &d.cs.field, h);
    EXPECT_EQ(after.flipped, stats.flippedAfter);
    EXPECT_EQ(after.collapsed, 0u);
    EXPECT_TRUE(measureSeams(mesh, d.cs.s.topology, d.cs.cut, d.map.cornerUV).isSeamless());
    EXPECT_EQ(t, d.map.translations);
    // Vertices of flipped faces move: the damaged ones and their neighbours.
    std::vector<std::uint8_t> mayMove(mesh.numVertices(), 0);
    for (VertexId v : d.damaged) {
      d.cs.s.topology.forEachCornerAround(v, [&](CornerId c) {
        for (VertexId w : mesh.triangles[c / 3]) mayMove[w] = 1;
      });
    }
    for (CornerId c = 0; c < before.size(); ++c) {
      if (passes == 0 || !mayMove[d.cs.s.topology.vertex(c)]) EXPECT_EQ(d.map.cornerUV[c], before[c]) << "corner " << c;
      if (d.map.cornerUV[c] == before[c]) continue;
      // A moved vertex lands inside its fan: within the box of its neighbours' (u, v).
      Vec2d lo = Vec2d::Constant(1e300), hi = Vec2d::Constant(-1e300);
      d.cs.s.topology.forEachCornerAround(d.cs.s.topology.vertex(c), [&](CornerId a) {
        for (CornerId b : {nextCorner(a), prevCorner(a)}) lo = lo.cwiseMin(d.map.cornerUV[b]), hi = hi.cwiseMax(d.map.cornerUV[b]);
      });
      EXPECT_TRUE((d.map.cornerUV[c].array() >= lo.array()).all() && (d.map.cornerUV[c].array() <= hi.array()).all())
          << "corner " << c << " moved out of its fan";
    }
    if (passes == 0) {
      EXPECT_EQ(stats.flippedAfter, flipped);
      EXPECT_EQ(stats.relocatedVertices, 0u);
    } else {
      EXPECT_EQ(stats.flippedAfter, 0u);
      EXPECT_GE(stats.relocatedVertices, d.damaged.size());
    }
  }
}

// e turned by k quarter turns counter-clockwise.
Vec2d turned(Vec2d e, int k) {
  for (int j = 0; j < (k & 3); ++j) e = Vec2d(-e.y(), e.x());
  return e;
}

// Quarter turns from corner c's chart to its ccw neighbour's, from the edge they share (-1: none).
int turnToNext(const Topology& topology, const WedgeMap& uv, CornerId c) {
  const CornerId next = topology.ccw(c);
  const Vec2d e = uv[prevCorner(c)] - uv[c], e2 = uv[nextCorner(next)] - uv[next];
  for (int k = 0; k < 4; ++k) {
    if ((turned(e, k) - e2).norm() < 1e-9) return k;
  }
  return -1;
}

// Expects every corner the edit moved to lie inside the box of its fan's neighbours, all seen in
// the corner's own chart (turned across seams); returns the vertices that moved.
std::vector<VertexId> expectMovesInsideTheirFans(const Topology& topology, const WedgeMap& before, const WedgeMap& after) {
  std::vector<VertexId> moved;
  for (CornerId c = 0; c < before.size(); ++c) {
    if (after[c] == before[c]) continue;
    moved.push_back(topology.vertex(c));
    Vec2d lo = Vec2d::Constant(1e300), hi = Vec2d::Constant(-1e300);
    CornerId a = c;
    int k = 0;  // quarter turns from c's chart to a's
    do {
      for (CornerId b : {nextCorner(a), prevCorner(a)}) {
        const Vec2d q = after[c] + turned(after[b] - after[a], -k);
        lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
      }
      const int step = turnToNext(topology, after, a);
      EXPECT_GE(step, 0) << "corner " << a << ": no quarter turn maps its edge onto the next face's";
      k = (k + std::max(step, 0)) & 3;
      a = topology.ccw(a);
    } while (a != c);
    EXPECT_TRUE((after[c].array() >= lo.array()).all() && (after[c].array() <= hi.array()).all())
        << "corner " << c << " moved out of its fan";
  }
  std::sort(moved.begin(), moved.end());
  moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  return moved;
}

TEST(Untangle, RelocationLeavesFansWithFacesFoldedIn3DJointPatchesUnfoldThem) {
  // Damaged vertices fold their fans in (u, v); the first one's smoothed 3D position is pushed
  // far aside, so faces of its fan are also folded in 3D (flipped under any map that follows the
  // smooth surface): relocation must not move it, its neighbours may, and the flips never
  // increase. The joint patches then unfold those faces too (measured against their own 3D
  // shapes), seams and translations exact.
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const Topology& topology = d.cs.s.topology;
  const double h = 0.15;
  d.cs.field.framePositions = mesh.positions;
  const VertexId v = d.damaged.front();
  const VertexId neighbour = topology.vertex(nextCorner(topology.vertexCorner(v)));
  d.cs.field.framePositions[v] = mesh.positions[v] + 4.0f * (mesh.positions[neighbour] - mesh.positions[v]);
  const WedgeMap before = d.map.cornerUV;
  const MapQuality damaged = measureMap(mesh, before, &d.cs.field, h);
  ASSERT_GT(damaged.flippedFolded, 0u) << "no fan face folded in 3D: the test tests nothing";
  UntangleOptions options;
  options.edgeLength = h;
  options.maxRounds = 0;
  options.jointRings = 0;
  std::vector<std::complex<double>> t = d.map.translations;
  const UntangleStats stats = untangleFlips(mesh, topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options);
  const MapQuality after = measureMap(mesh, d.map.cornerUV, &d.cs.field, h);
  EXPECT_LE(after.flipped, damaged.flipped);
  EXPECT_EQ(after.flipped, stats.flippedAfter);
  EXPECT_EQ(after.flippedFolded, stats.foldedIn3D);
  EXPECT_GT(stats.relocatedVertices, 0u);
  EXPECT_LT(after.flipped - after.flippedFolded, damaged.flipped - damaged.flippedFolded);
  ASSERT_GT(after.flippedFolded, 0u) << "relocation alone unfolded the faces folded in 3D";
  EXPECT_TRUE(measureSeams(mesh, topology, d.cs.cut, d.map.cornerUV).isSeamless());
  const std::vector<VertexId> moved = expectMovesInsideTheirFans(topology, before, d.map.cornerUV);
  EXPECT_FALSE(std::binary_search(moved.begin(), moved.end(), v)) << "a vertex next to a face folded in 3D moved";

  options.jointRings = UntangleOptions().jointRings;
  const UntangleStats joint = untangleFlips(mesh, topology, d.cs.field, d.cs.cut, d.map.cornerUV, t, options);
  const MapQuality unfolded = measureMap(mesh, d.map.cornerUV, &d.cs.field, h);
  EXPECT_EQ(joint.flippedBefore, after.flipped);
  EXPECT_GT(joint.jointVertices, 0u);
  EXPECT_EQ(unfolded.flipped, 0u);
  EXPECT_EQ(unfolded.collapsed, 0u);
  EXPECT_EQ(joint.flippedAfter, 0u);
  EXPECT_EQ(joint.foldedIn3D, 0u);
  const SeamQuality seams = measureSeams(mesh, topology, d.cs.cut, d.map.cornerUV);
  EXPECT_LT(seams.maxResidual, 1e-10);
  EXPECT_LT(seams.maxIntegerDistance, 1e-10);
  EXPECT_EQ(t, d.map.translations);
}

/// Grid spacing of flipFreeSphereMap.
constexpr double kSphereMapH = 0.15;

/// A 6000-face sphere with its hat map at h = kSphereMapH (no flips: the tests fold it themselves).
struct SphereMap {
  testing::CutSurface cs;
  ParamResult map;
};
SphereMap flipFreeSphereMap() {
  SphereMap out;
  out.cs = testing::makeCutSurface(sphere(6000));
  ParamOptions param;
  param.edgeLength = kSphereMapH;
  out.map = parameterizeMesh(out.cs.s.mesh, out.cs.s.topology, out.cs.field, out.cs.cut, param);
  return out;
}

TEST(Untangle, SeamVerticesMoveThroughTheTransitions) {
  // Vertices inside seam curves, moved by one displacement turned into each of their wedges'
  // charts (the map stays seamless), fold their fans; relocation alone moves them back into
  // their kernels, all wedges together: no flip left, seams exact, translations as they were.
  SphereMap sphereMap = flipFreeSphereMap();
  testing::CutSurface& cs = sphereMap.cs;
  ParamResult& map = sphereMap.map;
  const TriangleMesh& mesh = cs.s.mesh;
  const Topology& topology = cs.s.topology;
  const double h = kSphereMapH;
  ASSERT_EQ(measureMap(mesh, map.cornerUV, &cs.field, h).flipped, 0u);
  std::vector<std::uint8_t> cone(mesh.numVertices(), 0);
  for (VertexId c : cs.cut.cones) cone[c] = 1;
  std::vector<VertexId> damaged;
  for (const SeamCurve& seam : cs.cut.seams) {
    if (seam.corners.size() < 8 || damaged.size() >= 4) continue;
    const VertexId v = topology.vertex(nextCorner(seam.corners[seam.corners.size() / 2]));
    if (cone[v]) continue;
    bool clear = true;
    for (VertexId w : damaged) clear = clear && (mesh.position(v) - mesh.position(w)).norm() > 0.5;
    if (!clear) continue;
    // Turns per corner, then every wedge moved by the displacement turned into its chart.
    std::vector<std::pair<CornerId, int>> fan;
    int turn = 0;
    topology.forEachCornerAround(v, [&](CornerId c) {
      fan.emplace_back(c, turn);
      const int k = turnToNext(topology, map.cornerUV, c);
      turn = k < 0 ? -100 : (turn + k) & 3;
    });
    if (turn != 0) continue;
    std::vector<std::uint32_t> wedges;
    for (const auto& [c, k] : fan) {
      const std::uint32_t w = map.cornerUV.wedge(c);
      if (std::find(wedges.begin(), wedges.end(), w) != wedges.end()) continue;
      wedges.push_back(w);
      map.cornerUV.setWedgeValue(w, map.cornerUV.wedgeValue(w) + turned(Vec2d(0.9, -0.6), k));
    }
    if (wedges.size() > 1) damaged.push_back(v);
  }
  ASSERT_GE(damaged.size(), 2u) << "too few seam vertices to damage";
  const SeamQuality seamsBefore = measureSeams(mesh, topology, cs.cut, map.cornerUV);
  ASSERT_LT(seamsBefore.maxResidual, 1e-10);
  const MapQuality broken = measureMap(mesh, map.cornerUV, &cs.field, h);
  ASSERT_GT(broken.flipped, 0u);
  const WedgeMap before = map.cornerUV;
  UntangleOptions options;
  options.edgeLength = h;
  options.maxRounds = 0;
  options.jointRings = 0;  // the relocation alone
  std::vector<std::complex<double>> t = map.translations;
  const UntangleStats stats = untangleFlips(mesh, topology, cs.field, cs.cut, map.cornerUV, t, options);
  EXPECT_EQ(stats.flippedBefore, broken.flipped);
  EXPECT_LT(stats.flippedAfter, broken.flipped);
  EXPECT_EQ(measureMap(mesh, map.cornerUV, &cs.field, h).flipped, stats.flippedAfter);
  const SeamQuality seams = measureSeams(mesh, topology, cs.cut, map.cornerUV);
  EXPECT_LT(seams.maxResidual, 1e-10);
  EXPECT_LT(seams.maxIntegerDistance, 1e-10);
  EXPECT_EQ(t, map.translations);
  const std::vector<VertexId> moved = expectMovesInsideTheirFans(topology, before, map.cornerUV);
  std::size_t seamMoved = 0;
  for (VertexId v : damaged) seamMoved += std::binary_search(moved.begin(), moved.end(), v);
  EXPECT_GT(seamMoved, 0u) << "no seam vertex moved";
}

// Vertices within `rings` vertex rings of v (v is ring 0), and their ring numbers.
std::vector<std::pair<VertexId, std::uint32_t>> ringsAround(const TriangleMesh& mesh, const Topology& topology,
                                                            VertexId v, std::uint32_t rings) {
  std::vector<std::uint32_t> ring(mesh.numVertices(), kInvalidId);
  std::vector<std::pair<VertexId, std::uint32_t>> out = {{v, 0}};
  ring[v] = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto [w, r] = out[i];
    if (r == rings) continue;
    topology.forEachCornerAround(w, [&](CornerId c) {
      for (VertexId x : mesh.triangles[c / 3]) {
        if (ring[x] == kInvalidId) ring[x] = r + 1, out.emplace_back(x, r + 1);
      }
    });
  }
  return out;
}

// The hat map of the shared armadillo and rocker arm leaves valence-5 cones at 90 degrees, the
// map folded beside them. Without the cones' own re-solves the repair unfolds that only by
// winding a neighbour twice (no face flipped, a vertex the map covers twice); with them every
// such cone is opened to its 450 degrees and nothing is wound.
TEST(Untangle, ConesLeftAFullTurnShortAreReSolvedNotWound) {
  std::size_t meshes = 0;
  for (const char* name : {"armadillo.obj", "rocker-arm.obj"}) {
    const std::string path = testing::sharedMesh(name);
    if (path.empty()) {
      std::printf("skipping %s: %s\n", name, testing::missingSharedMessage(name).c_str());
      continue;
    }
    SCOPED_TRACE(name);
    ++meshes;
    PipelineOptions options;
    options.solver.solver = ParamSolver::Hat;
    const PipelineResult fixed = parameterize(readMesh(path), options);
    EXPECT_GT(fixed.untangle.miswoundCones, 0u);
    EXPECT_EQ(fixed.untangle.miswoundConesAfter, 0u);
    EXPECT_EQ(fixed.mapQuality.flipped, 0u);
    EXPECT_TRUE(fixed.mapQuality.woundCounted);
    EXPECT_EQ(fixed.mapQuality.wound, 0u);
    EXPECT_TRUE(fixed.isSeamless());
    options.untangleOptions.coneRepairRadius = 0.0;
    const PipelineResult off = parameterize(readMesh(path), options);
    EXPECT_GT(off.untangle.miswoundConesAfter, 0u);
    EXPECT_TRUE(off.isSeamless());
  }
  if (meshes == 0) GTEST_SKIP() << "no shared mesh";
}


// The cone step lists the cones it re-solved and left a full turn short (conesLeftShort), and a
// later repair of the same map given them (conesNotRetried) does not solve their patches again:
// the shared armadillo's hat map, the cone step alone with patches of two rings (too small to
// open every fold), run once from the map as solved, then from that map again with the cones it
// left short listed (none of them tried again, all still counted), and with every cone listed
// (nothing changes: no other step runs).
TEST(Untangle, ConesLeftShortAreNotRetriedWhenListed) {
  const std::string path = testing::sharedMesh("armadillo.obj");
  if (path.empty()) GTEST_SKIP() << testing::missingSharedMessage("armadillo.obj");
  testing::CutSurface cs = testing::makeCutSurface(testing::loadShared(path).mesh);
  const TriangleMesh& mesh = cs.s.mesh;
  const double h = computeBoundingBox(mesh.positions).diagonal() / 100.0;
  ParamOptions param;
  param.edgeLength = h;
  const ParamResult solved = parameterizeMesh(mesh, cs.s.topology, cs.field, cs.cut, param);
  UntangleOptions options;
  options.edgeLength = h;
  options.maxRounds = 0;
  options.relocationPasses = 0;
  options.jointRings = 0;
  options.coneRepairRadius = 1e-3;  // two rings
  WedgeMap first = solved.cornerUV;
  std::vector<std::complex<double>> t = solved.translations;
  const UntangleStats once = untangleFlips(mesh, cs.s.topology, cs.field, cs.cut, first, t, options);
  ASSERT_FALSE(once.conesLeftShort.empty()) << "every cone opened: the case no longer leaves one short";
  EXPECT_TRUE(std::is_sorted(once.conesLeftShort.begin(), once.conesLeftShort.end()));
  EXPECT_LE(once.conesLeftShort.size(), once.miswoundConesAfter);
  bool changed = false;
  for (CornerId c = 0; c < 3u * mesh.numFaces() && !changed; ++c) changed = first[c] != solved.cornerUV[c];
  EXPECT_TRUE(changed) << "the cone step re-solved nothing";
  for (VertexId c : once.conesLeftShort) {
    EXPECT_NE(std::find(cs.cut.cones.begin(), cs.cut.cones.end(), c), cs.cut.cones.end()) << "not a cone: " << c;
  }
  // Again from that map with those cones listed: none of them is re-solved (other cones the first
  // run's patches left short may be).
  options.conesNotRetried = &once.conesLeftShort;
  WedgeMap second = first;
  std::vector<std::complex<double>> t2 = t;
  const UntangleStats again = untangleFlips(mesh, cs.s.topology, cs.field, cs.cut, second, t2, options);
  EXPECT_EQ(again.miswoundCones, once.miswoundConesAfter);  // counted all the same
  for (VertexId c : again.conesLeftShort) {
    EXPECT_FALSE(std::binary_search(once.conesLeftShort.begin(), once.conesLeftShort.end(), c)) << "cone " << c;
  }
  // With every cone listed the cone step solves nothing: the map and translations stay.
  std::vector<VertexId> every = cs.cut.cones;
  std::sort(every.begin(), every.end());
  options.conesNotRetried = &every;
  WedgeMap third = first;
  std::vector<std::complex<double>> t3 = t;
  const UntangleStats none = untangleFlips(mesh, cs.s.topology, cs.field, cs.cut, third, t3, options);
  EXPECT_TRUE(none.conesLeftShort.empty());
  EXPECT_EQ(none.miswoundConesAfter, once.miswoundConesAfter);
  EXPECT_EQ(t3, t);
  for (CornerId c = 0; c < 3u * mesh.numFaces(); ++c) ASSERT_EQ(third[c], first[c]) << "corner " << c;
}

TEST(Untangle, JointPatchesUnfoldAMirroredDiskThatRelocationCannot) {
  // A disk of two rings mirrored in (u, v): its inner fans are reversed, so no vertex alone has a
  // kernel to move into. Relocation alone leaves flips; the joint patches move the disk's
  // vertices together and unfold it, seams and translations exact, cones and the rest unmoved.
  SphereMap sphereMap = flipFreeSphereMap();
  testing::CutSurface& cs = sphereMap.cs;
  const ParamResult& clean = sphereMap.map;
  const TriangleMesh& mesh = cs.s.mesh;
  const Topology& topology = cs.s.topology;
  const double h = kSphereMapH;
  ASSERT_EQ(measureMap(mesh, clean.cornerUV, &cs.field, h).flipped, 0u);
  std::vector<std::uint8_t> onCut(mesh.numVertices(), 0);
  for (VertexId c : cs.cut.cones) onCut[c] = 1;
  for (const SeamCurve& seam : cs.cut.seams) {
    for (CornerId c : seam.corners) onCut[topology.vertex(c)] = onCut[topology.vertex(nextCorner(c))] = 1;
  }
  std::vector<std::pair<VertexId, std::uint32_t>> disk;
  for (VertexId v = 0; v < mesh.numVertices() && disk.empty(); v += 7) {
    const auto around = ringsAround(mesh, topology, v, 8);  // far from seams and cones
    bool clear = true;
    for (const auto& [w, r] : around) clear = clear && !onCut[w] && !topology.isBoundaryVertex(w);
    if (clear) disk = ringsAround(mesh, topology, v, 2);
  }
  ASSERT_FALSE(disk.empty()) << "no vertex far enough from the cut";
  const Vec2d centre = clean.cornerUV[topology.vertexCorner(disk.front().first)];
  for (bool joint : {false, true}) {
    ParamResult map = clean;
    for (const auto& [w, r] : disk) {  // one wedge each: off the cut
      const std::uint32_t wedge = map.cornerUV.wedge(topology.vertexCorner(w));
      const Vec2d q = map.cornerUV.wedgeValue(wedge);
      map.cornerUV.setWedgeValue(wedge, Vec2d(q.x(), 2.0 * centre.y() - q.y()));
    }
    const WedgeMap before = map.cornerUV;
    const std::uint64_t broken = measureMap(mesh, before, &cs.field, h).flipped;
    ASSERT_GT(broken, 10u);
    UntangleOptions options;
    options.edgeLength = h;
    options.maxRounds = 0;
    options.jointRings = joint ? 6 : 0;
    std::vector<std::complex<double>> t = map.translations;
    const UntangleStats stats = untangleFlips(mesh, topology, cs.field, cs.cut, map.cornerUV, t, options);
    EXPECT_EQ(stats.flippedBefore, broken);
    const MapQuality after = measureMap(mesh, map.cornerUV, &cs.field, h);
    EXPECT_EQ(after.flipped, stats.flippedAfter);
    EXPECT_EQ(after.collapsed, 0u);
    if (!joint) {
      EXPECT_GT(stats.flippedAfter, 0u) << "relocation alone unfolded the disk: the test needs a harder case";
      EXPECT_EQ(stats.jointVertices, 0u);
      continue;
    }
    EXPECT_EQ(stats.flippedAfter, 0u);
    EXPECT_GT(stats.jointVertices, 0u);
    const SeamQuality seams = measureSeams(mesh, topology, cs.cut, map.cornerUV);
    EXPECT_LT(seams.maxResidual, 1e-10);
    EXPECT_LT(seams.maxIntegerDistance, 1e-10);
    EXPECT_EQ(t, map.translations);
    // Only vertices within the largest patch (6 rings of a flipped face) moved; cones never.
    const auto reach = ringsAround(mesh, topology, disk.front().first, 2 + 6);
    std::vector<std::uint8_t> mayMove(mesh.numVertices(), 0);
    for (const auto& [w, r] : reach) mayMove[w] = 1;
    for (CornerId c = 0; c < before.size(); ++c) {
      if (map.cornerUV[c] != before[c]) EXPECT_TRUE(mayMove[topology.vertex(c)]) << "corner " << c << " moved";
    }
    for (VertexId cone : cs.cut.cones) {
      topology.forEachCornerAround(cone, [&](CornerId c) { EXPECT_EQ(map.cornerUV[c], before[c]); });
    }
  }
}

// Several mirrored disks far apart, each with many flipped faces: the joint patches of one wave
// (disjoint reaches) run in parallel and a disk's other seeds wait for the next wave. The map is
// the same with one thread or two, every disk unfolds, seams and translations exact.
TEST(Untangle, JointPatchesOfSeveralFoldsGiveTheSameMapAtAnyThreadCount) {
  testing::CutSurface cs = testing::makeCutSurface(sphere(24000));
  const TriangleMesh& mesh = cs.s.mesh;
  const Topology& topology = cs.s.topology;
  const double h = 0.1;
  ParamOptions param;
  param.edgeLength = h;
  const ParamResult clean = parameterizeMesh(mesh, topology, cs.field, cs.cut, param);
  ASSERT_EQ(measureMap(mesh, clean.cornerUV, &cs.field, h).flipped, 0u);
  std::vector<std::uint8_t> blocked(mesh.numVertices(), 0);  // the cut, and near a disk already
  for (VertexId c : cs.cut.cones) blocked[c] = 1;
  for (const SeamCurve& seam : cs.cut.seams) {
    for (CornerId c : seam.corners) blocked[topology.vertex(c)] = blocked[topology.vertex(nextCorner(c))] = 1;
  }
  ParamResult broken = clean;
  std::size_t disks = 0;
  for (VertexId v = 0; v < mesh.numVertices() && disks < 4; v += 13) {
    bool clear = true;
    for (const auto& [w, r] : ringsAround(mesh, topology, v, 8)) clear = clear && !blocked[w] && !topology.isBoundaryVertex(w);
    if (!clear) continue;
    for (const auto& [w, r] : ringsAround(mesh, topology, v, 12)) blocked[w] = 1;
    const Vec2d centre = broken.cornerUV[topology.vertexCorner(v)];
    for (const auto& [w, r] : ringsAround(mesh, topology, v, 2)) {  // one wedge each: off the cut
      const std::uint32_t wedge = broken.cornerUV.wedge(topology.vertexCorner(w));
      const Vec2d q = broken.cornerUV.wedgeValue(wedge);
      broken.cornerUV.setWedgeValue(wedge, Vec2d(q.x(), 2.0 * centre.y() - q.y()));
    }
    ++disks;
  }
  ASSERT_GE(disks, 3u) << "too few places far from the cut";
  const std::uint64_t flips = measureMap(mesh, broken.cornerUV, &cs.field, h).flipped;
  ASSERT_GT(flips, 10 * disks);
  std::vector<WedgeMap> maps;
  for (std::size_t threads : {1u, 2u}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    ParamResult map = broken;
    UntangleOptions options;
    options.edgeLength = h;
    options.maxRounds = 0;
    options.relocationPasses = 0;
    options.jointRings = 6;
    std::vector<std::complex<double>> t = map.translations;
    const UntangleStats stats = untangleFlips(mesh, topology, cs.field, cs.cut, map.cornerUV, t, options);
    EXPECT_EQ(stats.flippedBefore, flips);
    EXPECT_EQ(stats.flippedAfter, 0u);
    EXPECT_GT(stats.jointVertices, 0u);
    EXPECT_TRUE(stats.leftFaces.empty());
    EXPECT_EQ(measureMap(mesh, map.cornerUV, &cs.field, h).flipped, 0u);
    const SeamQuality seams = measureSeams(mesh, topology, cs.cut, map.cornerUV);
    EXPECT_LT(seams.maxResidual, 1e-10);
    EXPECT_EQ(t, map.translations);
    maps.push_back(map.cornerUV);
  }
  std::size_t differ = 0;
  for (CornerId c = 0; c < maps[0].size(); ++c) differ += maps[0][c] != maps[1][c];
  EXPECT_EQ(differ, 0u) << "corners whose (u, v) differ between one and two threads";
}

// With the faces that may be flipped given (a caller that knows the rest of the map is fine), the
// repair measures only those and gives the same map as one that measures every face; the faces
// it leaves flipped are listed. Faces left out are taken as fine and never touched.
TEST(Untangle, CandidateFacesGiveTheSameRepairAsTheWholeMap) {
  DamagedMap d = damagedSphereMap();
  const TriangleMesh& mesh = d.cs.s.mesh;
  const double h = 0.15;
  std::vector<FaceId> flipped;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (isFlippedRatio(parameterAreaRatio(mesh, d.map.cornerUV, f, h))) flipped.push_back(f);
  }
  ASSERT_GT(flipped.size(), 0u);
  UntangleOptions options;
  options.edgeLength = h;
  options.maxRounds = 1;
  options.maxSolves = 1;  // leaves flips, so that the list of faces left is tested too
  options.relocationPasses = 0;
  options.jointRings = 0;
  ParamResult whole = d.map, listed = d.map;
  const UntangleStats a = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, whole.cornerUV,
                                        whole.translations, options);
  options.candidateFaces = &flipped;
  const UntangleStats b = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, listed.cornerUV,
                                        listed.translations, options);
  EXPECT_EQ(a.flippedBefore, flipped.size());
  EXPECT_EQ(b.flippedBefore, a.flippedBefore);
  EXPECT_EQ(b.flippedAfter, a.flippedAfter);
  EXPECT_EQ(b.leftFaces, a.leftFaces);
  std::size_t differ = 0;
  for (CornerId c = 0; c < whole.cornerUV.size(); ++c) differ += whole.cornerUV[c] != listed.cornerUV[c];
  EXPECT_EQ(differ, 0u);
  std::vector<FaceId> left;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    if (isFlippedRatio(parameterAreaRatio(mesh, whole.cornerUV, f, h))) left.push_back(f);
  }
  EXPECT_EQ(a.leftFaces, left);
  EXPECT_EQ(a.flippedAfter, left.size());

  // Half the flips left out: they are not counted and their faces keep their values.
  const std::vector<FaceId> half(flipped.begin(), flipped.begin() + flipped.size() / 2);
  ParamResult some = d.map;
  options.candidateFaces = &half;
  const UntangleStats c = untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, some.cornerUV,
                                        some.translations, options);
  EXPECT_EQ(c.flippedBefore, half.size());
  const std::vector<FaceId> unsorted = {flipped.back(), flipped.front()};
  options.candidateFaces = &unsorted;
  EXPECT_THROW(untangleFlips(mesh, d.cs.s.topology, d.cs.field, d.cs.cut, some.cornerUV, some.translations, options),
               InputError);
}

TEST(Untangle, NothingToDoLeavesTheMapAsItIs) {
  testing::CutSurface cs = testing::makeCutSurface(testing::torusMesh(40, 20));
  ParamOptions param;
  param.edgeLength = 0.2;
  ParamResult map = parameterizeMesh(cs.s.mesh, cs.s.topology, cs.field, cs.cut, param);
  ASSERT_EQ(measureMap(cs.s.mesh, map.cornerUV, &cs.field, 0.2).flipped, 0u);
  const WedgeMap before = map.cornerUV;
  UntangleOptions options;
  options.edgeLength = 0.2;
  const UntangleStats stats = untangleFlips(cs.s.mesh, cs.s.topology, cs.field, cs.cut, map.cornerUV, map.translations, options);
  EXPECT_EQ(stats.flippedBefore, 0u);
  EXPECT_EQ(stats.solves, 0u);
  for (CornerId c = 0; c < before.size(); ++c) EXPECT_EQ(map.cornerUV[c], before[c]);
}

TEST(Untangle, RejectsMismatchedSizes) {
  DamagedMap d = damagedSphereMap();
  UntangleOptions options;
  options.edgeLength = 0.15;
  std::vector<std::complex<double>> tooFew;
  EXPECT_THROW(untangleFlips(d.cs.s.mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV, tooFew, options),
               InputError);
  options.stiffening = 1.0;
  EXPECT_THROW(untangleFlips(d.cs.s.mesh, d.cs.s.topology, d.cs.field, d.cs.cut, d.map.cornerUV,
                             d.map.translations, options),
               InputError);
}

// The pipeline runs the repair by default as its own stage; off, it reports none. On a fine mesh
// (hat flips around cones) the repair lowers the flips and the map stays seamless.
TEST(Untangle, PipelineStageLowersFlips) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.spacing.cells = 30;  // a coarse grid on a fine mesh: the hat map flips near cones
  options.coneWeightRadius = 0.0;
  options.untangle = false;
  const PipelineResult off = parameterize(generatedMesh(MeshKind::Genus2, 30000), options);
  EXPECT_FALSE(off.untangled);
  ASSERT_GT(off.mapQuality.flipped, 0u) << "the test needs a map with flips";
  options.untangle = true;
  StageMeter meter;
  options.meter = &meter;
  const PipelineResult on = parameterize(generatedMesh(MeshKind::Genus2, 30000), options);
  ASSERT_TRUE(on.untangled);
  EXPECT_TRUE(on.isSeamless());
  EXPECT_EQ(on.untangle.flippedBefore, off.mapQuality.flipped);
  EXPECT_EQ(on.untangle.flippedAfter, on.mapQuality.flipped);
  EXPECT_LE(on.mapQuality.flipped, off.mapQuality.flipped);
  bool stage = false;
  for (const StageFigures& s : meter.stages()) stage = stage || s.name == "untangle";
  EXPECT_TRUE(stage);
}

// The per-component figures count the flips measureMap listed: the same as measuring every face
// again, with the pipeline's flips left unrepaired on two components.
TEST(Untangle, ComponentFlipsFromTheListedFacesEqualThoseMeasuredAgain) {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  options.spacing.cells = 30;
  options.coneWeightRadius = 0.0;
  options.untangle = false;
  TriangleMesh mesh = generatedMesh(MeshKind::Genus2, 30000);
  const TriangleMesh second = sphere(2000);
  const VertexId offset = mesh.numVertices();
  for (const Vec3f& p : second.positions) mesh.positions.push_back(p + Vec3f(5.0f, 0.0f, 0.0f));
  for (Triangle t : second.triangles) mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const PipelineResult r = parameterize(std::move(mesh), options);
  ASSERT_GT(r.mapQuality.flipped, 0u) << "the test needs a map with flips";
  ASSERT_GE(r.components.count, 2u);
  const ComponentSummary again = summarizeComponents(r.mesh, r.topology, r.cones, r.solved.param.unsolvedFaces,
                                                     r.solved.param.anchoredFaces, r.edgeLength, 100);
  ASSERT_EQ(again.listed.size(), r.components.listed.size());
  std::uint64_t sum = 0;
  for (std::size_t k = 0; k < again.listed.size(); ++k) {
    EXPECT_EQ(r.components.listed[k].flippedFaces, again.listed[k].flippedFaces) << "component " << k;
    sum += r.components.listed[k].flippedFaces;
  }
  EXPECT_EQ(sum, r.mapQuality.flipped);
}

// Scan noise folds faces in 3D, which flip under the least-squares map; the repair unfolds them
// too (against their own 3D shapes), so a noisy scan's map has no flips left, stays seamless and
// keeps its gradient error within 1.05x.
TEST(Untangle, NoisyScanMapHasNoFlipsLeftFoldedFacesIncluded) {
  TriangleMesh raw = noisyScan(60000, 0.5, 7);
  PipelineOptions options;
  options.untangle = false;
  const PipelineResult off = parameterize(TriangleMesh(raw), options);
  ASSERT_GT(off.mapQuality.flippedFolded, 0u) << "the noise folds no flipped face: the test tests nothing";
  options.untangle = true;
  const PipelineResult on = parameterize(std::move(raw), options);
  EXPECT_TRUE(on.isSeamless());
  EXPECT_EQ(on.untangle.flippedBefore, off.mapQuality.flipped);
  EXPECT_EQ(on.mapQuality.flipped, 0u);
  EXPECT_EQ(on.untangle.flippedAfter, 0u);
  EXPECT_EQ(on.mapQuality.collapsed, 0u);
  EXPECT_LE(on.mapQuality.relativeGradientError, 1.05 * off.mapQuality.relativeGradientError);
}

// The stiffening rounds keep a patch component's re-solve only when it has fewer flips than the
// component came in with, so on maps with many cones (random fields: the stiffened solves often
// flip more faces than the first) the rounds alone never add flips and the map stays seamless.
// A voxloc map's flips all lie in the faces its refinement solved: the repair measures only those
// and still counts every flip the whole map's measure counts (the map with the repair off), and
// leaves as many as the final measure counts; the hat map has no such list, every face is measured.
TEST(Untangle, VoxLocRepairMeasuresTheRefinedFacesOnlyAndMissesNoFlip) {
  const TriangleMesh raw = noisyScan(60000, 0.5, 7);
  for (const ParamSolver solver : {ParamSolver::VoxLoc, ParamSolver::Hat}) {
    SCOPED_TRACE(paramSolverName(solver));
    PipelineOptions options;
    options.solver.solver = solver;
    options.solver.gridResolution = 32;
    options.maxConePasses = 1;  // no repair next to close cones first (it may move any face)
    options.untangle = false;
    const PipelineResult off = parameterize(TriangleMesh(raw), options);
    ASSERT_GT(off.mapQuality.flipped, 0u) << "no flips: the test tests nothing";
    options.untangle = true;
    const PipelineResult on = parameterize(TriangleMesh(raw), options);
    ASSERT_EQ(on.solved.solver, solver);
    EXPECT_EQ(on.conePasses, off.conePasses);
    EXPECT_EQ(on.untangle.flippedBefore, off.mapQuality.flipped);
    EXPECT_EQ(on.mapQuality.flipped, on.untangle.flippedAfter);
    if (solver == ParamSolver::VoxLoc) {
      EXPECT_EQ(on.untangle.measuredFaces, off.solved.refine.regionFaces);
      EXPECT_LT(on.untangle.measuredFaces, on.mesh.numFaces() / 2);
    } else {
      EXPECT_EQ(on.untangle.measuredFaces, on.mesh.numFaces());
    }
  }
}

TEST(Untangle, StiffeningRoundsNeverAddFlips) {
  std::uint64_t repaired = 0;
  for (std::uint32_t seed : {3u, 5u, 8u}) {
    testing::CutSurface cs = testing::makeCutSurface(sphere(6000), seed);
    ParamOptions param;
    param.edgeLength = 0.12;
    ParamResult map = parameterizeMesh(cs.s.mesh, cs.s.topology, cs.field, cs.cut, param);
    UntangleOptions options;
    options.edgeLength = param.edgeLength;
    options.coneRepairRadius = 0.0;  // the rounds only
    options.relocationPasses = 0;
    options.jointRings = 0;
    const MapQuality before = measureMap(cs.s.mesh, map.cornerUV, &cs.field, param.edgeLength);
    const UntangleStats stats =
        untangleFlips(cs.s.mesh, cs.s.topology, cs.field, cs.cut, map.cornerUV, map.translations, options);
    EXPECT_EQ(stats.flippedBefore, before.flipped) << "seed " << seed;
    EXPECT_LE(stats.flippedAfter, stats.flippedBefore) << "seed " << seed;
    EXPECT_EQ(measureMap(cs.s.mesh, map.cornerUV, &cs.field, param.edgeLength).flipped, stats.flippedAfter);
    EXPECT_TRUE(measureSeams(cs.s.mesh, cs.s.topology, cs.cut, map.cornerUV).isSeamless()) << "seed " << seed;
    repaired += stats.flippedBefore - std::min(stats.flippedBefore, stats.flippedAfter);
  }
  EXPECT_GT(repaired, 0u) << "no round lowered any flip: the maps test nothing";
}

}  // namespace
}  // namespace seamvox
