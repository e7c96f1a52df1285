#include "stream/map_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/system/stopwatch.h"
#include "stream/corner_positions.h"
#include "stream/map_passes.h"
#include "stream/external_sort.h"
#include "stream/wound_count.h"

namespace seamvox {
namespace {

using namespace map_pass;

// Records of the sorts and scratch files (plain arrays: written as bytes).
struct SeamLength {
  std::uint64_t corner;
  double length;
  bool operator<(const SeamLength& o) const { return corner < o.corner; }
};
struct FaceArea {  // signed parameter area, 3D area and gradientNormSquared of a cleaned face
  double uv, area, gradient;
};
struct FaceGeometry {  // a cleaned face's gluingNormal and edge lengths (of corner j's edge)
  double normal[3], length[3];
};

// The geometry of the cleaned faces, read back for the few corners that need it (seam edges,
// edges of more than two faces).
using FaceGeometries = RecordsByFace<FaceGeometry>;

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
                 ExternalSorter<SeamLength>& lengths, FanAngleSums<float>& wound, std::vector<std::uint8_t>& used) {
  bool clash = false;
  const auto glued = glueSides(
      sides, [&](std::size_t i) { return vec3(geometry.at(sides[i].corner()).normal); }, clash);
  for (const auto& [first, second] : glued) measureSeam(sides[first], sides[second], geometry, seams, lengths);
  addSidesToFans(wound, sides, glued, used);
  return !clash;
}

}  // namespace

std::uint64_t mapCheckScratchBytes(std::uint64_t vertices, std::uint64_t faces) {
  // Faces, areas and duplicate keys, the edge runs, and (positions not in memory) the positions
  // file with the runs of the corner requests and positions: an upper bound of the peak.
  return vertices * sizeof(Vec3f) +
         faces * (sizeof(FaceRecord) + sizeof(FaceArea) + sizeof(FaceGeometry) + sizeof(DuplicateKey) + 3 * sizeof(EdgeRecord) +
                  3 * (sizeof(corner_detail::CornerRequest) + sizeof(corner_detail::CornerPosition)) +
                  3 * FanAngleSums<float>::kBytesPerSide);
}

MapCheckResult checkMapStream(MeshStream& stream, const MapCheckOptions& options) {
  const std::string& name = stream.name();
  ScratchFolder scratch(options.scratchParent,
                        mapCheckScratchBytes(stream.declaredVertices(), stream.expectedTriangles()));
  if (options.onScratch) options.onScratch(scratch);
  std::uint64_t sortMemory = options.memoryBytes / 5;  // up to five sorts alive at a time
  auto sortOptions = [&](const char* stage) {
    return ExternalSortOptions{std::max<std::uint64_t>(sortMemory, kMinimumSortBytes), stage};
  };

  // Positions in memory when they take at most half the memory; the sorts share the rest.
  CornerPositions positions(name, scratch, stream.declaredVertices(), options.memoryBytes / 2, sortOptions("corners"));
  if (positions.inMemory()) sortMemory -= stream.declaredVertices() * sizeof(Vec3f) / 5;
  auto duplicateKeys = std::make_unique<ExternalSorter<DuplicateKey>>(scratch, sortOptions("duplicates"));
  MapCheckResult result;
  SteadyClock::time_point start = SteadyClock::now();
  auto finishStage = [&](const char* stage) {
    result.stageSeconds.push_back({stage, secondsSince(start)});
    start = SteadyClock::now();
  };
  const ReadPass read = readStream(stream, scratch, *duplicateKeys, positions);
  finishStage("read");
  Duplicates duplicates = findDuplicateFaces(name, read, *duplicateKeys, scratch, sortOptions("duplicates"));
  duplicateKeys.reset();

  finishStage("duplicates");
  // Pass over the faces in order: areas, and the sides of every edge.
  ExternalSorter<EdgeRecord> edges(scratch, sortOptions("edges"));
  FanAngleSums<float> wound(scratch, read.vertices, read.kept, sortOptions("wound"));
  ScratchWriter areas(scratch, "faces"), geometries(scratch, "faces");
  double areaSum = 0.0, uvAreaSum = 0.0;
  {
    forEachKeptFace(scratch, read, duplicates, positions, [&](const FaceRecord& face, const Vec3d (&p)[3]) {
      const std::uint64_t f = result.faces++;
      const double length = (p[1] - p[0]).cross(p[2] - p[0]).norm();
      const Vec3d normal = gluingNormal(p[0], p[1], p[2]);
      const Vec2d a = vec2(face.uv[1]) - vec2(face.uv[0]), b = vec2(face.uv[2]) - vec2(face.uv[0]);
      const FaceArea area{0.5 * (a.x() * b.y() - a.y() * b.x()), 0.5 * length,
                          gradientNormSquared({p[0], p[1], p[2]}, {vec2(face.uv[0]), vec2(face.uv[1]), vec2(face.uv[2])})};
      areas.write(&area, sizeof area);
      areaSum += area.area;
      uvAreaSum += std::abs(area.uv);
      FaceGeometry geometry{{normal.x(), normal.y(), normal.z()}, {}};
      for (int j = 0; j < 3; ++j) {
        const int s = (j + 1) % 3, e = (j + 2) % 3;
        EdgeRecord edge(face.v[s], face.v[e], 3 * f + j);
        for (int k = 0; k < 2; ++k) edge.uvStart[k] = face.uv[s][k], edge.uvEnd[k] = face.uv[e][k];
        edge.startAngle = cornerUVAngle(vec2(face.uv[s]), vec2(face.uv[e]), vec2(face.uv[j]));
        edges.add(edge);
        geometry.length[j] = (p[s] - p[e]).norm();
      }
      geometries.write(&geometry, sizeof geometry);
    });
  }
  duplicates.ranks.reset();
  scratch.remove(read.faces);
  const ScratchFile areaFile = areas.finish(), geometryFile = geometries.finish();

  finishStage("faces");
  // Edges: glue the sides, measure the seams; their lengths summed in corner order.
  {
    ExternalSorter<SeamLength> lengths(scratch, sortOptions("seams"));
    FaceGeometries geometry(scratch, geometryFile, "edges");
    edges.finish();
    std::vector<EdgeRecord> sides;
    std::vector<std::uint8_t> used;
    EdgeRecord edge;
    std::uint64_t clashes = 0;
    auto flush = [&] {
      clashes += !measureEdge(sides, geometry, result.seams, lengths, wound, used);
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
  result.map.wound = countWoundFans(wound);
  result.map.woundCounted = true;

  finishStage("wound");
  // Flips, collapses and stretches for the spacing h, given or fitted (measureMap without a field).
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
      } else {
        map.stretched += isStretched(area.gradient, map.edgeLength);
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
