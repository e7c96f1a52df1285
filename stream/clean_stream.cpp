#include "stream/clean_stream.h"

#include "core/basis/islands.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "core/mesh/topology.h"
#include "core/system/errors.h"
#include "core/system/parallel.h"
#include "stream/clean_front.h"
#include "stream/external_sort.h"
#include "stream/keyed_sort.h"
#include "stream/paged_corner_table.h"
#include "stream/paged_reader.h"
#include "stream/scratch_union_find.h"

namespace seamvox {

namespace {

constexpr std::size_t kChunkFaces = 1u << 16;
constexpr std::uint64_t kMinimumSortBytes = std::uint64_t(1) << 20;
/// Pieces of at least this many faces count as large when edges of more than two faces are
/// paired (cleanMesh's kLargePieceFaces).
constexpr std::uint32_t kLargePieceFaces = 1024;

/// A side of an edge: corner c's edge runs vertex(next c) -> vertex(prev c).
struct EdgeSide {
  VertexId from, to;  ///< in the face's direction (12 bytes: the direction is their order)
  CornerId corner;
  VertexId lo() const { return std::min(from, to); }
  VertexId hi() const { return std::max(from, to); }
  bool forward() const { return from < to; }  ///< runs lo -> hi
};
static_assert(sizeof(EdgeSide) == 12, "the edge sort's records");
/// A kept vertex: its new id, welded id and position (20 bytes).
/// A corner (its index in the Morton order of the faces) at its welded vertex; and a vertex's
/// first corner or new id, for the renumbering by sorts.
struct VertexCorner {
  std::uint32_t vertex = 0, corner = 0;
  bool operator<(const VertexCorner& o) const { return std::tie(vertex, corner) < std::tie(o.vertex, o.corner); }
};
struct CornerValue {
  std::uint32_t corner = 0, value = 0;
  bool operator<(const CornerValue& o) const { return corner < o.corner; }
};

struct NumberedVertex {
  std::uint32_t id = 0, origin = 0;
  float position[3] = {0.0f, 0.0f, 0.0f};  // plain floats: written as bytes
};
struct NumberedVertexLess {
  bool operator()(const NumberedVertex& a, const NumberedVertex& b) const { return a.id < b.id; }
};

struct EdgeSideLess {
  bool operator()(const EdgeSide& a, const EdgeSide& b) const {
    const VertexId alo = a.lo(), ahi = a.hi(), blo = b.lo(), bhi = b.hi();
    return std::tie(alo, ahi, a.corner) < std::tie(blo, bhi, b.corner);
  }
};

struct CornerPair {
  CornerId corner, other;
  bool operator<(const CornerPair& o) const { return corner < o.corner; }
};

/// The keys of the keyed sorts: an edge's smaller vertex, a pair's corner, a corner's vertex.
struct EdgeSideKey {
  std::uint64_t operator()(const EdgeSide& s) const { return s.lo(); }
};
struct CornerPairKey {
  std::uint64_t operator()(const CornerPair& p) const { return p.corner; }
};
using EdgeSorter = KeyedSorter<EdgeSide, EdgeSideLess, EdgeSideKey>;
using PairSorter = KeyedSorter<CornerPair, std::less<CornerPair>, CornerPairKey>;

/// A boundary vertex's position and input vertex.
struct BoundaryPoint {
  float p[3];
  VertexId origin;
  bool operator<(const BoundaryPoint& o) const {
    return std::tie(p[0], p[1], p[2], origin) < std::tie(o.p[0], o.p[1], o.p[2], o.origin);
  }
};

using detail::CornerAround;
struct CornerAroundLess {
  bool operator()(const CornerAround& a, const CornerAround& b) const {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.corner < b.corner;
  }
};
struct CornerAroundKey {
  std::uint64_t operator()(const CornerAround& a) const { return a.vertex; }
};

/// The corner of a face after the face was flipped (its corners 1 and 2 swapped).
CornerId flippedCorner(CornerId c) {
  const CornerId k = c % 3;
  return c - k + (k == 0 ? 0 : 3 - k);
}

class CleanPass {
 public:
  CleanPass(ScratchFolder& folder, const WeldedScratch& welded, const WeldCensus& census, const CleanStreamOptions& options)
      : folder_(folder), welded_(welded), options_(options) {
    const std::uint64_t memoryBytes = options.memoryBytes;
    const bool setsOnDisk = options.setsOnDisk;
    sort_.memoryBytes = std::max(kMinimumSortBytes, memoryBytes / 2);
    // Per-face sets and flags within shares of the memory (on disk beyond them; tests: always):
    // the orientation's union-find alone (half), then the flips (an eighth) for the rest of the
    // cleaning and the pieces' union-find (a quarter) beside the gluing's sort.
    orientBytes_ = setsOnDisk ? 0 : memoryBytes / 2;
    flipBytes_ = setsOnDisk ? 0 : memoryBytes / 8;
    piecesBytes_ = setsOnDisk ? 0 : memoryBytes / 4;
    // New vertex ids in memory (4 B per welded vertex) while they fit half the sorts' share (a
    // quarter of memoryBytes: 200 MB at 100M faces in a 2 GiB budget), else by sorts.
    renumberBySorts_ = options.renumberBySorts || 4 * welded.numVertices > sort_.memoryBytes / 2;
    out_.numFaces = welded.numFaces;
    out_.origin = census.origin;
    out_.report = weldCleanReport(census);
    // The weld counted them on the kept faces with the same box (of the same referenced
    // positions) and threshold as cleanMesh; flips and splits do not change an area.
    out_.report.zeroAreaFaces = census.zeroAreaFaces;
  }

  CleanScratch run() {
    const std::pair<const char*, void (CleanPass::*)()> passes[] = {
        {"vertices", &CleanPass::renumberVertices}, {"faces", &CleanPass::readFaces},
        {"front", &CleanPass::glueAlongFront},      {"glue", &CleanPass::orientAndGlue},
        {"fans", &CleanPass::splitVertices},        {"write", &CleanPass::writeFaces},
        {"measure", &CleanPass::measure}};
    for (const auto& [name, pass] : passes) {
      const auto start = std::chrono::steady_clock::now();
      (this->*pass)();
      out_.stageSeconds.emplace_back(name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    out_.report.outputVertices = out_.numVertices;
    out_.report.outputFaces = out_.numFaces;
    out_.setsOnDisk = setsOnDisk_ || (flip_ && flip_->onDisk());
    return std::move(out_);
  }

 private:
  ExternalSortOptions sortOptions(const char* stage) const { return sort_.named(stage); }

  /// Welded vertices that some face references, numbered in the order the (Morton-ordered) faces
  /// first name them, so that a vertex's id is near its faces' ids (cleanMesh's
  /// dropUnreferencedVertices on vertices so numbered); their positions and input ids, put in
  /// that order in memory when they fit beside the new ids (half the sorts' share), else by a sort.
  void renumberVertices() {
    if (renumberBySorts_) return renumberVerticesBySorts();
    // The faces on their new ids in the same pass (a vertex's id is set where a face first names it).
    newId_.assign(welded_.numVertices, kInvalidId);
    startFaces(welded_.numVertices);
    WeldedFaceReader faces(folder_, welded_, "clean: vertices");
    ScratchWriter facesOut(folder_, "clean: vertices");
    std::vector<WeldedFace> chunk;
    std::uint32_t n = 0;
    CornerId corner = 0;
    while (faces.next(chunk, kChunkFaces)) {
      for (const WeldedFace& f : chunk) {
        CleanFace face{{}, f.face};
        for (int k = 0; k < 3; ++k) {
          VertexId& id = newId_[f.triangle[k]];
          if (id == kInvalidId) id = n++;
          face.triangle[k] = id;
        }
        facesOut.write(&face, sizeof face);
        addFace(face, corner);
      }
    }
    faces_ = facesOut.finish();
    if (tryFront_) lastFace_.resize(n);
    facesRead_ = true;
    if (std::uint64_t(n) * (sizeof(Vec3f) + sizeof(VertexId)) <= sort_.memoryBytes / 2) {
      std::vector<Vec3f> positions(n);
      std::vector<VertexId> origin(n);
      ScratchReader in(folder_, welded_.positions, "clean: vertices");
      Vec3f p;
      for (VertexId v = 0; v < newId_.size(); ++v) {
        if (!in.read(&p, sizeof p)) throw IoError(welded_.positions.path + ": scratch positions end early");
        if (newId_[v] == kInvalidId) continue;
        positions[newId_[v]] = p;
        origin[newId_[v]] = v;
      }
      ScratchWriter positionsOut(folder_, "clean: vertices"), originOut(folder_, "clean: vertices");
      positionsOut.write(positions.data(), positions.size() * sizeof(Vec3f));
      originOut.write(origin.data(), origin.size() * sizeof(VertexId));
      setNumberedVertices(positionsOut.finish(), originOut.finish(), n);
      return;
    }
    ExternalSorter<NumberedVertex, NumberedVertexLess> sorter(folder_, sortOptions("clean: vertices"));
    {
      ScratchReader in(folder_, welded_.positions, "clean: vertices");
      NumberedVertex record;
      for (VertexId v = 0; v < newId_.size(); ++v) {
        if (!in.read(&record.position, sizeof record.position)) {
          throw IoError(welded_.positions.path + ": scratch positions end early");
        }
        if (newId_[v] == kInvalidId) continue;
        record.id = newId_[v];
        record.origin = v;
        sorter.add(record);
      }
    }
    sorter.finish();
    writeNumberedVertices(sorter, [](VertexId, std::uint32_t) {});
  }

  /// The numbered vertices, in the sorter's order, into the positions and input-id files: new
  /// ids 0, 1, ... in that order, each given to numbered(welded id, new id).
  template <class Sorter, class Numbered>
  void writeNumberedVertices(Sorter& sorter, Numbered&& numbered) {
    ScratchWriter positions(folder_, "clean: vertices"), origin(folder_, "clean: vertices");
    NumberedVertex record;
    std::uint32_t n = 0;
    while (sorter.next(record)) {
      positions.write(&record.position, sizeof record.position);
      origin.write(&record.origin, sizeof record.origin);
      numbered(record.origin, n++);
    }
    setNumberedVertices(positions.finish(), origin.finish(), n);
  }

  void setNumberedVertices(const ScratchFile& positions, const ScratchFile& origin, std::uint32_t n) {
    positions_ = positions;
    out_.vertexOrigin = origin;
    out_.numVertices = n;
    // The welded vertices no kept face uses (the weld's census counts them too, when it runs).
    out_.report.unreferencedVertices = out_.report.inputVertices - out_.report.weldedVertices - n;
  }

  /// renumberVertices without 4 B per welded vertex in memory (a mesh whose ids do not fit): the
  /// corners sorted by vertex give each vertex its first corner; the vertices sorted by that are
  /// numbered in order; the new ids joined back to the corners by vertex, then sorted by corner
  /// into a file readFaces reads alongside the faces. The same ids as in memory.
  void renumberVerticesBySorts() {
    const char* stage = "clean: vertices";
    ExternalSorter<VertexCorner> byVertex(folder_, sortOptions(stage));
    {
      WeldedFaceReader faces(folder_, welded_, stage);
      std::vector<WeldedFace> chunk;
      std::uint32_t corner = 0;
      while (faces.next(chunk, kChunkFaces)) {
        for (const WeldedFace& f : chunk) {
          for (const VertexId v : f.triangle) byVertex.add({v, corner++});
        }
      }
    }
    byVertex.finish();
    // Per vertex (increasing): its first corner; its corners kept in a file for the join.
    ExternalSorter<NumberedVertex, NumberedVertexLess> byFirstCorner(folder_, sortOptions(stage));
    ScratchWriter cornersByVertex(folder_, stage);
    {
      ScratchReader positions(folder_, welded_.positions, stage);
      NumberedVertex record;
      VertexCorner c;
      VertexId at = 0;  // the next welded vertex whose position is to be read
      bool more = byVertex.next(c);
      while (more) {
        const VertexCorner first = c;
        for (; at <= first.vertex; ++at) {
          if (!positions.read(&record.position, sizeof record.position)) {
            throw IoError(welded_.positions.path + ": scratch positions end early");
          }
        }
        record.id = first.corner;  // ordered by first corner; numbered when read back
        record.origin = first.vertex;
        byFirstCorner.add(record);
        do {
          cornersByVertex.write(&c, sizeof c);
        } while ((more = byVertex.next(c)) && c.vertex == first.vertex);
      }
    }
    const ScratchFile corners = cornersByVertex.finish();
    byFirstCorner.finish();
    // Numbered in first-corner order; the (vertex, new id) pairs back in vertex order.
    ExternalSorter<VertexCorner> newIdByVertex(folder_, sortOptions(stage));
    writeNumberedVertices(byFirstCorner, [&](VertexId v, std::uint32_t id) { newIdByVertex.add({v, id}); });
    newIdByVertex.finish();
    // Each corner's new id, by corner.
    ExternalSorter<CornerValue> byCorner(folder_, sortOptions(stage));
    {
      ScratchReader in(folder_, corners, stage);
      VertexCorner c, id{};
      bool haveId = newIdByVertex.next(id);
      while (in.read(&c, sizeof c)) {
        while (haveId && id.vertex < c.vertex) haveId = newIdByVertex.next(id);
        if (!haveId || id.vertex != c.vertex) throw IoError(corners.path + ": a vertex without a new id");
        byCorner.add({c.corner, id.corner});
      }
    }
    folder_.remove(corners);
    byCorner.finish();
    ScratchWriter cornerIds(folder_, stage);
    CornerValue c;
    while (byCorner.next(c)) cornerIds.write(&c.value, sizeof c.value);
    cornerNewId_ = cornerIds.finish();
  }

  /// The faces on the new ids (a scratch file) and, for the front pass, each vertex's last face;
  /// without the front pass, their edges' sides into a sort by edge.
  void readFaces() {
    if (!facesRead_) readFacesByCorner();
    std::vector<std::uint32_t>().swap(newId_);
    if (edges_) edges_->finish();
  }

  /// For the faces on vertices [0, numVertices) about to be read: each vertex's last face (the
  /// front pass), or their edges' sides into the sort by edge.
  void startFaces(std::uint64_t numVertices) {
    tryFront_ = !options_.gluingBySorts && 8 * numVertices <= std::max(kMinimumSortBytes, options_.memoryBytes / 4);
    if (tryFront_) {
      lastFace_.assign(numVertices, 0);
    } else {
      out_.gluing = options_.gluingBySorts ? "sorts" : "sorts: the front pass's 8 bytes per vertex do not fit a quarter of the memory";
      edges_ = std::make_unique<EdgeSorter>(folder_, numVertices, 3 * out_.numFaces, sortOptions("clean: edges"));
    }
  }

  /// The next face read (its first corner `corner`, advanced past it): its vertices' last face, or
  /// its edge sides into the sort.
  void addFace(const CleanFace& face, CornerId& corner) {
    if (tryFront_) {
      for (const VertexId v : face.triangle) lastFace_[v] = corner / 3;
      corner += 3;
      return;
    }
    for (int k = 0; k < 3; ++k, ++corner) edges_->add({face.triangle[(k + 1) % 3], face.triangle[(k + 2) % 3], corner});
  }

  /// The faces on the new ids of renumberVerticesBySorts (each corner's id from its file).
  void readFacesByCorner() {
    startFaces(out_.numVertices);
    WeldedFaceReader faces(folder_, welded_, "clean: faces");
    ScratchWriter out(folder_, "clean: faces");
    auto cornerIds = std::make_unique<ScratchReader>(folder_, cornerNewId_, "clean: faces");
    std::vector<WeldedFace> chunk;
    CornerId corner = 0;
    while (faces.next(chunk, kChunkFaces)) {
      for (const WeldedFace& f : chunk) {
        CleanFace face{{}, f.face};
        if (!cornerIds->read(face.triangle.data(), sizeof face.triangle)) {
          throw IoError(cornerNewId_.path + ": scratch file ends early");
        }
        out.write(&face, sizeof face);
        addFace(face, corner);
      }
    }
    cornerIds.reset();
    folder_.remove(cornerNewId_);
    faces_ = out.finish();
  }

  /// The gluing and fans in one pass along the faces (stream/clean_front) when the mesh allows it;
  /// else the edges' sides into their sort for the passes that follow.
  void glueAlongFront() {
    if (!tryFront_) return;
    detail::FrontGlueOptions front;
    front.memoryBytes = options_.frontBytes > 0 ? options_.frontBytes : std::max(kMinimumSortBytes, options_.memoryBytes / 4);
    // The two in-order windows take at most an eighth of that.
    front.windowValues = std::min<std::uint64_t>(options_.frontWindow, std::max<std::uint64_t>(64, front.memoryBytes / 64));
    // The islands on a thread of their own beside the serial front pass, kept when it splits no fan.
    std::future<std::vector<FaceId>> islands;
    if (options_.islandFaces > 0) islands = std::async(std::launch::async, [this] { return islandsBySharedVertices(); });
    detail::FrontGlueResult r = detail::glueAlongFront(folder_, faces_, out_.numFaces, out_.numVertices, lastFace_, front);
    if (islands.valid()) {
      std::vector<FaceId> found = islands.get();
      if (r.glued && r.copies.empty()) out_.islands = std::move(found);
    }
    std::vector<FaceId>().swap(lastFace_);
    out_.largestFront = r.largestFront;
    out_.frontLateValues = r.lateValues;
    if (!r.glued) {
      out_.gluing = "sorts: the front pass met " + r.why;
      sortEdges();
      return;
    }
    glued_ = true;
    out_.gluing = "front";
    out_.opposite = r.opposite;
    out_.vertexCorner = r.vertexCorner;
    boundary_ = std::move(r.boundary);
    out_.report.nonManifoldVertices = r.nonManifoldVertices;
    moved_ = std::make_unique<ExternalSorter<CornerPair>>(folder_, sortOptions("clean: fans"));
    std::vector<VertexId> copyOf;
    for (std::size_t i = 0; i < r.copies.size(); ++i) {
      copyOf.push_back(r.copies[i].vertex);
      for (const CornerId c : r.copies[i].corners) moved_->add({c, static_cast<CornerId>(out_.numVertices + i)});
    }
    moved_->finish();
    placeCopies(copyOf);
  }

  /// scratchIslandFaces' islands with the faces joined through their vertices (each face to each
  /// of its vertices' last face) rather than their glued edges: the same components when no vertex
  /// has two fans. Within an eighth of the memory for the faces' union-find and one for the counts.
  std::vector<FaceId> islandsBySharedVertices() {
    ScratchUnionFind sets(folder_, out_.numFaces, options_.memoryBytes / 8, "clean: islands");
    {
      ScratchReader in(folder_, faces_, "clean: islands");
      std::vector<CleanFace> block(kChunkFaces);
      for (FaceId f = 0; f < out_.numFaces;) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), out_.numFaces - f));
        if (!in.read(block.data(), n * sizeof(CleanFace))) throw IoError(faces_.path + ": scratch faces end early");
        for (std::size_t i = 0; i < n; ++i, ++f) {
          for (const VertexId v : block[i].triangle) sets.unite(f, lastFace_[v]);
        }
      }
    }
    ScratchArray<std::uint32_t> counts(folder_, out_.numFaces, options_.memoryBytes / 8, "clean: islands");
    return detail::islandFacesOf(out_.numFaces, sets, counts, options_.islandFaces);
  }

  /// The faces' edge sides into the sort by edge (after a front pass that stopped).
  void sortEdges() {
    edges_ = std::make_unique<EdgeSorter>(folder_, out_.numVertices, 3 * out_.numFaces, sortOptions("clean: edges"));
    ScratchReader in(folder_, faces_, "clean: edges");
    CleanFace face;
    for (CornerId corner = 0; in.read(&face, sizeof face);) {
      for (int k = 0; k < 3; ++k, ++corner) edges_->add({face.triangle[(k + 1) % 3], face.triangle[(k + 2) % 3], corner});
    }
    edges_->finish();
  }

  /// Calls visit(sides) for the sides of each edge in turn (sorted by corner) until it returns
  /// false; false then.
  template <class Visit>
  bool forEachEdge(Visit&& visit) {
    edges_->rewind();
    std::vector<EdgeSide> sides;
    EdgeSide side{};
    while (edges_->next(side)) {
      if (!sides.empty() && (side.lo() != sides[0].lo() || side.hi() != sides[0].hi())) {
        if (!visit(sides)) return false;
        sides.clear();
      }
      sides.push_back(side);
    }
    return sides.empty() || visit(sides);
  }

  /// Gluing and orientation. Most meshes have only edges of two sides in opposite directions (or
  /// one side): the gluing assumes so and stops at the first edge that is not, which is then
  /// counted, oriented and glued in full.
  void orientAndGlue() {
    if (glued_) return;
    if (glue(true)) return edges_.reset();
    forEachEdge([&](const std::vector<EdgeSide>& sides) {
      clashes_ += sides.size() == 2 && sides[0].forward() == sides[1].forward();
      multiEdges_ += sides.size() > 2;
      return true;
    });
    orient();
    glue(false);
    edges_.reset();
  }

  /// cleanMesh's orientation: when two faces meet along an edge in the same direction, each
  /// component (through edges of exactly two faces) is oriented like most of its faces, the
  /// edges united in order (a non-orientable loop keeps the edge closing it as a clash).
  void orient() {
    if (clashes_ == 0) return;
    ScratchParityUnionFind faces(folder_, out_.numFaces, orientBytes_, "clean: orient");
    forEachEdge([&](const std::vector<EdgeSide>& sides) {
      if (sides.size() == 2) faces.unite(sides[0].corner / 3, sides[1].corner / 3, sides[0].forward() == sides[1].forward());
      return true;
    });
    flip_ = std::make_unique<ScratchArray<std::uint8_t>>(folder_, out_.numFaces, flipBytes_, "clean: orient");
    faces.majorityFlips(*flip_);
    for (FaceId f = 0; f < out_.numFaces; ++f) out_.report.flippedFaces += flip_->get(f);
    setsOnDisk_ |= faces.onDisk();
  }

  /// The sides of an edge after the flips: corners renamed, directions turned, by corner again.
  void applyFlips(std::vector<EdgeSide>& sides) {
    if (!flip_) return;
    bool changed = false;
    for (EdgeSide& s : sides) {
      if (!flip_->get(s.corner / 3)) continue;
      s.corner = flippedCorner(s.corner);
      std::swap(s.from, s.to);
      changed = true;
    }
    if (changed) std::sort(sides.begin(), sides.end(), EdgeSideLess{});
  }

  /// cleanMesh's gluing: an edge of two faces in opposite directions is glued, two in the same
  /// direction stay open (a clash); on an edge of more than two faces, pairs of opposite
  /// directions are glued, pairs between large pieces first, then the most aligned normals.
  /// `simple`: stops (false) at the first edge of two sides in one direction or of more than two.
  bool glue(bool simple) {
    PairSorter pairs(folder_, 3 * out_.numFaces, 3 * out_.numFaces, sortOptions("clean: glue"));
    std::unique_ptr<ScratchUnionFind> pieces;
    if (multiEdges_ > 0) pieces = std::make_unique<ScratchUnionFind>(folder_, out_.numFaces, piecesBytes_, "clean: glue");
    std::vector<std::vector<EdgeSide>> multi;
    const bool whole = forEachEdge([&](std::vector<EdgeSide>& sides) {
      applyFlips(sides);
      if (simple && (sides.size() > 2 || (sides.size() == 2 && sides[0].forward() == sides[1].forward()))) return false;
      if (sides.size() > 2) {
        ++out_.report.nonManifoldEdges;
        multi.push_back(sides);
      } else if (sides.size() == 2 && sides[0].forward() == sides[1].forward()) {
        ++out_.report.nonManifoldEdges;
      } else if (sides.size() == 2) {
        pairs.add({sides[0].corner, sides[1].corner});
        pairs.add({sides[1].corner, sides[0].corner});
        if (pieces) pieces->unite(sides[0].corner / 3, sides[1].corner / 3);
      }
      return true;
    });
    if (!whole) return false;
    if (!multi.empty()) pairMultiEdges(multi, *pieces, pairs);
    if (pieces) setsOnDisk_ |= pieces->onDisk();
    pieces.reset();
    pairs.finish();
    ScratchWriter out(folder_, "clean: glue");
    CornerPair next{kInvalidId, kInvalidId};
    bool more = pairs.next(next);
    for (CornerId c = 0; c < 3 * out_.numFaces; ++c) {
      CornerId o = kInvalidId;
      if (more && next.corner == c) {
        o = next.other;
        more = pairs.next(next);
      }
      out.write(&o, sizeof o);
    }
    out_.opposite = out.finish();
    return true;
  }

  /// The faces' gluing normals (cleanMesh's gluingNormal of the oriented face) for the few faces
  /// on edges of more than two faces: their triangles and positions read where they lie.
  std::unordered_map<FaceId, Vec3d> gluingNormals(const std::vector<std::vector<EdgeSide>>& multi) {
    std::vector<FaceId> faces;
    for (const auto& sides : multi) {
      for (const EdgeSide& s : sides) faces.push_back(s.corner / 3);
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    std::unordered_map<FaceId, Vec3d> normal;
    ScratchRandomReader triangles(folder_, faces_, "clean: glue"), positions(folder_, positions_, "clean: glue");
    for (const FaceId f : faces) {
      CleanFace face;
      triangles.readAt(std::uint64_t(f) * sizeof(CleanFace), &face, sizeof face);
      Vec3d p[3];
      for (int k = 0; k < 3; ++k) {
        Vec3f q;
        positions.readAt(std::uint64_t(face.triangle[k]) * sizeof(Vec3f), &q, sizeof q);
        p[k] = q.cast<double>();
      }
      if (flip_ && flip_->get(f)) std::swap(p[1], p[2]);
      normal[f] = gluingNormal(p[0], p[1], p[2]);
    }
    return normal;
  }

  void pairMultiEdges(const std::vector<std::vector<EdgeSide>>& multi, ScratchUnionFind& pieces, PairSorter& pairs) {
    // Per face, its piece's size (capped): counted per root.
    std::unordered_map<std::uint32_t, std::uint32_t> wanted;
    for (const auto& sides : multi) {
      for (const EdgeSide& s : sides) wanted[pieces.find(s.corner / 3)] = 0;
    }
    for (FaceId f = 0; f < out_.numFaces; ++f) {
      const auto it = wanted.find(pieces.find(f));
      if (it != wanted.end() && it->second < kLargePieceFaces) ++it->second;
    }
    const std::unordered_map<FaceId, Vec3d> normal = gluingNormals(multi);
    struct Pair {
      std::uint32_t smallerPiece;
      double alignment;
      CornerId x, y;
    };
    std::vector<Pair> candidates;
    for (const auto& sides : multi) {
      // `same`: the sides running like the edge's smallest corner; `reverse`: the others.
      const bool direction = sides[0].forward();
      candidates.clear();
      for (const EdgeSide& x : sides) {
        if (x.forward() != direction) continue;
        for (const EdgeSide& y : sides) {
          if (y.forward() == direction) continue;
          const FaceId fx = x.corner / 3, fy = y.corner / 3;
          candidates.push_back({std::min(wanted.at(pieces.find(fx)), wanted.at(pieces.find(fy))),
                                gluingAlignment(normal.at(fx), normal.at(fy)), x.corner, y.corner});
        }
      }
      std::sort(candidates.begin(), candidates.end(), [](const Pair& p, const Pair& q) {
        if (p.smallerPiece != q.smallerPiece) return p.smallerPiece > q.smallerPiece;
        return p.alignment != q.alignment ? p.alignment > q.alignment : p.x != q.x ? p.x < q.x : p.y < q.y;
      });
      std::vector<CornerId> used;
      for (const Pair& p : candidates) {
        if (std::find(used.begin(), used.end(), p.x) != used.end() ||
            std::find(used.begin(), used.end(), p.y) != used.end()) {
          continue;
        }
        used.push_back(p.x);
        used.push_back(p.y);
        pairs.add({p.x, p.y});
        pairs.add({p.y, p.x});
      }
    }
  }

  /// Fans: the corners around each vertex joined through glued edges (a sort by vertex). A
  /// vertex's first fan (the one with its smallest corner) keeps it; every further fan gets a new
  /// vertex, numbered after all others in the order of their vertices (cleanMesh's
  /// splitNonManifoldVertices). Fan starts as Topology::build picks them.
  void splitVertices() {
    if (glued_) return;
    KeyedSorter<CornerAround, CornerAroundLess, CornerAroundKey> around(folder_, out_.numVertices, 3 * out_.numFaces,
                                                                         sortOptions("clean: fans"));
    {
      ScratchReader faces(folder_, faces_, "clean: fans"), opposite(folder_, out_.opposite, "clean: fans");
      CleanFace face;
      CornerId o[3];
      for (FaceId f = 0; faces.read(&face, sizeof face); ++f) {
        if (!opposite.read(o, sizeof o)) throw IoError(out_.opposite.path + ": scratch corner table ends early");
        const Triangle t = oriented(f, face.triangle);
        for (int k = 0; k < 3; ++k) {
          // Clockwise of corner c around its vertex: prev(opposite(prev c)).
          const CornerId across = o[(k + 2) % 3];
          around.add({t[k], 3 * f + k, across == kInvalidId ? kInvalidId : prevCorner(across)});
        }
      }
    }
    around.finish();
    ScratchWriter starts(folder_, "clean: fans");
    moved_ = std::make_unique<ExternalSorter<CornerPair>>(folder_, sortOptions("clean: fans"));
    ExternalSorter<CornerPair>& moved = *moved_;
    std::vector<VertexId> copyBoundary;  // the copies with an open fan (their ids follow the others')
    std::vector<CornerId> copyStarts;
    std::vector<VertexId> copyOf;
    std::vector<CornerAround> group;
    std::vector<std::uint32_t> root, fanOf;  // findFans', reused from vertex to vertex
    std::vector<detail::FanStart> fans;
    CornerAround next{};
    bool more = around.next(next);
    VertexId copy = static_cast<VertexId>(out_.numVertices);
    while (more) {
      group.assign(1, next);
      while ((more = around.next(next)) && next.vertex == group[0].vertex) group.push_back(next);
      detail::findFans(group, root, fanOf, fans);
      if (fans[0].open) boundary_.push_back(group[0].vertex);
      starts.write(&fans[0].start, sizeof fans[0].start);
      for (std::uint32_t i = 1; i < fans.size(); ++i) {
        if (fans[i].open) copyBoundary.push_back(copy);
        copyStarts.push_back(fans[i].start);
        copyOf.push_back(group[0].vertex);
        for (std::size_t j = 0; j < group.size(); ++j) {
          if (fanOf[j] == i) moved.add({group[j].corner, copy});
        }
        ++copy;
      }
      out_.report.nonManifoldVertices += fans.size() > 1;
    }
    for (const CornerId c : copyStarts) starts.write(&c, sizeof c);
    boundary_.insert(boundary_.end(), copyBoundary.begin(), copyBoundary.end());
    out_.vertexCorner = starts.finish();
    moved.finish();
    placeCopies(copyOf);
  }

  /// The copies of split vertices (copyOf: the vertex each copies, in the copies' order) get
  /// their vertices' positions and origins, after the others'.
  void placeCopies(const std::vector<VertexId>& copyOf) {
    if (!copyOf.empty()) {
      ScratchRandomReader positions(folder_, positions_, "clean: fans"), origin(folder_, out_.vertexOrigin, "clean: fans");
      std::vector<Vec3f> p(copyOf.size());
      std::vector<VertexId> from(copyOf.size());
      for (std::size_t i = 0; i < copyOf.size(); ++i) {
        positions.readAt(std::uint64_t(copyOf[i]) * sizeof(Vec3f), &p[i], sizeof(Vec3f));
        origin.readAt(std::uint64_t(copyOf[i]) * sizeof(VertexId), &from[i], sizeof(VertexId));
      }
      positions_ = appendTo(positions_, p.data(), p.size() * sizeof(Vec3f), "clean: fans");
      out_.vertexOrigin = appendTo(out_.vertexOrigin, from.data(), from.size() * sizeof(VertexId), "clean: fans");
    }
    out_.positions = positions_;
    out_.numVertices += copyOf.size();
  }

  /// A copy of a scratch file with bytes appended (the old one removed).
  ScratchFile appendTo(const ScratchFile& file, const void* data, std::size_t bytes, const char* stage) {
    ScratchReader in(folder_, file, stage);
    ScratchWriter out(folder_, stage);
    std::vector<char> buffer(1u << 20);
    for (std::size_t n; (n = in.readUpTo(buffer.data(), buffer.size())) > 0;) out.write(buffer.data(), n);
    out.write(data, bytes);
    folder_.remove(file);
    return out.finish();
  }

  Triangle oriented(FaceId f, Triangle t) {
    if (flip_ && flip_->get(f)) std::swap(t[1], t[2]);
    return t;
  }

  /// The final faces: oriented, corners of split fans on their copies.
  void writeFaces() {
    if (!flip_ && moved_->size() == 0) {
      out_.faces = faces_;  // none oriented, none moved: the faces as read are final
      return;
    }
    ScratchReader in(folder_, faces_, "clean: write");
    ScratchWriter out(folder_, "clean: write");
    CornerPair next{kInvalidId, kInvalidId};
    bool more = moved_->next(next);
    CleanFace face;
    for (FaceId f = 0; in.read(&face, sizeof face); ++f) {
      face.triangle = oriented(f, face.triangle);
      for (CornerId c = 3 * f; c < 3 * f + 3; ++c) {
        if (more && next.corner == c) {
          face.triangle[c - 3 * f] = next.other;
          more = moved_->next(next);
        }
      }
      out.write(&face, sizeof face);
    }
    folder_.remove(faces_);
    out_.faces = out.finish();
  }

  /// Spikes (cleanMesh's count): per vertex the lengths of the two edges of each of its corners
  /// (as forEachEdgeLength gives them), their median (typical) and least (shortest); then a
  /// vertex whose shortest edge is over kSpikeRatio times the least and the median of its
  /// neighbours' typical lengths, that median positive. Increasing. One walk around each fan, in
  /// blocks of spikeBlock vertices: a block's neighbour lists and lengths, and its verdicts once
  /// the next block's are in (a neighbour outside those three blocks: its typical length by a walk
  /// of its own).
  std::vector<VertexId> findSpikes() {
    struct Block {
      std::uint64_t first = 0, count = 0;
      std::vector<double> typical, shortest;
      // Per chunk of kChunk vertices their neighbours, as the walk meets them, and where each starts.
      std::vector<std::vector<VertexId>> neighbours;
      std::vector<std::vector<std::uint32_t>> start;
    };
    const std::uint64_t kBlock = std::max<std::uint64_t>(1, options_.spikeBlock), kChunk = 1024;
    const std::uint64_t nv = out_.numVertices;
    const std::size_t cacheBytes = pageCacheBytes(sort_.memoryBytes);
    struct Readers {
      PagedCornerTable table;
      PagedReader<Vec3f> positions;
      std::vector<VertexId> around;
      std::vector<double> values;
      // Typical lengths of neighbours beyond the blocks held, walked once per block (a pole
      // named early has every vertex of its ring beyond its block).
      std::unordered_map<VertexId, double> far;
      std::uint64_t farBlock = ~std::uint64_t(0);
    };
    ReaderPool<Readers> pool([&] {
      return std::unique_ptr<Readers>(new Readers{PagedCornerTable(out_, cacheBytes), PagedReader<Vec3f>(out_.positions, cacheBytes), {}, {}, {}});
    });
    // v's neighbours (each edge once around an interior vertex, both of each corner's on the
    // boundary) into r.around, and its typical and shortest lengths (squared lengths, two roots:
    // the same values as findSpikeVertices).
    const auto walk = [](Readers& r, VertexId v, double& typical, double& shortest) {
      r.around.clear();
      r.values.clear();
      const Vec3d p = r.positions[v].cast<double>();
      const bool interior = !r.table.isBoundaryVertex(v);
      r.table.forEachCornerAround(v, [&](CornerId c) {
        r.around.push_back(r.table.vertex(nextCorner(c)));
        if (!interior) r.around.push_back(r.table.vertex(prevCorner(c)));
      });
      for (const VertexId w : r.around) r.values.push_back((r.positions[w].cast<double>() - p).squaredNorm());
      typical = shortest = 0.0;
      if (r.values.empty()) return;
      shortest = std::sqrt(*std::min_element(r.values.begin(), r.values.end()));
      const auto middle = r.values.begin() + static_cast<std::ptrdiff_t>(r.values.size() / 2);
      std::nth_element(r.values.begin(), middle, r.values.end());
      typical = std::sqrt(*middle);
    };
    const auto measureBlock = [&](Block& block, std::uint64_t first) {
      block.first = first;
      block.count = std::min(kBlock, nv - first);
      block.typical.assign(block.count, 0.0);
      block.shortest.assign(block.count, 0.0);
      const std::size_t chunks = static_cast<std::size_t>((block.count + kChunk - 1) / kChunk);
      block.neighbours.resize(chunks);
      block.start.resize(chunks);
      parallelFor(chunks, 1, [&](const IndexRange& range) {
        auto r = pool.take();
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          std::vector<VertexId>& ids = block.neighbours[k];
          std::vector<std::uint32_t>& start = block.start[k];
          ids.clear();
          start.assign(1, 0);
          for (std::uint64_t i = k * kChunk; i < std::min(block.count, (k + 1) * kChunk); ++i) {
            walk(*r, static_cast<VertexId>(first + i), block.typical[i], block.shortest[i]);
            ids.insert(ids.end(), r->around.begin(), r->around.end());
            start.push_back(static_cast<std::uint32_t>(ids.size()));
          }
        }
      });
    };
    std::vector<VertexId> spikes;
    std::mutex spikesMutex;
    Block before, current, after;
    if (nv > 0) measureBlock(after, 0);
    for (std::uint64_t first = 0; first < nv; first += kBlock) {
      std::swap(before, current);
      std::swap(current, after);
      if (first + kBlock < nv) {
        measureBlock(after, first + kBlock);
      } else {
        after.count = 0;
      }
      const Block* window[3] = {&before, &current, &after};
      const std::size_t chunks = current.neighbours.size();
      parallelFor(chunks, 1, [&](const IndexRange& range) {
        auto r = pool.take();
        std::vector<double> around;
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          for (std::uint64_t i = k * kChunk; i < std::min(current.count, (k + 1) * kChunk); ++i) {
            const std::uint32_t local = static_cast<std::uint32_t>(i - k * kChunk);
            const VertexId* from = current.neighbours[k].data() + current.start[k][local];
            const VertexId* to = current.neighbours[k].data() + current.start[k][local + 1];
            if (from == to) continue;
            around.clear();
            for (const VertexId* at = from; at != to; ++at) {
              const VertexId w = *at;
              const Block* in = nullptr;
              for (const Block* b : window) {
                if (b->count > 0 && w >= b->first && w < b->first + b->count) in = b;
              }
              double typical = 0.0, shortest = 0.0;
              if (in) {
                typical = in->typical[w - in->first];
              } else {
                if (r->farBlock != first) r->far.clear(), r->farBlock = first;
                const auto [known, added] = r->far.emplace(w, 0.0);
                if (added) walk(*r, w, known->second, shortest);
                typical = known->second;
              }
              around.push_back(typical);
            }
            // The median is at least the least value: most vertices are decided without it.
            const double least = current.shortest[i];
            if (!(least > kSpikeRatio * *std::min_element(around.begin(), around.end()))) continue;
            const auto middle = around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2);
            std::nth_element(around.begin(), middle, around.end());
            const double scale = *middle;
            if (scale > 0.0 && least > kSpikeRatio * scale) {
              std::lock_guard<std::mutex> lock(spikesMutex);
              spikes.push_back(static_cast<VertexId>(first + i));
            }
          }
        }
      });
    }
    pool.forEach([&](Readers& r) { folder_.countRead("clean: measure", r.table.bytesRead() + r.positions.bytesRead()); });
    std::sort(spikes.begin(), spikes.end());
    return spikes;
  }

  /// cleanMesh's last counts (the zero-area faces come from the weld): boundary vertices at the
  /// position of another of another origin (cracks), spikes and the bounding box diagonal without
  /// them.
  void measure() {
    CleanReport& r = out_.report;
    const std::vector<VertexId> spikes = findSpikes();
    r.spikeVertices = spikes.size();
    // Boundary points at one position with two origins, and the box without the spikes.
    ExternalSorter<BoundaryPoint> points(folder_, sortOptions("clean: measure"));
    BoundingBox kept;
    {
      ScratchReader positions(folder_, out_.positions, "clean: measure"), origin(folder_, out_.vertexOrigin, "clean: measure");
      Vec3f p;
      VertexId from = 0;
      std::size_t nextSpike = 0, nextBoundary = 0;
      for (VertexId v = 0; positions.read(&p, sizeof p); ++v) {
        if (!origin.read(&from, sizeof from)) throw IoError(out_.vertexOrigin.path + ": scratch file ends early");
        if (nextBoundary < boundary_.size() && boundary_[nextBoundary] == v) {
          ++nextBoundary;
          points.add({{p.x(), p.y(), p.z()}, from});
        }
        if (nextSpike < spikes.size() && spikes[nextSpike] == v) {
          ++nextSpike;
          continue;
        }
        kept.min = kept.min.cwiseMin(p.cast<double>());
        kept.max = kept.max.cwiseMax(p.cast<double>());
      }
    }
    r.diagonalWithoutSpikes = kept.isEmpty() ? 0.0 : kept.diagonal();
    points.finish();
    std::vector<BoundaryPoint> same;
    BoundaryPoint point{};
    bool more = points.next(point);
    while (more) {
      same.assign(1, point);
      while ((more = points.next(point)) && point.p[0] == same[0].p[0] && point.p[1] == same[0].p[1] &&
             point.p[2] == same[0].p[2]) {
        same.push_back(point);
      }
      if (same.back().origin != same.front().origin) r.unweldedBoundaryVertices += same.size();
    }
    std::vector<VertexId>().swap(boundary_);
  }

  ScratchFolder& folder_;
  const WeldedScratch& welded_;
  CleanStreamOptions options_;
  ExternalSortOptions sort_;
  CleanScratch out_;
  std::vector<VertexId> newId_;
  bool renumberBySorts_ = false;
  bool facesRead_ = false;  // renumberVertices wrote the faces on their new ids
  bool tryFront_ = false, glued_ = false;  // the front pass runs; it glued the edges and split the fans
  std::vector<FaceId> lastFace_;           // per vertex, for the front pass
  ScratchFile cornerNewId_;  // with renumberBySorts_: each corner's new vertex id, in face order
  ScratchFile positions_, faces_;
  std::unique_ptr<EdgeSorter> edges_;  // kept until the gluing is done
  std::unique_ptr<ExternalSorter<CornerPair>> moved_;  // corners moved to a copy of their vertex
  std::unique_ptr<ScratchArray<std::uint8_t>> flip_;  // per face, when the orientation changed any
  std::uint64_t orientBytes_ = 0, flipBytes_ = 0, piecesBytes_ = 0;
  bool setsOnDisk_ = false;
  std::uint64_t multiEdges_ = 0, clashes_ = 0;  ///< edges of more than two sides; of two in one direction
  std::vector<VertexId> boundary_;  // the vertices whose fan is open, increasing
};

}  // namespace

CleanScratch cleanWeldedMesh(ScratchFolder& folder, const WeldedScratch& welded, const WeldCensus& census,
                             const CleanStreamOptions& options) {
  return CleanPass(folder, welded, census, options).run();
}

namespace {

/// Joins the faces of every glued edge (one pass over the opposite corners).
void uniteGluedFaces(ScratchFolder& folder, const CleanScratch& scratch, ScratchUnionFind& faces,
                     const std::string& stage) {
  ScratchReader opposite(folder, scratch.opposite, stage);
  CornerId o;
  for (CornerId c = 0; opposite.read(&o, sizeof o); ++c) {
    if (o != kInvalidId && c < o) faces.unite(c / 3, o / 3);
  }
}

}  // namespace

ComponentsResult cleanedComponents(ScratchFolder& folder, const CleanScratch& scratch, std::uint64_t memoryBytes) {
  const std::uint64_t nf = scratch.numFaces, nv = scratch.numVertices;
  // Faces joined through glued edges; a component's id in the order of its smallest face.
  ScratchUnionFind faces(folder, nf, memoryBytes / 2, "components");
  uniteGluedFaces(folder, scratch, faces, "components");
  std::unordered_map<std::uint32_t, std::uint32_t> id;  // root face -> component
  std::vector<ComponentInfo> comps;
  for (FaceId f = 0; f < nf; ++f) {
    const std::uint32_t root = faces.find(f);
    if (root == f) id[f] = static_cast<std::uint32_t>(comps.size()), comps.emplace_back();
    ++comps[id.at(root)].faces;
  }
  const auto componentOf = [&](FaceId f) -> ComponentInfo& { return comps[id.at(faces.find(f))]; };
  {
    ScratchReader starts(folder, scratch.vertexCorner, "components");
    CornerId c;
    while (starts.read(&c, sizeof c)) {
      if (c != kInvalidId) ++componentOf(c / 3).vertices;
    }
  }
  // Edges: one per glued pair and per boundary corner. Boundary loops: the cycles of boundary
  // edges (every boundary vertex has one edge in and one out), as sets of vertices joined by them.
  ScratchUnionFind loops(folder, nv, memoryBytes / 4, "components");
  const auto forEachCorner = [&](auto&& visit) {
    ScratchReader triangles(folder, scratch.faces, "components"), opposite(folder, scratch.opposite, "components");
    CleanFace face;
    CornerId o[3];
    for (FaceId f = 0; triangles.read(&face, sizeof face); ++f) {
      if (!opposite.read(o, sizeof o)) throw IoError(scratch.opposite.path + ": scratch corner table ends early");
      for (int k = 0; k < 3; ++k) visit(3 * f + k, o[k], face.triangle[(k + 1) % 3], face.triangle[(k + 2) % 3]);
    }
  };
  forEachCorner([&](CornerId c, CornerId o, VertexId a, VertexId b) {
    if (o == kInvalidId) loops.unite(a, b);
    if (o == kInvalidId || c < o) ++componentOf(c / 3).edges;
  });
  ScratchArray<std::uint8_t> counted(folder, nv, memoryBytes / 8, "components");
  forEachCorner([&](CornerId c, CornerId o, VertexId a, VertexId) {
    if (o != kInvalidId) return;
    const std::uint32_t loop = loops.find(a);
    if (!counted.get(loop)) ++componentOf(c / 3).boundaryLoops;
    counted.set(loop, 1);
  });
  ComponentsResult result;
  for (ComponentInfo& info : comps) {
    info.eulerCharacteristic = std::int64_t(info.vertices) - std::int64_t(info.edges) + info.faces;
    info.genus = (2 - info.eulerCharacteristic - info.boundaryLoops) / 2;
    result.boundaryLoops += info.boundaryLoops;
  }
  std::stable_sort(comps.begin(), comps.end(), [](const ComponentInfo& a, const ComponentInfo& b) { return a.faces > b.faces; });
  result.components = std::move(comps);
  return result;
}

std::vector<FaceId> scratchIslandFaces(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t maxFaces,
                                       std::uint64_t memoryBytes) {
  ScratchUnionFind faces(folder, scratch.numFaces, memoryBytes / 2, "islands");
  uniteGluedFaces(folder, scratch, faces, "islands");
  ScratchArray<std::uint32_t> counts(folder, scratch.numFaces, memoryBytes / 4, "islands");
  return detail::islandFacesOf(scratch.numFaces, faces, counts, maxFaces);
}

BoundingBox scratchBoundingBox(ScratchFolder& folder, const ScratchFile& positions, const std::string& stage) {
  BoundingBox box;
  ScratchReader reader(folder, positions, stage);
  std::vector<Vec3f> block(std::size_t(1) << 16);
  for (std::uint64_t left = positions.bytes / sizeof(Vec3f); left > 0;) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, block.size()));
    if (!reader.read(block.data(), n * sizeof(Vec3f))) throw IoError(positions.path + ": scratch positions end early");
    for (std::size_t i = 0; i < n; ++i) {
      box.min = box.min.cwiseMin(block[i].cast<double>());
      box.max = box.max.cwiseMax(block[i].cast<double>());
    }
    left -= n;
  }
  return box;
}

CleanResult readCleanScratch(ScratchFolder& folder, const CleanScratch& scratch) {
  CleanResult r;
  const std::vector<CleanFace> faces = readWholeScratch<CleanFace>(folder, scratch.faces, scratch.numFaces, "clean: read");
  r.mesh.triangles.resize(faces.size());
  r.faceOrigin.resize(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    r.mesh.triangles[f] = faces[f].triangle;
    r.faceOrigin[f] = faces[f].inputFace;
  }
  r.mesh.positions = readWholeScratch<Vec3f>(folder, scratch.positions, scratch.numVertices, "clean: read");
  r.mesh.origin = scratch.origin;
  r.vertexOrigin = readWholeScratch<VertexId>(folder, scratch.vertexOrigin, scratch.numVertices, "clean: read");
  r.topology = Topology::viewParts(r.mesh.triangles, readWholeScratch<CornerId>(folder, scratch.opposite, 3 * scratch.numFaces, "clean: read"),
                                   readWholeScratch<CornerId>(folder, scratch.vertexCorner, scratch.numVertices, "clean: read"));
  r.report = scratch.report;
  return r;
}

}  // namespace seamvox
