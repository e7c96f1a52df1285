#include "stream/map_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/stopwatch.h"
#include "stream/external_sort.h"

namespace seamvox {
namespace {

// Records of the sorts and scratch files (plain arrays: written as bytes).
struct FaceRecord {  // a face that is not degenerate, in input order
  std::uint32_t v[3], inputFace;
  double uv[3][2];
};
struct DuplicateKey {  // its sorted vertex set; face = its rank among non-degenerate faces
  std::uint32_t a, b, c, face;
  bool operator<(const DuplicateKey& o) const { return std::tie(a, b, c, face) < std::tie(o.a, o.b, o.c, o.face); }
};
struct CornerRequest {  // corner j of face (non-degenerate rank) at vertex; inputFace for messages
  std::uint32_t vertex, face, j, inputFace;
  bool operator<(const CornerRequest& o) const { return std::tie(vertex, face, j) < std::tie(o.vertex, o.face, o.j); }
};
struct CornerPosition {
  std::uint64_t corner;  // 3 face + j
  float p[3];
  bool operator<(const CornerPosition& o) const { return corner < o.corner; }
};
struct EdgeRecord {  // corner c of the cleaned mesh: its edge runs from a = vertex(next c) to b = vertex(prev c)
  std::uint64_t edge;     // min(a, b) << 32 | max(a, b): the sort key
  std::uint64_t corner2;  // 2 c + (a < b): by corner within an edge, with the direction
  double uvStart[2], uvEnd[2];  // UV at a, at b
  EdgeRecord() = default;
  EdgeRecord(std::uint32_t a, std::uint32_t b, std::uint64_t c)
      : edge(std::uint64_t(std::min(a, b)) << 32 | std::max(a, b)), corner2(2 * c + (a < b)) {}
  std::uint64_t corner() const { return corner2 >> 1; }
  bool forward() const { return corner2 & 1; }
  bool operator<(const EdgeRecord& o) const { return edge != o.edge ? edge < o.edge : corner2 < o.corner2; }
};
struct SeamLength {
  std::uint64_t corner;
  double length;
  bool operator<(const SeamLength& o) const { return corner < o.corner; }
};
struct FaceArea {  // signed parameter area and 3D area of a cleaned face
  double uv, area;
};
struct FaceGeometry {  // a cleaned face's unit normal (0 when degenerate) and edge lengths (of corner j's edge)
  double normal[3], length[3];
};

Vec2d vec2(const double (&x)[2]) { return {x[0], x[1]}; }
Vec3d vec3(const double (&x)[3]) { return {x[0], x[1], x[2]}; }

// Sorted vertex sets: the faces (non-degenerate ranks) repeating an earlier face's set, increasing.
struct Duplicates {
  std::unique_ptr<ExternalSorter<std::uint32_t>> ranks;
  std::uint64_t count = 0;
};
Duplicates findDuplicateFaces(ExternalSorter<DuplicateKey>& keys, ScratchFolder& scratch,
                              const ExternalSortOptions& options) {
  Duplicates out;
  out.ranks = std::make_unique<ExternalSorter<std::uint32_t>>(scratch, options);
  keys.finish();
  DuplicateKey key, previous{kInvalidId, kInvalidId, kInvalidId, kInvalidId};
  while (keys.next(key)) {
    if (key.a == previous.a && key.b == previous.b && key.c == previous.c) {
      out.ranks->add(key.face);
      ++out.count;
    }
    previous = key;
  }
  out.ranks->finish();
  return out;
}

// The positions of the corners, face by face in order: held in memory when the header declares
// a vertex count whose positions fit the given share of memory (the common case), else corner
// requests sorted by vertex, joined with the positions file and sorted back by corner.
class CornerPositions {
 public:
  CornerPositions(const std::string& name, ScratchFolder& scratch, std::uint64_t declaredVertices,
                  std::uint64_t memoryBytes, const ExternalSortOptions& sortOptions)
      : name_(name), scratch_(scratch), sortOptions_(sortOptions) {
    if (declaredVertices > 0 && declaredVertices * sizeof(Vec3f) <= memoryBytes) {
      positions_.reserve(declaredVertices);
    } else {
      file_ = std::make_unique<ScratchWriter>(scratch, "read");
      requests_ = std::make_unique<ExternalSorter<CornerRequest>>(scratch, sortOptions);
    }
  }
  bool inMemory() const { return !requests_ && !corners_; }
  std::uint64_t vertices() const { return vertices_; }

  void addVertex(const Vec3f& p) {
    ++vertices_;
    if (!file_) {
      positions_.push_back(p);
      return;
    }
    const float xyz[3] = {p.x(), p.y(), p.z()};
    file_->write(xyz, sizeof xyz);
  }
  void addFace(std::uint32_t rank, const Triangle& t, std::uint32_t inputFace) {
    if (!requests_) return;
    for (std::uint32_t j = 0; j < 3; ++j) requests_->add({t[j], rank, j, inputFace});
  }
  /// After the last vertex and face: the join (InputError for a vertex out of range).
  void finish() {
    if (!requests_) return;
    const ScratchFile positions = file_->finish();
    file_.reset();
    corners_ = std::make_unique<ExternalSorter<CornerPosition>>(scratch_, sortOptions_);
    join(positions);
    requests_.reset();
    scratch_.remove(positions);
  }
  /// The positions of face `rank`'s corners; faces are asked for in increasing rank, each once.
  void face(std::uint64_t rank, const FaceRecord& face, Vec3d (&p)[3]) {
    for (int j = 0; j < 3; ++j) {
      if (!corners_) {
        if (face.v[j] >= positions_.size()) {
          throw InputError(name_ + ": face " + std::to_string(face.inputFace) + " refers to vertex " +
                           std::to_string(face.v[j]) + " but there are only " + std::to_string(positions_.size()) +
                           " vertices");
        }
        p[j] = positions_[face.v[j]].cast<double>();
        continue;
      }
      CornerPosition c;
      if (!corners_->next(c) || c.corner != 3 * rank + j) throw IoError(scratch_.path() + ": corner positions out of step");
      p[j] = Vec3f(c.p[0], c.p[1], c.p[2]).cast<double>();
    }
  }

 private:
  void join(const ScratchFile& positions) {
    requests_->finish();
    ScratchReader reader(scratch_, positions, "positions");
    std::uint64_t vertex = 0;
    float p[3] = {0, 0, 0};
    bool haveVertex = false;
    CornerRequest r;
    // Out of range (the readers check first): the first face in input order that refers to one.
    CornerRequest bad{0, 0, 0, kInvalidId};
    while (requests_->next(r)) {
      if (r.vertex >= vertices_) {
        if (r.inputFace < bad.inputFace || (r.inputFace == bad.inputFace && r.j < bad.j)) bad = r;
        continue;
      }
      while (!haveVertex || vertex < r.vertex) {
        if (!reader.read(p, sizeof p)) throw IoError(positions.path + ": scratch positions end early");
        vertex += haveVertex;
        haveVertex = true;
      }
      corners_->add({3 * std::uint64_t(r.face) + r.j, {p[0], p[1], p[2]}});
    }
    if (bad.inputFace != kInvalidId) {
      throw InputError(name_ + ": face " + std::to_string(bad.inputFace) + " refers to vertex " +
                       std::to_string(bad.vertex) + " but there are only " + std::to_string(vertices_) + " vertices");
    }
    corners_->finish();
  }

  std::string name_;
  ScratchFolder& scratch_;
  ExternalSortOptions sortOptions_;
  std::uint64_t vertices_ = 0;
  std::vector<Vec3f> positions_;
  std::unique_ptr<ScratchWriter> file_;
  std::unique_ptr<ExternalSorter<CornerRequest>> requests_;
  std::unique_ptr<ExternalSorter<CornerPosition>> corners_;
};

// The geometry of the cleaned faces, read back for the few corners that need it (seam edges,
// edges of more than two faces).
class FaceGeometries {
 public:
  FaceGeometries(ScratchFolder& scratch, const ScratchFile& file) : reader_(scratch, file, "edges") {}
  const FaceGeometry& at(std::uint64_t corner) {
    if (corner / 3 != face_) {
      face_ = corner / 3;
      reader_.readAt(face_ * sizeof(FaceGeometry), &geometry_, sizeof geometry_);
    }
    return geometry_;
  }

 private:
  ScratchRandomReader reader_;
  std::uint64_t face_ = ~std::uint64_t(0);
  FaceGeometry geometry_{};
};

// Measures the seam between the glued sides c < o of an edge.
void measureSeam(const EdgeRecord& c, const EdgeRecord& o, FaceGeometries& geometry, SeamQuality& seams,
                 ExternalSorter<SeamLength>& lengths) {
  const Vec2d leftA = vec2(c.uvStart), rightA = vec2(o.uvEnd), leftB = vec2(c.uvEnd), rightB = vec2(o.uvStart);
  if (leftA == rightA && leftB == rightB) return;
  const SeamEdgeFit fit = fitSeamEdge(leftA, rightA, leftB, rightB);
  if (fit.residual > seams.maxResidual) seams.worstEdgeCorner = c.corner();
  seams.maxResidual = std::max(seams.maxResidual, fit.residual);
  seams.maxIntegerDistance = std::max(seams.maxIntegerDistance, fit.integerDistance);
  ++seams.seamEdges;
  lengths.add({c.corner(), geometry.at(c.corner()).length[c.corner() % 3]});
}

// Glues the sides of one edge (sorted by corner) as cleanMesh glues them and measures the glued
// pairs: two sides in opposite directions are glued; on an edge of more than two sides, pairs of
// opposite directions with the most aligned normals first (ties: smaller corners first). Returns
// false for two sides in the same direction (an orientation clash: cleanMesh would reorient).
bool measureEdge(const std::vector<EdgeRecord>& sides, FaceGeometries& geometry, SeamQuality& seams,
                 ExternalSorter<SeamLength>& lengths) {
  if (sides.size() < 2) return true;  // boundary
  const bool firstForward = sides[0].forward();
  if (sides.size() == 2) {
    if (sides[1].forward() == firstForward) return false;
    measureSeam(sides[0], sides[1], geometry, seams, lengths);
    return true;
  }
  struct Pair {
    double alignment;
    std::size_t x, y;  // same direction as the first side, reverse
  };
  std::vector<Vec3d> normals;
  for (const EdgeRecord& side : sides) normals.push_back(vec3(geometry.at(side.corner()).normal));
  std::vector<Pair> pairs;
  for (std::size_t x = 0; x < sides.size(); ++x) {
    if (sides[x].forward() != firstForward) continue;
    for (std::size_t y = 0; y < sides.size(); ++y) {
      if (sides[y].forward() == firstForward) continue;
      const double alignment = normals[x].dot(normals[y]);  // as cleanMesh computes it
      pairs.push_back({std::isfinite(alignment) ? alignment : -2.0, x, y});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& p, const Pair& q) {
    return p.alignment != q.alignment ? p.alignment > q.alignment : p.x != q.x ? p.x < q.x : p.y < q.y;
  });
  std::vector<std::uint8_t> glued(sides.size(), 0);
  for (const Pair& pair : pairs) {
    if (glued[pair.x] || glued[pair.y]) continue;
    glued[pair.x] = glued[pair.y] = 1;
    const bool xFirst = sides[pair.x].corner() < sides[pair.y].corner();
    measureSeam(sides[xFirst ? pair.x : pair.y], sides[xFirst ? pair.y : pair.x], geometry, seams, lengths);
  }
  return true;
}

// Pass 1: the stream into the corner positions, the non-degenerate faces file and the sort that
// finds duplicate faces.
struct ReadPass {
  ScratchFile faces;
  std::uint64_t vertices = 0, inputFaces = 0, kept = 0;
};
ReadPass readStream(MeshStream& stream, ScratchFolder& scratch, ExternalSorter<DuplicateKey>& duplicates,
                    CornerPositions& positions) {
  const std::string& name = stream.name();
  ReadPass out;
  ScratchWriter faces(scratch, "read");
  MeshChunk chunk;
  bool uvDecided = false, withUV = false;
  std::uint64_t nonFinite = kInvalidId;
  while (stream.next(chunk)) {
    if (chunk.firstVertex != out.vertices) {
      throw InputError(name + ": stream chunk starts at vertex " + std::to_string(chunk.firstVertex) + " but " +
                       std::to_string(out.vertices) + " vertices came before it");
    }
    if (out.vertices + chunk.positions.size() >= kInvalidId || out.inputFaces + chunk.triangles.size() >= kInvalidId) {
      throw InputError(name + ": more than 2^32 - 1 vertices or faces (ids are 32-bit)");
    }
    for (const Vec3f& p : chunk.positions) {
      if (!p.allFinite() && nonFinite == kInvalidId) nonFinite = out.vertices;
      positions.addVertex(p);
      ++out.vertices;
    }
    if (chunk.triangles.empty()) continue;
    const bool chunkUV = !chunk.cornerUV.empty();
    if (chunkUV && chunk.cornerUV.size() != 3 * chunk.triangles.size()) {
      throw InputError(name + ": stream chunk has " + std::to_string(chunk.cornerUV.size()) + " corner UVs for " +
                       std::to_string(chunk.triangles.size()) + " triangles");
    }
    if (!uvDecided) {
      withUV = chunkUV;
      uvDecided = true;
    } else if (withUV != chunkUV) {
      throw InputError(name + ": some triangles have texture coordinates and others do not");
    }
    for (std::size_t f = 0; f < chunk.triangles.size(); ++f, ++out.inputFaces) {
      const Triangle& t = chunk.triangles[f];
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // degenerate: dropped
      FaceRecord record{{t[0], t[1], t[2]}, static_cast<std::uint32_t>(out.inputFaces), {}};
      for (int j = 0; j < 3; ++j) {
        if (withUV) record.uv[j][0] = chunk.cornerUV[3 * f + j].x(), record.uv[j][1] = chunk.cornerUV[3 * f + j].y();
      }
      positions.addFace(static_cast<std::uint32_t>(out.kept), t, static_cast<std::uint32_t>(out.inputFaces));
      faces.write(&record, sizeof record);
      Triangle s = t;
      std::sort(s.begin(), s.end());
      duplicates.add({s[0], s[1], s[2], static_cast<std::uint32_t>(out.kept)});
      ++out.kept;
    }
  }
  if (out.inputFaces == 0) throw InputError(name + ": the mesh has no faces");
  if (!withUV) throw InputError(name + ": the mesh has no per-corner texture coordinates");
  if (nonFinite != kInvalidId) {
    throw InputError(name + ": vertex " + std::to_string(nonFinite) + " has a non-finite coordinate (NaN or inf)");
  }
  positions.finish();
  out.faces = faces.finish();
  return out;
}

}  // namespace

std::uint64_t mapCheckScratchBytes(std::uint64_t vertices, std::uint64_t faces) {
  // Faces, areas and duplicate keys, the edge runs, and (positions not in memory) the positions
  // file with the runs of the corner requests and positions: an upper bound of the peak.
  return vertices * sizeof(Vec3f) +
         faces * (sizeof(FaceRecord) + sizeof(FaceArea) + sizeof(FaceGeometry) + sizeof(DuplicateKey) + 3 * sizeof(EdgeRecord) +
                  3 * (sizeof(CornerRequest) + sizeof(CornerPosition)));
}

MapCheckResult checkMapStream(MeshStream& stream, const MapCheckOptions& options) {
  const std::string& name = stream.name();
  ScratchFolder scratch(options.scratchParent,
                        mapCheckScratchBytes(stream.declaredVertices(), stream.expectedTriangles()));
  if (options.onScratch) options.onScratch(scratch);
  std::uint64_t sortMemory = options.memoryBytes / 4;  // up to four sorts alive at a time
  auto sortOptions = [&](const char* stage) {
    return ExternalSortOptions{std::max<std::uint64_t>(sortMemory, kMinimumSortBytes), stage};
  };

  // Positions in memory when they take at most half the memory; the sorts share the rest.
  CornerPositions positions(name, scratch, stream.declaredVertices(), options.memoryBytes / 2, sortOptions("corners"));
  if (positions.inMemory()) sortMemory -= stream.declaredVertices() * sizeof(Vec3f) / 4;
  auto duplicateKeys = std::make_unique<ExternalSorter<DuplicateKey>>(scratch, sortOptions("duplicates"));
  MapCheckResult result;
  SteadyClock::time_point start = SteadyClock::now();
  auto finishStage = [&](const char* stage) {
    result.stageSeconds.push_back({stage, secondsSince(start)});
    start = SteadyClock::now();
  };
  const ReadPass read = readStream(stream, scratch, *duplicateKeys, positions);
  finishStage("read");
  Duplicates duplicates = findDuplicateFaces(*duplicateKeys, scratch, sortOptions("duplicates"));
  duplicateKeys.reset();
  if (read.kept == duplicates.count) {
    throw InputError(name + ": the mesh has no valid faces (" + std::to_string(read.inputFaces) +
                     " faces in the input, all degenerate or duplicates)");
  }

  finishStage("duplicates");
  // Pass over the faces in order: areas, and the sides of every edge.
  ExternalSorter<EdgeRecord> edges(scratch, sortOptions("edges"));
  ScratchWriter areas(scratch, "faces"), geometries(scratch, "faces");
  double areaSum = 0.0, uvAreaSum = 0.0;
  {
    ScratchReader faces(scratch, read.faces, "faces");
    FaceRecord face;
    std::uint32_t nextDuplicate = kInvalidId;
    bool moreDuplicates = duplicates.ranks->next(nextDuplicate);
    for (std::uint64_t k = 0; k < read.kept; ++k) {
      if (!faces.read(&face, sizeof face)) throw IoError(read.faces.path + ": scratch faces end early");
      Vec3d p[3];
      positions.face(k, face, p);
      if (moreDuplicates && nextDuplicate == k) {
        moreDuplicates = duplicates.ranks->next(nextDuplicate);
        continue;
      }
      const std::uint64_t f = result.faces++;
      const Vec3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
      const double length = cross.norm();
      const Vec3d normal = length > 0.0 ? Vec3d(cross / length) : Vec3d::Zero();
      const Vec2d a = vec2(face.uv[1]) - vec2(face.uv[0]), b = vec2(face.uv[2]) - vec2(face.uv[0]);
      const FaceArea area{0.5 * (a.x() * b.y() - a.y() * b.x()), 0.5 * length};
      areas.write(&area, sizeof area);
      areaSum += area.area;
      uvAreaSum += std::abs(area.uv);
      FaceGeometry geometry{{normal.x(), normal.y(), normal.z()}, {}};
      for (int j = 0; j < 3; ++j) {
        const int s = (j + 1) % 3, e = (j + 2) % 3;
        EdgeRecord edge(face.v[s], face.v[e], 3 * f + j);
        for (int k = 0; k < 2; ++k) edge.uvStart[k] = face.uv[s][k], edge.uvEnd[k] = face.uv[e][k];
        edges.add(edge);
        geometry.length[j] = (p[s] - p[e]).norm();
      }
      geometries.write(&geometry, sizeof geometry);
    }
  }
  duplicates.ranks.reset();
  scratch.remove(read.faces);
  const ScratchFile areaFile = areas.finish(), geometryFile = geometries.finish();

  finishStage("faces");
  // Edges: glue the sides, measure the seams; their lengths summed in corner order.
  {
    ExternalSorter<SeamLength> lengths(scratch, sortOptions("seams"));
    FaceGeometries geometry(scratch, geometryFile);
    edges.finish();
    std::vector<EdgeRecord> sides;
    EdgeRecord edge;
    std::uint64_t clashes = 0;
    auto flush = [&] {
      clashes += !measureEdge(sides, geometry, result.seams, lengths);
      sides.clear();
    };
    while (edges.next(edge)) {
      if (!sides.empty() && sides[0].edge != edge.edge) flush();
      sides.push_back(edge);
    }
    flush();
    if (clashes > 0) {
      throw InputError(name + ": " + std::to_string(clashes) +
                       " edges join two faces of the same orientation; the out-of-core check does not "
                       "reorient faces: check it in memory (a larger --memory-budget)");
    }
    lengths.finish();
    SeamLength seam;
    while (lengths.next(seam)) result.seams.seamLength += seam.length;
  }
  scratch.remove(geometryFile);

  finishStage("edges");
  // Flips and collapses for the spacing h, given or fitted (measureMap without a field).
  MapQuality& map = result.map;
  map.faces = result.faces;
  map.edgeLength = options.edgeLength > 0.0 ? options.edgeLength
                                            : (uvAreaSum > 0.0 ? std::sqrt(areaSum / uvAreaSum) : 1.0);
  map.relativeGradientError = std::numeric_limits<double>::quiet_NaN();
  {
    ScratchReader reader(scratch, areaFile, "flips");
    FaceArea area;
    const double h2 = map.edgeLength * map.edgeLength;
    while (reader.read(&area, sizeof area)) {
      const double ratio = area.uv * h2 / area.area;
      if (std::abs(ratio) < kCollapsedAreaFraction) {
        ++map.collapsed;
      } else if (ratio < 0.0) {
        ++map.flipped;
      }
    }
    map.flippedFraction = map.faces ? static_cast<double>(map.flipped) / map.faces : 0.0;
  }
  scratch.remove(areaFile);
  finishStage("flips");
  result.positionsInMemory = positions.inMemory();
  result.traffic = scratch.traffic();
  result.scratchPeakBytes = scratch.peakBytesOnDisk();
  return result;
}

}  // namespace seamvox
