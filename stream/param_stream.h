#pragma once
/// param out of core: the mesh streamed once into a scratch folder and every stage a pass over
/// scratch files within a memory budget (weld and clean, proxy field, cones, cut, voxel basis, Vox
/// solve, local refinement, foldover repair in a window around the flips, measures), the map
/// written chunk by chunk. Each stage equals its in-memory counterpart (the stream_* tests), so the
/// map is the in-memory pipeline's on the cleaned mesh with the proxy field, its cone passes
/// included.
#include <complex>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/basis/smoothed_evaluation.h"
#include "core/field/cone_merge.h"
#include "core/field/field_proxy.h"
#include "core/mesh/clean.h"
#include "core/pipeline/grid_spacing.h"
#include "core/quality/metrics.h"
#include "core/refine/refine.h"
#include "core/refine/untangle.h"
#include "core/solve/seamless_solve.h"
#include "core/system/memory.h"
#include "core/system/progress.h"
#include "stream/clean_stream.h"
#include "stream/evaluate_stream.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox {

struct StreamParamOptions {
  /// What the sorts, page caches and blocks may hold; the grid-sized system comes on top.
  std::uint64_t memoryBytes = std::uint64_t(1) << 30;
  /// What the passes before the voxel basis (weld, cleaning, field, cut) may hold: the grid-sized
  /// system does not exist yet (0: memoryBytes).
  std::uint64_t earlyMemoryBytes = 0;
  bool weld = false;  ///< join vertices at exactly equal positions (CleanOptions::weldVertices)
  GridSpacing spacing;
  double mergeCones = kConeMergeFraction;  ///< in grid spacings (PipelineOptions::mergeCones)
  /// Cone passes at most (PipelineOptions::maxConePasses): a later pass merges the cone pairs the
  /// map put on one point; none without merging.
  std::uint32_t maxConePasses = 3;
  std::int32_t gridResolution = 128;
  /// Smoothing steps of the field's surface (FieldSource::smoothingSteps).
  std::uint32_t fieldSmoothing = kFieldSmoothingIterations;
  /// Rough spots of the field's surface smoothed within h (FieldSource::roughSpots).
  bool roughSpots = true;
  /// voxloc: refine near cones and wherever the map collapses or flips; vox: only the faces of
  /// basis functions the reduction left inconsistent (one round).
  bool voxLoc = true;
  RefineOptions refine;  ///< rings, rounds, cone weight (edgeLength and the seeds are set here)
  /// The Vox map re-evaluated at the smoothed surface where it folds (evaluateScratchFoldsAtSmoothedSurface).
  bool smoothedEvaluation = true;
  /// Foldover repair after the refinement (untangleScratchFlips; edgeLength set here).
  bool untangle = true;
  UntangleOptions untangleOptions;
  ProgressFn progress;
  /// Stages are closed on it when given: weld, clean, field, cut, basis, solve, refine, untangle,
  /// write, metrics.
  StageMeter* meter = nullptr;
  /// Writes the map once it is final (e.g. writeScratchMap into the output file), before the
  /// measures; required.
  std::function<void(const CleanScratch&, const ScratchMap&)> writeMap;
  /// Test hook, run before each voxel solve (the first, and the second with more B-splines
  /// joined): a SolverError it throws takes the path of a system that cannot be factored.
  std::function<void()> beforeVoxelSolve;
};

struct StreamParamResult {
  std::uint64_t inputFaces = 0, faces = 0, vertices = 0, wedges = 0;
  CleanReport cleanReport;
  double diagonal = 0.0, edgeLength = 0.0;
  std::uint32_t fieldElements = 0;
  std::uint64_t roughVertices = 0, roughSpotVertices = 0;  ///< ScratchField's
  bool roughSpotsCapped = false;                           ///< ScratchField's
  std::uint32_t conesBeforeMerge = 0;
  std::uint32_t conePasses = 0;
  std::uint32_t conePassKept = 0;  ///< the pass whose map is written (PipelineResult::conePassKept)
  std::vector<std::uint64_t> conePassFlips;  ///< PipelineResult::conePassFlips
  ConeMergeResult merged;  ///< of the kept pass
  std::vector<VertexId> cones;        ///< of the cleaned mesh, increasing
  std::vector<std::int32_t> coneIndex4;  ///< per cone
  std::uint32_t seams = 0, components = 0;
  /// The Vox solve.
  SeamlessStats solve;
  std::uint32_t translationConstraints = 0, determinedBasis = 0, inconsistentBasis = 0, failedAttempts = 0;
  std::uint64_t domains = 0, basisFunctions = 0, elements = 0, fragments = 0;
  std::uint64_t islandFaces = 0;  ///< faces of the islands, left out of the voxel basis
  std::string voxelRetryReason;  ///< why the voxel system was solved a second time, more B-splines joined (empty: once)
  std::uint64_t markedFaces = 0;
  SmoothedEvaluationStats smoothedEvaluation;
  bool refined = false;
  RefineStats refine;
  bool untangled = false;
  UntangleStats untangle;
  std::uint64_t untangleWindowFaces = 0;  ///< faces paged in around the flips
  /// Seconds of the weld's, cleaning's and field's passes ("weld: read", "clean: faces", ...).
  std::vector<std::pair<std::string, double>> passSeconds;
  /// How the cleaning glued the edges: CleanScratch::gluing ("front", or "sorts" and why).
  std::string cleanGluing;
  SeamQuality seamQuality;
  MapQuality mapQuality;  ///< gradient error against the proxy field; flips folded in 3D on its smoothed surface
  bool isSeamless() const { return seamQuality.isSeamless(); }
};

/// Runs param out of core on the stream, scratch in folder; options.writeMap writes the cleaned
/// mesh with its map. Throws
/// InputError (bad input, an empty mesh), TopologyError, SolverError (the voxel system could not
/// be factored even with the nearly dependent B-splines joined), IoError (scratch, a full disk,
/// naming the folder).
StreamParamResult parameterizeOutOfCore(MeshStream& stream, ScratchFolder& folder, const StreamParamOptions& options);

}  // namespace seamvox
