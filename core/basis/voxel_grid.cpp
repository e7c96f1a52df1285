#include "core/basis/voxel_grid.h"
#include "core/basis/islands.h"

#include <openvdb/openvdb.h>

#include <chrono>
#include <cmath>
#include <mutex>

#include "core/basis/detail_voxel_elements.h"
#include "core/system/errors.h"
#include "core/system/memory.h"
#include "core/solve/evaluate.h"
#include "core/solve/hat_solver.h"
#include "core/basis/reduce.h"
#include "core/solve/assemble.h"
#include "core/solve/seamless_solve.h"
#include "core/system/stopwatch.h"

namespace seamvox {

namespace {

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::Coord toCoord(const VoxelCoord& v) { return openvdb::Coord(v[0], v[1], v[2]); }


}  // namespace

struct VoxelGrid::Impl {
  openvdb::Int32Tree tree{-1};
  openvdb::tree::ValueAccessor<openvdb::Int32Tree> accessor{tree};
};

VoxelGrid::VoxelGrid() : impl_(std::make_unique<Impl>()) { initializeOpenVdb(); }
VoxelGrid::~VoxelGrid() = default;
VoxelGrid::VoxelGrid(VoxelGrid&&) noexcept = default;
VoxelGrid& VoxelGrid::operator=(VoxelGrid&&) noexcept = default;

std::uint32_t VoxelGrid::insert(const VoxelCoord& voxel) {
  const openvdb::Coord xyz = toCoord(voxel);
  std::int32_t id = -1;
  if (impl_->accessor.probeValue(xyz, id)) return static_cast<std::uint32_t>(id);
  if (coords_.size() >= 0x7fffffffu) throw InputError("voxel grid: more than 2^31 voxels");
  id = static_cast<std::int32_t>(coords_.size());
  impl_->accessor.setValue(xyz, id);
  coords_.push_back(voxel);
  return static_cast<std::uint32_t>(id);
}

std::uint32_t VoxelGrid::find(const VoxelCoord& voxel) const {
  const std::int32_t id = impl_->tree.getValue(toCoord(voxel));
  return id < 0 ? kInvalidId : static_cast<std::uint32_t>(id);
}

std::uint64_t VoxelGrid::treeBytes() const { return impl_->tree.memUsage(); }

std::vector<std::uint32_t> VoxelGrid::orderByBlocks() {
  std::vector<std::uint32_t> remap(coords_.size(), kInvalidId);
  std::vector<VoxelCoord> coords;
  coords.reserve(coords_.size());
  blockStarts_.clear();
  for (auto leaf = impl_->tree.beginLeaf(); leaf; ++leaf) {
    blockStarts_.push_back(static_cast<std::uint32_t>(coords.size()));
    for (auto voxel = leaf->beginValueOn(); voxel; ++voxel) {
      const std::uint32_t old = static_cast<std::uint32_t>(*voxel);
      remap[old] = static_cast<std::uint32_t>(coords.size());
      voxel.setValue(static_cast<std::int32_t>(coords.size()));
      coords.push_back(coords_[old]);
    }
  }
  if (coords.size() != coords_.size()) {
    throw InputError("voxel grid: " + std::to_string(coords.size()) + " active voxels in the tree, " +
                     std::to_string(coords_.size()) + " ids");
  }
  blockStarts_.push_back(static_cast<std::uint32_t>(coords.size()));
  coords_ = std::move(coords);
  impl_->accessor.clear();
  return remap;
}

VoxelBuildResult buildVoxelBasis(const TriangleMesh& mesh, const Topology& topology,
                                 const CrossField& field, const CutResult& cut,
                                 const VoxelBasisOptions& options) {
  if (mesh.numFaces() != topology.numFaces()) {
    throw InputError("voxel basis: mesh has " + std::to_string(mesh.numFaces()) +
                     " faces but its topology " + std::to_string(topology.numFaces()));
  }
  VoxelBuildResult out;
  auto start = std::chrono::steady_clock::now();
  const VoxelGridGeometry geometry =
      makeVoxelGrid(computeBoundingBox(mesh.positions), options.gridResolution);
  const FaceId nf = mesh.numFaces();
  std::vector<VoxelFragment> fragments;
  fragments.reserve(nf + nf / 2);
  detail::clipFacesInOrder(
      nf, options.chunkFaces,
      [&](detail::ClippedChunk& chunk) {
        detail::clipChunk(geometry, [&](FaceId f) { return faceGridCoords(mesh, geometry, f); }, chunk,
                          options.leftOut);
      },
      out.grid, [&](const VoxelFragment& fragment) { fragments.push_back(fragment); },
      [&](const detail::ClippedChunk& chunk) { reportProgress(options.progress, "voxel clip", double(chunk.end) / nf); });
  // No shrink_to_fit: the reserve's unused tail was never touched (not resident), and the copy
  // would hold the fragments twice.
  // Ids in tree order: the elements of one 8^3 leaf block are contiguous, and the assembly takes
  // them block by block.
  const std::vector<std::uint32_t> remap = out.grid.orderByBlocks();
  for (VoxelFragment& fragment : fragments) fragment.voxel = remap[fragment.voxel];
  out.secondsClip = secondsSince(start);

  start = std::chrono::steady_clock::now();
  out.basis = std::make_unique<VoxelBasis>(mesh, topology, field, cut, geometry, out.grid.coords(),
                                           std::move(fragments), options);
  out.basis->setVoxelBlocks(out.grid.blockStarts());
  out.secondsBasis = secondsSince(start);
  return out;
}

SeamlessSolution solveVoxelSeamless(VoxelBasis& basis, const Reduction& reduction, const RoundOptions& options,
                                    std::uint32_t& failedAttempts) {
  // The reduction depends on domains and adjacency only, and the basis keeps the
  // normal-derivative integrals apart: a stronger regularization only re-assembles and refactors.
  for (;;) {
    try {
      return solveSeamless(basis, reduction, options);
    } catch (const SolverError&) {
      if (basis.regularization() >= kMaxVoxelRegularization) throw;
      const double stronger = std::max(100.0 * basis.regularization(), 1e-7);
      basis.setRegularization(std::min(stronger, kMaxVoxelRegularization));
      ++failedAttempts;
    }
  }
}

std::vector<FaceId> withFaces(const std::vector<FaceId>& faces, const std::vector<FaceId>& more) {
  std::vector<FaceId> out;
  out.reserve(faces.size() + more.size());
  std::set_union(faces.begin(), faces.end(), more.begin(), more.end(), std::back_inserter(out));
  return out;
}

VoxelParamResult parameterizeMeshVoxel(const TriangleMesh& mesh, const Topology& topology,
                                       const CrossField& field, const CutResult& cut,
                                       const ParamOptions& options, std::int32_t gridResolution,
                                       double minDomainWeight) {
  VoxelParamResult out;
  ParamResult& param = out.param;
  auto start = std::chrono::steady_clock::now();
  // The translation constraints always come from the hat basis (DESIGN section 7).
  const std::vector<GaussVector> constraints =
      seamCycleConstraints(mesh, topology, field, cut, options.edgeLength);
  VoxelBasisOptions basisOptions;
  basisOptions.gridResolution = gridResolution;
  basisOptions.edgeLength = options.edgeLength;
  basisOptions.progress = options.progress;
  if (minDomainWeight >= 0.0) basisOptions.minDomainWeight = minDomainWeight;
  basisOptions.leftOut = islandFaces(topology);
  start = std::chrono::steady_clock::now();
  VoxelBuildResult built = buildVoxelBasis(mesh, topology, field, cut, basisOptions);
  VoxelBasis& basis = *built.basis;
  const auto recordBasis = [&] {  // its figures, again after joinDomains
    param.basisFunctions = basis.numBasisFunctions();
    param.domains = basis.numDomains();
    param.seamAdjacencies = static_cast<std::uint32_t>(basis.adjacencies().size());
    out.basisStats = basis.stats();
  };
  recordBasis();
  param.secondsBasis = secondsSince(start);
  out.voxelSize = basis.grid().voxelSize;
  if (options.basisBuilt) options.basisBuilt();

  start = std::chrono::steady_clock::now();
  ReduceOptions reduceOptions;
  reduceOptions.translationConstraints = &constraints;
  const std::vector<GaussVector> holes = closeSmallHoles(mesh, topology, cut, options, param);
  reduceOptions.extraConstraints = &holes;
  reduceOptions.progress = options.progress;
  RoundOptions roundOptions;
  roundOptions.greedy = options.greedyRounding;
  roundOptions.progress = options.progress;
  roundOptions.failsToFactor = options.failsToFactor;
  Reduction reduction = reduceBasis(basis, reduceOptions);
  param.secondsReduce = secondsSince(start);
  SeamlessSolution solution;
  try {
    if (options.beforeVoxelSolve) options.beforeVoxelSolve();
    solution = solveVoxelSeamless(basis, reduction, roundOptions, out.failedAttempts);
  } catch (const SolverError& first) {
    // Nearly dependent B-splines that barely touch the surface, which no regularization makes
    // definite: joined to a neighbour (kRetryMinDomainWeight) and solved again, the faces'
    // fragments and integrals kept.
    if (!(basisOptions.minDomainWeight < kRetryMinDomainWeight)) throw;
    out.retryReason = first.what();
    out.failedAttempts = 0;
    reduction = Reduction();
    basis.joinDomains(kRetryMinDomainWeight);
    recordBasis();
    reduction = reduceBasis(basis, reduceOptions);
    if (options.beforeVoxelSolve) options.beforeVoxelSolve();
    solution = solveVoxelSeamless(basis, reduction, roundOptions, out.failedAttempts);
  }
  param.translationConstraints = static_cast<std::uint32_t>(constraints.size());
  out.determinedBasis = static_cast<std::uint32_t>(reduction.determinedBasis.size());
  out.inconsistentBasis = static_cast<std::uint32_t>(reduction.inconsistentBasis.size());
  // The islands are mapped by the local hat solve: every face of theirs is marked for it.
  out.islandFaces = basisOptions.leftOut.size();
  out.markedFaces = withFaces(basis.markedFaces(reduction), basisOptions.leftOut);
  out.inconsistentFaces = withFaces(basis.supportFaces(reduction.inconsistentBasis), basisOptions.leftOut);
  out.islands = basisOptions.leftOut;
  out.invisibleTranslations = reduction.invisibleTranslations;
  out.regularization = basis.regularization();
  // The factorizations leave many freed blocks in the heap (150 MB at grid 128): back to the
  // system before the map (20 bytes per face) is built next to the basis.
  releaseFreedMemory();
  std::vector<std::complex<double>> coefficients;
  if (options.smoothedEvaluation) coefficients = expandCoefficients(reduction, solution.unknowns);
  storeSeamlessSolution(basis, reduction, std::move(solution), topology, cut, param, options.mapViewsTriangles);
  if (options.smoothedEvaluation) {
    out.smoothedEvaluation = evaluateFoldsAtSmoothedSurface(mesh, topology, field, basis, coefficients,
                                                            options.edgeLength, param.cornerUV,
                                                            options.smoothedBatchVertices ? options.smoothedBatchVertices
                                                                                          : kSmoothedBatchVertices);
  }
  return out;
}

}  // namespace seamvox
