#pragma once
/// Per-component figures of a parameterized mesh (`param --report`): size, topology, area, how
/// the component was mapped, its cones and flipped faces; bounded to the largest components with
/// a summary of the rest, so a scan with 100K islands keeps a small report. And the removal of
/// the components the solve could not map (`param --drop-unsolved`).
#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace seamvox {

/// How a component was mapped; when several apply, the first in this order is reported.
enum class ComponentMapping : std::uint8_t {
  Unsolved,  ///< its system could not be factored: left at (u, v) = 0 (written unmapped or dropped)
  Point,     ///< every corner within kCoincidentConeDistance of one (u, v): smaller than a cell
  Anchored,  ///< closed, every position a cone: its shift was fixed through a translation
  Solved,    ///< its own chart in the global map
};
/// "unsolved", "point", "anchored", "solved".
const char* componentMappingName(ComponentMapping mapping);

struct ComponentFigures {
  /// Components are numbered in the order of their lowest face (cleaning keeps the input's face
  /// order), so an id names the same component whatever the solver.
  std::uint32_t id = 0;
  std::uint32_t faces = 0, vertices = 0, boundaryLoops = 0;
  std::int64_t eulerCharacteristic = 0, genus = 0;
  double area = 0.0;  ///< mesh units squared
  ComponentMapping mapping = ComponentMapping::Solved;
  std::uint32_t cones = 0;
  std::uint64_t flippedFaces = 0;  ///< negative parameter area, not collapsed (metrics.h)
};

struct ComponentSummary {
  std::uint32_t count = 0;
  std::uint32_t mapped[4] = {0, 0, 0, 0};  ///< components per ComponentMapping
  std::uint32_t limit = 0;                 ///< most components listed
  std::vector<ComponentFigures> listed;    ///< the largest by faces (then by id), <= limit
  std::uint32_t unlisted = 0;              ///< the others: count and faces
  std::uint64_t unlistedFaces = 0;
  std::vector<std::uint32_t> unsolvedIds;  ///< every unsolved component, listed or not
  std::vector<std::uint32_t> droppedIds;   ///< unsolved components removed from the mesh
  std::uint64_t droppedFaces = 0;
};

/// Figures of every component of mesh (its cornerUV holds the map, spacing edgeLength) with the
/// solver's facts: cones (vertex ids), the faces of unsolved and of anchored components (sorted,
/// ParamResult). When unsolvedComponentFaces is given it receives the faces of the components
/// reported unsolved. flippedFaces (when given: the map's flipped faces, as measureMap lists them)
/// spares measuring every face's flip again. Linear, parallel; 10 bytes per face while it runs.
ComponentSummary summarizeComponents(const TriangleMesh& mesh, const Topology& topology,
                                     const std::vector<VertexId>& cones,
                                     const std::vector<FaceId>& unsolvedFaces,
                                     const std::vector<FaceId>& anchoredFaces, double edgeLength,
                                     std::uint32_t limit,
                                     std::vector<FaceId>* unsolvedComponentFaces = nullptr,
                                     const std::vector<FaceId>* flippedFaces = nullptr);

/// The mesh without the given faces (sorted) and without the vertices only they used; the map
/// (cornerUV) follows. Order of the kept faces and vertices is kept; vertexMap (when given)
/// receives the new id of every old vertex (kInvalidId when removed).
TriangleMesh removeFaces(const TriangleMesh& mesh, const std::vector<FaceId>& faces,
                         std::vector<VertexId>* vertexMap = nullptr);

}  // namespace seamvox
