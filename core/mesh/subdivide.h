#pragma once
/// 1-to-4 midpoint subdivision (the scaling series of the paper: each level quadruples the faces).
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct SubdivideOptions {
  std::uint32_t levels = 1;
  ProgressFn progress;
};

/// Child face 4 f + k (k < 3) is the corner triangle at triangles[f][k], 4 f + 3 the middle one.
/// New vertices come after the old ones, one per undirected edge, numbered in increasing order of
/// the edge's corner (edgeCorner = min(c, opposite(c)), topology.h), at the exact edge midpoint
/// (computed in double, rounded once to float). Its vertex attributes are the mean of the edge's
/// two ends (integers such as 8-bit colors rounded to nearest).
struct SubdivideResult {
  TriangleMesh mesh;                 ///< 4^levels #F faces; orientation kept
  std::vector<FaceId> parentFace;    ///< #F out: the input face each output face lies in
  std::uint64_t edges = 0;           ///< undirected edges of the input (V' = V + E for one level)
};

/// Subdivides a manifold mesh (with its corner table) `levels` times. Linear per level,
/// parallel; cornerUV is not carried. Throws TopologyError if topology does not match mesh.
SubdivideResult subdivideMesh(const TriangleMesh& mesh, const Topology& topology,
                              const SubdivideOptions& options = {});

/// subdivideMesh's edge numbers per corner: counted in corner order over the owning corners (the
/// smaller of c and opposite(c); c itself on a boundary), both corners of an edge sharing one.
/// edges receives the count.
std::vector<std::uint32_t> subdivisionEdgeNumbers(const Topology& topology, std::uint64_t& edges);

/// The point subdivideMesh puts on an edge from a to b: the midpoint in double, rounded once.
inline Vec3f subdivisionMidpoint(const Vec3f& a, const Vec3f& b) {
  return ((a.cast<double>() + b.cast<double>()) * 0.5).cast<float>();
}

/// Carries per-face vectors (e.g. a field) to the children: out[f] = values[parentFace[f]].
std::vector<Vec3d> inheritFaceVectors(const std::vector<Vec3d>& values,
                                      const std::vector<FaceId>& parentFace);

}  // namespace seamvox
