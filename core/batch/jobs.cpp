#include "core/batch/jobs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>
#include <unordered_map>

#include "core/solve/param_solver.h"
#include "core/system/errors.h"

namespace seamvox {
namespace {

bool isAbsolute(const std::string& path) { return !path.empty() && path[0] == '/'; }

std::string joinPath(const std::string& base, const std::string& path) {
  if (isAbsolute(path) || base.empty()) return path;
  return base.back() == '/' ? base + path : base + "/" + path;
}

/// File name without folder and last extension.
std::string stemOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.resize(dot);
  return name;
}

std::vector<std::string> tokenize(const std::string& line) {
  std::vector<std::string> tokens;
  std::istringstream in(line);
  std::string token;
  while (in >> token) tokens.push_back(token);
  return tokens;
}

/// Value of "--name value" in args (the last one given), or fallback.
std::string optionValue(const std::vector<std::string>& args, const std::string& name,
                        const std::string& fallback) {
  std::string value = fallback;
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == name) value = args[i + 1];
  }
  return value;
}

}  // namespace

namespace {

/// One manifest line: its directive, arguments and job options (after ':'; for 'param' all of
/// them). Options the job runner sets itself are refused.
struct ManifestLine {
  std::string directive;
  std::vector<std::string> tokens, options;
};

ManifestLine splitManifestLine(std::vector<std::string> tokens, const std::string& where) {
  ManifestLine l;
  l.directive = tokens[0];
  tokens.erase(tokens.begin());
  // Job options after ':'.
  const auto colon = std::find(tokens.begin(), tokens.end(), ":");
  if (colon != tokens.end()) {
    l.options.assign(colon + 1, tokens.end());
    tokens.erase(colon, tokens.end());
  }
  if (l.directive == "param") {
    l.options = tokens;
    tokens.clear();
  }
  for (const std::string& option : l.options) {
    if (option == "-o" || option == "--output" || option == "--report") {
      throw InputError(where + "'" + option + "' is set by the job runner; remove it");
    }
  }
  l.tokens = std::move(tokens);
  return l;
}

/// The jobs of a 'mesh' line (one per matched file) or a 'tiles' line (one job of every file).
std::vector<JobSpec> jobsOfLine(const ManifestLine& l, JobSpec base, const std::string& where,
                                const std::string& baseDir, const ExpandFn& expand) {
  const bool tiled = base.tiled;
  std::vector<std::string> files;
  for (std::size_t i = tiled ? 1 : 0; i < l.tokens.size(); ++i) {
    const std::vector<std::string> matched = expand(joinPath(baseDir, l.tokens[i]));
    if (matched.empty()) throw InputError(where + "no file matches '" + l.tokens[i] + "'");
    files.insert(files.end(), matched.begin(), matched.end());
  }
  std::vector<JobSpec> made;
  if (tiled) {
    base.name = l.tokens[0];
    if (base.name.find('/') != std::string::npos) {
      throw InputError(where + "a tiles name cannot contain '/': " + base.name);
    }
    base.inputs = files;
    std::set<std::string> stems;
    for (const std::string& f : files) {
      if (!stems.insert(stemOf(f)).second) {
        throw InputError(where + "two tiles named '" + stemOf(f) + "' (outputs would collide)");
      }
    }
    made.push_back(base);
  } else {
    for (const std::string& f : files) {
      JobSpec job = base;
      job.name = stemOf(f);
      job.inputs = {f};
      made.push_back(job);
    }
  }
  return made;
}

}  // namespace

Manifest parseManifest(const std::string& text, const std::string& source, const std::string& baseDir,
                       const ExpandFn& expand) {
  Manifest manifest;
  manifest.outputDir = joinPath(baseDir, "out");
  std::string format = "drc";
  std::vector<std::string> defaults;
  std::set<std::string> names;
  std::istringstream lines(text);
  std::string line;
  std::uint32_t number = 0;
  while (std::getline(lines, line)) {
    ++number;
    const std::string where = source + ":" + std::to_string(number) + ": ";
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::vector<std::string> tokens = tokenize(line);
    if (tokens.empty()) continue;
    const ManifestLine l = splitManifestLine(std::move(tokens), where);
    const std::string& directive = l.directive;
    auto requireArguments = [&](std::size_t count, const char* what) {
      if (l.tokens.size() < count) throw InputError(where + "'" + directive + "' needs " + what);
    };
    if (directive == "output") {
      requireArguments(1, "a folder");
      if (l.tokens.size() > 1 || !l.options.empty()) throw InputError(where + "'output' takes one folder");
      manifest.outputDir = joinPath(baseDir, l.tokens[0]);
    } else if (directive == "format") {
      requireArguments(1, "one of drc, obj, ply");
      format = l.tokens[0];
      if (!format.empty() && format[0] == '.') format.erase(0, 1);
      if (format != "drc" && format != "obj" && format != "ply") {
        throw InputError(where + "unknown format '" + l.tokens[0] + "' (use drc, obj or ply)");
      }
    } else if (directive == "param") {
      defaults = l.options;
    } else if (directive == "mesh" || directive == "tiles") {
      const bool tiled = directive == "tiles";
      requireArguments(tiled ? 2 : 1, tiled ? "a name and at least one tile file" : "a file or glob");
      JobSpec base;
      base.paramArgs = defaults;
      base.paramArgs.insert(base.paramArgs.end(), l.options.begin(), l.options.end());
      base.format = format;
      base.tiled = tiled;
      base.line = number;
      for (JobSpec& job : jobsOfLine(l, std::move(base), where, baseDir, expand)) {
        if (!names.insert(job.name).second) {
          throw InputError(where + "two jobs named '" + job.name + "' (their outputs would collide)");
        }
        manifest.jobs.push_back(std::move(job));
      }
    } else {
      throw InputError(where + "unknown directive '" + directive +
                       "' (known: output, format, param, mesh, tiles)");
    }
  }
  return manifest;
}

std::uint64_t estimateJobPeakBytes(std::uint64_t faces, const std::vector<std::string>& paramArgs,
                                   std::uint64_t propertyBytes) {
  // The rule `seamvox param` checks against its own budget (estimateParamPeakBytes), with the
  // job's --solver and --grid; malformed values fall back to the defaults (param reports them).
  ParamSolver solver = ParamSolver::Auto;
  try {
    solver = parseParamSolver(optionValue(paramArgs, "--solver", "auto"));
  } catch (const InputError&) {
  }
  const int grid = std::atoi(optionValue(paramArgs, "--grid", "128").c_str());
  const std::uint64_t bytes =
      estimateParamPeakBytes(faces, solver, grid >= 4 && grid <= 1024 ? grid : kDefaultGridResolution);
  return bytes + 3 * propertyBytes;
}

std::uint64_t jobOutOfCoreMinimumBytes(const std::vector<std::string>& paramArgs) {
  const int grid = std::atoi(optionValue(paramArgs, "--grid", "128").c_str());
  return outOfCoreMinimumBytes(grid >= 4 && grid <= 1024 ? grid : kDefaultGridResolution);
}

std::uint64_t reserveJobMemory(std::uint64_t estimate, std::uint64_t outOfCoreMinimum, std::uint64_t budget) {
  if (estimate <= budget) return estimate;
  return outOfCoreMinimum <= budget ? budget : 0;
}

std::int64_t pickNextJob(const std::vector<std::uint64_t>& pendingEstimates, std::uint64_t runningBytes,
                         std::uint64_t budget) {
  for (std::size_t i = 0; i < pendingEstimates.size(); ++i) {
    if (runningBytes <= budget && pendingEstimates[i] <= budget - runningBytes) {
      return static_cast<std::int64_t>(i);
    }
  }
  return -1;
}

std::uint64_t hashBytes(const void* data, std::size_t bytes, std::uint64_t seed) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  std::uint64_t h = seed;
  // Eight bytes per step (a word-wise FNV-1a variant), then the tail byte by byte.
  std::size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + i, 8);
    h = (h ^ word) * 0x100000001b3ull;
    h ^= h >> 29;
  }
  for (; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

namespace {

using PositionKey = std::array<std::uint32_t, 3>;
using FaceKey = std::array<std::uint32_t, 9>;

PositionKey keyOf(const Vec3f& p) {
  PositionKey key;
  std::memcpy(key.data(), p.data(), sizeof(key));
  // +0 and -0 are the same point.
  for (std::uint32_t& k : key) {
    if (k == 0x80000000u) k = 0;
  }
  return key;
}

struct KeyHash {
  template <std::size_t N>
  std::size_t operator()(const std::array<std::uint32_t, N>& key) const {
    return static_cast<std::size_t>(hashBytes(key.data(), N * sizeof(std::uint32_t)));
  }
};

/// The three corner positions of a face, sorted: the same for any rotation or reflection.
FaceKey faceKeyOf(const TriangleMesh& mesh, FaceId f) {
  std::array<PositionKey, 3> corners;
  for (int k = 0; k < 3; ++k) corners[k] = keyOf(mesh.positions[mesh.triangles[f][k]]);
  std::sort(corners.begin(), corners.end());
  FaceKey key;
  for (int k = 0; k < 3; ++k) std::copy(corners[k].begin(), corners[k].end(), key.begin() + 3 * k);
  return key;
}

}  // namespace

WeldedTiles weldTiles(const std::vector<TriangleMesh>& tiles) {
  WeldedTiles result;
  std::unordered_map<PositionKey, VertexId, KeyHash> earlier;  // positions of finished tiles
  std::uint64_t faces = 0;
  for (const TriangleMesh& tile : tiles) faces += tile.numFaces();
  result.mesh.triangles.reserve(faces);
  result.faceTile.reserve(faces);
  if (!tiles.empty()) result.mesh.attributes = tiles[0].attributes.emptyCopy();
  if (!tiles.empty()) result.mesh.origin = tiles[0].origin;
  for (std::uint32_t t = 0; t < tiles.size(); ++t) {
    const TriangleMesh& tile = tiles[t];
    if (tile.origin != result.mesh.origin) {
      throw InputError("tile " + std::to_string(t) + ": its positions are kept about another origin than the first "
                       "tile's (read the tiles with ReadOptions::origin)");
    }
    std::vector<VertexId> merged(tile.numVertices()), fresh;
    for (VertexId v = 0; v < tile.numVertices(); ++v) {
      const auto found = earlier.find(keyOf(tile.positions[v]));
      if (found != earlier.end()) {
        merged[v] = found->second;
        ++result.weldedVertices;
      } else {
        merged[v] = static_cast<VertexId>(result.mesh.positions.size());
        result.mesh.positions.push_back(tile.positions[v]);
        fresh.push_back(v);
      }
    }
    // A welded vertex keeps the properties of the tile that brought it first.
    try {
      result.mesh.attributes.append(tile.attributes.gathered(fresh));
    } catch (const InputError& e) {
      throw InputError("tile " + std::to_string(t) + ": " + e.what());
    }
    for (const Triangle& tri : tile.triangles) {
      result.mesh.triangles.push_back({merged[tri[0]], merged[tri[1]], merged[tri[2]]});
      result.faceTile.push_back(t);
    }
    // Only now: vertices within one tile are never merged with each other.
    for (VertexId v = 0; v < tile.numVertices(); ++v) earlier.emplace(keyOf(tile.positions[v]), merged[v]);
  }
  return result;
}

SplitTiles splitTiles(const TriangleMesh& mesh, const std::vector<TriangleMesh>& tiles) {
  std::unordered_map<FaceKey, std::uint32_t, KeyHash> faceTile;
  std::uint64_t tileFaces = 0;
  for (std::uint32_t t = 0; t < tiles.size(); ++t) {
    tileFaces += tiles[t].numFaces();
    for (FaceId f = 0; f < tiles[t].numFaces(); ++f) faceTile.emplace(faceKeyOf(tiles[t], f), t);
  }
  // Tile of every face, then the faces bucketed by tile (counting sort, order kept).
  std::vector<std::uint32_t> tileOf(mesh.numFaces());
  std::vector<std::uint64_t> first(tiles.size() + 1, 0);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const auto found = faceTile.find(faceKeyOf(mesh, f));
    if (found == faceTile.end()) {
      throw InputError("face " + std::to_string(f) + " of the parameterized mesh matches no tile face");
    }
    tileOf[f] = found->second;
    ++first[found->second + 1];
  }
  faceTile = {};
  for (std::size_t t = 0; t < tiles.size(); ++t) first[t + 1] += first[t];
  std::vector<FaceId> order(mesh.numFaces());
  {
    std::vector<std::uint64_t> next(first.begin(), first.end() - 1);
    for (FaceId f = 0; f < mesh.numFaces(); ++f) order[next[tileOf[f]]++] = f;
  }
  SplitTiles result;
  result.tiles.resize(tiles.size());
  std::vector<VertexId> map(mesh.numVertices(), kInvalidId);  // reset after each tile
  std::vector<VertexId> source;                                 // of each tile vertex
  for (std::size_t t = 0; t < tiles.size(); ++t) {
    TriangleMesh& out = result.tiles[t];
    out.origin = mesh.origin;
    source.clear();
    out.triangles.reserve(first[t + 1] - first[t]);
    WedgeMapBuilder uv;
    if (mesh.hasUV()) uv.reserve(3 * (first[t + 1] - first[t]));
    for (std::uint64_t i = first[t]; i < first[t + 1]; ++i) {
      const FaceId f = order[i];
      Triangle tri;
      for (int k = 0; k < 3; ++k) {
        const VertexId v = mesh.triangles[f][k];
        if (map[v] == kInvalidId) {
          map[v] = out.numVertices();
          out.positions.push_back(mesh.positions[v]);
          source.push_back(v);
        }
        tri[k] = map[v];
        if (mesh.hasUV()) uv.add(tri[k], mesh.cornerUV[3 * f + k]);
      }
      out.triangles.push_back(tri);
    }
    if (mesh.hasUV()) out.cornerUV = uv.finish();
    out.attributes = mesh.attributes.gathered(source);
    for (std::uint64_t i = first[t]; i < first[t + 1]; ++i) {
      for (const VertexId v : mesh.triangles[order[i]]) map[v] = kInvalidId;
    }
  }
  std::uint64_t placed = 0;
  for (const TriangleMesh& tile : result.tiles) placed += tile.numFaces();
  result.missingFaces = tileFaces > placed ? tileFaces - placed : 0;
  return result;
}

}  // namespace seamvox
