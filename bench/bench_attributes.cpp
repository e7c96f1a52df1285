// Writes a generated scan twice as binary PLY: plain, and with per-vertex colors (uchar red green
// blue, a function of the position) and area-weighted vertex normals (float nx ny nz), so the cost
// of carrying vertex properties through `seamvox convert`, `param` or `subdivide` can be timed
// against the same mesh without them (bench/RESULTS.md, vertex properties).
//   bench_attributes OUT_PREFIX [FACES=2000000]  ->  OUT_PREFIX_plain.ply, OUT_PREFIX_colored.ply
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/synth/generate.h"
#include "io/mesh_io.h"

int main(int argc, char** argv) {
  using namespace seamvox;
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_attributes OUT_PREFIX [FACES]\n");
    return 2;
  }
  const std::string prefix = argv[1];
  GenerateOptions options;
  options.kind = MeshKind::Scan;
  options.faces = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 2000000;
  TriangleMesh mesh = generateMesh(options).mesh;
  writeMesh(prefix + "_plain.ply", mesh);

  const std::uint32_t nv = mesh.numVertices();
  const BoundingBox box = computeBoundingBox(mesh.positions);
  std::vector<Vec3d> normals(nv, Vec3d::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3d a = mesh.position(t[0]), b = mesh.position(t[1]), c = mesh.position(t[2]);
    const Vec3d n = (b - a).cross(c - a);  // length: twice the area
    for (const VertexId v : t) normals[v] += n;
  }
  const char* colors[] = {"red", "green", "blue"};
  const char* axes[] = {"nx", "ny", "nz"};
  for (int k = 0; k < 3; ++k) {
    VertexProperty& color = mesh.attributes.add(colors[k], ScalarType::UInt8, nv);
    const double extent = std::max(box.extent()[k], 1e-30);
    for (VertexId v = 0; v < nv; ++v) color.setValue(v, 255.0 * (mesh.position(v)[k] - box.min[k]) / extent);
  }
  for (int k = 0; k < 3; ++k) {
    VertexProperty& normal = mesh.attributes.add(axes[k], ScalarType::Float32, nv);
    for (VertexId v = 0; v < nv; ++v) {
      const double length = normals[v].norm();
      normal.setValue(v, length > 0.0 ? normals[v][k] / length : 0.0);
    }
  }
  writeMesh(prefix + "_colored.ply", mesh);
  std::printf("%s_plain.ply, %s_colored.ply: %u faces, %u vertices, properties %s\n", prefix.c_str(),
              prefix.c_str(), mesh.numFaces(), nv, mesh.attributes.describe().c_str());
  return 0;
}
