#pragma once
/// Wound vertices (metrics.h woundVertices) counted out of core: each corner's (u, v) angle
/// (cornerUVAngle) goes into an external sort by vertex, and a vertex is wound when the angles of
/// a closed fan around it sum to kWoundAngleSum or more. Memory: the sorts' limit and the corners
/// of one vertex.
#include <cstdint>
#include <functional>
#include <memory>

#include "core/mesh/mesh.h"
#include "stream/external_sort.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// For a mesh whose vertices each have one fan (a cleaned mesh: CleanScratch): per vertex the sum
/// of its corners' angles, a float per vertex in memory when the vertices fit memoryBytes, else
/// in ranges that do, the corners written to a scratch file per range (8 bytes each) and summed
/// range by range. The sums are the same either way (added in the order given).
class ManifoldWoundCounter {
 public:
  ManifoldWoundCounter(ScratchFolder& scratch, std::uint64_t vertices, std::uint64_t memoryBytes, const char* stage);
  ~ManifoldWoundCounter();
  /// A corner's angle at vertex v (woundCornerAngle).
  void add(std::uint32_t v, float angle);
  /// Ends the input and counts (once).
  std::uint64_t count();
  /// The vertices were summed in ranges through scratch files.
  bool inRanges() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// What ManifoldWoundCounter sums for a corner: its (u, v) angle (cornerUVAngle of q and its
/// face's next and previous corners' (u, v)), or -infinity when one of its two edges at the
/// vertex has no other side (the vertex is on the boundary, never wound).
float woundCornerAngle(const Vec2d& q, const Vec2d& next, const Vec2d& prev, bool onBoundary);

/// A closed fan around a vertex (FanAngleSums): the vertex, its corners' angles summed and its
/// smallest corner.
struct ClosedFan {
  std::uint32_t vertex = 0;
  double angleSum = 0.0;
  std::uint64_t corner = 0;
};

/// For any mesh, the sides of whose edges are glued by a caller (map_pass::glueSides): per side
/// of an edge, the corner at its first vertex with its angle and, when the side is glued, the
/// corner at that vertex across the edge. A vertex's corners joined so are one fan (a bowtie
/// vertex has several, as cleanMesh splits it); a fan whose every corner is joined across its
/// edge is closed. A record per side sorted by vertex (a counting sort): 24 bytes with float
/// angles, 32 with double.
template <class Angle>
class FanAngleSums {
 public:
  /// vertices: the ids are below it; faces: about how many (sizes the sort's partitions).
  FanAngleSums(ScratchFolder& scratch, std::uint64_t vertices, std::uint64_t faces, const ExternalSortOptions& options);
  ~FanAngleSums();
  /// Corner c's side, its edge from vertex a to b: the corner next(c) at a with its angle, unglued.
  void addSide(std::uint32_t a, std::uint64_t c, Angle angle);
  /// The glued sides of corners c and o (the edge of c from a to b, that of o from b to a) with
  /// the angles of next(c) at a and next(o) at b: next(c) joined to prev(o), next(o) to prev(c).
  void addGluedSides(std::uint32_t a, std::uint32_t b, std::uint64_t c, std::uint64_t o, Angle angleC, Angle angleO);
  /// Ends the input and visits every closed fan, by vertex, a vertex's fans by smallest corner (once).
  void forEachClosedFan(const std::function<void(const ClosedFan&)>& visit);
  /// Bytes sorted per side.
  static constexpr std::uint64_t kBytesPerSide = sizeof(Angle) == sizeof(float) ? 24 : 32;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};
extern template class FanAngleSums<float>;
extern template class FanAngleSums<double>;

/// The wound vertices of the closed fans (angles by cornerUVAngle): those summing to
/// kWoundAngleSum or more. Ends the input of sums.
std::uint64_t countWoundFans(FanAngleSums<float>& sums);

}  // namespace seamvox
