#include "core/mesh/mesh.h"

#include <algorithm>
#include <cmath>

namespace seamvox {

Vec3d originFor(const Vec3d& p) {
  if (!p.allFinite() || !(p.cwiseAbs().maxCoeff() > kOriginBeyond)) return Vec3d::Zero();
  return p.array().round().matrix();
}

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
  return faceNormal(mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2]));
}

Vec3d faceNormal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0.0 ? Vec3d(n / len) : Vec3d::Zero();
}

Vec3d gluingNormal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  constexpr double kSliver = 1e-4;
  const Vec3d n = (b - a).cross(c - a);
  const double length = n.norm();
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  if (!(length > kSliver * longest * longest) || !std::isfinite(length)) return Vec3d::Zero();
  return n / length;
}

double gluingAlignment(const Vec3d& n0, const Vec3d& n1) {
  if (n0.isZero() || n1.isZero()) return -3.0;
  const double alignment = n0.dot(n1);
  return std::isfinite(alignment) ? alignment : -2.0;
}

double faceArea(const TriangleMesh& mesh, FaceId f) {
  const Triangle& t = mesh.triangles[f];
  return faceArea(mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2]));
}

double faceArea(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return 0.5 * (b - a).cross(c - a).norm(); }

}  // namespace seamvox
