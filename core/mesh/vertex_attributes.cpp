#include "core/mesh/vertex_attributes.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/system/errors.h"
#include "core/system/parallel.h"

namespace seamvox {
namespace {

/// Calls f(T{}) with the C++ type of a scalar type.
template <class F>
decltype(auto) withType(ScalarType type, F&& f) {
  switch (type) {
    case ScalarType::Int8: return f(std::int8_t{});
    case ScalarType::UInt8: return f(std::uint8_t{});
    case ScalarType::Int16: return f(std::int16_t{});
    case ScalarType::UInt16: return f(std::uint16_t{});
    case ScalarType::Int32: return f(std::int32_t{});
    case ScalarType::UInt32: return f(std::uint32_t{});
    case ScalarType::Float32: return f(float{});
    default: return f(double{});
  }
}

/// x as a T: floats converted, integers rounded to nearest and clamped.
template <class T>
T toScalar(double x) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(x);
  } else {
    if (std::isnan(x)) return T(0);
    const double r = std::round(x);
    return static_cast<T>(std::clamp(r, double(std::numeric_limits<T>::lowest()),
                                     double(std::numeric_limits<T>::max())));
  }
}

template <class T>
T load(const std::uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

}  // namespace

std::size_t scalarSize(ScalarType type) {
  return withType(type, [](auto t) { return sizeof(t); });
}

bool isFloatingType(ScalarType type) { return type == ScalarType::Float32 || type == ScalarType::Float64; }

const char* scalarTypeName(ScalarType type) {
  static const char* const kNames[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};
  return kNames[static_cast<int>(type)];
}

double VertexProperty::value(VertexId v) const {
  return withType(type, [&](auto t) {
    return static_cast<double>(load<decltype(t)>(bytes.data() + std::size_t(v) * sizeof(t)));
  });
}

void VertexProperty::setValue(VertexId v, double x) {
  withType(type, [&](auto t) {
    const auto value = toScalar<decltype(t)>(x);
    std::memcpy(bytes.data() + std::size_t(v) * sizeof(t), &value, sizeof(t));
  });
}

std::size_t VertexAttributes::memoryBytes() const {
  std::size_t total = 0;
  for (const VertexProperty& p : properties) total += p.bytes.capacity();
  return total;
}

VertexProperty& VertexAttributes::add(std::string name, ScalarType type, std::size_t numVertices) {
  VertexProperty& p = properties.emplace_back();
  p.name = std::move(name);
  p.type = type;
  p.bytes.assign(numVertices * scalarSize(type), 0);
  return p;
}

const VertexProperty* VertexAttributes::find(std::string_view name) const {
  for (const VertexProperty& p : properties) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

std::string VertexAttributes::describe() const {
  std::string out;
  for (const VertexProperty& p : properties) {
    if (!out.empty()) out += ", ";
    out += scalarTypeName(p.type);
    out += ' ';
    out += p.name;
  }
  return out;
}

VertexAttributes VertexAttributes::gathered(const std::vector<VertexId>& source) const {
  VertexAttributes out = emptyCopy();
  for (std::size_t i = 0; i < properties.size(); ++i) {
    const VertexProperty& from = properties[i];
    VertexProperty& to = out.properties[i];
    const std::size_t width = scalarSize(from.type);
    to.bytes.resize(source.size() * width);
    parallelFor(source.size(), 16384, [&](const IndexRange& r) {
      for (std::uint64_t v = r.begin(); v != r.end(); ++v) {
        std::memcpy(to.bytes.data() + v * width, from.bytes.data() + std::size_t(source[v]) * width, width);
      }
    });
  }
  return out;
}

VertexAttributes VertexAttributes::withMidpoints(const std::vector<std::array<VertexId, 2>>& ends) const {
  VertexAttributes out = *this;
  for (VertexProperty& p : out.properties) {
    const std::size_t first = p.size();
    p.bytes.resize((first + ends.size()) * scalarSize(p.type));
    withType(p.type, [&](auto t) {
      using T = decltype(t);
      parallelForEach(ends.size(), 16384, [&](std::uint64_t e) {
        const double a = load<T>(p.bytes.data() + std::size_t(ends[e][0]) * sizeof(T));
        const double b = load<T>(p.bytes.data() + std::size_t(ends[e][1]) * sizeof(T));
        const T mean = toScalar<T>(0.5 * (a + b));
        std::memcpy(p.bytes.data() + (first + e) * sizeof(T), &mean, sizeof(T));
      });
    });
  }
  return out;
}

void VertexAttributes::append(const VertexAttributes& more) {
  bool same = more.properties.size() == properties.size();
  for (std::size_t i = 0; same && i < properties.size(); ++i) {
    same = properties[i].name == more.properties[i].name && properties[i].type == more.properties[i].type;
  }
  if (!same) {
    throw InputError("vertex properties differ between parts of the mesh (" + describe() + " and " +
                     more.describe() + ")");
  }
  for (std::size_t i = 0; i < properties.size(); ++i) {
    properties[i].bytes.insert(properties[i].bytes.end(), more.properties[i].bytes.begin(),
                               more.properties[i].bytes.end());
  }
}

VertexAttributes VertexAttributes::emptyCopy() const {
  VertexAttributes out;
  for (const VertexProperty& p : properties) out.add(p.name, p.type, 0);
  return out;
}

void VertexAttributes::clearValues() {
  for (VertexProperty& p : properties) p.bytes.clear();
}

void VertexAttributes::checkSize(std::size_t numVertices) const {
  for (const VertexProperty& p : properties) {
    if (p.bytes.size() != numVertices * scalarSize(p.type)) {
      throw InputError("vertex property '" + p.name + "' has " + std::to_string(p.bytes.size()) +
                       " bytes for " + std::to_string(numVertices) + " vertices (expected " +
                       std::to_string(numVertices * scalarSize(p.type)) + ")");
    }
  }
}

}  // namespace seamvox
