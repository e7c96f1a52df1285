#include "testing.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/system/errors.h"

namespace seamvox::testing {

std::string sharedMesh(const std::string& name) {
  std::string dir = SEAMVOX_SHARED_DATA;
  if (const char* env = std::getenv("SEAMVOX_DATA")) dir = env;
  const std::string path = dir + "/" + name;
  return std::filesystem::exists(path) ? path : std::string();
}

std::string missingSharedMessage(const std::string& name) {
  return "shared test mesh " + name + " not found (looked in " SEAMVOX_SHARED_DATA
         " and $SEAMVOX_DATA); skipping";
}

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "seamvox-test-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  dir_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

int runSeamvox(const std::string& arguments, std::string* output) {
  const std::string cmd = std::string(SEAMVOX_BINARY) + " " + arguments + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed");
  std::string text;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) text.append(buf.data(), n);
  const int status = pclose(pipe);
  if (output) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string seamvoxBinary() { return SEAMVOX_BINARY; }

std::vector<std::string> temporaryFilesIn(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".tmp-") != std::string::npos) found.push_back(name);
  }
  return found;
}

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

VertexId addPowerFan(TriangleMesh& mesh, std::vector<Vec2d>& uv, double power, float z, int faces, VertexId centre) {
  constexpr int n = 10;
  if (centre == kInvalidId) {
    centre = mesh.numVertices();
    mesh.positions.push_back(Vec3f(0.0f, 0.0f, z - 0.5f));
  }
  const VertexId rim = mesh.numVertices();
  for (int j = 0; j < n; ++j) {
    const double a = 2.0 * M_PI * j / n;
    mesh.positions.push_back(Vec3f(float(std::cos(a)), float(std::sin(a)), z));
  }
  for (int j = 0; j < faces; ++j) {
    mesh.triangles.push_back({centre, rim + j, rim + (j + 1) % n});
    uv.push_back(Vec2d::Zero());
    for (int k : {j, j + 1}) uv.push_back(Vec2d(std::cos(power * 2.0 * M_PI * k / n), std::sin(power * 2.0 * M_PI * k / n)));
  }
  return centre;
}

std::vector<Vec2d> cornerValues(const WedgeMap& map) {
  std::vector<Vec2d> values(map.size());
  for (CornerId c = 0; c < map.size(); ++c) values[c] = map[c];
  return values;
}

void expectScratchFull(const ScratchFolder& folder, const std::function<void()>& run) {
  std::string message;
  try {
    run();
  } catch (const IoError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find(folder.path()), std::string::npos) << message;
  EXPECT_NE(message.find("full"), std::string::npos) << message;
}

}  // namespace seamvox::testing
