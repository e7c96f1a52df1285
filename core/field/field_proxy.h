#pragma once
/// Scalable cross field for massive meshes (DESIGN section 4, "scalable field"): the smoothest
/// field solved on a coarse proxy (connected pieces of the mesh inside the cells of a grid over
/// the bounding box), transferred to faces and smoothed by a few coloured sweeps. Time and memory
/// are linear in the mesh; the solve's size depends on the grid only. Conventions: field.h.
#include <cstdint>
#include <string>

#include "core/field/field.h"
#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

namespace seamvox {

struct ProxyFieldOptions {
  /// Cells along the longest axis of the bounding box (4..1024). The proxy has about one
  /// element per cell the surface crosses (more where thin parts put two sheets in one cell).
  std::int32_t gridResolution = 128;
  /// Gauss-Seidel sweeps on the faces after the transfer (each face := normalized transported
  /// average of its neighbours' 4th powers), one colour of the face graph at a time.
  std::int32_t smoothingSweeps = 4;
  /// The sweeps' order: blocks of this many faces in face order, and within a block one colour
  /// after another (a colour's faces in parallel). Later blocks see the earlier blocks' new
  /// directions, and a pass out of core reads each block and its neighbours once per sweep. Every
  /// path (in memory, out of core at any budget) updates the faces in this order.
  std::uint32_t sweepBlockFaces = std::uint32_t(1) << 16;
  ProgressFn progress;
  FieldSolveStats* stats = nullptr;  ///< the element solve's figures, filled when set
};

struct ProxyFieldResult {
  CrossField field;
  std::uint32_t elements = 0;      ///< proxy elements (graph nodes)
  std::uint64_t elementEdges = 0;  ///< adjacent element pairs
  std::uint32_t colours = 0;       ///< colours of the face graph used by the sweeps
};

/// Smoothest 4-direction field through the proxy. Extra memory at most 12 bytes per face beyond
/// the output, plus the proxy solve (bounded by the grid). Deterministic for any thread count.
ProxyFieldResult computeProxyField(const TriangleMesh& mesh, const Topology& topology,
                                   const ProxyFieldOptions& options = {});

/// How the field of computeCrossField is computed.
enum class FieldMethod {
  Auto,    ///< Direct up to kDirectFieldMaxFaces faces, Proxy above
  Direct,  ///< computeSmoothestField: one CHOLMOD solve over all faces
  Proxy,   ///< computeProxyField
};
/// Largest mesh Auto solves directly: the hat solver's limit (kAutoHatMaxFacesGrid128). Above it
/// the default solver is voxloc, which aligns no feature curves, so the direct field's creases go
/// unused while it costs most of the run: 4.3 of 6.3 s at 422K faces (lilium subdivided), 9.0 of
/// 12.2 s at 576K (fertility), against 0.4-0.6 s for the proxy at the same or lower gradient error
/// (bench/RESULTS.md, session 25); at 1M faces the direct field took 39 s, the proxy 5.6 s.
constexpr std::uint32_t kDirectFieldMaxFaces = 400000;
/// Direct or Proxy: Auto resolved by the face count.
FieldMethod resolveFieldMethod(FieldMethod method, std::uint32_t numFaces);
/// "auto", "direct", "proxy".
const char* fieldMethodName(FieldMethod method);
/// Parses "auto", "direct" (or "smooth"), "proxy"; throws InputError listing them.
FieldMethod parseFieldMethod(const std::string& name);

/// Uniform Laplacian steps of the surface computeCrossField works on by default: two leave a
/// fold-over of a scan jittered by half an edge length, three remove those of spikes and folds
/// too (bench/RESULTS.md, noisy scans).
constexpr std::uint32_t kFieldSmoothingIterations = 3;

/// The surface the field is computed on (CrossField::framePositions).
struct FieldGeometryOptions {
  /// smoothPositions steps before the field is computed; 0 computes it on the mesh itself.
  std::uint32_t smoothingIterations = kFieldSmoothingIterations;
  /// The grid's edge length h: the smoothed surface's rough spots (crumpled vertices spaced below
  /// h / 16 and half the mesh's mean spacing) are smoothed further within h (smoothRoughSpots).
  /// 0: not.
  double roughSpotGrid = 0.0;
  /// The most vertices a rough spot's region may hold (roughRegionBoundInMemory); above it the
  /// rounds stop (FieldSolveStats::roughSpotsCapped). Unbounded by default.
  std::uint64_t roughSpotMaxRegion = ~std::uint64_t(0);
};

/// The smoothest field by the given method, computed on the mesh smoothed by
/// geometry.smoothingIterations steps (kept in framePositions, so that computeSingularities
/// reads the cones off that surface) and projected onto the mesh's own faces. Extra memory
/// while it runs: 24 bytes per vertex (mesh.positions hold the smoothed positions while the field
/// is solved, and get their own back on every exit). Faces of smooth.alignCorners end exactly
/// along their edges (snapToFeatureEdges). Throws InputError when curvature or feature alignment
/// is asked of the proxy field (it computes the smoothest field only).
CrossField computeCrossField(TriangleMesh& mesh, const Topology& topology, FieldMethod method,
                             const SmoothFieldOptions& smooth = {},
                             const ProxyFieldOptions& proxy = {},
                             const FieldGeometryOptions& geometry = {});
/// The same on a const mesh (a copy of it: 12 more bytes per face and per vertex).
CrossField computeCrossField(const TriangleMesh& mesh, const Topology& topology, FieldMethod method,
                             const SmoothFieldOptions& smooth = {},
                             const ProxyFieldOptions& proxy = {},
                             const FieldGeometryOptions& geometry = {});

/// Smoothness energy of a field: sum over interior edges of w_e |z_g - T_fg z_f|^2, z the unit
/// 4th powers, T_fg the rotation about the shared edge, w_e = |e| / |b_f - b_g| (bounded).
/// Zero for a parallel field on a flat mesh. Linear, parallel.
double measureFieldEnergy(const TriangleMesh& mesh, const Topology& topology, const CrossField& field);

}  // namespace seamvox
