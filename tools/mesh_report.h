#pragma once
/// The mesh summary shared by `seamvox info` and `seamvox demo`: read, clean, components,
/// bounding box, timings and memory, printed as text or JSON.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/mesh.h"
#include "stream/mesh_stream.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"
#include "tools/memory_path.h"

namespace seamvox {
struct WeldCensus;
}

namespace seamvox::cli {

struct MeshSummary {
  std::string path;
  std::uint64_t vertices = 0, faces = 0;  ///< after cleaning
  CleanReport clean;
  VertexAttributes properties;  ///< the vertex properties read (names and types, no values)
  std::uint64_t propertyBytes = 0;  ///< their values in memory after cleaning
  std::vector<ComponentInfo> components;  ///< all, by decreasing face count
  std::uint32_t boundaryLoops = 0;
  BoundingBox box;
  double readSeconds = 0, cleanSeconds = 0, componentsSeconds = 0;
  std::uint64_t peakResidentBytes = 0;
  /// Measured out of core (stream/welded_scratch, stream/clean_stream): the same figures, and the
  /// edges counted by their faces before cleaning.
  bool outOfCore = false;
  std::uint64_t edges = 0, boundaryEdges = 0, manifoldEdges = 0, clashEdges = 0, edgesOfMoreFaces = 0;
  std::vector<std::pair<std::string, double>> stageSeconds;  ///< the weld pass's
  MemoryPath memoryPath;  ///< which path ran (printed last)
};

struct SummarizeOptions {
  bool weld = false;
  double weldTolerance = 0.0;
  ProgressFn progress;
};

/// Reads, cleans and measures a mesh file. Throws IoError / InputError from the reader.
MeshSummary summarizeMeshFile(const std::string& path, const SummarizeOptions& options);
/// The same from a stream opened on path (read time counted from start).
MeshSummary summarizeMeshStream(const std::string& path, MeshStream& stream, const SummarizeOptions& options,
                                std::chrono::steady_clock::time_point start);
/// The same from the weld pass's census and the streamed cleaning's report and components (out
/// of core).
MeshSummary summarizeCensus(const std::string& path, const WeldCensus& census, const CleanReport& cleaned,
                            ComponentsResult components, double seconds);
/// Human-readable report; lists the `largest` biggest components.
std::string formatSummaryText(const MeshSummary& summary, std::size_t largest = 5);
/// The same as a JSON document.
std::string formatSummaryJson(const MeshSummary& summary, std::size_t largest = 5);

}  // namespace seamvox::cli
