#pragma once
/// Checks of an extracted quad mesh against its map: an oriented 2-manifold polygon mesh with the
/// Euler characteristic, genus and boundary loops of the map per component, valence 4 away from
/// cones and 4 - k at a cone of index k.
#include <cstdint>
#include <vector>

#include "core/mesh/topology.h"
#include "core/quads/extract.h"

namespace seamvox {

struct QuadComponentCheck {
  std::uint32_t component = 0;  ///< of the map (ComponentsResult::components)
  std::uint64_t vertices = 0, edges = 0, faces = 0;
  std::uint32_t boundaryLoops = 0, mapBoundaryLoops = 0;
  std::int64_t eulerCharacteristic = 0, mapEulerCharacteristic = 0;
  std::int64_t genus = 0, mapGenus = 0;
  bool matches() const {
    return eulerCharacteristic == mapEulerCharacteristic && boundaryLoops == mapBoundaryLoops;
  }
};

struct QuadValidation {
  std::uint64_t vertices = 0, edges = 0, faces = 0;
  std::uint64_t quads = 0, triangles = 0, pentagons = 0, otherFaces = 0;  ///< by degree
  double quadFraction = 0.0;
  std::uint64_t boundaryEdges = 0, boundaryLoops = 0;
  /// Directed edges in more than one face (two faces of opposite orientation, or an edge in
  /// three or more faces): 0 for an oriented 2-manifold.
  std::uint64_t nonManifoldEdges = 0;
  std::uint64_t nonManifoldVertices = 0;  ///< vertices with boundary edges in != out or > 1
  std::uint64_t degenerateFaces = 0;      ///< faces that visit a vertex twice
  /// Interior vertices off cones with valence != 4 (less QuadResult::vertexLostEdges)
  std::uint64_t irregularVertices = 0;
  std::uint64_t conesOnVertices = 0;      ///< interior vertices on a cone
  std::uint64_t conesWithWrongValence = 0;  ///< of them, valence != 4 - index
  std::uint64_t interiorNonQuads = 0;     ///< faces without a boundary edge whose degree is not 4
  std::vector<QuadComponentCheck> components;  ///< components of the map that have faces
  std::uint64_t componentsDiffering = 0;  ///< of them, Euler characteristic or loops differ
  /// Every check holds (isolated cones in cells are allowed to make non-quads).
  bool isValid() const {
    return nonManifoldEdges == 0 && nonManifoldVertices == 0 && degenerateFaces == 0 &&
           irregularVertices == 0 && conesWithWrongValence == 0 && componentsDiffering == 0;
  }
};

/// Checks a quad mesh made by extractQuads from the map whose components are `map`
/// (computeComponents of its topology). Linear after a sort of the edges.
QuadValidation validateQuads(const QuadResult& quads, const ComponentsResult& map);

}  // namespace seamvox
