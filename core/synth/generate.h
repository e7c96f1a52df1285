#pragma once
/// Synthetic scan-like test meshes. Deterministic: the same options give bit-identical
/// positions and triangles on every machine (own integer RNG and value noise, only IEEE
/// +, -, *, /, sqrt in the geometry). Linear time and memory, parallel over rows.
#include <cstdint>
#include <string>

#include "core/mesh/mesh.h"
#include "core/system/progress.h"

namespace seamvox {

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

}  // namespace seamvox
