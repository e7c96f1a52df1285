// Builds a tetrahedron, cleans it and checks its topology through the installed headers.
#include <seamvox/core/mesh/clean.h>
#include <seamvox/core/mesh/topology.h>

#include <cstdio>

int main() {
  seamvox::TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  const seamvox::CleanResult clean = seamvox::cleanMesh(mesh);
  clean.topology.validate();
  const auto comps = seamvox::computeComponents(clean.topology);
  std::printf("components %zu euler %lld\n", comps.components.size(),
              static_cast<long long>(comps.components[0].eulerCharacteristic));
  return comps.components.size() == 1 && comps.components[0].eulerCharacteristic == 2 ? 0 : 1;
}
