#pragma once
/// Batch jobs for `seamvox jobs`: the manifest, memory estimates, the scheduling rule, and tile
/// sets (several files that form one surface). No file access here: the caller expands globs and
/// reads the files.
///
/// Manifest format (text, one directive per line, '#' starts a comment, tokens separated by
/// blanks, so paths cannot contain blanks; relative paths are relative to the manifest's folder):
///   output DIR                    output folder (default: "out" next to the manifest)
///   format drc|obj|ply            output format of the jobs below (default drc)
///   param OPTIONS...              default `seamvox param` options of the jobs below (replaces
///                                 the previous defaults; e.g. "param --solver hat --cells 80")
///   mesh PATH|GLOB... [: OPTIONS...]        one job per file; OPTIONS are added to the defaults
///   tiles NAME PATH|GLOB... [: OPTIONS...]  one job: the files are tiles of one surface
/// A mesh job writes DIR/<file stem>.<format> and DIR/<file stem>.json; a tiles job writes one
/// DIR/NAME/<tile stem>.<format> per tile and DIR/NAME.json.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"

namespace seamvox {

struct JobSpec {
  std::string name;                    ///< output stem (mesh) or the tiles' NAME
  std::vector<std::string> inputs;     ///< one file, or the tiles in manifest order
  std::vector<std::string> paramArgs;  ///< `seamvox param` options (defaults, then the job's)
  std::string format = "drc";          ///< output extension without the dot
  bool tiled = false;
  std::uint32_t line = 0;  ///< manifest line that made the job
};

struct Manifest {
  std::string outputDir;
  std::vector<JobSpec> jobs;
};

/// Expands one path or glob (already made absolute) into the matching files, sorted; a plain
/// path that does not exist expands to itself (the job then fails with the reader's message).
using ExpandFn = std::function<std::vector<std::string>(const std::string& pattern)>;

/// Parses manifest text. Relative paths are joined to baseDir. Throws InputError naming
/// source:line for unknown directives, missing arguments, output options (-o, --report) in
/// OPTIONS, an unknown format, a glob without matches and two jobs with the same name.
Manifest parseManifest(const std::string& text, const std::string& source, const std::string& baseDir,
                       const ExpandFn& expand);

/// Estimated peak resident bytes of one `seamvox param` run on `faces` faces with these param
/// options (--solver, default auto; --grid): the rule param itself checks against its budget
/// (estimateParamPeakBytes), plus three times propertyBytes of vertex properties (colors,
/// normals...: read, gathered by cleaning, written).
std::uint64_t estimateJobPeakBytes(std::uint64_t faces, const std::vector<std::string>& paramArgs,
                                   std::uint64_t propertyBytes = 0);

/// The smallest budget of param's out-of-core path for the job's --grid (outOfCoreMinimumBytes).
std::uint64_t jobOutOfCoreMinimumBytes(const std::vector<std::string>& paramArgs);

/// The memory a job reserves under the budget, by param's own rule: its estimate when that fits;
/// else the whole budget, in which param takes its out-of-core path, when the budget holds that
/// path (outOfCoreMinimum); else 0: the job cannot run within the budget.
std::uint64_t reserveJobMemory(std::uint64_t estimate, std::uint64_t outOfCoreMinimum, std::uint64_t budget);

/// The scheduling rule: the first pending job (in order) whose estimate fits next to the running
/// ones (runningBytes + estimate <= budget), or -1 when none fits now. A job larger than the whole
/// budget is the caller's to fail (it could never start).
std::int64_t pickNextJob(const std::vector<std::uint64_t>& pendingEstimates, std::uint64_t runningBytes,
                         std::uint64_t budget);

/// 64-bit FNV-1a style hash of a byte range, continuing from seed (chain calls to hash several).
std::uint64_t hashBytes(const void* data, std::size_t bytes, std::uint64_t seed = 0xcbf29ce484222325ull);

/// Tiles welded into one mesh: vertices of different tiles at exactly the same position become
/// one (vertices within a tile are never merged). faceTile[f] is the tile of merged face f; faces
/// keep their order, tile by tile. UVs are dropped; vertex properties are kept (a welded vertex
/// takes the first tile's values) and must be the same in every tile (InputError otherwise).
struct WeldedTiles {
  TriangleMesh mesh;
  std::vector<std::uint32_t> faceTile;
  std::uint64_t weldedVertices = 0;  ///< tile vertices merged into an earlier tile's vertex
};
WeldedTiles weldTiles(const std::vector<TriangleMesh>& tiles);

/// Splits a parameterized mesh of welded tiles back into one mesh per tile: each face goes to the
/// tile holding a face with the same three positions (any order or orientation); vertices are
/// compacted per tile and UVs and vertex properties kept. Throws InputError when a face matches no tile. missingFaces
/// counts tile faces absent from the mesh (dropped as degenerate or duplicate by cleaning).
struct SplitTiles {
  std::vector<TriangleMesh> tiles;
  std::uint64_t missingFaces = 0;
};
SplitTiles splitTiles(const TriangleMesh& mesh, const std::vector<TriangleMesh>& tiles);

}  // namespace seamvox
