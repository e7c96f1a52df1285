#pragma once
/// Small meshes built in code for the test suites (closed, boundary, several components).
#include <string>

#include "core/cut/cut.h"
#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/synth/generate.h"

namespace seamvox::testing {

/// Flat n x m grid of unit squares in the z = 0 plane, each split in two triangles (a disk).
TriangleMesh gridMesh(int n, int m, double cell = 1.0);
/// Torus with n segments around the big circle and m around the tube (closed, genus 1).
TriangleMesh torusMesh(int n, int m, double bigRadius = 2.0, double tubeRadius = 0.7);
/// Icosahedron subdivided `levels` times and projected on the unit sphere (closed, genus 0).
TriangleMesh icosphereMesh(int levels);
/// Open cylinder of radius r and height hgt, n segments around and m along (two boundary loops).
TriangleMesh cylinderMesh(int n, int m, double radius = 1.0, double height = 2.0);
/// seamvox's generated mesh of this kind with about this many faces (seed 1).
TriangleMesh generatedMesh(MeshKind kind, std::uint64_t faces);
/// Concatenates meshes into one with several components.
TriangleMesh concatMeshes(const std::vector<TriangleMesh>& parts);
/// torusMesh(n, m) and islands: `specks` flat grids of 2 x 1 or 2 x 2 cells of size `cell` at
/// random places above it (seed; the odd ones tilted, the even ones level), then an icosphere of
/// `ballLevels` levels and radius `ballRadius` below it (cones and seams of its own).
TriangleMesh torusWithIslands(int n, int m, int specks, double cell, int ballLevels, float ballRadius,
                              std::uint32_t seed);
/// The same surface with its vertices and faces in a random order (seeded).
TriangleMesh shuffledMesh(const TriangleMesh& mesh, std::uint32_t seed);
/// The mesh with one face in every `every` removed where none of its vertices touches a removed
/// face: separate one-triangle holes, as a scan's missing triangles.
TriangleMesh withOneTriangleHoles(TriangleMesh mesh, std::uint32_t every);

/// A mesh with its corner table (the table views mesh.triangles, whose buffer moves with it).
struct Surface {
  TriangleMesh mesh;
  Topology topology;
};
/// Corner table of a mesh that is already clean (Topology::build throws otherwise).
Surface makeSurface(TriangleMesh mesh);
/// A surface with a field and the field's cut (cutToDisk).
struct CutSurface {
  Surface s;
  CrossField field;
  CutResult cut;
};
/// randomFieldSeed 0: the smoothest field (few cones); else randomField(seed) (many cones).
CutSurface makeCutSurface(TriangleMesh mesh, std::uint32_t randomFieldSeed = 0);
/// Reads and cleans a mesh file.
Surface loadShared(const std::string& path);
/// A cut made of the boundary only: no seams, no combing (flat meshes, hand-built seams).
CutResult boundaryCut(const Topology& topology);
/// The same direction on every face (stored as float).
CrossField constantField(const TriangleMesh& mesh, const Vec3d& direction = Vec3d::UnitX());
/// Unit tangent directions at pseudo-random angles (a field with many cones); deterministic.
CrossField randomField(const TriangleMesh& mesh, std::uint32_t seed);

/// A Moebius strip of n quads (two triangles each) at `at`.
TriangleMesh moebiusStrip(int n, const Vec3f& at);

/// A flat disk in z = 0: `rings` rings of n vertices (radii 1, 2, ...) around a centre of valence
/// n (vertex 0), each ring turned by half a step against the one inside.
TriangleMesh fanDiskMesh(int n, int rings);
/// Per face, a direction turning turns / 4 times the polar angle of the face's centroid around
/// the origin: on fanDiskMesh with n > 2 |turns|, index4 `turns` at the centre and no other cone.
CrossField turningField(const TriangleMesh& mesh, double turns);
/// A 6K-face scan with fins, bowties, flipped patches, duplicates, a Moebius strip and books of
/// faces on one edge: every kind of damage cleaning repairs.
TriangleMesh damagedMesh(std::uint32_t seed);
/// A plane of unit cells, 2 * outer across, whose centre square of side 2 * inner is cut into
/// cells 1 / dense across (a part tessellated far finer than the rest, as an over-sampled part of
/// a scan). Every vertex moves along z by a uniform amount in [-jitter, jitter] (world units, as a
/// scanner's depth noise; seeded).
TriangleMesh denseSpotPlane(int outer, int inner, int dense, double jitter, std::uint32_t seed);

}  // namespace seamvox::testing
