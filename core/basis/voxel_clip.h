#pragma once
/// Kernels of the volumetric basis (DESIGN section 6): the voxel grid over the padded bounding
/// box, clipping of triangles against voxels, and exact integrals of the trilinear B-splines on
/// the clipped fragments. Everything here works in grid coordinates g = (x - origin) / voxelSize,
/// where voxel (i, j, k) is the cube [i, i+1] x [j, j+1] x [k, k+1].
#include <array>
#include <complex>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"

namespace seamvox {

using VoxelCoord = std::array<std::int32_t, 3>;

/// Cubic voxels, resolution per axis. Points on a grid plane belong to the voxel above it.
struct VoxelGridGeometry {
  Vec3d origin = Vec3d::Zero();  ///< world position of grid corner (0, 0, 0)
  double voxelSize = 1.0;
  std::int32_t resolution = 128;
  Vec3d toGrid(const Vec3d& x) const { return (x - origin) / voxelSize; }
  /// Voxel holding grid point g (floor, clamped to the grid).
  VoxelCoord voxelOf(const Vec3d& g) const;
};

/// Grid of `resolution` (a power of two, 2..1024) voxels per axis whose cube holds the box with
/// at least half a voxel of padding; the origin is deliberately not aligned with the box so that
/// axis-aligned input rarely lies on grid planes. Throws InputError on a bad resolution.
VoxelGridGeometry makeVoxelGrid(const BoundingBox& box, std::int32_t resolution);

/// The three corners of face f in grid coordinates (the one conversion every pass uses, so that
/// clipping is reproducible).
std::array<Vec3d, 3> faceGridCoords(const TriangleMesh& mesh, const VoxelGridGeometry& grid,
                                    FaceId f);

/// A convex planar polygon in grid coordinates (a triangle clipped by at most six planes).
struct ClipPolygon {
  static constexpr int kCapacity = 16;
  std::array<Vec3d, kCapacity> point;
  int size = 0;
};

/// One positive-area piece of a triangle inside one voxel.
struct VoxelPiece {
  VoxelCoord voxel{};
  ClipPolygon polygon;
  double area = 0.0;  ///< in grid units (world area / voxelSize^2)
};

/// Splits a triangle (grid coordinates) into its pieces per voxel by slab splitting along x, y,
/// z; out is cleared first and receives every piece of positive area. The pieces partition the
/// triangle. Cost proportional to the number of pieces.
void clipTriangleToVoxels(const std::array<Vec3d, 3>& g, std::int32_t resolution,
                          std::vector<VoxelPiece>& out);

/// The part of a triangle (grid coordinates) inside the closed voxel cube; empty polygon when
/// they do not overlap.
ClipPolygon clipTriangleToVoxel(const std::array<Vec3d, 3>& g, const VoxelCoord& voxel);

/// Does segment a-b overlap the closed box [lo, hi] in a piece of positive length? The box may
/// be flat (lo == hi on some axes: a voxel face or edge).
bool segmentOverlapsBox(const Vec3d& a, const Vec3d& b, const Vec3d& lo, const Vec3d& hi);

/// Bit j set when the edge of corner j (from g[j+1] to g[j+2], topology.h) has a piece of
/// positive length in the closed voxel cube.
std::uint8_t voxelEdgeMask(const std::array<Vec3d, 3>& g, const VoxelCoord& voxel);

/// The 8 trilinear B-splines of a voxel, numbered k = kx + 2 ky + 4 kz for the corner at
/// voxel + (kx, ky, kz); t in [0, 1]^3 are local coordinates.
void trilinearWeights(const Vec3d& t, double weights[8]);

/// Integrals of one element (symmetric 8 x 8 stiffness stored as the upper triangle, row-major).
struct VoxelIntegrals {
  std::array<double, 36> stiffness{};
  std::array<std::complex<double>, 8> rhs{};
  double area = 0.0;  ///< world units
};
/// Index of (a, b) in VoxelIntegrals::stiffness.
inline int packedIndex(int a, int b) {
  if (a > b) std::swap(a, b);
  return a * 8 - a * (a - 1) / 2 + (b - a);
}

/// Adds the exact integrals of the voxel's 8 B-splines over a planar fragment (grid coordinates,
/// unit normal n of its triangle) to acc: L_ab = int <grad_M phi_a, grad_M phi_b>,
/// rhs_a = int <grad_M phi_a, u> + i <grad_M phi_a, n x u>, u scaled by 1 / edgeLength.
/// With normalWeight > 0, L_ab also gets normalWeight * int (n . grad phi_a)(n . grad phi_b): it
/// removes the null space of B-splines restricted to a surface (they are linearly dependent on
/// planes) without touching maps whose 3D gradient is tangent (linear maps on planes stay exact).
/// normalAcc (36 packed entries, optional) receives the unweighted normal-derivative integrals.
/// Fan triangulation with a degree-4 exact triangle rule (the integrands have degree <= 4);
/// pieces under a quarter of a voxel across take a degree-2 rule (relative error below 1e-4).
void addFragmentIntegrals(const ClipPolygon& fragment, const VoxelCoord& voxel, double voxelSize,
                          const Vec3d& n, const Vec3d& u, double edgeLength, VoxelIntegrals& acc,
                          double normalWeight = 0.0, double* normalAcc = nullptr);

/// addFragmentIntegrals in two steps, for the many fragments of one element: accumulateFragment
/// adds a fragment's per-axis weight products, normal-derivative pairs, area and right-hand side
/// to sums; finishElement assembles the 36 pairs once and adds them to acc. The same figures as
/// one addFragmentIntegrals per fragment, up to rounding.
struct FragmentSums {
  double yz[10] = {}, xz[10] = {}, xy[10] = {};  ///< per-axis bilinear weight products
  double normal[36] = {};                        ///< (n . g_a)(n . g_b), packedIndex order
  std::array<std::complex<double>, 8> rhs{};
  double area = 0.0;
  bool any = false;  ///< a fragment of positive area was added
};
void accumulateFragment(const ClipPolygon& fragment, const VoxelCoord& voxel, double voxelSize,
                        const Vec3d& n, const Vec3d& u, double edgeLength, FragmentSums& sums);
void finishElement(const FragmentSums& sums, VoxelIntegrals& acc, double normalWeight = 0.0,
                   double* normalAcc = nullptr);

}  // namespace seamvox
