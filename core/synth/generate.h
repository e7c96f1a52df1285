#pragma once
/// Synthetic scan-like test meshes. Deterministic: the same options give bit-identical
/// positions and triangles on every machine (own integer RNG and value noise, only IEEE
/// +, -, *, /, sqrt in the geometry). Linear time and memory, parallel over rows.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"

namespace seamvox {
namespace detail {
struct GeneratedSequence;
}

enum class MeshKind {
  Sphere,  ///< bumpy cube-sphere, closed, genus 0
  Torus,   ///< bumpy torus, closed, genus 1
  Genus2,  ///< two bumpy tori joined by a tube, closed, genus 2
  Scan,    ///< bumpy sphere with holes, floating islands, an unwelded seam, bad faces
};
/// "sphere", "torus", "genus2", "scan".
const char* meshKindName(MeshKind kind);
/// Parses a kind name; throws InputError listing the known kinds.
MeshKind parseMeshKind(const std::string& name);
/// Smallest face count a kind can be generated with.
std::uint64_t minimumFaces(MeshKind kind);

struct GenerateOptions {
  MeshKind kind = MeshKind::Sphere;
  std::uint64_t faces = 100000;  ///< target face count; the result is within a few percent
  std::uint64_t seed = 1;
  ProgressFn progress;
};

/// What the scan kind injected on purpose (all zero for the clean kinds); cleaning must find it.
struct ScanDefects {
  std::uint32_t holes = 0;               ///< boundary loops cut into the main surface
  std::uint32_t openIslands = 0;         ///< floating disc patches (one boundary loop each)
  std::uint32_t closedIslands = 0;       ///< floating closed blobs (no boundary)
  std::uint32_t seamDuplicates = 0;      ///< unwelded copies along the seam line (exact positions)
  std::uint32_t degenerateFaces = 0;     ///< faces with a repeated vertex
  std::uint32_t duplicateFaces = 0;      ///< faces with the vertex set of an earlier face
};

struct GenerateResult {
  TriangleMesh mesh;
  ScanDefects defects;
};

/// Generates a mesh of the given kind with about options.faces faces, outward oriented.
/// Throws InputError when faces < minimumFaces(kind) or faces >= 2^31.
GenerateResult generateMesh(const GenerateOptions& options);

/// The mesh generateMesh makes, handed out piece by piece in its order (vertices by id, then
/// triangles by id) with the same bits, for writing meshes larger than memory. Memory: the
/// kind's parameters and a list of the vertices the scan's holes drop (about 1% of the
/// vertices, 4 bytes each), whatever the face count. Positions are computed in parallel.
class MeshGenerator {
 public:
  /// Throws InputError as generateMesh does.
  explicit MeshGenerator(const GenerateOptions& options);
  ~MeshGenerator();
  MeshGenerator(const MeshGenerator&) = delete;
  MeshGenerator& operator=(const MeshGenerator&) = delete;

  std::uint64_t numVertices() const;
  std::uint64_t numFaces() const;
  const ScanDefects& defects() const;
  /// Appends the positions of the next (at most count) vertices to out; false once all were given.
  bool nextPositions(std::size_t count, std::vector<Vec3f>& out);
  /// Appends the next triangles (about count; after all positions) to out; false once all were given.
  bool nextTriangles(std::size_t count, std::vector<Triangle>& out);

 private:
  std::unique_ptr<detail::GeneratedSequence> impl_;
};

/// Scanner defects added to an existing mesh: per-vertex noise, outlier spikes and small folds.
/// Lengths are in units of the mean edge length L (over the triangles' edges).
struct ScanNoiseOptions {
  /// Every vertex moves by at most amplitude * L along its normal and at most tangential *
  /// amplitude * L tangentially (uniform in [-A L, A L] along the normal, uniform in the disc of
  /// radius t A L).
  double amplitude = 0.0;
  /// The per-vertex noise in units of each vertex's own mean edge length (the edges at it, summed
  /// over coincident copies) instead of L: a scanner's noise at the scale of its sampling on a
  /// mesh whose triangles vary in size, where L would move the vertices of small triangles by
  /// many of their own edges. Spikes and folds stay in units of L.
  bool localScale = false;
  /// The tangential part's share of the amplitude, 0 to 1 (0: along the normal only, as a range
  /// scanner's depth noise; on uneven triangles the tangential part folds the thin ones in 3D).
  double tangential = 1.0;
  /// Vertices pushed along their normal by 2..6 L (outliers), one sign at random each.
  std::uint32_t spikes = 0;
  /// Small fold-overs: a vertex moved 2 L along a tangent, its ring 1 L, so the faces around it
  /// overlap (a foldover of two rings).
  std::uint32_t folds = 0;
  std::uint64_t seed = 1;
};

struct ScanNoiseResult {
  double meanEdgeLength = 0.0;     ///< L
  double maxDisplacement = 0.0;    ///< largest vertex move of the per-vertex noise (mesh units)
  std::uint32_t spikes = 0, folds = 0;
};

/// Moves the vertices of mesh in place; triangles (the topology) stay as they are. Deterministic
/// for any thread count: a vertex's noise depends on the seed and its position only, so exactly
/// coincident vertices (unwelded seams) get the same normal and the same move and stay
/// coincident. Normals: area-weighted, summed over coincident copies. Throws InputError when
/// amplitude is negative or not finite, or spikes + folds exceed the vertex count.
ScanNoiseResult addScanNoise(TriangleMesh& mesh, const ScanNoiseOptions& options);

}  // namespace seamvox
