#pragma once
/// The mesh summary shared by `seamvox info` and `seamvox demo`: read, clean, components,
/// bounding box, timings and memory, printed as text or JSON.
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/clean.h"
#include "core/mesh/mesh.h"
#include "core/system/progress.h"
#include "core/mesh/topology.h"

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
};

struct SummarizeOptions {
  bool weld = false;
  double weldTolerance = 0.0;
  ProgressFn progress;
};

/// Reads, cleans and measures a mesh file. Throws IoError / InputError from the reader.
MeshSummary summarizeMeshFile(const std::string& path, const SummarizeOptions& options);
/// Human-readable report; lists the `largest` biggest components.
std::string formatSummaryText(const MeshSummary& summary, std::size_t largest = 5);
/// The same as a JSON document.
std::string formatSummaryJson(const MeshSummary& summary, std::size_t largest = 5);

}  // namespace seamvox::cli
