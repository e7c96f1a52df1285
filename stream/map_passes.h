#pragma once
/// The passes the out-of-core map commands share (stream/map_check, stream/map_render): the read
/// pass (vertices into CornerPositions, faces without a repeated vertex into a scratch file with
/// their (u, v), keys that find duplicate faces), the duplicate faces, and the gluing of an
/// edge's sides as cleanMesh glues them.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/errors.h"
#include "stream/corner_positions.h"
#include "stream/external_sort.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"
#include "stream/wound_count.h"

namespace seamvox::map_pass {

// Records of the sorts and scratch files (plain arrays: written as bytes).
struct FaceRecord {  // a face that is not degenerate, in input order
  std::uint32_t v[3], inputFace;
  double uv[3][2];
};
struct DuplicateKey {  // its sorted vertex set; face = its rank among non-degenerate faces
  std::uint32_t a, b, c, face;
  bool operator<(const DuplicateKey& o) const { return std::tie(a, b, c, face) < std::tie(o.a, o.b, o.c, o.face); }
};
struct WeldKey {  // a vertex by its position (-0 and 0 equal, as cleanMesh compares them)
  float p[3];
  std::uint32_t vertex;
  bool operator<(const WeldKey& o) const;
};
struct EdgeRecord {  // corner c of the cleaned mesh: its edge runs from a = vertex(next c) to b = vertex(prev c)
  std::uint64_t edge;     // min(a, b) << 32 | max(a, b): the sort key
  std::uint64_t corner2;  // 2 c + (a < b): by corner within an edge, with the direction
  double uvStart[2], uvEnd[2];  // UV at a, at b
  double startAngle = 0.0;      // the (u, v) angle of corner next c (at a), as its command sums them
  EdgeRecord() = default;
  EdgeRecord(std::uint32_t a, std::uint32_t b, std::uint64_t c)
      : edge(std::uint64_t(std::min(a, b)) << 32 | std::max(a, b)), corner2(2 * c + (a < b)) {}
  std::uint64_t corner() const { return corner2 >> 1; }
  bool forward() const { return corner2 & 1; }
  bool operator<(const EdgeRecord& o) const { return edge != o.edge ? edge < o.edge : corner2 < o.corner2; }
};

inline Vec2d vec2(const double (&x)[2]) { return {x[0], x[1]}; }
inline Vec3d vec3(const double (&x)[3]) { return {x[0], x[1], x[2]}; }


// Sorted vertex sets: the faces (non-degenerate ranks) repeating an earlier face's set, increasing.
struct Duplicates {
  std::unique_ptr<ExternalSorter<std::uint32_t>> ranks;
  std::uint64_t count = 0;
};


// Pass 1: the stream into the corner positions, the non-degenerate faces file and the sort that
// finds duplicate faces. Throws InputError for no faces, no (u, v), non-finite coordinates and
// chunks out of step.
struct ReadPass {
  ScratchFile faces;
  std::uint64_t vertices = 0, inputFaces = 0, kept = 0;
};
ReadPass readStream(MeshStream& stream, ScratchFolder& scratch, ExternalSorter<DuplicateKey>& duplicates,
                    CornerPositions& positions, ExternalSorter<WeldKey>* weld = nullptr);

/// Welding vertices at exactly equal positions (cleanMesh's weld with tolerance 0): per vertex the
/// smallest id at its position, from the keys readStream added (4 bytes per vertex in memory).
std::vector<std::uint32_t> weldMap(ExternalSorter<WeldKey>& keys, std::uint64_t vertices);

/// The duplicate faces of a read pass from its keys; InputError naming the stream when no face is left.
Duplicates findDuplicateFaces(const std::string& name, const ReadPass& read, ExternalSorter<DuplicateKey>& keys,
                              ScratchFolder& scratch, const ExternalSortOptions& options);

/// The faces of the read pass in order with their corner positions (every face is asked of
/// positions, in step), duplicates left out: visit(face, p) for each.
template <class Visit>
void forEachKeptFace(ScratchFolder& scratch, const ReadPass& read, Duplicates& duplicates, CornerPositions& positions,
                     Visit&& visit) {
  ScratchReader faces(scratch, read.faces, "faces");
  FaceRecord face;
  std::uint32_t nextDuplicate = kInvalidId;
  bool moreDuplicates = duplicates.ranks->next(nextDuplicate);
  for (std::uint64_t k = 0; k < read.kept; ++k) {
    if (!faces.read(&face, sizeof face)) throw IoError(read.faces.path + ": scratch faces end early");
    Vec3d p[3];
    positions.face(k, face.v, face.inputFace, p);
    if (moreDuplicates && nextDuplicate == k) {
      moreDuplicates = duplicates.ranks->next(nextDuplicate);
      continue;
    }
    visit(face, p);
  }
}

/// Records of a scratch file, one per face, read back by corner for the few corners that need
/// them (pread, the last face's record kept).
template <class Record>
class RecordsByFace {
 public:
  RecordsByFace(ScratchFolder& scratch, const ScratchFile& file, const char* stage) : reader_(scratch, file, stage) {}
  const Record& at(std::uint64_t corner) {
    if (corner / 3 != face_) {
      face_ = corner / 3;
      reader_.readAt(face_ * sizeof(Record), &record_, sizeof record_);
    }
    return record_;
  }

 private:
  ScratchRandomReader reader_;
  std::uint64_t face_ = ~std::uint64_t(0);
  Record record_{};
};

/// The sides of one edge (sorted by corner) glued as cleanMesh glues them: two sides in opposite
/// directions; on an edge of more than two sides, pairs of opposite directions with the most
/// aligned normals first (ties: smaller corners first), normalOf(i) giving side i's face's
/// gluingNormal.
/// Each pair is (smaller corner, larger). Two sides in the same direction (an orientation clash)
/// give no pair and set clash.
std::vector<std::pair<std::size_t, std::size_t>> glueSides(const std::vector<EdgeRecord>& sides,
                                                           const std::function<Vec3d(std::size_t)>& normalOf,
                                                           bool& clash);

/// The sides of one edge into fan sums: the glued pairs (glueSides) joined across the edge, every
/// other side (an unpaired one, a clash's) opening its vertex's fan; each with its startAngle.
/// used: scratch flags, reused across edges.
template <class Angle>
void addSidesToFans(FanAngleSums<Angle>& fans, const std::vector<EdgeRecord>& sides,
                    const std::vector<std::pair<std::size_t, std::size_t>>& glued, std::vector<std::uint8_t>& used);
extern template void addSidesToFans(FanAngleSums<float>&, const std::vector<EdgeRecord>&,
                                    const std::vector<std::pair<std::size_t, std::size_t>>&, std::vector<std::uint8_t>&);
extern template void addSidesToFans(FanAngleSums<double>&, const std::vector<EdgeRecord>&,
                                    const std::vector<std::pair<std::size_t, std::size_t>>&, std::vector<std::uint8_t>&);

}  // namespace seamvox::map_pass
