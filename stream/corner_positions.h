#pragma once
/// The positions of a streamed mesh's corners, face by face in order, for the out-of-core passes
/// (check, render): the vertex positions are held in memory when the header declares a count
/// whose positions fit the given share of memory (the common case), else the corner requests are
/// sorted by vertex, joined with the positions written to the scratch folder and sorted back by
/// corner.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "stream/external_sort.h"
#include "stream/scratch_folder.h"

namespace seamvox {

namespace corner_detail {
struct CornerRequest {  // corner j of face (rank among the faces asked for) at vertex; inputFace for messages
  std::uint32_t vertex, face, j, inputFace;
  bool operator<(const CornerRequest& o) const;
};
struct CornerPosition {
  std::uint64_t corner;  // 3 face + j
  float p[3];
  bool operator<(const CornerPosition& o) const { return corner < o.corner; }
};
}  // namespace corner_detail

class CornerPositions {
 public:
  /// name: the stream's, for messages; memoryBytes: what the positions may take in memory.
  CornerPositions(const std::string& name, ScratchFolder& scratch, std::uint64_t declaredVertices,
                  std::uint64_t memoryBytes, const ExternalSortOptions& sortOptions);
  ~CornerPositions();
  bool inMemory() const { return !requests_ && !corners_; }
  std::uint64_t vertices() const { return vertices_; }

  /// The vertices in stream order, then (or interleaved) the faces in increasing rank.
  void addVertex(const Vec3f& p);
  void addFace(std::uint32_t rank, const Triangle& t, std::uint32_t inputFace);
  /// After the last vertex and face: the join (InputError for a vertex out of range).
  void finish();
  /// The positions of face `rank`'s corners; faces are asked for in increasing rank, each once.
  /// v: its vertices, inputFace: its index in the input (for messages).
  void face(std::uint64_t rank, const std::uint32_t (&v)[3], std::uint32_t inputFace, Vec3d (&p)[3]);

 private:
  void join(const ScratchFile& positions);

  std::string name_;
  ScratchFolder& scratch_;
  ExternalSortOptions sortOptions_;
  std::uint64_t vertices_ = 0;
  std::vector<Vec3f> positions_;
  std::unique_ptr<ScratchWriter> file_;
  std::unique_ptr<ExternalSorter<corner_detail::CornerRequest>> requests_;
  std::unique_ptr<ExternalSorter<corner_detail::CornerPosition>> corners_;
};

}  // namespace seamvox
