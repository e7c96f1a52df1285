// Quad extraction (core/quads): the quad mesh of a seamless map is an oriented 2-manifold with
// the map's Euler characteristic and boundary loops per component, valence 4 away from cones and
// 4 - k on a cone of index k, about one face per unit of parameter area; damaged maps still
// extract or say what failed; malformed maps are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/pipeline/parameterize.h"
#include "core/quads/extract.h"
#include "core/quads/validate.h"
#include "core/system/errors.h"
#include "test_meshes.h"
#include "testing.h"

namespace seamvox {
namespace {

struct Extracted {
  PipelineResult map;
  QuadResult quads;
  QuadValidation check;
};

PipelineResult mapOf(TriangleMesh mesh, double cells) {
  PipelineOptions options;
  options.spacing.cells = cells;
  return parameterize(std::move(mesh), options);
}

Extracted extract(PipelineResult map, std::int64_t scale = 1) {
  Extracted e{std::move(map), {}, {}};
  QuadOptions options;
  options.scale = scale;
  e.quads = extractQuads(e.map.mesh, e.map.topology, options);
  e.check = validateQuads(e.quads, computeComponents(e.map.topology));
  return e;
}

// Total |parameter area| of the map (grid units squared).
double parameterArea(const TriangleMesh& mesh) {
  double area = 0.0;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const Vec2d a = mesh.cornerUV[3 * f + 1] - mesh.cornerUV[3 * f], b = mesh.cornerUV[3 * f + 2] - mesh.cornerUV[3 * f];
    area += 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
  }
  return area;
}

void print(const Extracted& e) {
  const QuadStats& s = e.quads.stats;
  const QuadValidation& v = e.check;
  std::printf("map %u faces, %u cones; grid %llu, boundary %llu, traced %llu, untraced %llu, unpaired %llu, "
              "open faces %llu, flipped %llu, open fans %llu, holes %llu, islands %llu, snap %.2g\n",
              e.map.mesh.numFaces(), e.quads.cones, (unsigned long long)s.gridVertices,
              (unsigned long long)s.boundaryVertices, (unsigned long long)s.tracedEdges,
              (unsigned long long)s.untracedEdges, (unsigned long long)s.unpairedEdges,
              (unsigned long long)s.openFaces, (unsigned long long)s.flippedFaces,
              (unsigned long long)s.openVertexFans, (unsigned long long)s.holesWithoutVertex,
              (unsigned long long)s.islands, s.maxSnap);
  std::printf("quads V %llu E %llu F %llu, quads %llu tri %llu pent %llu other %llu (%.3f), nonmanifold %llu/%llu, "
              "degenerate %llu, irregular %llu, cones on vertices %llu wrong %llu, interior non-quads %llu, "
              "components differing %llu\n",
              (unsigned long long)v.vertices, (unsigned long long)v.edges, (unsigned long long)v.faces,
              (unsigned long long)v.quads, (unsigned long long)v.triangles, (unsigned long long)v.pentagons,
              (unsigned long long)v.otherFaces, v.quadFraction, (unsigned long long)v.nonManifoldEdges,
              (unsigned long long)v.nonManifoldVertices, (unsigned long long)v.degenerateFaces,
              (unsigned long long)v.irregularVertices, (unsigned long long)v.conesOnVertices,
              (unsigned long long)v.conesWithWrongValence, (unsigned long long)v.interiorNonQuads,
              (unsigned long long)v.componentsDiffering);
  for (const QuadComponentCheck& c : v.components) {
    if (!c.matches()) {
      std::printf("  component %u: chi %lld (map %lld), loops %u (map %u)\n", c.component,
                  (long long)c.eulerCharacteristic, (long long)c.mapEulerCharacteristic, c.boundaryLoops,
                  c.mapBoundaryLoops);
    }
  }
}

TEST(Quads, TorusClosedAllQuads) {
  const Extracted e = extract(mapOf(testing::generatedMesh(MeshKind::Torus, 20000), 40));
  print(e);
  EXPECT_TRUE(e.check.isValid());
}

TEST(Quads, SphereCones) {
  const Extracted e = extract(mapOf(testing::generatedMesh(MeshKind::Sphere, 20000), 40));
  print(e);
  EXPECT_TRUE(e.check.isValid());
}

}  // namespace
}  // namespace seamvox
