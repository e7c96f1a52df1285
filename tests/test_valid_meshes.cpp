// Valid meshes that real scans contain: tiny closed components, lone triangles, spikes and
// non-manifold pieces get a seamless map, and what param reports is what check finds in the file.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <numeric>

#include <cmath>
#include <complex>
#include <string>

#include "core/basis/reduce.h"
#include "core/cut/cut.h"
#include "core/field/cone_merge.h"
#include "core/field/field.h"
#include "core/mesh/clean.h"
#include "core/pipeline/parameterize.h"
#include "core/quality/metrics.h"
#include "core/solve/param_solver.h"
#include "core/solve/seamless_solve.h"
#include "core/system/errors.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "io/param_report.h"
#include "tests/test_meshes.h"
#include "tests/testing.h"

namespace seamvox {
namespace {

TriangleMesh tetrahedron(const Vec3d& origin, double size) {
  TriangleMesh mesh;
  for (const Vec3d& p : {Vec3d(1, 1, 1), Vec3d(1, -1, -1), Vec3d(-1, 1, -1), Vec3d(-1, -1, 1)}) {
    mesh.positions.push_back((origin + size * p).cast<float>());
  }
  mesh.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return mesh;
}

TriangleMesh octahedron() {
  TriangleMesh mesh;
  mesh.positions = {Vec3f(1, 0, 0), Vec3f(-1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, -1, 0), Vec3f(0, 0, 1), Vec3f(0, 0, -1)};
  mesh.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return mesh;
}

TriangleMesh triangle(const Vec3d& origin, double size) {
  TriangleMesh mesh;
  mesh.positions = {origin.cast<float>(), (origin + Vec3d(size, 0, 0.3 * size)).cast<float>(),
                    (origin + Vec3d(0, size, 0)).cast<float>()};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

/// Deterministic offsets in a 100-unit cube.
Vec3d scatter(int i) {
  return Vec3d(std::fmod(i * 37.13, 100.0), std::fmod(i * 53.71, 100.0), std::fmod(i * 71.29, 100.0));
}

struct Solved {
  SolverResult result;
  SeamQuality seams, rebuilt;
};

/// Clean, smoothest field, cut and solve with `solver` at h = diagonal / cells.
Solved solve(TriangleMesh input, ParamSolver solver, double cells = 100.0) {
  CleanResult clean = cleanMesh(std::move(input));
  const TriangleMesh& mesh = clean.mesh;
  const CrossField field = computeSmoothestField(mesh, clean.topology);
  const CutResult cut = cutToDisk(mesh, clean.topology, field, computeSingularities(mesh, clean.topology, field));
  ParamOptions options;
  options.edgeLength = clean.report.diagonalWithoutSpikes / cells;
  SolverOptions solverOptions;
  solverOptions.solver = solver;
  solverOptions.gridResolution = 32;  // 128 on a 4-face mesh: 190K voxel unknowns, 30 s
  Solved out;
  out.result = parameterizeMeshWithSolver(mesh, clean.topology, field, cut, options, solverOptions);
  out.seams = measureSeams(mesh, clean.topology, cut, out.result.param.cornerUV);
  out.rebuilt = measureSeamsFromUV(mesh, clean.topology, out.result.param.cornerUV);
  return out;
}

void expectSeamless(const Solved& s, const std::string& what) {
  EXPECT_TRUE(s.seams.isSeamless()) << what << ": residual " << s.seams.maxResidual;
  EXPECT_TRUE(s.rebuilt.isSeamless()) << what << ": residual from UVs " << s.rebuilt.maxResidual;
  for (const auto& t : s.result.param.translations) EXPECT_LT(gaussianIntegerDistance(t), 1e-9) << what;
}

TEST(ValidMeshes, ClosedComponentsWhoseEveryVertexIsAConeAreSolved) {
  TriangleMesh many;
  {
    std::vector<TriangleMesh> parts;
    for (int i = 0; i < 40; ++i) parts.push_back(tetrahedron(scatter(i), 0.1));
    many = testing::concatMeshes(parts);
  }
  TriangleMesh shared = testing::concatMeshes({tetrahedron(Vec3d(0, 0, 0), 1.0), tetrahedron(Vec3d(2, 2, 2), 1.0)});
  for (Triangle& t : shared.triangles) {  // the second one's vertex 4 (2+1, ...) -> vertex 0 (1, 1, 1)
    for (VertexId& v : t) v = v == 6 ? 0 : v;
  }
  const std::pair<const char*, TriangleMesh> meshes[] = {
      {"tetrahedron", tetrahedron(Vec3d(0, 0, 0), 1.0)}, {"octahedron", octahedron()},
      {"40 tiny tetrahedra", many}, {"two tetrahedra sharing a vertex", shared}};
  for (const auto& [name, mesh] : meshes) {
    for (ParamSolver solver : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
      const std::string what = std::string(name) + " " + paramSolverName(solver);
      const Solved s = solve(mesh, solver);
      expectSeamless(s, what);
      EXPECT_EQ(s.result.param.stats.unsolvedComponents, 0u) << what;
      if (solver == ParamSolver::Hat) EXPECT_GT(s.result.param.stats.anchoredComponents, 0u) << what;
    }
  }
}

TEST(ValidMeshes, ComponentsWithoutInteriorEdgesTakeTheirFirstEdge) {
  std::vector<TriangleMesh> loose;
  for (int i = 0; i < 300; ++i) loose.push_back(triangle(scatter(i), 1.0));
  for (const TriangleMesh& input : {triangle(Vec3d(0, 0, 0), 1.0), testing::concatMeshes(loose),
                                    testing::concatMeshes({testing::icosphereMesh(2), triangle(Vec3d(3, 0, 0), 0.5)})}) {
    CleanResult clean = cleanMesh(TriangleMesh(input));
    const CrossField field = computeSmoothestField(clean.mesh, clean.topology);
    for (FaceId f = 0; f < clean.mesh.numFaces(); ++f) {
      bool lone = true;
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) lone = lone && clean.topology.opposite(c) == kInvalidId;
      if (!lone) continue;
      const Triangle& t = clean.mesh.triangles[f];
      const Vec3d edge = (clean.mesh.position(t[1]) - clean.mesh.position(t[0])).normalized();
      EXPECT_NEAR(field.at(f).dot(edge), 1.0, 1e-6) << "face " << f;
    }
    expectSeamless(solve(TriangleMesh(input), ParamSolver::Hat), "lone triangles hat");
    expectSeamless(solve(TriangleMesh(input), ParamSolver::Vox), "lone triangles vox");
    expectSeamless(solve(TriangleMesh(input), ParamSolver::VoxLoc), "lone triangles voxloc");
  }
}

TEST(ValidMeshes, ASpikeIsReportedAndTheMapAwayFromItStaysValid) {
  TriangleMesh sphere = testing::icosphereMesh(4);
  sphere.positions[7] *= 1000.0f;
  CleanResult clean = cleanMesh(TriangleMesh(sphere));
  EXPECT_EQ(clean.report.spikeVertices, 1u);
  ASSERT_EQ(clean.spikes.size(), 1u);
  EXPECT_EQ(clean.spikes[0], 7u);
  EXPECT_LT(clean.report.diagonalWithoutSpikes, 4.0);  // the unit sphere's own extent
  for (ParamSolver solver : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
    const Solved s = solve(sphere, solver, 30.0);
    expectSeamless(s, std::string("spiked sphere ") + paramSolverName(solver));
    const MapQuality map = measureMap(sphere, s.result.param.cornerUV, nullptr, 0.0);
    EXPECT_LT(map.flipped, sphere.numFaces() / 25) << paramSolverName(solver);
  }
  EXPECT_EQ(cleanMesh(testing::icosphereMesh(4)).report.spikeVertices, 0u);
}

// A basis of 1D hat pieces: component 0 a chain of 4 functions, component 1 a chain of 3 whose
// elements have an indefinite stiffness (eigenvalues -1 and 3), so it cannot be factored.
class ChainBasis final : public Basis {
 public:
  ChainBasis() {
    numBasisFunctions_ = 7;
    for (std::uint32_t b = 0; b < 7; ++b) domainBasis_.push_back(b);
  }
  std::uint64_t numElements() const override { return 5; }
  std::uint32_t elementDomains(std::uint64_t e, std::uint32_t* out) const override {
    const std::uint32_t first = e < 3 ? std::uint32_t(e) : std::uint32_t(e + 1);
    out[0] = first, out[1] = first + 1;
    return 2;
  }
  void elementIntegrals(std::uint64_t e, ElementIntegrals& out) const override {
    out.count = elementDomains(e, out.domain.data());
    out.stiffness = {};
    out.stiffness[0] = out.stiffness[3] = 1.0;
    out.stiffness[1] = out.stiffness[2] = e < 3 ? -1.0 : -2.0;
    out.rhs = {};
    out.rhs[0] = -1.0, out.rhs[1] = 1.0;  // gradient target 1
    out.area = 1.0;
  }
  void evaluateCorners(const std::vector<std::complex<double>>&, WedgeMap&) const override {}
};

TEST(ValidMeshes, AComponentThatCannotBeFactoredIsLeftUnsolvedAndTheRestSolved) {
  const ChainBasis basis;
  const Reduction reduction = reduceBasis(basis);
  ASSERT_EQ(reduction.numComponents, 2u);
  const SeamlessSolution solution = solveSeamless(basis, reduction);
  ASSERT_EQ(solution.unsolvedComponents.size(), 1u);
  const std::uint32_t bad = solution.unsolvedComponents[0];
  EXPECT_EQ(bad, reduction.unknownComponent[reduction.basisPositional[4]]);
  EXPECT_NE(solution.unsolvedReasons[0].find("component"), std::string::npos) << solution.unsolvedReasons[0];
  EXPECT_EQ(solution.stats.unsolvedComponents, 1u);
  for (std::uint32_t b = 0; b < 7; ++b) {
    const std::complex<double> x = solution.unknowns[reduction.basisPositional[b]];
    if (b >= 4) EXPECT_EQ(x, 0.0) << b;
  }
  // The good chain follows its target: consecutive coefficients differ by 1.
  for (std::uint32_t b = 0; b + 1 < 4; ++b) {
    const auto step = solution.unknowns[reduction.basisPositional[b + 1]] - solution.unknowns[reduction.basisPositional[b]];
    EXPECT_NEAR(std::abs(step - 1.0), 0.0, 1e-9) << b;
  }
  RoundOptions strict;
  strict.dropUnsolvable = false;
  EXPECT_THROW(solveSeamless(basis, reduction, strict), SolverError);
}

// --- per-component figures ---------------------------------------------------------------------

/// A sphere, then tiny closed tetrahedra, then loose triangles, and (optionally) an open patch.
TriangleMesh sphereAndIslands(int tetrahedra, int triangles, bool patch) {
  std::vector<TriangleMesh> parts{testing::icosphereMesh(3)};
  for (int i = 0; i < tetrahedra; ++i) parts.push_back(tetrahedron(Vec3d(3, 0, 0) + 0.02 * scatter(i), 0.01));
  for (int i = 0; i < triangles; ++i) parts.push_back(triangle(Vec3d(-5, 0, 0) + 0.02 * scatter(i), 0.02));
  if (patch) {
    TriangleMesh grid = testing::gridMesh(6, 6, 0.1);
    for (Vec3f& p : grid.positions) p += Vec3f(0.0f, 3.0f, 0.0f);
    parts.push_back(grid);
  }
  return testing::concatMeshes(parts);
}

/// Faces of each component, components numbered by their lowest face (the report's ids).
std::vector<std::vector<FaceId>> facesById(const Topology& topology) {
  const ComponentsResult components = computeComponents(topology);
  std::vector<std::uint32_t> idOf(components.components.size(), kInvalidId);
  std::vector<std::vector<FaceId>> out;
  for (FaceId f = 0; f < topology.numFaces(); ++f) {
    std::uint32_t& id = idOf[components.faceComponent[f]];
    if (id == kInvalidId) {
      id = static_cast<std::uint32_t>(out.size());
      out.emplace_back();
    }
    out[id].push_back(f);
  }
  return out;
}

double uvExtent(const WedgeMap& uv, const std::vector<FaceId>& faces) {
  Vec2d lo = Vec2d::Constant(1e300), hi = Vec2d::Constant(-1e300);
  for (FaceId f : faces) {
    for (CornerId c = 3 * f; c < 3 * f + 3; ++c) lo = lo.cwiseMin(uv[c]), hi = hi.cwiseMax(uv[c]);
  }
  return (hi - lo).maxCoeff();
}

PipelineOptions smallRun(ParamSolver solver) {
  PipelineOptions options;
  options.solver.solver = solver;
  options.solver.gridResolution = 32;
  options.spacing.cells = 40;
  return options;
}

/// A double cone of 2 n long faces: two poles of valence n on a rim of n vertices, a sharp crease.
TriangleMesh doubleCone(std::uint32_t n) {
  TriangleMesh mesh;
  for (std::uint32_t i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    mesh.positions.push_back(Vec3f(float(std::cos(t)), float(std::sin(t)), 0.f));
  }
  mesh.positions.push_back(Vec3f(0.f, 0.f, 1.f));
  mesh.positions.push_back(Vec3f(0.f, 0.f, -1.f));
  for (std::uint32_t i = 0; i < n; ++i) {
    mesh.triangles.push_back({n, i, (i + 1) % n});
    mesh.triangles.push_back({n + 1, (i + 1) % n, i});
  }
  return mesh;
}

// The direct field, held along the rim (with the hat solver), turns a full turn around each pole
// (the many thin faces make that cheap): those cones (angle 0) are split, and the map neither
// collapses nor flips, with either solver.
TEST(ValidMeshes, PolesOfHighValenceGetNoConeOfAFullTurn) {
  for (ParamSolver solver : {ParamSolver::Hat, ParamSolver::VoxLoc}) {
    const std::string what = paramSolverName(solver);
    PipelineOptions options;
    options.solver.solver = solver;
    options.solver.gridResolution = 32;
    options.features.autoFeatureAngle = true;  // as param: the rim is a CAD-like crease
    const PipelineResult r = parameterize(doubleCone(1000), options);
    if (solver == ParamSolver::Hat) {  // the aligned field (hat only holds the creases)
      EXPECT_TRUE(r.featureAngleAuto) << what;
      EXPECT_GT(r.merged.splitCones, 0u) << what;
    }
    EXPECT_EQ(std::accumulate(r.coneIndex4.begin(), r.coneIndex4.end(), 0), 8) << what;  // 4 chi
    for (std::int32_t k : r.coneIndex4) EXPECT_LT(k, kFullTurnIndex4) << what;
    EXPECT_TRUE(r.isSeamless()) << what;
    EXPECT_EQ(r.mapQuality.collapsed, 0u) << what;
    EXPECT_EQ(r.mapQuality.flipped, 0u) << what;
  }
}

TEST(ValidMeshes, EveryComponentIsReportedWithHowItWasMapped) {
  const TriangleMesh input = sphereAndIslands(30, 20, false);
  const std::uint32_t sphereFaces = testing::icosphereMesh(3).numFaces();
  for (ParamSolver solver : {ParamSolver::Hat, ParamSolver::VoxLoc}) {
    const std::string what = paramSolverName(solver);
    const PipelineResult r = parameterize(TriangleMesh(input), smallRun(solver));
    const ComponentSummary& s = r.components;
    const auto faces = facesById(r.topology);
    ASSERT_EQ(s.count, 51u) << what;
    ASSERT_EQ(s.listed.size(), 51u) << what;
    EXPECT_EQ(s.unlisted, 0u) << what;
    EXPECT_EQ(s.mapped[0] + s.mapped[1] + s.mapped[2] + s.mapped[3], s.count) << what;
    EXPECT_EQ(s.listed[0].id, 0u) << what << ": the sphere comes first in the input and is the largest";
    EXPECT_EQ(s.listed[0].faces, sphereFaces) << what;
    EXPECT_EQ(s.listed[0].eulerCharacteristic, 2) << what;
    EXPECT_EQ(s.listed[0].mapping, ComponentMapping::Solved) << what;
    std::vector<std::uint8_t> seen(s.count, 0);
    std::uint64_t cones = 0, flipped = 0, facesSum = 0;
    double area = 0.0;
    for (std::size_t k = 0; k < s.listed.size(); ++k) {
      const ComponentFigures& c = s.listed[k];
      ASSERT_LT(c.id, s.count) << what;
      EXPECT_FALSE(seen[c.id]++) << what << ": id " << c.id << " twice";
      if (k) EXPECT_GE(s.listed[k - 1].faces, c.faces) << what << ": largest first";
      EXPECT_EQ(c.faces, faces[c.id].size()) << what << " id " << c.id;
      const double extent = uvExtent(r.mesh.cornerUV, faces[c.id]);
      EXPECT_EQ(c.mapping == ComponentMapping::Point, extent <= kCoincidentConeDistance)
          << what << " id " << c.id << " extent " << extent;
      EXPECT_NE(c.mapping, ComponentMapping::Unsolved) << what;
      if (c.faces == 4) EXPECT_EQ(c.eulerCharacteristic, 2) << what << ": a tetrahedron";
      if (c.faces == 1) EXPECT_EQ(c.boundaryLoops, 1u) << what << ": a loose triangle";
      cones += c.cones, flipped += c.flippedFaces, facesSum += c.faces, area += c.area;
    }
    EXPECT_EQ(cones, r.cones.size()) << what;
    EXPECT_EQ(flipped, r.mapQuality.flipped) << what;
    EXPECT_EQ(facesSum, r.mesh.numFaces()) << what;
    double meshArea = 0.0;
    for (FaceId f = 0; f < r.mesh.numFaces(); ++f) meshArea += faceArea(r.mesh, f);
    EXPECT_NEAR(area, meshArea, 1e-9 * meshArea) << what;
    if (solver == ParamSolver::Hat) {
      // Every vertex of a tetrahedron is a cone: anchored, or on one point when all four cones
      // round to the same lattice point.
      EXPECT_EQ(s.mapped[int(ComponentMapping::Anchored)] + s.mapped[int(ComponentMapping::Point)], 30u) << what;
    }
  }
}

TEST(ValidMeshes, TheReportListsTheLargestComponentsAndSumsTheRest) {
  PipelineOptions options = smallRun(ParamSolver::Hat);
  options.listComponents = 5;
  const PipelineResult r = parameterize(sphereAndIslands(100, 100, false), options);
  ASSERT_EQ(r.components.count, 201u);
  ASSERT_EQ(r.components.listed.size(), 5u);
  EXPECT_EQ(r.components.unlisted, 196u);
  std::uint64_t listedFaces = 0;
  for (const ComponentFigures& c : r.components.listed) listedFaces += c.faces;
  EXPECT_EQ(listedFaces + r.components.unlistedFaces, r.mesh.numFaces());
  ParamReportContext context;
  const JsonValue report = parseJson(paramReportJson(r, context));
  const JsonValue& list = report["componentList"];
  EXPECT_EQ(list["count"].number, 201);
  EXPECT_EQ(list["components"].items.size(), 5u);
  EXPECT_EQ(list["unlisted"].number, 196);
  EXPECT_EQ(list["unlistedFaces"].number, double(r.components.unlistedFaces));
  EXPECT_NE(list.textAt("note").find("5 largest"), std::string::npos);
  EXPECT_EQ(list["components"].items[0].textAt("mapping"), "solved");
}

TEST(ValidMeshes, AnUnsolvableComponentIsReportedByIdAndWrittenUnmappedOrDropped) {
  const TriangleMesh input = sphereAndIslands(10, 10, true);
  const std::uint32_t patchFaces = testing::gridMesh(6, 6, 0.1).numFaces();
  PipelineOptions options = smallRun(ParamSolver::Hat);
  // The patch's 49 hat unknowns; a tetrahedron or a triangle has fewer, the sphere more.
  options.failsToFactor = [](std::uint32_t unknowns) { return unknowns >= 20 && unknowns <= 100; };
  // The final map handed to withFinalMap (param writes it there) is the one returned: beside
  // the figures when nothing is dropped after them, after them when the patch is dropped.
  int calls = 0;
  TriangleMesh handed;
  options.withFinalMap = [&](const TriangleMesh& map) { handed = map, ++calls; };
  const auto expectHanded = [&](const PipelineResult& r, bool beside) {
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(r.finalMapBesideMetrics, beside);
    EXPECT_EQ(handed.triangles, r.mesh.triangles);
    EXPECT_EQ(handed.positions, r.mesh.positions);
    ASSERT_EQ(handed.cornerUV.size(), r.mesh.cornerUV.size());
    for (CornerId c = 0; c < r.mesh.cornerUV.size(); ++c) ASSERT_EQ(handed.cornerUV[c], r.mesh.cornerUV[c]) << c;
    calls = 0;
  };
  const bool severalThreads = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
  const PipelineResult kept = parameterize(TriangleMesh(input), options);
  expectHanded(kept, severalThreads);
  {
    const tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
    expectHanded(parameterize(TriangleMesh(input), options), false);
  }
  const auto faces = facesById(kept.topology);
  ASSERT_EQ(kept.components.unsolvedIds.size(), 1u);
  const std::uint32_t patch = kept.components.unsolvedIds[0];
  EXPECT_EQ(patch, 21u) << "the patch comes last in the input";
  EXPECT_EQ(faces[patch].size(), patchFaces);
  for (FaceId f : faces[patch]) {
    for (CornerId c = 3 * f; c < 3 * f + 3; ++c) EXPECT_EQ(kept.mesh.cornerUV[c], Vec2d::Zero());
  }
  EXPECT_EQ(kept.components.mapped[int(ComponentMapping::Unsolved)], 1u);
  EXPECT_TRUE(kept.components.droppedIds.empty());
  EXPECT_TRUE(kept.isSeamless());
  EXPECT_EQ(kept.mesh.numFaces(), input.numFaces());

  options.dropUnsolved = true;
  const PipelineResult dropped = parameterize(TriangleMesh(input), options);
  expectHanded(dropped, false);
  EXPECT_EQ(dropped.components.droppedIds, kept.components.unsolvedIds);
  EXPECT_EQ(dropped.components.droppedFaces, patchFaces);
  EXPECT_EQ(dropped.mesh.numFaces(), input.numFaces() - patchFaces);
  EXPECT_EQ(dropped.mesh.numVertices(), kept.mesh.numVertices() - testing::gridMesh(6, 6, 0.1).numVertices());
  EXPECT_NO_THROW(dropped.topology.validate());
  EXPECT_EQ(computeComponents(dropped.topology).components.size(), kept.components.count - 1);
  EXPECT_EQ(dropped.cones.size(), kept.cones.size()) << "the patch has no cone";
  for (VertexId v : dropped.cones) EXPECT_LT(v, dropped.mesh.numVertices());
  EXPECT_TRUE(measureSeamsFromUV(dropped.mesh, dropped.topology, dropped.mesh.cornerUV).isSeamless());
  ParamReportContext context;
  const JsonValue report = parseJson(paramReportJson(dropped, context));
  ASSERT_EQ(report["componentList"]["droppedIds"].items.size(), 1u);
  EXPECT_EQ(report["componentList"]["droppedIds"].items[0].number, patch);
  EXPECT_EQ(report.numberAt("componentList.mapped.unsolved"), 1);
  EXPECT_EQ(report.numberAt("faces"), dropped.mesh.numFaces());
}

TEST(ValidMeshes, ParamListsAsManyComponentsAsAskedFor) {
  testing::TempDir dir;
  const std::string input = dir.path("islands.obj"), output = dir.path("out.ply"), report = dir.path("r.json");
  writeMesh(input, sphereAndIslands(10, 10, false));
  std::string log;
  ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --cells 40 --quiet --report-components 3 --report '" +
                                report + "'", &log), 0) << log;
  const JsonValue r = parseJson(testing::readFile(report));
  EXPECT_EQ(r.numberAt("componentList.count"), 21);
  EXPECT_EQ(r["componentList"]["components"].items.size(), 3u);
  EXPECT_EQ(r.numberAt("componentList.unlisted"), 18);
  EXPECT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --report-components -1", &log), 2) << log;
}

TEST(ValidMeshes, RemoveFacesKeepsOrderAndTheMap) {
  TriangleMesh mesh = testing::concatMeshes({testing::gridMesh(2, 2, 1.0), testing::gridMesh(1, 1, 1.0)});
  std::vector<Vec2d> uv;
  for (CornerId c = 0; c < 3 * mesh.numFaces(); ++c) uv.push_back(Vec2d(c, -double(c)));
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  std::vector<VertexId> vertexMap;
  const TriangleMesh out = removeFaces(mesh, {1, 2, 3}, &vertexMap);  // all but face 0 of the 2x2 grid
  ASSERT_EQ(out.numFaces(), mesh.numFaces() - 3);
  std::uint32_t kept = 0;
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    if (vertexMap[v] == kInvalidId) continue;
    EXPECT_EQ(vertexMap[v], kept++) << "vertex order kept";
    EXPECT_EQ(out.positions[vertexMap[v]], mesh.positions[v]);
  }
  EXPECT_EQ(kept, out.numVertices());
  std::vector<FaceId> from{0};
  for (FaceId f = 4; f < mesh.numFaces(); ++f) from.push_back(f);
  for (FaceId f = 0; f < out.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(out.triangles[f][k], vertexMap[mesh.triangles[from[f]][k]]);
      EXPECT_EQ(out.cornerUV[3 * f + k], mesh.cornerUV[3 * from[f] + k]);
    }
  }
}

// --- param's verdict is check's verdict on the written file ---------------------------------------

TriangleMesh withFins(int fins) {
  TriangleMesh mesh = testing::icosphereMesh(3);
  const Triangle t = mesh.triangles[0];
  for (int k = 0; k < fins; ++k) {
    const auto apex = static_cast<VertexId>(mesh.positions.size());
    mesh.positions.push_back(mesh.positions[t[k % 2]] * (1.3f + 0.2f * k));
    mesh.triangles.push_back(k % 2 ? Triangle{t[1], t[0], apex} : Triangle{t[0], t[1], apex});
  }
  return mesh;
}

TriangleMesh bowtie() {
  const TriangleMesh a = testing::icosphereMesh(2);
  TriangleMesh b = a;
  const Vec3f touch = a.positions[0];
  for (Vec3f& p : b.positions) p = 2.0f * touch - p;
  for (Triangle& t : b.triangles) std::swap(t[1], t[2]);
  TriangleMesh mesh = testing::concatMeshes({a, b});
  const auto offset = static_cast<VertexId>(a.numVertices());
  for (Triangle& t : mesh.triangles) {
    for (VertexId& v : t) v = v == offset ? 0 : v;
  }
  return mesh;
}

TriangleMesh moebius(int n, int w) {
  TriangleMesh mesh;
  for (int i = 0; i < n; ++i) {
    const double th = 2.0 * M_PI * i / n;
    for (int j = 0; j <= w; ++j) {
      const double s = (double(j) / w - 0.5) * 0.6, r = 1.0 + s * std::cos(th / 2);
      mesh.positions.push_back(Vec3f(float(r * std::cos(th)), float(r * std::sin(th)), float(s * std::sin(th / 2))));
    }
  }
  auto id = [&](int i, int j) { return static_cast<VertexId>(i * (w + 1) + j); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < w; ++j) {
      const bool wrap = i + 1 == n;
      const VertexId a0 = id(i, j), a1 = id(i, j + 1);
      const VertexId b0 = wrap ? id(0, w - j) : id(i + 1, j), b1 = wrap ? id(0, w - j - 1) : id(i + 1, j + 1);
      mesh.triangles.push_back({a0, b0, a1});
      mesh.triangles.push_back({a1, b0, b1});
    }
  }
  return mesh;
}

/// A grid cut in two halves along x = 2 (equal positions, distinct vertices: an unwelded seam),
/// with a fin (a non-manifold edge, split by cleaning).
TriangleMesh unweldedSeamWithFin() {
  TriangleMesh mesh = testing::gridMesh(4, 4, 1.0);
  for (Triangle& t : mesh.triangles) {
    const double cx = (mesh.positions[t[0]].x() + mesh.positions[t[1]].x() + mesh.positions[t[2]].x()) / 3.0;
    if (cx < 2.0) continue;
    for (VertexId& v : t) {
      if (mesh.positions[v].x() != 2.0f) continue;
      mesh.positions.push_back(mesh.positions[v]);
      v = static_cast<VertexId>(mesh.positions.size() - 1);
    }
  }
  mesh.positions.push_back(Vec3f(0.5f, 0.5f, 1.0f));
  mesh.triangles.push_back({mesh.triangles[0][0], mesh.triangles[0][1], static_cast<VertexId>(mesh.positions.size() - 1)});
  return mesh;
}

/// Every kind of valid but awkward mesh a scan contains, small enough to solve many times.
std::vector<std::pair<std::string, TriangleMesh>> awkwardMeshes() {
  TriangleMesh duplicates = testing::icosphereMesh(3);
  for (FaceId f = 0; f < 10; ++f) duplicates.triangles.push_back(duplicates.triangles[f]);
  for (FaceId f = 10; f < 15; ++f) {
    const Triangle t = duplicates.triangles[f];
    duplicates.triangles.push_back({t[0], t[2], t[1]});
  }
  TriangleMesh flipped = testing::icosphereMesh(3);
  for (FaceId f = 0; f < flipped.numFaces(); f += 7) std::swap(flipped.triangles[f][1], flipped.triangles[f][2]);
  TriangleMesh spike = testing::icosphereMesh(3);
  spike.positions[7] *= 50.0f;
  // A sphere whose faces on one side of x = 0 get their own copies of the vertices they share
  // with the other side: an unwelded seam along a closed curve.
  TriangleMesh unwelded = testing::icosphereMesh(2);
  {
    std::vector<VertexId> copy(unwelded.numVertices(), kInvalidId);
    for (Triangle& t : unwelded.triangles) {
      if (unwelded.positions[t[0]].x() + unwelded.positions[t[1]].x() + unwelded.positions[t[2]].x() < 0.0f) continue;
      for (VertexId& v : t) {
        if (copy[v] == kInvalidId) {
          copy[v] = unwelded.numVertices();
          unwelded.positions.push_back(unwelded.positions[v]);
        }
        v = copy[v];
      }
    }
  }
  return {{"bowtie", bowtie()},       {"fin3", withFins(1)},    {"fin4", withFins(2)},
          {"duplicates", duplicates}, {"moebius", moebius(40, 4)}, {"flipped", flipped},
          {"200 tiny", sphereAndIslands(100, 99, false)}, {"spike", spike},
          {"unwelded", unwelded},     {"unwelded grid with fin", unweldedSeamWithFin()}};
}

/// check's verdict on a file (tools/cmd_check.cpp): read with UVs, clean, seams from the UVs;
/// and the vertices it finds wound.
bool checkFindsSeamless(const std::string& path, std::size_t* wound = nullptr) {
  ReadOptions options;
  options.readUV = true;
  CleanResult clean = cleanMesh(readMesh(path, options));
  if (wound) *wound = woundVertices(clean.topology, clean.mesh.cornerUV).size();
  return measureSeamsFromUV(clean.mesh, clean.topology, clean.mesh.cornerUV).isSeamless();
}

TEST(ValidMeshes, ParamVerdictIsCheckVerdictForEverySolverAndFormat) {
  struct Format {
    const char* name;
    const char* ext;
    bool binary;
  };
  const Format formats[] = {{"obj", ".obj", true}, {"ply binary", ".ply", true}, {"ply ascii", ".ply", false}, {"drc", ".drc", true}};
  testing::TempDir dir;
  for (const auto& [name, mesh] : awkwardMeshes()) {
    for (ParamSolver solver : {ParamSolver::Hat, ParamSolver::Vox, ParamSolver::VoxLoc}) {
      const PipelineResult r = parameterize(TriangleMesh(mesh), smallRun(solver));
      EXPECT_TRUE(r.isSeamless()) << name << " " << paramSolverName(solver) << ": residual " << r.seamQuality.maxResidual;
      EXPECT_EQ(r.mesh.numVertices(), r.cleanReport.outputVertices) << name;
      for (const Format& format : formats) {
        const std::string what = name + " " + paramSolverName(solver) + " " + format.name;
        const std::string path = dir.path("out" + std::string(format.ext));
        WriteOptions options;
        options.binary = format.binary;
        writeMesh(path, r.mesh, options);
        std::size_t wound = 0;
        EXPECT_EQ(checkFindsSeamless(path, &wound), r.isSeamless()) << what;
        EXPECT_TRUE(r.mapQuality.woundCounted) << what;
        EXPECT_EQ(wound, r.mapQuality.wound) << what;
        if (format.ext != std::string(".drc")) {
          // The non-manifold splits are in the file: one vertex per written vertex.
          EXPECT_EQ(readMesh(path).numVertices(), r.mesh.numVertices()) << what;
        }
      }
    }
  }
}

TEST(ValidMeshes, ParamVerdictIsCheckVerdictOnTheWrittenFile) {
  // The commands themselves, once per output format (the loop above covers solvers and meshes).
  testing::TempDir dir;
  const std::string input = dir.path("bowtie_fin.obj");
  writeMesh(input, testing::concatMeshes({bowtie(), withFins(2)}));
  for (const char* ext : {".obj", ".ply", ".drc"}) {
    const std::string output = dir.path(std::string("out") + ext);
    std::string log;
    ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --cells 40 --quiet", &log), 0) << ext << "\n" << log;
    const bool paramSeamless = log.find(": seamless") != std::string::npos;
    EXPECT_TRUE(paramSeamless) << ext << "\n" << log;
    EXPECT_EQ(testing::runSeamvox("check '" + output + "'", &log) == 0, paramSeamless) << ext << "\n" << log;
  }
}

TEST(ValidMeshes, InfoAndTheReportCountTheVerticesNonManifoldSplitsDuplicate) {
  testing::TempDir dir;
  const TriangleMesh mesh = withFins(2);  // every vertex used, nothing to weld or remove
  const std::string input = dir.path("fins.obj"), output = dir.path("out.obj"), report = dir.path("r.json");
  writeMesh(input, mesh);
  std::string log;
  ASSERT_EQ(testing::runSeamvox("info --quiet --json '" + input + "'", &log), 0) << log;
  const JsonValue info = parseJson(log);
  const double split = info.numberAt("clean.nonManifoldVertices");
  EXPECT_GT(split, 0);
  ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --solver hat --cells 40 --quiet --report '" +
                                report + "'", &log), 0) << log;
  const JsonValue param = parseJson(testing::readFile(report));
  EXPECT_EQ(param.numberAt("nonManifoldVerticesSplit"), split);
  EXPECT_EQ(readMesh(output).numVertices(), mesh.numVertices() + split);
  EXPECT_EQ(param.numberAt("vertices"), mesh.numVertices() + split);
}

TEST(ValidMeshes, InfoAndParamNameAnUnweldedCrackAndWeldingJoinsIt) {
  testing::TempDir dir;
  const std::string input = dir.path("seam.obj"), output = dir.path("out.obj"), report = dir.path("r.json");
  writeMesh(input, unweldedSeamWithFin());
  std::string log;
  ASSERT_EQ(testing::runSeamvox("info --quiet --json '" + input + "'", &log), 0) << log;
  const double crack = parseJson(log).numberAt("clean.unweldedBoundaryVertices");
  EXPECT_GT(crack, 0);
  ASSERT_EQ(testing::runSeamvox("info --quiet --weld --json '" + input + "'", &log), 0) << log;
  EXPECT_EQ(parseJson(log).numberAt("clean.unweldedBoundaryVertices"), 0);
  ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --solver hat --cells 8 --quiet --report '" +
                                report + "'", &log), 0) << log;
  EXPECT_NE(log.find("lie exactly on another boundary vertex"), std::string::npos) << log;
  EXPECT_EQ(parseJson(testing::readFile(report)).numberAt("unweldedBoundaryVertices"), crack);
  ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --weld --solver hat --cells 8 --quiet", &log), 0)
      << log;
  EXPECT_EQ(log.find("lie exactly on another boundary vertex"), std::string::npos) << log;
}

TEST(ValidMeshes, DracoDecodesToTheWrittenConnectivity) {
  const TriangleMesh mesh = unweldedSeamWithFin();
  ASSERT_GT(mesh.numVertices(), testing::gridMesh(4, 4, 1.0).numVertices());
  testing::TempDir dir;
  const std::string input = dir.path("seam.obj");
  writeMesh(input, mesh);
  for (const char* ext : {".drc", ".obj"}) {
    const std::string output = dir.path(std::string("seam_uv") + ext);
    std::string log;
    ASSERT_EQ(testing::runSeamvox("param '" + input + "' -o '" + output + "' --solver hat --cells 10 --quiet", &log), 0) << log;
    EXPECT_NE(log.find(": seamless"), std::string::npos) << log;
    EXPECT_EQ(testing::runSeamvox("check '" + output + "'", &log), 0) << ext << "\n" << log;
    ReadOptions options;
    options.readUV = true;
    CleanResult written = cleanMesh(readMesh(output, options));
    CleanResult solved = cleanMesh(TriangleMesh(mesh));
    EXPECT_EQ(written.mesh.numVertices(), solved.mesh.numVertices()) << ext;
    EXPECT_EQ(written.mesh.numFaces(), solved.mesh.numFaces()) << ext;
    EXPECT_EQ(computeComponents(written.topology).components.size(),
              computeComponents(solved.topology).components.size()) << ext;
    std::uint32_t boundaryWritten = 0, boundarySolved = 0;
    for (CornerId c = 0; c < written.topology.numCorners(); ++c) boundaryWritten += written.topology.isBoundaryEdge(c);
    for (CornerId c = 0; c < solved.topology.numCorners(); ++c) boundarySolved += solved.topology.isBoundaryEdge(c);
    EXPECT_EQ(boundaryWritten, boundarySolved) << ext;
    EXPECT_EQ(written.report.nonManifoldEdges, 0u) << ext << ": the split is in the file";
  }
}

}  // namespace
}  // namespace seamvox
