// numpy arrays in and out of the Python module, checked element by element.
#include "tools/python/arrays.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/system/errors.h"

namespace seamvox::python {
namespace {

std::string shapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) text += (d ? ", " : "") + std::to_string(a.shape(d));
  return text + (a.ndim() == 1 ? ",)" : ")");
}

/// obj as an array (a nested list is converted), with the shape (rows, trailing...); rows < 0: any.
py::array checkedArray(const py::handle& obj, const char* name, py::ssize_t rows,
                       const std::vector<py::ssize_t>& trailing, const char* shapeName) {
  if (obj.is_none()) throw InputError(std::string(name) + " is None; expected an array of shape " + shapeName);
  py::array a = py::array::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw InputError(std::string(name) + " is not an array (a numpy array or nested list of shape " +
                     shapeName + ")");
  }
  const char order = a.dtype().byteorder();
  const std::uint16_t one = 1;
  const bool littleEndian = *reinterpret_cast<const std::uint8_t*>(&one) == 1;
  if (order == (littleEndian ? '>' : '<')) {  // numbers of the other byte order: converted
    a = py::array::ensure(a.attr("astype")(a.dtype().attr("newbyteorder")("=")));
  }
  bool ok = a.ndim() == static_cast<py::ssize_t>(1 + trailing.size()) && (rows < 0 || a.shape(0) == rows);
  for (std::size_t d = 0; ok && d < trailing.size(); ++d) ok = a.shape(d + 1) == trailing[d];
  if (!ok) {
    throw InputError(std::string(name) + " must have shape " + shapeName + ", got " + shapeText(a));
  }
  return a;
}

/// Value k (row-major over the trailing dimensions) of row i, whatever the strides and alignment.
template <class T>
T valueAt(const py::array& a, py::ssize_t i, py::ssize_t k) {
  const char* p = static_cast<const char*>(a.data()) + i * a.strides(0);
  for (py::ssize_t d = a.ndim() - 1; d >= 1; --d) {
    p += (k % a.shape(d)) * a.strides(d);
    k /= a.shape(d);
  }
  T value;
  std::memcpy(&value, p, sizeof value);
  return value;
}

/// "[i, j]" or "[i, j, l]" for value k of row i.
std::string elementText(const py::array& a, py::ssize_t i, py::ssize_t k) {
  std::string index;
  for (py::ssize_t d = a.ndim() - 1; d >= 1; --d) {
    index = ", " + std::to_string(k % a.shape(d)) + index;
    k /= a.shape(d);
  }
  return "[" + std::to_string(i) + index + "]";
}

/// Calls fn(T{}) with T the array's float type (native byte order); anything else is an error.
template <class Fn>
void withFloatType(const py::array& a, const char* name, Fn&& fn) {
  if (a.dtype().equal(py::dtype::of<float>())) return fn(float{});
  if (a.dtype().equal(py::dtype::of<double>())) return fn(double{});
  throw InputError(std::string(name) + " must hold float32 or float64 values, got " +
                   a.dtype().attr("name").cast<std::string>());
}

template <class Fn>
void withIntegerType(const py::array& a, const char* name, Fn&& fn) {
  const py::dtype dt = a.dtype();
  if (dt.equal(py::dtype::of<std::int32_t>())) return fn(std::int32_t{});
  if (dt.equal(py::dtype::of<std::int64_t>())) return fn(std::int64_t{});
  if (dt.equal(py::dtype::of<std::uint32_t>())) return fn(std::uint32_t{});
  if (dt.equal(py::dtype::of<std::uint64_t>())) return fn(std::uint64_t{});
  if (dt.equal(py::dtype::of<std::int16_t>())) return fn(std::int16_t{});
  if (dt.equal(py::dtype::of<std::uint16_t>())) return fn(std::uint16_t{});
  if (dt.equal(py::dtype::of<std::int8_t>())) return fn(std::int8_t{});
  if (dt.equal(py::dtype::of<std::uint8_t>())) return fn(std::uint8_t{});
  throw InputError(std::string(name) + " must hold integers (int32, int64, uint32, ...), got " +
                   dt.attr("name").cast<std::string>());
}

/// Every value of a float array as double, finite (and within float range when asFloat32).
std::vector<double> finiteValues(const py::array& a, const char* name, bool asFloat32) {
  const py::ssize_t rows = a.shape(0), perRow = a.size() / std::max<py::ssize_t>(rows, 1);
  std::vector<double> values(static_cast<std::size_t>(a.size()));
  withFloatType(a, name, [&](auto tag) {
    using T = decltype(tag);
    for (py::ssize_t i = 0; i < rows; ++i) {
      for (py::ssize_t k = 0; k < perRow; ++k) {
        const double x = valueAt<T>(a, i, k);
        if (!std::isfinite(x) || (asFloat32 && std::abs(x) > std::numeric_limits<float>::max())) {
          throw InputError(std::string(name) + elementText(a, i, k) + " is " +
                           (std::isnan(x) ? "NaN" : std::isinf(x) ? (x > 0 ? "inf" : "-inf")
                                                                  : std::to_string(x) + ", beyond float32 range"));
        }
        values[i * perRow + k] = x;
      }
    }
  });
  return values;
}

std::vector<Triangle> checkedFaces(const py::handle& obj, std::size_t numVertices) {
  const py::array a = checkedArray(obj, "F", -1, {3}, "(m, 3)");
  if (a.shape(0) == 0) throw InputError("F has no faces");
  if (a.shape(0) > std::numeric_limits<std::uint32_t>::max() / 3) {
    throw InputError("F has " + std::to_string(a.shape(0)) + " faces, more than seamvox's 32-bit corner ids hold");
  }
  std::vector<Triangle> triangles(static_cast<std::size_t>(a.shape(0)));
  withIntegerType(a, "F", [&](auto tag) {
    using T = decltype(tag);
    for (py::ssize_t f = 0; f < a.shape(0); ++f) {
      for (py::ssize_t k = 0; k < 3; ++k) {
        const T v = valueAt<T>(a, f, k);
        if constexpr (std::is_signed_v<T>) {
          if (v < 0) throw InputError("F" + elementText(a, f, k) + " = " + std::to_string(v) + " is negative");
        }
        if (static_cast<std::uint64_t>(v) >= numVertices) {
          throw InputError("F" + elementText(a, f, k) + " = " + std::to_string(v) + " is out of range: V has " +
                           std::to_string(numVertices) + " vertices");
        }
        triangles[f][k] = static_cast<VertexId>(v);
      }
    }
  });
  return triangles;
}

}  // namespace

TriangleMesh meshFromArrays(const py::handle& V, const py::handle& F, const py::handle& uv) {
  const py::array positions = checkedArray(V, "V", -1, {3}, "(n, 3)");
  if (positions.shape(0) >= kInvalidId) throw InputError("V has more vertices than seamvox's 32-bit ids hold");
  TriangleMesh mesh;
  const std::vector<double> xyz = finiteValues(positions, "V", true);
  mesh.positions.resize(static_cast<std::size_t>(positions.shape(0)));
  // Far from zero, kept relative to an origin as the file readers keep them (TriangleMesh::origin).
  if (!mesh.positions.empty()) mesh.origin = originFor(Vec3d(xyz[0], xyz[1], xyz[2]));
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    mesh.positions[v] = (Vec3d(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]) - mesh.origin).cast<float>();
  }
  mesh.triangles = checkedFaces(F, mesh.positions.size());
  if (!uv.is_none()) {
    const py::array corners = checkedArray(uv, "uv", static_cast<py::ssize_t>(mesh.triangles.size()), {3, 2},
                                           "(m, 3, 2) with m the faces of F");
    const std::vector<double> q = finiteValues(corners, "uv", false);
    std::vector<Vec2d> values(3 * mesh.triangles.size());
    for (std::size_t c = 0; c < values.size(); ++c) values[c] = Vec2d(q[2 * c], q[2 * c + 1]);
    mesh.cornerUV = WedgeMap::fromCorners(mesh.triangles, values);
  }
  return mesh;
}

std::vector<Vec3d> vectorsFromArray(const py::handle& array, std::size_t rows, const char* name) {
  const std::string shape = "(m, 3) with m the faces of F (" + std::to_string(rows) + ")";
  const py::array a = checkedArray(array, name, static_cast<py::ssize_t>(rows), {3}, shape.c_str());
  const std::vector<double> xyz = finiteValues(a, name, false);
  std::vector<Vec3d> vectors(rows);
  for (std::size_t f = 0; f < rows; ++f) vectors[f] = Vec3d(xyz[3 * f], xyz[3 * f + 1], xyz[3 * f + 2]);
  return vectors;
}

py::array_t<double> positionsArray(const TriangleMesh& mesh) {
  py::array_t<double> out({static_cast<py::ssize_t>(mesh.numVertices()), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (VertexId v = 0; v < mesh.numVertices(); ++v) {
    for (int k = 0; k < 3; ++k) o(v, k) = mesh.origin[k] + mesh.positions[v][k];
  }
  return out;
}

py::array_t<std::int64_t> facesArray(const TriangleMesh& mesh) {
  py::array_t<std::int64_t> out({static_cast<py::ssize_t>(mesh.numFaces()), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) o(f, k) = mesh.triangles[f][k];
  }
  return out;
}

py::array_t<double> cornerUVArray(const TriangleMesh& mesh) {
  py::array_t<double> out({static_cast<py::ssize_t>(mesh.numFaces()), py::ssize_t{3}, py::ssize_t{2}});
  auto o = out.mutable_unchecked<3>();
  for (FaceId f = 0; f < mesh.numFaces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Vec2d q = mesh.cornerUV[3 * f + k];
      o(f, k, 0) = q.x();
      o(f, k, 1) = q.y();
    }
  }
  return out;
}

py::array_t<double> vectorsArray(const std::vector<Vec3d>& vectors) {
  py::array_t<double> out({static_cast<py::ssize_t>(vectors.size()), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < vectors.size(); ++i) {
    for (int k = 0; k < 3; ++k) o(i, k) = vectors[i][k];
  }
  return out;
}

py::array_t<std::int64_t> conesArray(const std::vector<VertexId>& cones, const std::vector<std::int32_t>& index4) {
  py::array_t<std::int64_t> out({static_cast<py::ssize_t>(cones.size()), py::ssize_t{2}});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < cones.size(); ++i) {
    o(i, 0) = cones[i];
    o(i, 1) = index4[i];
  }
  return out;
}

std::pair<py::array_t<std::int64_t>, py::list> polygonFacesArrays(const PolygonMesh& mesh) {
  std::size_t quads = 0;
  for (std::uint32_t f = 0; f < mesh.numFaces(); ++f) quads += mesh.degree(f) == 4;
  py::array_t<std::int64_t> quadArray({static_cast<py::ssize_t>(quads), py::ssize_t{4}});
  auto q = quadArray.mutable_unchecked<2>();
  py::list polygons;
  py::ssize_t row = 0;
  for (std::uint32_t f = 0; f < mesh.numFaces(); ++f) {
    const std::uint32_t* corners = mesh.faceVertices.data() + mesh.faceStart[f];
    if (mesh.degree(f) == 4) {
      for (int k = 0; k < 4; ++k) q(row, k) = corners[k];
      ++row;
      continue;
    }
    py::array_t<std::int64_t> polygon(static_cast<py::ssize_t>(mesh.degree(f)));
    auto p = polygon.mutable_unchecked<1>();
    for (py::ssize_t k = 0; k < p.shape(0); ++k) p(k) = corners[k];
    polygons.append(std::move(polygon));
  }
  return {std::move(quadArray), std::move(polygons)};
}

}  // namespace seamvox::python
