// Mesh I/O benchmark: writes and reads a generated binary PLY of N triangles and prints the wall
// time and peak resident memory (VmHWM, reset before each step) of every step.
//   bench_io [N=20000000] [path=/tmp/seamvox_bench_io.ply] [uv]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>

#include "io/mesh_io.h"
#include "stream/mesh_stream.h"

namespace {

using namespace seamvox;

/// A field from /proc/self/status in MiB (VmHWM, VmRSS).
double statusMiB(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(field);
  while (std::getline(status, line)) {
    if (line.compare(0, n, field) == 0 && line.size() > n && line[n] == ':') {
      return std::atof(line.c_str() + n + 1) / 1024.0;
    }
  }
  return -1;
}

/// Resets VmHWM to the current RSS (Linux: "5" into clear_refs), so each step shows its own peak.
void resetPeak() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
}

void step(const char* name, const std::function<std::string()>& body) {
  resetPeak();
  const double before = statusMiB("VmRSS");
  const auto start = std::chrono::steady_clock::now();
  const std::string detail = body();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%-28s %8.2f s   peak RSS %8.1f MiB (%.1f MiB at start)   %s\n", name, seconds,
              statusMiB("VmHWM"), before, detail.c_str());
  std::fflush(stdout);
}

/// A nearly square grid with exactly n triangles (the last row may be partial).
TriangleMesh makeGrid(std::uint64_t n, bool withUV) {
  const std::uint64_t cols = static_cast<std::uint64_t>(std::ceil(std::sqrt(n / 2.0)));
  const std::uint64_t rows = (n + 2 * cols - 1) / (2 * cols);
  TriangleMesh mesh;
  mesh.positions.reserve((rows + 1) * (cols + 1));
  for (std::uint64_t i = 0; i <= rows; ++i) {
    for (std::uint64_t j = 0; j <= cols; ++j) {
      mesh.positions.emplace_back(0.001f * j, 0.001f * i, 0.01f * std::sin(0.01f * (i + j)));
    }
  }
  mesh.triangles.reserve(n);
  auto id = [&](std::uint64_t i, std::uint64_t j) { return static_cast<VertexId>(i * (cols + 1) + j); };
  for (std::uint64_t i = 0; i < rows && mesh.triangles.size() < n; ++i) {
    for (std::uint64_t j = 0; j < cols && mesh.triangles.size() < n; ++j) {
      mesh.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      if (mesh.triangles.size() < n) mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  }
  if (withUV) {
    WedgeMapBuilder uv;
    uv.reserve(3 * n);
    for (const Triangle& t : mesh.triangles) {
      for (const VertexId v : t) uv.add(v, Vec2d(mesh.positions[v][0] * 3.1, mesh.positions[v][1] / 7.0));
    }
    mesh.cornerUV = uv.finish();
  }
  return mesh;
}

}  // namespace

int main(int argc, char** argv) {
  const std::uint64_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 20000000ull;
  const std::string path = argc > 2 ? argv[2] : "/tmp/seamvox_bench_io.ply";
  const bool withUV = argc > 3 && std::string(argv[3]) == "uv";
  std::printf("bench_io: %llu triangles%s -> %s\n", static_cast<unsigned long long>(n),
              withUV ? " with per-corner UVs" : "", path.c_str());
  try {
    TriangleMesh mesh;
    step("generate grid", [&] {
      mesh = makeGrid(n, withUV);
      return std::to_string(mesh.numVertices()) + " vertices";
    });
    step("write binary PLY", [&] {
      writeMesh(path, mesh);
      std::ifstream file(path, std::ios::binary | std::ios::ate);
      return std::to_string(static_cast<long long>(file.tellg()) >> 20) + " MiB file";
    });
    mesh = TriangleMesh();
    ReadOptions options;
    options.readUV = withUV;
    step("stream (chunks only)", [&] {
      auto stream = openMeshStream(path, options);
      MeshChunk chunk;
      std::uint64_t triangles = 0, chunks = 0;
      while (stream->next(chunk)) {
        triangles += chunk.triangles.size();
        ++chunks;
      }
      return std::to_string(triangles) + " triangles in " + std::to_string(chunks) + " chunks";
    });
    step("readMesh", [&] {
      mesh = readMesh(path, options);
      return std::to_string(mesh.numFaces()) + " triangles";
    });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_io: %s\n", e.what());
    std::remove(path.c_str());
    return 1;
  }
  std::remove(path.c_str());
  return 0;
}
