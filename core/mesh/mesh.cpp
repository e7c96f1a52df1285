#include "core/mesh/mesh.h"

namespace seamvox {

BoundingBox computeBoundingBox(const std::vector<Vec3f>& positions) {
  BoundingBox box;
  for (const Vec3f& p : positions) {
    const Vec3d q = p.cast<double>();
    box.min = box.min.cwiseMin(q);
    box.max = box.max.cwiseMax(q);
  }
  return box;
}

Vec3d faceNormal(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d a = mesh.position(t[0]), b = mesh.position(t[1]), c = mesh.position(t[2]);
  const Vec3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
}

double faceArea(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  const Vec3d a = mesh.position(t[0]), b = mesh.position(t[1]), c = mesh.position(t[2]);
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace seamvox
