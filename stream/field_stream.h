#pragma once
/// The field stage of the out-of-core param, on the cleaned mesh in the scratch folder
/// (clean_stream): each step equals its in-memory counterpart on readCleanScratch's mesh, and
/// reads the scratch through page caches (paged_reader) in the faces' Morton order.
#include <algorithm>
#include <climits>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/field/cone_merge.h"
#include "core/field/field_proxy.h"
#include "core/field/rough_spots.h"
#include "stream/clean_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

/// Memory of a streamed pass.
struct StreamPassOptions {
  std::uint64_t memoryBytes = std::uint64_t(256) << 20;  ///< the sorts' and page caches' share
  /// Records (faces, vertices) computed and written at once; small in tests, so that passes run
  /// over many blocks.
  std::uint64_t blockRecords = std::uint64_t(1) << 20;
};

/// smoothPositions(mesh, topology, iterations) of the cleaned mesh: Vec3f per vertex, a new file
/// (the cleaned positions themselves when iterations is 0).
ScratchFile smoothScratchPositions(ScratchFolder& folder, const CleanScratch& scratch, std::uint32_t iterations,
                                   const StreamPassOptions& pass);

/// The most vertices a round's region may hold out of core: half the pass's memory, at
/// kRoughRegionBytes each, and at least kRoughRegionMinVertices. Above it the rough spots are
/// left as they are (ScratchField::roughSpotsCapped): a scan crumpled nearly everywhere, which the
/// global steps are for, within a small budget.
std::uint64_t roughRegionBound(std::uint64_t memoryBytes);

struct ScratchField;
/// smoothRoughSpots on the smoothed surface `surface` (a file of smoothScratchPositions): the
/// rough vertices found by a pass over the vertices, the rounds on their regions through page
/// caches (the regions in memory, at most roughRegionBound(pass.memoryBytes) vertices), then new
/// files: the surface with the moved vertices (returned) and with their moves' normal parts
/// (counts.mapPositions, detail::normalPartOfMoves). surface itself is returned, unchanged, when
/// nothing moved; it stays either way.
/// The figures go to counts.roughVertices and roughSpotVertices.
ScratchFile smoothScratchRoughSpots(ScratchFolder& folder, const CleanScratch& scratch, const ScratchFile& surface,
                                    double gridLength, const StreamPassOptions& pass, ScratchField& counts);

/// computeCrossField(mesh, topology, FieldMethod::Proxy, {}, proxy, geometry) of the cleaned mesh,
/// in the scratch folder.
struct ScratchField {
  ScratchFile directions;      ///< Vec3f per face, tangent to the mesh's own faces
  ScratchFile framePositions;  ///< Vec3f per vertex, the smoothed surface (none without smoothing)
  /// When rough spots moved vertices: the surface the map's stages after the cones read, the
  /// smoothed surface with their moves' parts along the normal only (param, as in memory
  /// setFrameOverridesAside; framePositions has the whole moves).
  ScratchFile mapPositions;
  /// With angles: the singularities' angles per face (16 bytes), which computeScratchSingularities
  /// reads instead of computing them and removes.
  ScratchFile angles;
  std::uint32_t elements = 0, colours = 0;
  std::uint64_t elementEdges = 0;
  /// Rough spots of the surface (FieldGeometryOptions::roughSpotGrid): rough vertices found,
  /// vertices moved.
  std::uint64_t roughVertices = 0, roughSpotVertices = 0;
  /// A region exceeded roughRegionBound: the rounds stopped there (roughSpotVertices: those moved
  /// before it).
  bool roughSpotsCapped = false;
  /// Wall seconds of the passes: smooth, rough spots (with roughSpotGrid), cells, elements, solve, transfer, colour, sweeps, finish.
  std::vector<std::pair<std::string, double>> stageSeconds;
};

/// The proxy field out of core: the faces' cells (a file), the elements by a union-find of the
/// faces across edges within a cell (its links in memory within a quarter of the pass's memory,
/// else on disk) and their sums in face order; the element solve is grid-sized; the transfer, the
/// greedy colouring in face order, one pass per sweep and colour and the last projection stream
/// the faces. Equal, bit for bit, to the in-memory field (with the BLAS on one thread, as the
/// seamvox command runs it). Memory: the links, the caches, a block of faces, the elements.
/// IoError naming the folder on a full disk.
ScratchField computeScratchField(ScratchFolder& folder, const CleanScratch& scratch, const ProxyFieldOptions& proxy,
                                 const FieldGeometryOptions& geometry, const StreamPassOptions& pass,
                                 bool withAngles = false);

/// computeSingularities of the out-of-core field (its smoothed surface when it has one).
struct ScratchSingularities {
  ScratchFile matching;  ///< std::uint8_t per corner, FieldSingularities::matching
  /// The nonzero entries of FieldSingularities::index4 and boundaryIndex4, by vertex.
  std::vector<std::pair<VertexId, std::int32_t>> index4, boundaryIndex4;
  std::vector<VertexId> cones;  ///< vertices with index4 != 0, increasing
};

/// index4 of vertex v in the out-of-core singularities (0: not a cone).
inline std::int32_t coneIndexOf(const ScratchSingularities& singularities, VertexId v) {
  const auto it = std::lower_bound(singularities.index4.begin(), singularities.index4.end(), std::make_pair(v, INT32_MIN));
  return it != singularities.index4.end() && it->first == v ? it->second : 0;
}

/// Per face its angles (a file of 16 bytes per face, the field's when it has them, removed at the
/// end), per corner the matching across its edge, per vertex the index: an interior vertex's from
/// its corners' terms summed in face order in the matchings' pass (8 bytes per vertex within a
/// quarter of the pass's memory, else on disk), a boundary vertex's by a walk around its fan.
/// Equal to computeSingularities of the in-memory field on the cleaned mesh.
ScratchSingularities computeScratchSingularities(ScratchFolder& folder, const CleanScratch& scratch,
                                                 const ScratchField& field, const StreamPassOptions& pass);

/// mergeCloseCones on the out-of-core singularities (the cleaned mesh's own positions): the
/// matchings along the paths rewritten in place in the matching file, index4 and cones updated.
/// Memory: the searches' balls and the changed corners.
ConeMergeResult mergeScratchCones(ScratchFolder& folder, const CleanScratch& scratch, ScratchSingularities& singularities,
                                  const ConeMergeOptions& options, const StreamPassOptions& pass);

/// mergeCoincidentCones on the out-of-core singularities, as mergeScratchCones: the pairs a
/// solve put on one point (a later cone pass). InputError for a vertex out of range.
ConeMergeResult mergeScratchCoincidentCones(ScratchFolder& folder, const CleanScratch& scratch,
                                            ScratchSingularities& singularities,
                                            const std::vector<std::pair<VertexId, VertexId>>& pairs, double maxDistance,
                                            const StreamPassOptions& pass);

}  // namespace seamvox
