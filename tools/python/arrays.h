#pragma once
/// numpy arrays in and out of the seamvox Python module: every array a caller passes is checked
/// here (shape, dtype, index range, finite values) and a problem raises seamvox.InputError (a
/// ValueError) naming the array, the element and what is wrong. Any strides are accepted.
#include <pybind11/numpy.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/quads/extract.h"

namespace seamvox::python {

namespace py = pybind11;

/// A mesh from V (n x 3, float32 or float64) and F (m x 3, any integer dtype: int32, int64,
/// uint32, ...); with uv (m x 3 x 2 floats) also its per-corner map.
TriangleMesh meshFromArrays(const py::handle& V, const py::handle& F, const py::handle& uv = py::none());

/// One 3D vector per face: an m x 3 float array named `name` (a field).
std::vector<Vec3d> vectorsFromArray(const py::handle& array, std::size_t rows, const char* name);

/// V as an n x 3 float64 array, F as an m x 3 int64 array.
py::array_t<double> positionsArray(const TriangleMesh& mesh);
py::array_t<std::int64_t> facesArray(const TriangleMesh& mesh);
/// The per-corner map as an m x 3 x 2 float64 array.
py::array_t<double> cornerUVArray(const TriangleMesh& mesh);
/// Rows of 3D vectors as an n x 3 float64 array.
py::array_t<double> vectorsArray(const std::vector<Vec3d>& vectors);
/// A polygon mesh's faces in its order: the quads as a q x 4 int64 array, every other face as a
/// 1-D int64 array in a list.
std::pair<py::array_t<std::int64_t>, py::list> polygonFacesArrays(const PolygonMesh& mesh);
/// Cones as a k x 2 int64 array of rows (vertex id, index in quarter turns).
py::array_t<std::int64_t> conesArray(const std::vector<VertexId>& cones, const std::vector<std::int32_t>& index4);

}  // namespace seamvox::python
