#include "stream/welded_scratch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include "core/system/errors.h"
#include "stream/external_sort.h"
#include "stream/keyed_sort.h"
#include "stream/scratch_union_find.h"

namespace seamvox {
namespace {

constexpr std::uint64_t kMinimumSortBytes = std::uint64_t(1) << 20;

/// A vertex for the weld sort: its position (-0 as +0, so equal floats sort together) and id.
struct PositionRecord {
  float x, y, z;
  std::uint32_t id;
};
struct PositionLess {
  bool operator()(const PositionRecord& a, const PositionRecord& b) const {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    if (a.z != b.z) return a.z < b.z;
    return a.id < b.id;
  }
};

/// An input vertex and the lowest input vertex at its position, sorted by the first.
struct VertexPair {
  std::uint32_t vertex, other;
  bool operator<(const VertexPair& o) const { return vertex < o.vertex; }
};

/// A welded face for the duplicate sort: faces with the same vertex set sort together, the
/// lowest input index (the one cleanMesh keeps) first.
struct FaceRecord {
  std::array<VertexId, 3> vertices;  ///< sorted
  std::uint32_t face;
  std::uint32_t order;  ///< the input's corner k is vertices[(order >> 2k) & 3] (20 bytes, not 28)
  Triangle triangle() const {
    return {vertices[order & 3], vertices[(order >> 2) & 3], vertices[(order >> 4) & 3]};
  }
};
static_assert(sizeof(FaceRecord) == 20, "the duplicate sort's records");
FaceRecord faceRecord(const Triangle& t, std::uint32_t face) {
  FaceRecord r{{t[0], t[1], t[2]}, face, 0};
  std::sort(r.vertices.begin(), r.vertices.end());
  for (std::uint32_t k = 0; k < 3; ++k) {
    const std::uint32_t at = static_cast<std::uint32_t>(std::find(r.vertices.begin(), r.vertices.end(), t[k]) - r.vertices.begin());
    r.order |= at << (2 * k);
  }
  return r;
}
struct SameVerticesLess {
  bool operator()(const FaceRecord& a, const FaceRecord& b) const {
    return a.vertices != b.vertices ? a.vertices < b.vertices : a.face < b.face;
  }
};

/// One side of an edge: its vertices (lo < hi) and whether the face runs lo -> hi.
struct EdgeRecord {
  std::uint32_t lo, hi, forward;
};
struct EdgeLess {
  bool operator()(const EdgeRecord& a, const EdgeRecord& b) const {
    return a.lo != b.lo ? a.lo < b.lo : a.hi < b.hi;
  }
};

/// A corner waiting for its position (sorted by vertex), then with it (sorted by face, corner).
struct CornerRecord {
  std::uint32_t vertex, face, slot;
};
struct ByVertexLess {
  bool operator()(const CornerRecord& a, const CornerRecord& b) const { return a.vertex < b.vertex; }
};
struct PlacedCorner {
  std::uint32_t face, slot, vertex;
  std::array<float, 3> position;
};
struct ByCornerLess {
  bool operator()(const PlacedCorner& a, const PlacedCorner& b) const {
    return a.face != b.face ? a.face < b.face : a.slot < b.slot;
  }
};

/// A kept face with its corners' positions, between the weld's positions and Morton passes.
struct PlacedFace {
  WeldedFace face;
  std::array<float, 3> corners[3]{};  ///< plain floats: written as bytes
  Vec3f corner(int k) const { return Vec3f(corners[k][0], corners[k][1], corners[k][2]); }
};

/// The triangle's vertex ids in increasing order.
std::array<VertexId, 3> sortedVertices(const Triangle& t) {
  std::array<VertexId, 3> v{t[0], t[1], t[2]};
  std::sort(v.begin(), v.end());
  return v;
}

/// Morton order, then the vertex set, then the input index: faces on one vertex set (duplicates)
/// stay together, the one cleanMesh keeps first.
struct MortonLess {
  bool operator()(const WeldedFace& a, const WeldedFace& b) const {
    if (a.morton != b.morton) return a.morton < b.morton;
    const auto x = sortedVertices(a.triangle), y = sortedVertices(b.triangle);
    return x != y ? x < y : a.face < b.face;
  }
};

/// A face for the Morton sort that also finds duplicates (the weld without its census): its
/// code and its duplicate-sort record, in MortonLess's order.
struct MortonFace {
  std::uint32_t high, low;  ///< the Morton code's halves (28 bytes, not 32)
  FaceRecord record;
  std::uint64_t morton() const { return std::uint64_t(high) << 32 | low; }
};
static_assert(sizeof(MortonFace) == 28, "the fused Morton sort's records");
struct MortonFaceLess {
  bool operator()(const MortonFace& a, const MortonFace& b) const {
    if (a.high != b.high || a.low != b.low) return std::tie(a.high, a.low) < std::tie(b.high, b.low);
    return SameVerticesLess{}(a.record, b.record);
  }
};

/// The Morton sorts' keys: a code's leading 24 bits (256 cells along each axis of the box), so
/// the keyed sort's counts take 64 MB; the faces of one such cell are sorted by the whole order.
constexpr int kMortonKeyBits = 24;
constexpr std::uint64_t kMortonKeys = std::uint64_t(1) << kMortonKeyBits;
struct MortonKey {
  std::uint64_t operator()(const WeldedFace& f) const { return f.morton >> (3 * kMortonBits - kMortonKeyBits); }
  std::uint64_t operator()(const MortonFace& f) const { return f.morton() >> (3 * kMortonBits - kMortonKeyBits); }
};

/// The centroid summed in the order of the vertex ids: the same for every face on the vertex set.
template <class CornerOf>
Vec3d sortedCentroid(const Triangle& t, CornerOf&& corner) {
  int k[3] = {0, 1, 2};
  std::sort(k, k + 3, [&](int a, int b) { return t[a] < t[b]; });
  const Vec3d a = corner(k[0]), b = corner(k[1]), c = corner(k[2]);
  return (a + b + c) / 3.0;
}

/// Per component (by union-find root) what the passes count.
struct ComponentCount {
  std::uint64_t faces = 0, vertices = 0, edges = 0, loops = 0;
};

/// Boundary loops as sets of boundary vertices joined by their boundary edges: a map of the
/// boundary vertices while it fits memoryBytes, then a ScratchUnionFind over every vertex with a
/// flag per boundary vertex (a mesh of many holes or unwelded faces). The same loops either way.
class LoopSets {
 public:
  LoopSets(ScratchFolder& folder, std::uint64_t numVertices, std::uint64_t memoryBytes)
      : folder_(folder), numVertices_(numVertices), memoryBytes_(memoryBytes) {}

  void join(std::uint32_t a, std::uint32_t b) {
    if (sets_) {
      flags_->set(a, 1), flags_->set(b, 1);
      sets_->unite(a, b);
      return;
    }
    detail::uniteRoots(map_, a, b);
    if (map_.size() * kMapEntryBytes > memoryBytes_) moveToSets();
  }
  /// visit(v) for one vertex v of each loop.
  template <class Visit>
  void forEachLoop(Visit&& visit) {
    if (!sets_) {
      for (const auto& entry : map_.parent) {
        if (detail::findRoot(map_, entry.first) == entry.first) visit(entry.first);
      }
      return;
    }
    for (std::uint32_t v = 0; v < numVertices_; ++v) {
      if (flags_->get(v) && sets_->find(v) == v) visit(v);
    }
  }
  bool onDisk() const { return sets_ && sets_->onDisk(); }

 private:
  static constexpr std::uint64_t kMapEntryBytes = 48;  // a node, its bucket and the allocator's share

  /// The union-find's links over the boundary vertices seen so far (a vertex enters as its own root).
  struct MapLinks {
    std::unordered_map<std::uint32_t, std::uint32_t> parent;
    std::uint32_t parentOf(std::uint32_t x) { return parent.emplace(x, x).first->second; }
    void setParent(std::uint32_t x, std::uint32_t p) { parent[x] = p; }
    std::size_t size() const { return parent.size(); }
  };

  void moveToSets() {
    const std::uint64_t share = memoryBytes_ / 5;  // a byte of flags per 4 of links
    sets_ = std::make_unique<ScratchUnionFind>(folder_, numVertices_, 4 * share, "weld: loops");
    flags_ = std::make_unique<ScratchArray<std::uint8_t>>(folder_, numVertices_, share, "weld: loops");
    for (const auto& [v, parent] : map_.parent) {
      flags_->set(v, 1);
      sets_->unite(v, parent);
    }
    MapLinks().parent.swap(map_.parent);
  }

  ScratchFolder& folder_;
  std::uint64_t numVertices_, memoryBytes_;
  MapLinks map_;  // boundary vertex -> parent, while the map fits
  std::unique_ptr<ScratchUnionFind> sets_;
  std::unique_ptr<ScratchArray<std::uint8_t>> flags_;
};

/// The passes of weldMeshStream, in order; each reads what the one before wrote.
class WeldPass {
 public:
  WeldPass(MeshStream& stream, ScratchFolder& folder, const WeldStreamOptions& options)
      : stream_(stream), folder_(folder), options_(options), name_(stream.name()) {
    options_.weld = options_.weld || stream.cornerVertices();  // STL: its corners are welded always
    sort_.memoryBytes = std::max(kMinimumSortBytes, options.memoryBytes / 3);
    // The sets (components, boundary loops): a quarter each, alongside at most two sorts; tests
    // put them on disk with a small cache.
    setsBytes_ = options.setsOnDisk ? 0 : options.memoryBytes / 4;
  }

  WeldStreamResult run() {
    const std::pair<const char*, void (WeldPass::*)()> passes[] = {
        {"read", &WeldPass::readStream},       {"weld", &WeldPass::weldVertices},
        {"faces", &WeldPass::renumberFaces},   {"duplicates", &WeldPass::dropDuplicateFaces},
        {"edges", &WeldPass::countEdges},      {"positions", &WeldPass::placeCorners},
        {"morton", &WeldPass::sortByMorton},   {"components", &WeldPass::countComponents}};
    for (const auto& [name, pass] : passes) {
      const auto start = std::chrono::steady_clock::now();
      (this->*pass)();
      result_.census.stageSeconds.emplace_back(
          name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    result_.scratch.numVertices = welded_;
    return std::move(result_);
  }

 private:
  ExternalSortOptions sortOptions(const char* stage) const { return sort_.named(stage); }

  /// Pass 1: positions and triangles to scratch as read; the weld sort fed.
  void readStream() {
    StreamChecker checker(name_);
    ScratchWriter positions(folder_, "read"), triangles(folder_, "read");
    if (options_.weld) weldSort_ = std::make_unique<ExternalSorter<PositionRecord, PositionLess>>(folder_, sortOptions("weld"));
    MeshChunk chunk;
    bool first = true;
    while (stream_.next(chunk)) {
      checker.check(chunk);
      if (first && !chunk.positions.empty()) {
        result_.census.properties = chunk.attributes.emptyCopy();
        first = false;
      }
      for (std::size_t i = 0; i < chunk.positions.size(); ++i) {
        const Vec3f& p = chunk.positions[i];
        const std::uint32_t v = chunk.firstVertex + static_cast<std::uint32_t>(i);
        if (!p.allFinite()) {
          throw InputError(name_ + ": vertex " + std::to_string(v) + " has a non-finite coordinate (NaN or inf)");
        }
        if (weldSort_) weldSort_->add({p.x() + 0.0f, p.y() + 0.0f, p.z() + 0.0f, v});
      }
      positions.write(chunk.positions.data(), chunk.positions.size() * sizeof(Vec3f));
      triangles.write(chunk.triangles.data(), chunk.triangles.size() * sizeof(Triangle));
    }
    checker.finish();
    result_.census.origin = checker.origin();
    result_.census.inputVertices = checker.vertices();
    result_.census.inputFaces = checker.faces();
    if (checker.faces() == 0) throw InputError(name_ + ": the mesh has no faces");
    inputPositions_ = positions.finish();
    inputTriangles_ = triangles.finish();
  }

  /// Pass 2: welded id per input vertex (clusters numbered by their lowest input id) and the
  /// welded positions (the lowest input id's). The clusters come from the position sort; each
  /// vertex's lowest id goes back to input order through a sort by id, so that the welded ids
  /// are numbered in one pass in input order, the lowest id's looked up behind (the ids within a
  /// share of the memory, on disk beyond it).
  void weldVertices() {
    const std::uint64_t n = result_.census.inputVertices;
    if (!weldSort_) {
      welded_ = n;
      result_.scratch.positions = inputPositions_;
      return;
    }
    ExternalSorter<VertexPair> byId(folder_, sortOptions("weld"));
    weldSort_->finish();
    {
      PositionRecord r{}, first{};
      bool any = false;
      while (weldSort_->next(r)) {
        if (!any || r.x != first.x || r.y != first.y || r.z != first.z) first = r;
        any = true;
        byId.add({r.id, first.id});
      }
    }
    weldSort_.reset();
    byId.finish();
    weldId_ = std::make_unique<ScratchArray<std::uint32_t>>(folder_, n, setsBytes_, "weld");
    std::uint32_t next = 0;
    // A vertex keeps its place when it is its cluster's first: its welded id is the count so far.
    ScratchWriter out(folder_, "weld");
    {
      ScratchReader in(folder_, inputPositions_, "weld");
      Vec3f p;
      VertexPair pair{};
      for (std::uint32_t v = 0; byId.next(pair); ++v) {
        if (pair.vertex != v || !in.read(&p, sizeof p)) throw IoError(inputPositions_.path + ": weld records out of step");
        if (pair.other == v) {
          weldId_->set(v, next++);
          out.write(&p, sizeof p);
        } else {
          weldId_->set(v, weldId_->get(pair.other));
        }
      }
    }
    welded_ = next;
    result_.census.weldedVertices = n - next;
    folder_.remove(inputPositions_);
    result_.scratch.positions = out.finish();
  }

  /// Pass 3: triangles on welded ids; degenerate ones dropped, the others to the duplicate sort.
  /// Without the census, with the positions in three quarters of the memory, the Morton sort
  /// finds the duplicates instead (fused_): the faces wait in a file, the positions in memory.
  void renumberFaces() {
    fused_ = !options_.census && !options_.joinPositions && welded_ * sizeof(Vec3f) <= options_.memoryBytes / 4 * 3;
    if (fused_) {
      positionsInMemory_ = true;
      readPositions();
      keptFaces_ = std::make_unique<ScratchWriter>(folder_, "faces");
    } else {
      faceSort_ = std::make_unique<ExternalSorter<FaceRecord, SameVerticesLess>>(folder_, sortOptions("duplicates"));
    }
    ScratchReader in(folder_, inputTriangles_, "faces");
    Triangle t;
    for (std::uint32_t f = 0; in.read(&t, sizeof t); ++f) {
      if (weldId_) {
        for (VertexId& v : t) v = weldId_->get(v);
      }
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        ++result_.census.degenerateFaces;
        continue;
      }
      ++validFaces_;
      if (faceSort_) {
        faceSort_->add(faceRecord(t, f));
      } else {
        keptFaces_->write(&f, sizeof f);
        keptFaces_->write(&t, sizeof t);
        PlacedFace placed;
        placed.face.triangle = t;
        fillCorners(placed);
        includeInBox(placed);  // a duplicate's vertices are its kept face's: the same box
      }
    }
    weldId_.reset();
    folder_.remove(inputTriangles_);
  }

  /// The face's corner positions from the positions in memory.
  void fillCorners(PlacedFace& face) const {
    for (int k = 0; k < 3; ++k) {
      const Vec3f& p = positions_[face.face.triangle[k]];
      face.corners[k] = {p.x(), p.y(), p.z()};
    }
  }

  /// The census's bounding box grown by the face's corners.
  void includeInBox(const PlacedFace& face) {
    BoundingBox& box = result_.census.box;
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = face.corner(k).cast<double>();
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
    }
  }

  /// The welded positions whole into memory.
  void readPositions() {
    positions_.resize(welded_);
    ScratchReader in(folder_, result_.scratch.positions, "positions");
    if (welded_ > 0 && !in.read(positions_.data(), positions_.size() * sizeof(Vec3f))) {
      throw IoError(result_.scratch.positions.path + ": welded positions end early");
    }
  }

  void throwWithoutValidFaces() const {
    throw InputError(name_ + ": the mesh has no valid faces (" + std::to_string(result_.census.inputFaces) +
                     " faces in the input, all degenerate or duplicates)");
  }

  /// Pass 4: the first face of each vertex set kept; its vertices united, its edges and corners
  /// to their sorts.
  void dropDuplicateFaces() {
    if (fused_) {
      if (validFaces_ == 0) throwWithoutValidFaces();
      return;
    }
    faceSort_->finish();
    if (options_.census) {
      components_ = std::make_unique<ScratchUnionFind>(folder_, welded_, setsBytes_, "weld: components");
      edgeSort_ = std::make_unique<ExternalSorter<EdgeRecord, EdgeLess>>(folder_, sortOptions("edges"));
    }
    // Positions that fit three quarters of the memory with the union-find are read whole later
    // (the sorts before have ended; the Morton sort, fed from them, gets the rest of the memory)
    // and the kept faces wait in a file; otherwise the corners are joined with them by two sorts.
    const std::uint64_t unionFind =
        components_ ? std::min<std::uint64_t>(welded_ * sizeof(std::uint32_t), setsBytes_) : 0;
    positionsInMemory_ =
        !options_.joinPositions && unionFind + welded_ * sizeof(Vec3f) <= options_.memoryBytes / 4 * 3;
    if (positionsInMemory_) {
      keptFaces_ = std::make_unique<ScratchWriter>(folder_, "positions");
    } else {
      cornerSort_ = std::make_unique<ExternalSorter<CornerRecord, ByVertexLess>>(folder_, sortOptions("positions"));
    }
    FaceRecord r{};
    std::array<VertexId, 3> last{kInvalidId, kInvalidId, kInvalidId};
    while (faceSort_->next(r)) {
      const auto& key = r.vertices;
      if (key == last) {
        ++result_.census.duplicateFaces;
        continue;
      }
      last = key;
      const Triangle t = r.triangle();
      if (components_) {
        components_->unite(t[0], t[1]);
        components_->unite(t[1], t[2]);
      }
      for (std::uint32_t k = 0; k < 3; ++k) {
        const VertexId a = t[k], b = t[(k + 1) % 3];
        if (edgeSort_) edgeSort_->add({std::min(a, b), std::max(a, b), a < b ? 1u : 0u});
        if (cornerSort_) cornerSort_->add({t[k], r.face, k});
      }
      if (keptFaces_) {
        keptFaces_->write(&r.face, sizeof r.face);
        keptFaces_->write(&t, sizeof t);
      }
      ++result_.census.faces;
    }
    faceSort_.reset();
    if (result_.census.faces == 0) throwWithoutValidFaces();
  }

  /// Pass 5: edges grouped by their two vertices; boundary edges join their vertices' loops.
  void countEdges() {
    if (!edgeSort_) return;
    edgeSort_->finish();
    WeldCensus& c = result_.census;
    LoopSets loops(folder_, welded_, setsBytes_);
    EdgeRecord r{}, group{};
    std::uint32_t faces = 0, forward = 0;
    auto close = [&] {
      if (faces == 0) return;
      ++c.edges;
      ++counts_[components_->find(group.lo)].edges;
      if (faces == 1) {
        ++c.boundaryEdges;
        loops.join(group.lo, group.hi);
      } else if (faces == 2) {
        ++(forward == 1 ? c.manifoldEdges : c.clashEdges);
      } else {
        ++c.nonManifoldEdges;
      }
    };
    while (edgeSort_->next(r)) {
      if (faces > 0 && (r.lo != group.lo || r.hi != group.hi)) {
        close();
        faces = forward = 0;
      }
      group = r;
      ++faces;
      forward += r.forward;
    }
    close();
    edgeSort_.reset();
    loops.forEachLoop([&](std::uint32_t v) {
      ++c.boundaryLoops;
      ++counts_[components_->find(v)].loops;
    });
    result_.census.setsOnDisk = components_->onDisk() || loops.onDisk();
  }

  /// Pass 6: the bounding box of the referenced vertices (already grown when fused_). Positions
  /// held in memory stay for the Morton pass, which places the kept faces' corners itself;
  /// otherwise the kept faces with their corner positions go to a file.
  void placeCorners() {
    if (positionsInMemory_) {
      keptFile_ = keptFaces_->finish();
      keptFaces_.reset();
      if (fused_) return;  // the box grew as the faces were read
      readPositions();
      forEachKeptFace("positions", [&](const PlacedFace& face) { includeInBox(face); });
      return;
    }
    ScratchWriter out(folder_, "positions");
    joinCornersWithPositions([&](PlacedFace& face) {
      includeInBox(face);
      out.write(&face, sizeof face);
    });
    placedFaces_ = out.finish();
  }

  /// The kept faces (their file) with their corners placed from the positions in memory.
  template <class Visit>
  void forEachKeptFace(const char* stage, Visit&& visit) {
    ScratchReader in(folder_, keptFile_, stage);
    PlacedFace face;
    while (in.read(&face.face.face, sizeof face.face.face) && in.read(&face.face.triangle, sizeof face.face.triangle)) {
      fillCorners(face);
      visit(face);
    }
  }

  /// Corners sorted by vertex, joined with the positions read along their file, then regrouped
  /// by face.
  template <class Add>
  void joinCornersWithPositions(Add&& add) {
    cornerSort_->finish();
    auto placed = std::make_unique<ExternalSorter<PlacedCorner, ByCornerLess>>(folder_, sortOptions("positions"));
    {
      ScratchReader positions(folder_, result_.scratch.positions, "positions");
      CornerRecord r{};
      Vec3f p = Vec3f::Zero();
      std::int64_t at = -1;
      while (cornerSort_->next(r)) {
        while (at < static_cast<std::int64_t>(r.vertex)) {
          if (!positions.read(&p, sizeof p)) throw IoError(result_.scratch.positions.path + ": welded positions end early");
          ++at;
        }
        placed->add({r.face, r.slot, r.vertex, {p.x(), p.y(), p.z()}});
      }
    }
    cornerSort_.reset();
    placed->finish();
    PlacedCorner c[3];
    while (placed->next(c[0]) && placed->next(c[1]) && placed->next(c[2])) {
      PlacedFace face;
      face.face.face = c[0].face;
      for (int k = 0; k < 3; ++k) {
        face.face.triangle[k] = c[k].vertex;
        face.corners[k] = c[k].position;
      }
      add(face);
    }
  }

  /// Pass 7: Morton codes of the centroids, zero-area faces and faces per component; the
  /// faces written in Morton order.
  void sortByMorton() {
    WeldCensus& c = result_.census;
    const double diagonal = c.box.diagonal(), tiny = 1e-14 * diagonal * diagonal;
    // Beside positions held in memory the sort gets what they and the union-find leave of the
    // memory (at most its third).
    ExternalSortOptions options = sortOptions("morton");
    if (positionsInMemory_) {
      const std::uint64_t held = positions_.size() * sizeof(Vec3f) +
                                 (components_ ? std::min<std::uint64_t>(welded_ * sizeof(std::uint32_t), setsBytes_) : 0);
      options.memoryBytes = std::max(kMinimumSortBytes, std::min(options.memoryBytes,
                                                                 options_.memoryBytes - std::min(options_.memoryBytes, held)));
    }
    const auto isZeroArea = [&](const PlacedFace& placed) {
      const Vec3d a = placed.corner(0).cast<double>(), b = placed.corner(1).cast<double>(),
                  d = placed.corner(2).cast<double>();
      return 0.5 * (b - a).cross(d - a).norm() <= tiny;
    };
    const auto mortonOf = [&](const PlacedFace& placed) {
      return mortonCode(sortedCentroid(placed.face.triangle, [&](int k) -> Vec3d { return placed.corner(k).cast<double>(); }), c.box);
    };
    if (fused_) return sortByMortonWithDuplicates(options, isZeroArea, mortonOf);
    KeyedSorter<WeldedFace, MortonLess, MortonKey> sorter(folder_, kMortonKeys, validFaces_, options);
    auto take = [&](PlacedFace& placed) {
      c.zeroAreaFaces += isZeroArea(placed);
      placed.face.morton = mortonOf(placed);
      if (components_) ++counts_[components_->find(placed.face.triangle[0])].faces;
      sorter.add(placed.face);  // the corners stay behind: the cleaning reads positions by vertex
    };
    if (positionsInMemory_) {
      forEachKeptFace("morton", take);
      std::vector<Vec3f>().swap(positions_);
      folder_.remove(keptFile_);
    } else {
      ScratchReader in(folder_, placedFaces_, "morton");
      PlacedFace face;
      while (in.read(&face, sizeof face)) take(face);
      folder_.remove(placedFaces_);
    }
    sorter.finish();
    ScratchWriter out(folder_, "morton", std::size_t(1) << 20, sorter.size() * sizeof(WeldedFace));
    WeldedFace face;
    while (sorter.next(face)) out.write(&face, sizeof face);
    result_.scratch.faces = out.finish();
    result_.scratch.numFaces = c.faces;
  }

  /// sortByMorton when the duplicate sort did not run: all valid faces sorted, a face on the
  /// vertex set of the face before it dropped as a duplicate (the first, cleanMesh's, kept).
  template <class IsZeroArea, class MortonOf>
  void sortByMortonWithDuplicates(const ExternalSortOptions& options, IsZeroArea&& isZeroArea, MortonOf&& mortonOf) {
    WeldCensus& c = result_.census;
    {
      KeyedSorter<MortonFace, MortonFaceLess, MortonKey> sorter(folder_, kMortonKeys, validFaces_, options);
      forEachKeptFace("morton", [&](const PlacedFace& placed) {
        const std::uint64_t code = mortonOf(placed);
        sorter.add({static_cast<std::uint32_t>(code >> 32), static_cast<std::uint32_t>(code),
                    faceRecord(placed.face.triangle, placed.face.face)});
      });
      folder_.remove(keptFile_);
      sorter.finish();
      ScratchWriter out(folder_, "morton", std::size_t(1) << 20, sorter.size() * sizeof(WeldedFace));
      MortonFace record{};
      std::array<VertexId, 3> last{kInvalidId, kInvalidId, kInvalidId};
      while (sorter.next(record)) {
        if (record.record.vertices == last) {
          ++c.duplicateFaces;
          continue;
        }
        last = record.record.vertices;
        PlacedFace placed;
        placed.face = {record.morton(), record.record.face, record.record.triangle()};
        fillCorners(placed);
        c.zeroAreaFaces += isZeroArea(placed);
        ++c.faces;
        out.write(&placed.face, sizeof placed.face);
      }
      result_.scratch.faces = out.finish();
    }
    std::vector<Vec3f>().swap(positions_);
    result_.scratch.numFaces = c.faces;
  }

  /// Vertices per component (the union-find's last use), then the components' figures.
  void countComponents() {
    if (!components_) return;
    WeldCensus& c = result_.census;
    for (std::uint32_t v = 0; v < welded_; ++v) {
      const auto it = counts_.find(components_->find(v));
      if (it == counts_.end()) continue;  // a vertex no face uses
      ++it->second.vertices;
      ++c.vertices;
    }
    components_.reset();
    c.unreferencedVertices = c.inputVertices - c.vertices - c.weldedVertices;
    for (const auto& entry : counts_) {
      const ComponentCount& k = entry.second;
      ComponentInfo info;
      info.faces = static_cast<std::uint32_t>(k.faces);
      info.vertices = static_cast<std::uint32_t>(k.vertices);
      info.edges = k.edges;
      info.boundaryLoops = static_cast<std::uint32_t>(k.loops);
      info.eulerCharacteristic = std::int64_t(info.vertices) - std::int64_t(info.edges) + info.faces;
      info.genus = (2 - info.eulerCharacteristic - info.boundaryLoops) / 2;
      c.components.push_back(info);
    }
    std::sort(c.components.begin(), c.components.end(), [](const ComponentInfo& a, const ComponentInfo& b) {
      return std::tie(b.faces, b.vertices, b.edges, b.boundaryLoops) < std::tie(a.faces, a.vertices, a.edges, a.boundaryLoops);
    });
  }

  MeshStream& stream_;
  ScratchFolder& folder_;
  WeldStreamOptions options_;
  std::string name_;
  ExternalSortOptions sort_;
  WeldStreamResult result_;
  std::uint64_t welded_ = 0;
  ScratchFile inputPositions_, inputTriangles_, placedFaces_;
  std::unique_ptr<ScratchArray<std::uint32_t>> weldId_;  ///< input vertex -> welded id (null: no welding)
  std::unique_ptr<ExternalSorter<PositionRecord, PositionLess>> weldSort_;
  std::unique_ptr<ExternalSorter<FaceRecord, SameVerticesLess>> faceSort_;
  std::unique_ptr<ExternalSorter<EdgeRecord, EdgeLess>> edgeSort_;
  std::unique_ptr<ExternalSorter<CornerRecord, ByVertexLess>> cornerSort_;
  std::unique_ptr<ScratchWriter> keptFaces_;  ///< face and triangle, when positionsInMemory_
  ScratchFile keptFile_;                      ///< what keptFaces_ wrote
  std::vector<Vec3f> positions_;              ///< welded positions, from pass 6 to 7 when in memory
  bool positionsInMemory_ = false;
  bool fused_ = false;            ///< the Morton sort finds the duplicates (renumberFaces)
  std::uint64_t validFaces_ = 0;  ///< not degenerate
  std::uint64_t setsBytes_ = 0;
  std::unique_ptr<ScratchUnionFind> components_;
  std::unordered_map<std::uint32_t, ComponentCount> counts_;  ///< by union-find root
};

}  // namespace

CleanReport weldCleanReport(const WeldCensus& census) {
  CleanReport r;
  r.inputVertices = census.inputVertices;
  r.inputFaces = census.inputFaces;
  r.weldedVertices = census.weldedVertices;
  r.degenerateFaces = census.degenerateFaces;
  r.duplicateFaces = census.duplicateFaces;
  r.unreferencedVertices = census.unreferencedVertices;
  return r;
}

WeldStreamResult weldMeshStream(MeshStream& stream, ScratchFolder& folder, const WeldStreamOptions& options) {
  return WeldPass(stream, folder, options).run();
}

WeldedFaceReader::WeldedFaceReader(ScratchFolder& folder, const WeldedScratch& scratch, std::string stage)
    : reader_(folder, scratch.faces, std::move(stage)) {}

bool WeldedFaceReader::next(std::vector<WeldedFace>& chunk, std::size_t count) {
  chunk.clear();
  WeldedFace face;
  while (chunk.size() < count && reader_.read(&face, sizeof face)) chunk.push_back(face);
  return !chunk.empty();
}

}  // namespace seamvox
