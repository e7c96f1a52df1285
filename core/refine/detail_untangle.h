#pragma once
/// The untangling energy of the foldover repair's joint patches (untangle.cpp; Garanzha et al.
/// 2021) per face, with its gradient and Hessian in one corner's value: declared here for tests.
#include <vector>

#include <Eigen/Core>

#include "core/mesh/mesh.h"

namespace seamvox::detail {

/// A face's 3D shape in its own plane, in grid units (edges / h), as the inverse of its edge
/// matrix: J = (uv edges) * inverse is the map's Jacobian, a rotation for an ideal map.
struct ReferenceShape {
  Eigen::Matrix2d inverse;
  double area = 0.0;
};
ReferenceShape referenceShape(const TriangleMesh& mesh, FaceId f, double h);

/// Untangling energy of one face with corner values q: conformal term |J|^2 / chi plus area term
/// (det^2 + 1) / chi, times the reference area, chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2.
double untanglingEnergy(const ReferenceShape& shape, const Vec2d& q0, const Vec2d& q1, const Vec2d& q2, double eps);

/// untanglingEnergy and its gradient and Hessian with respect to corner k's value (k = 0, 1, 2).
struct UntanglingTerms {
  double energy = 0.0;
  Vec2d gradient = Vec2d::Zero();
  Eigen::Matrix2d hessian = Eigen::Matrix2d::Zero();
};
UntanglingTerms untanglingTerms(const ReferenceShape& shape, const Vec2d& q0, const Vec2d& q1, const Vec2d& q2, int k,
                                double eps);

/// The point p maximizing min_i (n_i . p + c_i) / w_i over the half-planes n_i . p + c_i >= 0
/// with weight w_i > 0, subject also to those with weight 0 (a bounding box): a 2D linear
/// programme solved by its vertices (the fans are small). Returns that margin (<= 0: the
/// weighted half-planes have no common interior), or -inf when no vertex is feasible; of equal
/// margins, the first vertex in the order of its constraints' indices.
double kernelCentre(const std::vector<Vec2d>& normal, const std::vector<double>& offset,
                    const std::vector<double>& weight, Vec2d& centre);

}  // namespace seamvox::detail
