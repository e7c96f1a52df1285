#pragma once
/// Helpers shared by the test suites: shared-data lookup, temporary folders, running the CLI.
#include <gtest/gtest.h>

#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/wedge_map.h"
#include "stream/mesh_stream.h"
#include "stream/scratch_folder.h"

namespace seamvox::testing {

/// The value of every corner of a map (tests compare and edit maps corner by corner; rebuild
/// with WedgeMap::fromCorners).
std::vector<Vec2d> cornerValues(const WedgeMap& map);

/// Appends a fan of `faces` of 10 triangles around `centre` (a new vertex at height z - 0.5 when
/// kInvalidId) with its rim at height z, mapped by z^power (per corner into uv: the centre at 0,
/// rim vertex k at angle power 2 pi k / 10); returns the centre.
VertexId addPowerFan(TriangleMesh& mesh, std::vector<Vec2d>& uv, double power, float z, int faces,
                     VertexId centre = kInvalidId);

/// Path of a file in ../shared/data (or $SEAMVOX_DATA), or "" when it is absent. Use
///   auto path = sharedMesh("bunny.off"); if (path.empty()) GTEST_SKIP() << ...;
std::string sharedMesh(const std::string& name);
/// The message to skip with when sharedMesh returned "".
std::string missingSharedMessage(const std::string& name);

/// Expects run() to fail on the folder's full scratch disk: an IoError naming the folder.
void expectScratchFull(const ScratchFolder& folder, const std::function<void()>& run);

/// A fresh temporary folder, removed when the object goes away.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

/// Runs the seamvox binary with the given argument string (shell syntax); returns its exit code
/// and fills output with stdout+stderr.
int runSeamvox(const std::string& arguments, std::string* output = nullptr);

/// Path of the seamvox binary under test (for commands that wrap it, e.g. mpirun).
std::string seamvoxBinary();

/// Names of the files under dir (recursively) that are unfinished outputs ("<name>.tmp-<pid>").
std::vector<std::string> temporaryFilesIn(const std::string& dir);

/// Runs f and returns the message of the exception of type E it must throw (a test failure when it
/// throws another type or nothing).
template <class E>
std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

/// Writes bytes to a file (for malformed-input tests).
void writeFile(const std::string& path, const std::string& bytes);
std::string readFile(const std::string& path);

/// A stream that hides its inner stream's declared counts (as a pipe's, or an OBJ file's).
class UndeclaredStream final : public MeshStream {
 public:
  explicit UndeclaredStream(std::unique_ptr<MeshStream> inner) : inner_(std::move(inner)) {}
  bool next(MeshChunk& chunk) override { return inner_->next(chunk); }
  const std::string& name() const override { return inner_->name(); }
  bool cornerVertices() const override { return inner_->cornerVertices(); }

 private:
  std::unique_ptr<MeshStream> inner_;
};

}  // namespace seamvox::testing
