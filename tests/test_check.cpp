// The check verdict (core/quality/check, io/check_report): a pipeline's map passes, a moved corner
// fails, the report says what the result says, and bad inputs are InputErrors.
#include <gtest/gtest.h>

#include <cmath>

#include "core/pipeline/parameterize.h"
#include "core/quality/check.h"
#include "core/system/errors.h"
#include "io/check_report.h"
#include "io/json_reader.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

PipelineResult mappedSphere() {
  PipelineOptions options;
  options.solver.solver = ParamSolver::Hat;
  return parameterize(testing::generatedMesh(MeshKind::Sphere, 2000), options);
}

TEST(Check, APipelineMapIsSeamlessAndAMovedCornerIsNot) {
  const PipelineResult r = mappedSphere();
  CheckOptions options;
  options.edgeLength = r.edgeLength;
  const CheckResult good = checkParameterization(r.mesh, options);
  EXPECT_TRUE(good.isSeamless);
  EXPECT_GT(good.seams.seamEdges, 0u);
  EXPECT_EQ(good.map.flipped, r.mapQuality.flipped);
  EXPECT_EQ(good.faces, r.mesh.numFaces());
  EXPECT_FALSE(good.hasField);

  TriangleMesh moved = r.mesh;
  moved.cornerUV.set(0, moved.cornerUV[0] + Vec2d(0.25, 0.0));
  const CheckResult bad = checkParameterization(std::move(moved), options);
  EXPECT_FALSE(bad.isSeamless);
  EXPECT_GT(std::max(bad.seams.maxResidual, bad.seams.maxIntegerDistance), 0.1);

  const JsonValue j = parseJson(checkReportJson("sphere.obj", bad));
  EXPECT_EQ(j.textAt("mesh"), "sphere.obj");
  EXPECT_EQ(j.numberAt("seamless"), 0.0);
  EXPECT_EQ(j.numberAt("faces"), bad.faces);
  EXPECT_EQ(j.numberAt("maxSeamResidual"), bad.seams.maxResidual);
  EXPECT_TRUE(j["relativeGradientError"].type == JsonValue::Type::Null);
}

TEST(Check, AFieldGivesTheGradientErrorAndMustMatchTheFaces) {
  const PipelineResult r = mappedSphere();
  CheckOptions options;
  options.fieldPerInputFace.assign(r.mesh.numFaces(), Vec3d(1, 0, 0));
  const CheckResult withField = checkParameterization(r.mesh, options);
  EXPECT_TRUE(withField.hasField);
  EXPECT_TRUE(std::isfinite(withField.map.relativeGradientError));
  EXPECT_FALSE(parseJson(checkReportJson("m", withField))["relativeGradientError"].type == JsonValue::Type::Null);
  options.fieldPerInputFace.pop_back();
  EXPECT_THROW(checkParameterization(r.mesh, options), InputError);
}

TEST(Check, AMeshWithoutUVIsAnInputError) {
  TriangleMesh mesh = testing::generatedMesh(MeshKind::Sphere, 500);
  try {
    checkParameterization(std::move(mesh));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no per-corner texture coordinates"), std::string::npos);
  }
}

}  // namespace
}  // namespace seamvox
