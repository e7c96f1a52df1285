#include "test_meshes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <utility>

#include "core/mesh/clean.h"
#include "io/mesh_io.h"

namespace seamvox::testing {

TriangleMesh gridMesh(int n, int m, double cell) {
  TriangleMesh mesh;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= n; ++i) mesh.positions.emplace_back(float(i * cell), float(j * cell), 0.f);
  auto id = [&](int i, int j) { return VertexId(j * (n + 1) + i); };
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TriangleMesh torusMesh(int n, int m, double R, double r) {
  TriangleMesh mesh;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double a = 2 * pi * i / n, b = 2 * pi * j / m;
      mesh.positions.emplace_back(float((R + r * std::cos(b)) * std::cos(a)),
                                  float((R + r * std::cos(b)) * std::sin(a)), float(r * std::sin(b)));
    }
  auto id = [&](int i, int j) { return VertexId(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TriangleMesh icosphereMesh(int levels) {
  TriangleMesh mesh;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const double raw[12][3] = {{-1, t, 0}, {1, t, 0},   {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (const auto& p : raw) mesh.positions.push_back(Vec3d(p[0], p[1], p[2]).normalized().cast<float>());
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<VertexId, VertexId>, VertexId> mid;
    auto midpoint = [&](VertexId a, VertexId b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3d p = (mesh.position(a) + mesh.position(b)).normalized();
      mesh.positions.push_back(p.cast<float>());
      return mid[key] = VertexId(mesh.positions.size() - 1);
    };
    std::vector<Triangle> finer;
    for (const Triangle& tri : mesh.triangles) {
      const VertexId a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], a, c});
      finer.push_back({tri[1], b, a});
      finer.push_back({tri[2], c, b});
      finer.push_back({a, b, c});
    }
    mesh.triangles = std::move(finer);
  }
  return mesh;
}

TriangleMesh cylinderMesh(int n, int m, double radius, double height) {
  TriangleMesh mesh;
  const double pi = std::acos(-1.0);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * pi * i / n;
      mesh.positions.emplace_back(float(radius * std::cos(a)), float(radius * std::sin(a)), float(height * j / m));
    }
  auto id = [&](int i, int j) { return VertexId(j * n + (i % n)); };
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TriangleMesh generatedMesh(MeshKind kind, std::uint64_t faces) {
  GenerateOptions options;
  options.kind = kind;
  options.faces = faces;
  return generateMesh(options).mesh;
}

TriangleMesh concatMeshes(const std::vector<TriangleMesh>& parts) {
  TriangleMesh out;
  for (const TriangleMesh& p : parts) {
    const VertexId base = out.numVertices();
    out.positions.insert(out.positions.end(), p.positions.begin(), p.positions.end());
    for (Triangle t : p.triangles) out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return out;
}

TriangleMesh torusWithIslands(int n, int m, int specks, double cell, int ballLevels, float ballRadius,
                              std::uint32_t seed) {
  std::vector<TriangleMesh> parts{torusMesh(n, m)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> at(-2.0f, 2.0f);
  for (int k = 0; k < specks; ++k) {
    TriangleMesh speck = gridMesh(2, 1 + k % 2, cell);
    const Vec3f shift(at(rng), at(rng), 1.2f + 0.1f * k);
    for (Vec3f& p : speck.positions) {
      if (k % 2) p = Vec3f(p[0], 0.6f * p[1], 0.8f * p[1] + 0.3f * p[0]);
      p += shift;
    }
    parts.push_back(speck);
  }
  TriangleMesh ball = icosphereMesh(ballLevels);
  for (Vec3f& p : ball.positions) p = ballRadius * p + Vec3f(0.0f, 0.0f, -1.4f);
  parts.push_back(ball);
  return concatMeshes(parts);
}

Surface makeSurface(TriangleMesh mesh) {
  Surface s;
  s.topology = Topology::build(mesh.triangles, mesh.numVertices());
  s.mesh = std::move(mesh);
  return s;
}

CutSurface makeCutSurface(TriangleMesh mesh, std::uint32_t randomFieldSeed) {
  CutSurface out;
  out.s = makeSurface(std::move(mesh));
  out.field = randomFieldSeed ? randomField(out.s.mesh, randomFieldSeed)
                              : computeSmoothestField(out.s.mesh, out.s.topology);
  out.cut = cutToDisk(out.s.mesh, out.s.topology, out.field,
                      computeSingularities(out.s.mesh, out.s.topology, out.field));
  return out;
}

Surface loadShared(const std::string& path) {
  CleanResult cleaned = cleanMesh(readMesh(path));
  return {std::move(cleaned.mesh), std::move(cleaned.topology)};
}

CutResult boundaryCut(const Topology& topology) {
  CutResult cut;
  cut.corners = CutCorners(topology.numCorners(), false);
  for (CornerId c = 0; c < topology.numCorners(); ++c) cut.corners.setCut(c, topology.isBoundaryEdge(c));
  cut.faceRotation = FaceRotations(topology.numFaces());
  return cut;
}

CrossField constantField(const TriangleMesh& mesh, const Vec3d& direction) {
  CrossField field;
  field.direction.assign(mesh.numFaces(), direction.normalized().cast<float>());
  return field;
}

CrossField randomField(const TriangleMesh& mesh, std::uint32_t seed) {
  std::vector<Vec3d> v(mesh.numFaces());
  std::uint64_t state = seed * 0x9E3779B97F4A7C15ull + 1;
  for (Vec3d& x : v) {
    for (int k = 0; k < 3; ++k) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      x[k] = double(state >> 11) / 9007199254740992.0 - 0.5;
    }
  }
  return projectToTangent(mesh, std::move(v));
}

TriangleMesh withOneTriangleHoles(TriangleMesh mesh, std::uint32_t every) {
  std::vector<Triangle> kept;
  std::vector<std::uint8_t> touched(mesh.numVertices(), 0);
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const bool remove = f % every == every / 2 && !touched[t[0]] && !touched[t[1]] && !touched[t[2]];
    if (remove) {
      for (VertexId v : t) touched[v] = 1;
    } else {
      kept.push_back(t);
    }
  }
  mesh.triangles = std::move(kept);
  return mesh;
}

TriangleMesh shuffledMesh(const TriangleMesh& mesh, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<VertexId> vertexPerm(mesh.numVertices());
  std::iota(vertexPerm.begin(), vertexPerm.end(), 0u);
  std::shuffle(vertexPerm.begin(), vertexPerm.end(), rng);
  std::vector<FaceId> facePerm(mesh.numFaces());
  std::iota(facePerm.begin(), facePerm.end(), 0u);
  std::shuffle(facePerm.begin(), facePerm.end(), rng);
  TriangleMesh out;
  out.positions.resize(mesh.numVertices());
  for (VertexId v = 0; v < mesh.numVertices(); ++v) out.positions[vertexPerm[v]] = mesh.positions[v];
  for (FaceId f : facePerm) {
    const Triangle& t = mesh.triangles[f];
    out.triangles.push_back({vertexPerm[t[0]], vertexPerm[t[1]], vertexPerm[t[2]]});
  }
  return out;
}

TriangleMesh fanDiskMesh(int n, int rings) {
  TriangleMesh mesh;
  mesh.positions.push_back(Vec3f::Zero());
  for (int k = 1; k <= rings; ++k) {
    for (int j = 0; j < n; ++j) {
      const double t = 2.0 * M_PI * (j + 0.5 * k) / n;
      mesh.positions.push_back(Vec3f(float(k * std::cos(t)), float(k * std::sin(t)), 0.f));
    }
  }
  const auto ring = [&](int k, int j) { return VertexId(k == 0 ? 0 : 1 + (k - 1) * n + (j % n)); };
  for (int j = 0; j < n; ++j) mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int k = 1; k < rings; ++k) {
    for (int j = 0; j < n; ++j) {
      mesh.triangles.push_back({ring(k, j), ring(k + 1, j), ring(k + 1, j + 1)});
      mesh.triangles.push_back({ring(k, j), ring(k + 1, j + 1), ring(k, j + 1)});
    }
  }
  return mesh;
}

CrossField turningField(const TriangleMesh& mesh, double turns) {
  CrossField field;
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const Vec3d x = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3.0;
    const double theta = turns * std::atan2(x.y(), x.x()) / 4.0;
    field.direction.push_back(Vec3f(float(std::cos(theta)), float(std::sin(theta)), 0.f));
  }
  return field;
}

// A Moebius strip of n quads (two triangles each), its last quad glued to the first turned over.
TriangleMesh moebiusStrip(int n, const Vec3f& at) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * M_PI * i / n;
    for (const double s : {-0.2, 0.2}) {
      m.positions.push_back(at + Vec3f(float((1.0 + s * std::cos(t / 2)) * std::cos(t)),
                                       float((1.0 + s * std::cos(t / 2)) * std::sin(t)), float(s * std::sin(t / 2))));
    }
  }
  for (int i = 0; i < n; ++i) {
    const VertexId a = 2 * i, b = 2 * i + 1;
    const bool last = i + 1 == n;
    const VertexId c = last ? 1 : 2 * (i + 1), d = last ? 0 : 2 * (i + 1) + 1;
    m.triangles.push_back({a, c, d});
    m.triangles.push_back({a, d, b});
  }
  return m;
}

// A scan-like mesh with every kind of damage cleaning repairs: fins (edges of three and four
// faces), bowties (a fan joined at one vertex), flipped patches, duplicate and reversed faces,
// a Moebius strip and a pair of faces meeting along an edge in the same direction.
TriangleMesh damagedMesh(std::uint32_t seed) {
  TriangleMesh m = generatedMesh(MeshKind::Scan, 6000);
  std::mt19937 random(seed);
  const std::uint32_t nf = m.numFaces();
  for (int k = 0; k < 12; ++k) {  // fins: one or two extra faces on an edge
    const Triangle t = m.triangles[random() % nf];
    for (int j = 0; j <= k % 2; ++j) {
      const Vec3f tip = m.positions[t[0]] + 0.3f * (m.positions[t[1]] - m.positions[t[0]]).cross(Vec3f::UnitZ()) +
                        Vec3f(0.0f, 0.0f, 0.01f * float(j + 1));
      m.positions.push_back(tip);
      m.triangles.push_back({t[0], t[1], VertexId(m.positions.size() - 1)});
    }
  }
  for (int k = 0; k < 8; ++k) {  // bowties: a small fan sharing one vertex with the surface
    const VertexId v = m.triangles[random() % nf][0];
    const VertexId base = static_cast<VertexId>(m.positions.size());
    for (int j = 0; j < 3; ++j) {
      const double a = 2.0 * M_PI * j / 3;
      m.positions.push_back(m.positions[v] + Vec3f(0.01f * float(std::cos(a)), 0.01f * float(std::sin(a)), 0.02f));
    }
    for (int j = 0; j < 3; ++j) m.triangles.push_back({v, base + VertexId(j), base + VertexId((j + 1) % 3)});
  }
  for (int k = 0; k < 300; ++k) {  // flipped faces
    Triangle& t = m.triangles[random() % nf];
    std::swap(t[1], t[2]);
  }
  for (int k = 0; k < 20; ++k) {  // cracks: faces on copies of their vertices
    Triangle& t = m.triangles[random() % nf];
    for (VertexId& v : t) {
      m.positions.push_back(m.positions[v]);
      v = static_cast<VertexId>(m.positions.size() - 1);
    }
  }
  for (int k = 0; k < 3; ++k) m.positions[m.triangles[random() % nf][0]] += Vec3f(0.0f, 0.0f, 5.0f);  // spikes
  for (int k = 0; k < 5; ++k) {  // zero-area faces: a point on an edge's middle
    const Triangle t = m.triangles[random() % nf];
    m.positions.push_back(0.5f * (m.positions[t[0]] + m.positions[t[1]]));
    m.triangles.push_back({t[1], t[0], VertexId(m.positions.size() - 1)});
  }
  for (int k = 0; k < 40; ++k) {  // duplicates, some reversed
    Triangle t = m.triangles[random() % nf];
    if (k % 2) std::swap(t[1], t[2]);
    m.triangles.push_back(t);
  }
  // Books: single triangles around one edge, two each way, paired by how flat they meet.
  TriangleMesh books;
  for (int b = 0; b < 4; ++b) {
    const Vec3f p(8.0f + float(b), 0.0f, 0.0f), q(8.0f + float(b), 0.0f, 0.5f);
    const VertexId base = static_cast<VertexId>(books.positions.size());
    books.positions.push_back(p);
    books.positions.push_back(q);
    const double angles[4] = {0.0, 1.2 + 0.3 * b, 3.3, 4.0 + 0.2 * b};
    for (int j = 0; j < 4; ++j) {
      books.positions.push_back(p + Vec3f(0.3f * float(std::cos(angles[j])), 0.3f * float(std::sin(angles[j])), 0.2f));
      const VertexId tip = static_cast<VertexId>(books.positions.size() - 1);
      books.triangles.push_back(j % 2 ? Triangle{base + 1, base, tip} : Triangle{base, base + 1, tip});
    }
  }
  return concatMeshes({m, moebiusStrip(24, Vec3f(5.0f, 0.0f, 0.0f)), books});
}

namespace {

/// Coordinates from -outer to outer: steps of 1 outside [-inner, inner], of 1 / `dense` inside.
std::vector<float> axisSteps(int outer, int inner, int dense) {
  std::vector<float> out;
  for (int i = -outer; i < -inner; ++i) out.push_back(static_cast<float>(i));
  for (int i = -inner * dense; i < inner * dense; ++i) out.push_back(static_cast<float>(i) / dense);
  for (int i = inner; i <= outer; ++i) out.push_back(static_cast<float>(i));
  return out;
}

}  // namespace

TriangleMesh denseSpotPlane(int outer, int inner, int dense, double jitter, std::uint32_t seed) {
  const std::vector<float> axis = axisSteps(outer, inner, dense);
  const int n = static_cast<int>(axis.size());
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> noise(-jitter, jitter);
  TriangleMesh mesh;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float z = jitter > 0.0 ? static_cast<float>(noise(random)) : 0.0f;
      mesh.positions.emplace_back(axis[i], axis[j], z);
    }
  }
  const auto id = [n](int i, int j) { return static_cast<VertexId>(j * n + i); };
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return mesh;
}

}  // namespace seamvox::testing
