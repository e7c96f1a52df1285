// Seeded mutants of small files in every format (byte flips, plausible text, truncations,
// insertions, deleted and duplicated chunks) through the readers: each either reads a valid mesh
// (indices in range, finite coordinates and UVs) or throws IoError / InputError naming the file;
// never another exception, a crash or a hang (a watchdog aborts a read that takes 10 s).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <random>
#include <string>
#include <thread>

#include "core/system/errors.h"
#include "io/mesh_io.h"
#include "testing.h"

namespace seamvox {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

/// A small bumpy grid with per-corner UVs (seams where the UV jumps).
TriangleMesh smallMesh() {
  TriangleMesh mesh;
  const int n = 4;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) mesh.positions.emplace_back(0.5f * j, 0.25f * i, 0.1f * ((i * j) % 3));
  }
  std::vector<Vec2d> uv;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const VertexId a = i * (n + 1) + j, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
      for (const VertexId v : {a, b, c, a, c, d}) uv.emplace_back(0.3 * (v % (n + 1)) + (j > 1), 0.7 * (v / (n + 1)));
    }
  }
  mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, uv);
  return mesh;
}

/// The binary little-endian PLY written by writeMesh (float x y z; uchar count + int indices;
/// uchar count + double texcoords) turned big-endian.
std::string toBigEndian(std::string ply, const TriangleMesh& mesh) {
  const std::string le = "binary_little_endian", be = "binary_big_endian";
  ply.replace(ply.find(le), le.size(), be);
  std::size_t at = ply.find("end_header\n") + 11;
  auto swap = [&](std::size_t width, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k, at += width) std::reverse(ply.begin() + at, ply.begin() + at + width);
  };
  swap(4, 3 * mesh.positions.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    ++at;
    swap(4, 3);
    ++at;
    swap(8, 6);
  }
  EXPECT_EQ(at, ply.size());
  return ply;
}

/// Aborts the process when a read runs longer than the limit (a hang would otherwise only end at
/// the test timeout, without saying which mutant).
class Watchdog {
 public:
  Watchdog() : thread_([this] { watch(); }) {}
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  void start(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex_);
    what_ = what;
    since_ = std::chrono::steady_clock::now();
    busy_ = true;
  }
  void done() {
    std::lock_guard<std::mutex> lock(mutex_);
    busy_ = false;
  }

 private:
  void watch() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      wake_.wait_for(lock, std::chrono::milliseconds(200));
      if (busy_ && std::chrono::steady_clock::now() - since_ > std::chrono::seconds(10)) {
        std::fprintf(stderr, "reading %s takes more than 10 s: a hang\n", what_.c_str());
        std::abort();
      }
    }
  }
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false, busy_ = false;
  std::string what_;
  std::chrono::steady_clock::time_point since_;
  std::thread thread_;
};

/// One to four random edits of bytes.
std::string mutate(std::string bytes, std::mt19937& rng) {
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !bytes.empty(); ++e) {
    const std::size_t at = rng() % bytes.size();
    const std::size_t length = 1 + rng() % std::min<std::size_t>(bytes.size() - at, 64);
    switch (rng() % 7) {
      case 0: bytes[at] = static_cast<char>(rng()); break;                          // any byte
      case 1: bytes[at] = static_cast<char>(bytes[at] ^ (1 << (rng() % 8))); break;  // a bit flip
      case 2: bytes[at] = "0123456789 -+.\n\r/e#"[rng() % 19]; break;              // plausible text
      case 3: bytes.resize(at); break;                                             // truncation
      case 4: bytes.insert(at, std::string(1 + rng() % 4, static_cast<char>(rng()))); break;
      case 5: bytes.erase(at, length); break;                                      // a chunk deleted
      default: bytes.insert(rng() % bytes.size(), bytes.substr(at, length)); break;  // duplicated
    }
  }
  return bytes;
}

TEST(Fuzz, MutantsOfEveryFormatReadValidOrFailWithTheFileName) {
  TempDir dir;
  const TriangleMesh mesh = smallMesh();
  WriteOptions ascii;
  ascii.binary = false;
  WriteOptions lossless;
  lossless.dracoUVBits = 0;
  writeMesh(dir.path("binary.ply"), mesh);
  writeMesh(dir.path("ascii.ply"), mesh, ascii);
  writeMesh(dir.path("mesh.obj"), mesh);
  writeMesh(dir.path("mesh.off"), mesh);
  writeMesh(dir.path("mesh.drc"), mesh);
  writeMesh(dir.path("lattice.drc"), mesh);
  // Vertex properties of every PLY type (and their Draco attributes) in the readers' paths too.
  TriangleMesh withProperties = mesh;
  const ScalarType types[] = {ScalarType::Int8,  ScalarType::UInt8, ScalarType::Int16,   ScalarType::UInt16,
                              ScalarType::Int32, ScalarType::UInt32, ScalarType::Float32, ScalarType::Float64};
  const char* names[] = {"red", "green", "blue", "quality", "label", "id", "nx", "confidence"};
  for (int k = 0; k < 8; ++k) {
    VertexProperty& p = withProperties.attributes.add(names[k], types[k], mesh.numVertices());
    for (VertexId v = 0; v < mesh.numVertices(); ++v) p.setValue(v, 37.0 * v - 50.0 * k);
  }
  writeMesh(dir.path("properties.ply"), withProperties);
  writeMesh(dir.path("properties_ascii.ply"), withProperties, ascii);
  writeMesh(dir.path("properties.drc"), withProperties);
  testing::writeFile(dir.path("big.ply"), toBigEndian(testing::readFile(dir.path("binary.ply")), mesh));
  ReadOptions withUV;
  withUV.readUV = true;
  ASSERT_EQ(readMesh(dir.path("big.ply"), withUV).triangles, mesh.triangles);

  // SEAMVOX_FUZZ_TRIALS=N runs a longer campaign by hand.
  const char* env = std::getenv("SEAMVOX_FUZZ_TRIALS");
  const int trials = env ? std::atoi(env) : 300;
  Watchdog watchdog;
  std::mt19937 rng(11);
  for (const char* name : {"binary.ply", "big.ply", "ascii.ply", "mesh.obj", "mesh.off", "mesh.drc", "lattice.drc",
                           "properties.ply", "properties_ascii.ply", "properties.drc"}) {
    const std::string original = testing::readFile(dir.path(name));
    const std::string path = dir.path(std::string("fuzz_") + name);
    int failures = 0, successes = 0;
    for (int trial = 0; trial < trials; ++trial) {
      testing::writeFile(path, mutate(original, rng));
      ReadOptions options;
      options.warn = [](const std::string&) {};  // mutants that add elements or properties
      options.readUV = trial % 2 == 0;
      options.chunkTriangles = 1 + trial % 7;
      const std::string what = std::string(name) + " trial " + std::to_string(trial);
      watchdog.start(what);
      try {
        const TriangleMesh m = readMesh(path, options);
        ++successes;
        for (const Triangle& t : m.triangles) {
          for (const VertexId v : t) ASSERT_LT(v, m.numVertices()) << what;
        }
        for (const Vec3f& p : m.positions) {
          ASSERT_TRUE(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) << what;
        }
        ASSERT_TRUE(m.cornerUV.empty() || m.cornerUV.size() == 3 * m.triangles.size()) << what;
        ASSERT_NO_THROW(m.attributes.checkSize(m.numVertices())) << what;
        for (CornerId c = 0; c < m.cornerUV.size(); ++c) {
          ASSERT_TRUE(std::isfinite(m.cornerUV[c][0]) && std::isfinite(m.cornerUV[c][1])) << what;
        }
      } catch (const IoError& e) {
        ++failures;
        EXPECT_THAT(e.what(), HasSubstr(path)) << what;
      } catch (const InputError& e) {
        ++failures;
        EXPECT_THAT(e.what(), HasSubstr(path)) << what;
      } catch (const std::exception& e) {
        ADD_FAILURE() << what << ": not an IoError or InputError: " << e.what();
      }
      watchdog.done();
    }
    EXPECT_GT(failures, trials / 10) << name;
    EXPECT_GT(successes, trials / 50) << name;
  }
}

}  // namespace
}  // namespace seamvox
