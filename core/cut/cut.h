#pragma once
/// Cut graph, combing and seam curves. DESIGN section 5.
///
/// CONVENTIONS (written once; see also topology.h and field.h):
/// * A seam curve is a chain of cut interior edges between seam nodes. It is stored as corners
///   c_0, c_1, ... whose faces lie on its LEFT: the edge of c_j (vertex(next c_j) ->
///   vertex(prev c_j)) is traversed in the curve's direction. The RIGHT face of that edge is
///   face(opposite(c_j)).
/// * After combing, the combed direction of face f is rot^faceRotation[f](field.direction[f]) and
///   corners.matching(c) is the matching (field.h) between combed directions: 0 across every
///   non-cut edge, and the same value k on every edge of one seam curve (asserted).
/// * Map across a seam (the solver's convention): crossing from the left face to the right face,
///   q_right = r q_left + t with r = i^(-k) = conj(i^k), k = seam.matching, t in Z + iZ.
#include <cstdint>
#include <functional>
#include <vector>

#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct SeamCurve {
  std::vector<CornerId> corners;  ///< left-side corners in curve order
  VertexId start = kInvalidId;    ///< first vertex of the curve (a seam node)
  VertexId end = kInvalidId;      ///< last vertex (== start for a closed loop)
  std::uint8_t matching = 0;      ///< combed matching k of every edge of the curve, left -> right
};

struct CutOptions {
  ProgressFn progress;
};

/// Per corner, four bits: whether the edge of corner c is cut (boundary edges included) and the
/// combed matching across it (0 on every non-cut edge). Two corners to a byte (1.5 #F bytes): the
/// table lives from the cut to the end of the map's repair, beside the map. A corner's bits are
/// written by one thread at a time, and two corners that share a byte are never written by two
/// threads at once (a parallel writer goes over whole bytes, numBytes).
class CutCorners {
 public:
  CutCorners() = default;
  /// n corners, every edge cut or none, matchings 0.
  CutCorners(std::size_t n, bool cut)
      : size_(n), bits_((n + 1) / 2, cut ? static_cast<std::uint8_t>(kCutBit | kCutBit << 4) : 0) {}
  std::size_t size() const { return size_; }
  bool isCut(CornerId c) const { return (byteOfCorner(c) & kCutBit) != 0; }
  std::uint8_t matching(CornerId c) const { return byteOfCorner(c) & kMatchingBits; }
  void setCut(CornerId c, bool cut) { setBits(c, kCutBit, cut ? kCutBit : 0); }
  /// k in 0..3 (taken mod 4).
  void setMatching(CornerId c, std::uint8_t k) { setBits(c, kMatchingBits, k & kMatchingBits); }
  std::size_t memoryBytes() const { return bits_.capacity(); }
  /// Corner c's bits in byteOf's form (the out-of-core cut writes these bytes, one per corner).
  std::uint8_t byteOfCorner(CornerId c) const {
    return static_cast<std::uint8_t>((bits_[c >> 1] >> ((c & 1u) * 4)) & kNibble);
  }
  /// One byte per corner, byteOf's form (what the out-of-core cut's file holds).
  std::vector<std::uint8_t> cornerBytes() const;
  /// Number of packed bytes; byte b holds corners 2b and 2b + 1.
  std::size_t numBytes() const { return bits_.size(); }
  static std::uint8_t byteOf(bool cut, std::uint8_t k) {
    return static_cast<std::uint8_t>((cut ? kCutBit : 0) | (k & kMatchingBits));
  }
  static bool isCutByte(std::uint8_t byte) { return (byte & kCutBit) != 0; }
  static std::uint8_t matchingOfByte(std::uint8_t byte) { return byte & kMatchingBits; }

 private:
  static constexpr std::uint8_t kMatchingBits = 3, kCutBit = 4, kNibble = 15;
  void setBits(CornerId c, std::uint8_t mask, std::uint8_t value) {
    const unsigned shift = (c & 1u) * 4;
    std::uint8_t& b = bits_[c >> 1];
    b = static_cast<std::uint8_t>((b & ~(mask << shift)) | (value << shift));
  }
  std::size_t size_ = 0;
  std::vector<std::uint8_t> bits_;
};

/// Per face the quarter turns combing applied (0..3), two bits each, four faces to a byte. Written
/// by one thread at a time.
class FaceRotations {
 public:
  FaceRotations() = default;
  /// n faces, every rotation 0.
  explicit FaceRotations(std::size_t n) : size_(n), bits_((n + 3) / 4, 0) {}
  std::size_t size() const { return size_; }
  std::uint8_t operator[](FaceId f) const { return static_cast<std::uint8_t>((bits_[f >> 2] >> (2 * (f & 3u))) & 3u); }
  /// r in 0..3 (taken mod 4).
  void set(FaceId f, std::uint8_t r) {
    const unsigned shift = 2 * (f & 3u);
    std::uint8_t& b = bits_[f >> 2];
    b = static_cast<std::uint8_t>((b & ~(3u << shift)) | ((r & 3u) << shift));
  }
  std::size_t memoryBytes() const { return bits_.capacity(); }
  /// One byte per face (what the out-of-core cut's file holds).
  std::vector<std::uint8_t> faceBytes() const;
  bool operator==(const FaceRotations& other) const { return size_ == other.size_ && bits_ == other.bits_; }
  bool operator!=(const FaceRotations& other) const { return !(*this == other); }

 private:
  std::size_t size_ = 0;
  std::vector<std::uint8_t> bits_;
};

struct CutResult {
  CutCorners corners;                        ///< 3 #F: cut flag and combed matching per corner
  FaceRotations faceRotation;                ///< #F, quarter turns applied by combing
  std::vector<SeamCurve> seams;
  std::vector<VertexId> cones;  ///< copy of the field's cones; every one lies on the cut
};

/// The seam of a corner's edge, looked up among the seam corners only (both sides, sorted):
/// 12 bytes per seam edge instead of a 3 #F array. Build it for the stage that needs it.
class SeamIndex {
 public:
  struct Side {
    std::uint32_t seam = kInvalidId;  ///< seam id, or kInvalidId: the edge is on no seam
    bool left = false;                ///< the corner is one of the seam's (left) corners
  };
  SeamIndex(const Topology& topology, const std::vector<SeamCurve>& seams);
  /// The same from an opposite-corner lookup over numCorners corners (a corner table out of core).
  SeamIndex(const std::vector<SeamCurve>& seams, std::uint64_t numCorners, const std::function<CornerId(CornerId)>& opposite);
  /// Seam and side of the edge of corner c; boundary edges are cut but are on no seam.
  Side find(CornerId c) const;
  std::uint32_t seamOf(CornerId c) const { return find(c).seam; }

 private:
  struct Entry {
    CornerId corner;
    std::uint32_t seam;
    bool left;
  };
  std::vector<Entry> entries_;  // sorted by corner
};

/// Dual spanning tree per component, pruning to a cut through every cone (boundary edges kept),
/// combing and seam curves. Each component's cut surface is a topological disk. Linear time.
/// A closed genus-0 component with at most one cone would prune to nothing: it keeps one edge
/// (at the cone if any), one seam of one edge, and is cut open along it. Throws TopologyError
/// when the matchings disagree with the cones (a rotation left off the cut or along a seam).
CutResult cutToDisk(const TriangleMesh& mesh, const Topology& topology, const CrossField& field,
                    const FieldSingularities& singularities, const CutOptions& options = {});

}  // namespace seamvox
