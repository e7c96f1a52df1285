#include "io/polygon_io.h"

#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/mesh_io.h"

namespace seamvox {

namespace {

/// Positions far from zero (a georeferenced map's quads) are written in double precision.
bool farFromZero(const PolygonMesh& mesh) {
  for (const Vec3d& p : mesh.positions) {
    if (p.cwiseAbs().maxCoeff() > kOriginBeyond) return true;
  }
  return false;
}

void writeObj(AtomicFile& file, const PolygonMesh& mesh) {
  std::string text;
  char buffer[96];
  auto flush = [&] {
    file.write(text);
    text.clear();
  };
  text += "# seamvox quads: " + std::to_string(mesh.numVertices()) + " vertices, " +
          std::to_string(mesh.numFaces()) + " faces\n";
  const char* format = farFromZero(mesh) ? "v %.17g %.17g %.17g\n" : "v %.9g %.9g %.9g\n";
  for (const Vec3d& p : mesh.positions) {
    const int n = std::snprintf(buffer, sizeof buffer, format, p.x(), p.y(), p.z());
    text.append(buffer, n);
    if (text.size() > (1u << 20)) flush();
  }
  for (std::uint32_t f = 0; f < mesh.numFaces(); ++f) {
    text += 'f';
    for (std::uint32_t i = mesh.faceStart[f]; i < mesh.faceStart[f + 1]; ++i) {
      text += ' ';
      text += std::to_string(mesh.faceVertices[i] + 1);
    }
    text += '\n';
    if (text.size() > (1u << 20)) flush();
  }
  flush();
}

void writePly(AtomicFile& file, const PolygonMesh& mesh) {
  for (std::uint32_t f = 0; f < mesh.numFaces(); ++f) {
    if (mesh.degree(f) > 255) {
      throw InputError(file.path() + ": face " + std::to_string(f) + " has " + std::to_string(mesh.degree(f)) +
                       " vertices, more than a PLY face list of uchar count holds");
    }
  }
  const bool far = farFromZero(mesh);
  file.write("ply\nformat binary_little_endian 1.0\ncomment seamvox quads\nelement vertex " +
             std::to_string(mesh.numVertices()) +
             (far ? "\nproperty double x\nproperty double y\nproperty double z\nelement face "
                  : "\nproperty float x\nproperty float y\nproperty float z\nelement face ") +
             std::to_string(mesh.numFaces()) + "\nproperty list uchar int vertex_indices\nend_header\n");
  std::string bytes;
  auto put = [&](const void* data, std::size_t n) {
    bytes.append(static_cast<const char*>(data), n);
    if (bytes.size() > (1u << 20)) file.write(bytes), bytes.clear();
  };
  static_assert(sizeof(float) == 4, "PLY floats are 4 bytes");
  const std::uint32_t probe = 1;
  if (*reinterpret_cast<const std::uint8_t*>(&probe) != 1) {
    throw IoError(file.path() + ": PLY output needs a little-endian machine");
  }
  for (const Vec3d& p : mesh.positions) {
    if (far) {
      put(p.data(), 3 * sizeof(double));
      continue;
    }
    const float xyz[3] = {float(p.x()), float(p.y()), float(p.z())};
    put(xyz, sizeof xyz);
  }
  for (std::uint32_t f = 0; f < mesh.numFaces(); ++f) {
    const std::uint8_t n = static_cast<std::uint8_t>(mesh.degree(f));
    put(&n, 1);
    for (std::uint32_t i = mesh.faceStart[f]; i < mesh.faceStart[f + 1]; ++i) {
      const std::int32_t index = static_cast<std::int32_t>(mesh.faceVertices[i]);
      put(&index, 4);
    }
  }
  file.write(bytes);
}

}  // namespace

void writePolygonMesh(AtomicFile& file, const PolygonMesh& mesh) {
  const MeshFormat format = formatFromPath(file.path());
  if (format == MeshFormat::Obj) return writeObj(file, mesh);
  if (format == MeshFormat::Ply) return writePly(file, mesh);
  throw InputError(file.path() + ": a quad mesh is written as .obj or .ply");
}

PolygonMesh readPolygonObj(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open (" + std::strerror(errno) + ")");
  PolygonMesh mesh;
  std::string line;
  std::uint64_t lineNumber = 0;
  auto fail = [&](const std::string& what) {
    throw InputError(path + ":" + std::to_string(lineNumber) + ": " + what);
  };
  std::vector<std::int64_t> corners;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const char* p = line.c_str();
    const char* end = p + line.size();
    auto skipSpace = [&] {
      while (p < end && (*p == ' ' || *p == '\t')) ++p;
    };
    skipSpace();
    if (end - p < 2 || (p[1] != ' ' && p[1] != '\t')) continue;
    if (p[0] == 'v') {
      ++p;
      double xyz[3];
      for (double& x : xyz) {
        skipSpace();
        const auto r = std::from_chars(p, end, x);
        if (r.ec != std::errc() || !std::isfinite(x)) fail("a vertex needs three finite coordinates");
        p = r.ptr;
      }
      mesh.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (p[0] == 'f') {
      ++p;
      corners.clear();
      while (true) {
        skipSpace();
        if (p >= end) break;
        std::int64_t index = 0;
        const auto r = std::from_chars(p, end, index);
        if (r.ec != std::errc() || index == 0) fail("a face corner must start with a vertex index other than 0");
        p = r.ptr;
        while (p < end && *p != ' ' && *p != '\t') ++p;  // the /vt/vn part
        corners.push_back(index);
      }
      if (corners.size() < 3) fail("a face needs at least 3 corners");
      for (std::int64_t index : corners) {
        const std::int64_t v = index > 0 ? index - 1 : std::int64_t(mesh.positions.size()) + index;
        if (v < 0 || v >= std::int64_t(mesh.positions.size())) {
          fail("vertex index " + std::to_string(index) + " out of range (" +
               std::to_string(mesh.positions.size()) + " vertices so far)");
        }
        mesh.faceVertices.push_back(static_cast<std::uint32_t>(v));
      }
      mesh.faceStart.push_back(static_cast<std::uint32_t>(mesh.faceVertices.size()));
    }
  }
  if (in.bad()) throw IoError(path + ": read error");
  if (mesh.numFaces() == 0) throw InputError(path + ": no faces");
  return mesh;
}

}  // namespace seamvox
