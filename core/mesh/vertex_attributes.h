#pragma once
/// Per-vertex properties a mesh carries through every edit (a scan's colors, normals, quality):
/// named scalar columns of any PLY scalar type, kept byte for byte in native byte order. Every
/// step that renumbers, copies or merges vertices calls gathered() (cleaning, welding, splits)
/// or withMidpoints() (subdivision), so the values follow their vertices.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/mesh_types.h"

namespace seamvox {

/// Scalar types of PLY properties (Draco's integer and float types map onto them).
enum class ScalarType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
/// Bytes of one value: 1, 2, 4 or 8.
std::size_t scalarSize(ScalarType type);
bool isFloatingType(ScalarType type);
/// The PLY type name: char uchar short ushort int uint float double.
const char* scalarTypeName(ScalarType type);

/// One named per-vertex value: #V values of one type.
struct VertexProperty {
  std::string name;
  ScalarType type = ScalarType::Float32;
  std::vector<std::uint8_t> bytes;  ///< #V * scalarSize(type), native byte order

  std::size_t size() const { return bytes.size() / scalarSize(type); }
  /// Value of vertex v converted to double (exact for every type).
  double value(VertexId v) const;
  /// Stores x at vertex v: integers rounded to nearest and clamped to the type's range.
  void setValue(VertexId v, double x);
};

/// The per-vertex properties of a mesh, none by default.
struct VertexAttributes {
  std::vector<VertexProperty> properties;

  bool empty() const { return properties.empty(); }
  /// Bytes held by the values.
  std::size_t memoryBytes() const;
  /// Appends a zero-filled property for numVertices vertices and returns it.
  VertexProperty& add(std::string name, ScalarType type, std::size_t numVertices);
  /// The property of that name, or nullptr.
  const VertexProperty* find(std::string_view name) const;
  /// "uchar red, uchar green, float nx": names with their types, for messages and `info`.
  std::string describe() const;

  /// New vertex i takes the values of old vertex source[i] (renumbering, removal, welding to one
  /// kept vertex, copies of split vertices). Linear, parallel.
  VertexAttributes gathered(const std::vector<VertexId>& source) const;
  /// These vertices, then one per pair with the mean of its two values (integers rounded to
  /// nearest, halves away from zero): the edge midpoints of a subdivision.
  VertexAttributes withMidpoints(const std::vector<std::array<VertexId, 2>>& ends) const;
  /// Appends the values of `more` (the same names and types in the same order) after these.
  /// Throws InputError when the layouts differ.
  void append(const VertexAttributes& more);
  /// Same names and types, no values.
  VertexAttributes emptyCopy() const;
  /// Drops the values, keeps the names and types.
  void clearValues();
  /// Throws InputError when a property does not hold exactly numVertices values.
  void checkSize(std::size_t numVertices) const;
};

}  // namespace seamvox
