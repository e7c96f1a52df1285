#pragma once
/// The proxy field's steps (field_proxy.cpp) as kernels on one face or one element, shared by the
/// in-memory computeProxyField and the out-of-core field stage (stream/field_stream), so both
/// compute the same numbers in the same order. Internal.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/system/progress.h"

namespace seamvox::detail {

/// Geometry of one face from its corners' positions: its frame (faceFrame; zero-area faces get a
/// fallback frame and are flagged), centroid and area (0 when degenerate).
struct FaceGeometry {
  Vec3d n, e1, e2, centroid;
  double area = 0.0;
  bool degenerate = false;
};
FaceGeometry faceGeometry(const std::array<Vec3d, 3>& p);

/// The proxy's cubic cells, the grid centred on the bounding box of the positions.
struct ProxyCells {
  Vec3d origin = Vec3d::Zero();
  double cellSize = 1.0;
  std::uint32_t resolution = 1;
  /// Cell key of a face centroid (NaN centroids land in cell 0).
  std::uint32_t cellOf(const Vec3d& centroid) const;
};
ProxyCells proxyCells(const BoundingBox& box, std::int32_t resolution);

/// The grid-sized part of the proxy: per element its area-weighted unit normal, centroid and area,
/// and its neighbours with the summed length of the edges they share (increasing element ids).
struct ProxyElements {
  std::vector<Vec3d> normal, centroid;
  std::vector<double> area;
  std::vector<std::uint32_t> neighbourStart;                 ///< #E + 1
  std::vector<std::pair<std::uint32_t, double>> neighbours;  ///< (element, shared edge length)
  double cellSize = 0.0;
  std::uint32_t numElements() const { return static_cast<std::uint32_t>(area.size()); }
};

/// One element's sums, fed its faces in increasing order and, per face, its edges to faces of
/// other elements in corner order.
class ElementSums {
 public:
  void addFace(const FaceGeometry& g);
  void addNeighbour(std::uint32_t other, double edgeLength);
  /// Stores normal, centroid and area of element e (sized by the caller) and returns its
  /// neighbours sorted by element.
  std::vector<std::pair<std::uint32_t, double>> finish(ProxyElements& elements, std::uint32_t e);

 private:
  Vec3d normal_ = Vec3d::Zero(), weighted_ = Vec3d::Zero(), plain_ = Vec3d::Zero();
  double area_ = 0.0;
  std::uint32_t count_ = 0;
  std::vector<std::pair<std::uint32_t, double>> list_;
};
/// The neighbour lists of elements 0.. in order as ProxyElements' CSR arrays (the lists are freed).
void storeNeighbours(std::vector<std::vector<std::pair<std::uint32_t, double>>>& lists, ProxyElements& elements);

/// Smallest eigenvector of the element connection Laplacian, normalized per component.
Eigen::VectorXcd solveElementField(const ProxyElements& elements, const ProgressFn& progress, FieldSolveStats* stats);

/// Element directions in world coordinates with |z| as confidence, for the transfer.
struct ElementDirections {
  std::vector<Vec3d> direction;
  std::vector<double> confidence;
  double radius = 0.0;  ///< of the transfer's bump: two cells
};
ElementDirections elementDirections(const ProxyElements& elements, const Eigen::VectorXcd& z);
/// The transferred direction of a face of element own (its geometry g): a TransferBatch of one.
Vec3d transferredDirection(const ProxyElements& elements, const ElementDirections& directions, const FaceGeometry& g,
                           std::uint32_t own);

/// transferredDirection for up to kLanes faces of one element at once, laid out lane by lane for
/// SIMD: each lane runs the same operations in the same order, so a face gets the same bits alone
/// or in a batch. add() flushes first when the element changes, and when the batch is full;
/// flush(done) calls done(id, direction) for every face added since the last flush.
class TransferBatch {
 public:
  static constexpr int kLanes = 8;
  TransferBatch(const ProxyElements& elements, const ElementDirections& directions)
      : elements_(elements), directions_(directions) {}
  template <class Done>
  void add(std::uint64_t id, const FaceGeometry& g, std::uint32_t own, Done&& done) {
    if (size_ > 0 && own != own_) flush(done);
    own_ = own;
    const int l = size_++;
    id_[l] = id;
    for (int i = 0; i < 3; ++i) n_[i][l] = g.n[i], e1_[i][l] = g.e1[i], e2_[i][l] = g.e2[i], centroid_[i][l] = g.centroid[i];
    if (size_ == kLanes) flush(done);
  }
  template <class Done>
  void flush(Done&& done) {
    if (size_ == 0) return;
    compute();
    for (int l = 0; l < size_; ++l) done(id_[l], Vec3d(out_[0][l], out_[1][l], out_[2][l]));
    size_ = 0;
  }

 private:
  void compute();
  const ProxyElements& elements_;
  const ElementDirections& directions_;
  std::uint32_t own_ = 0;
  int size_ = 0;
  std::uint64_t id_[kLanes];
  alignas(64) double n_[3][kLanes], e1_[3][kLanes], e2_[3][kLanes], centroid_[3][kLanes], out_[3][kLanes];
};

/// The greedy colouring's choice: the smallest colour not in `taken` (a bit per colour).
inline std::uint8_t firstFreeColour(unsigned taken) {
  std::uint8_t k = 0;
  while (taken & (1u << k)) ++k;
  return k;
}

/// sweptDirection takes a neighbour's direction by projection where the two normals' cosine is at
/// least this (a tilt of 18 degrees at most), by rotation about the shared edge where it is less.
constexpr double kProjectCosine = 0.95;

/// One Gauss-Seidel step at a face of unit float normal `normal` (not zero) and direction u:
/// the direction in the face's plane whose 4th power has the argument of the sum of its `count`
/// neighbours' unit 4th powers (their float normals, not zero, and directions) carried into the
/// plane; not renormalized (the caller projects after the last sweep). False when the face keeps u.
bool sweptDirection(const Vec3f& normal, const Vec3d& u, const Vec3f* neighbourNormal, const Vec3d* neighbourDirection,
                    int count, Vec3d& out);

/// sweptDirection for up to kLanes faces at once, laid out lane by lane for SIMD: every lane
/// runs sweptDirection's operations in the same order, so a face gets the same bits alone or in
/// a batch. Faces of one colour share no edge, so they may be swept in any grouping. add() a
/// face (its id, then sweptDirection's arguments); flush(done) calls done(id, direction) for every
/// face that changes and empties the batch. sweptDirection itself is a batch of one.
class SweepBatch {
 public:
  static constexpr int kLanes = 8;
  /// True when the batch is full (flush it before the next add).
  bool add(std::uint64_t id, const Vec3f& normal, const Vec3d& u, const Vec3f* neighbourNormal,
           const Vec3d* neighbourDirection, int count);
  template <class Done>
  void flush(Done&& done) {
    if (size_ == 0) return;
    compute();
    for (int l = 0; l < size_; ++l) {
      if (ok_[l] > 0.0) done(id_[l], Vec3d(out_[0][l], out_[1][l], out_[2][l]));
    }
    size_ = 0;
  }

 private:
  void compute();
  int size_ = 0;
  std::uint64_t id_[kLanes];
  // [coordinate][lane], neighbours [k][coordinate][lane]; lanes past size_ hold no neighbour.
  // Flags are doubles (1 or 0) so that every loop over lanes is one of doubles.
  alignas(64) double n_[3][kLanes], u_[3][kLanes], m_[3][3][kLanes], d_[3][3][kLanes], out_[3][kLanes];
  alignas(64) double weight_[3][kLanes], ok_[kLanes];  ///< neighbour k present; lane's direction changes
};

/// u projected onto the plane of unit normal n and normalized; false when it cannot be.
bool tangentOf(const Vec3d& n, const Vec3d& u, Vec3d& out);

inline bool isZero(const Vec3f& n) { return n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f; }

}  // namespace seamvox::detail
