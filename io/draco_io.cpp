// Draco (.drc) reading and writing. Positions are float32 (lossless, or quantized on request).
// UVs are rounded to a lattice of step 2^-k grid units with an integer origin and stored with
// Draco's own quantization, chosen so that every Draco decoder returns the lattice values exactly:
// the range fits 23 bits (the encoder rounds in float32), so the float32 values, the quantizer's
// delta 2^-k and the decoder's q * delta + origin are all exact. Rounding to such a lattice
// commutes with integer translations and quarter turns (up to ties), so q' = r q + t across a
// seam survives; a corner moves by at most 2^-k / sqrt(2). UVs too large for that range are stored losslessly as float64.
// The writer keeps the mesh's vertices apart even where positions are equal (an unwelded seam,
// a split non-manifold vertex): the archive decodes to the connectivity that was written.
// Vertex properties travel as COLOR (red green blue [alpha]), NORMAL (nx ny nz) and GENERIC
// attributes (named in their metadata), one value per vertex; the reader keeps every attribute
// but positions and UVs, and splits a position whose points carry different values.
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <unordered_map>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox {
namespace {

/// Largest magnitude (in lattice steps) a float32 holds exactly.
constexpr double kExactFloatSteps = 16777216.0;  // 2^24
/// Most quantization bits whose indices Draco's encoder computes exactly: it rounds with
/// floor(x + 0.5f) in float32, which is exact only below 2^23 (at 24 bits an index q >= 2^23
/// came back q + 1 on a spike's wide UV range).
constexpr int kMaxExactQuantizationBits = 23;

/// The lattice a Draco write rounds UVs to: step 2^-bits, per-component integer origin, and the
/// quantization bits covering the range; bits == 0 when UVs are stored losslessly.
struct UVLattice {
  int bits = 0;
  int quantizationBits = 0;
  float origin[2] = {0.0f, 0.0f};
  double step = 0.0;
};

UVLattice chooseUVLattice(const TriangleMesh& mesh, const WriteOptions& options) {
  UVLattice lattice;
  if (!mesh.hasUV() || options.dracoUVBits <= 0) return lattice;
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (CornerId c = 0; c < mesh.cornerUV.size(); ++c) {
    const Vec2d uv = mesh.cornerUV[c];
    if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) return lattice;
    for (int c = 0; c < 2; ++c) {
      lo[c] = std::min(lo[c], uv[c]);
      hi[c] = std::max(hi[c], uv[c]);
    }
  }
  const double scale = std::ldexp(1.0, options.dracoUVBits);
  double steps = 0.0, magnitude = 0.0;
  for (int c = 0; c < 2; ++c) {
    lo[c] = std::floor(lo[c]);
    steps = std::max(steps, std::ceil((hi[c] - lo[c]) * scale));
    magnitude = std::max({magnitude, std::abs(lo[c]), std::abs(hi[c]) + 1.0});
  }
  int quantizationBits = 1;
  while (quantizationBits < kMaxExactQuantizationBits && std::ldexp(1.0, quantizationBits) - 1.0 < steps) ++quantizationBits;
  if (std::ldexp(1.0, quantizationBits) - 1.0 < steps || magnitude * scale >= kExactFloatSteps) {
    return lattice;
  }
  lattice.bits = options.dracoUVBits;
  lattice.quantizationBits = quantizationBits;
  lattice.origin[0] = static_cast<float>(lo[0]);
  lattice.origin[1] = static_cast<float>(lo[1]);
  lattice.step = 1.0 / scale;
  return lattice;
}

/// Draco points of a mesh: one per (vertex, UV wedge) pair, so every vertex keeps its own
/// position entry; numbered in order of first use by a corner. A wedge normally belongs to one
/// vertex: pointOfWedge names its point, and the rare pairs of a wedge with a further vertex are
/// kept apart in `extra`. Memory follows the wedges (12 bytes each), not the corners.
struct DracoPoints {
  bool withUV = false;
  std::vector<std::uint32_t> pointOfWedge;                 ///< #wedges, kInvalidId when unused
  std::unordered_map<std::uint64_t, std::uint32_t> extra;  ///< (wedge, vertex) -> point
  std::vector<std::uint32_t> vertexOfPoint, wedgeOfPoint;  ///< #points (wedgeOfPoint: with UVs)

  static std::uint64_t key(std::uint32_t wedge, VertexId v) { return std::uint64_t(wedge) << 32 | v; }
  std::uint32_t point(const TriangleMesh& mesh, std::size_t corner) const {
    const VertexId v = mesh.triangles[corner / 3][corner % 3];
    if (!withUV) return v;
    const std::uint32_t w = mesh.cornerUV.wedge(static_cast<CornerId>(corner));
    const std::uint32_t p = pointOfWedge[w];
    return vertexOfPoint[p] == v ? p : extra.at(key(w, v));
  }
};

DracoPoints dracoPoints(const TriangleMesh& mesh, bool withUV) {
  DracoPoints out;
  out.withUV = withUV;
  if (!withUV) {
    out.vertexOfPoint.resize(mesh.numVertices());
    for (std::uint32_t v = 0; v < mesh.numVertices(); ++v) out.vertexOfPoint[v] = v;
    return out;
  }
  out.pointOfWedge.assign(mesh.cornerUV.numWedges(), kInvalidId);
  auto addPoint = [&](VertexId v, std::uint32_t w) {
    out.vertexOfPoint.push_back(v);
    out.wedgeOfPoint.push_back(w);
    return static_cast<std::uint32_t>(out.vertexOfPoint.size() - 1);
  };
  for (std::size_t c = 0; c < 3 * mesh.triangles.size(); ++c) {
    const VertexId v = mesh.triangles[c / 3][c % 3];
    const std::uint32_t w = mesh.cornerUV.wedge(static_cast<CornerId>(c));
    std::uint32_t& p = out.pointOfWedge[w];
    if (p == kInvalidId) {
      p = addPoint(v, w);
    } else if (out.vertexOfPoint[p] != v && !out.extra.count(DracoPoints::key(w, v))) {
      const std::uint32_t extra = addPoint(v, w);
      out.extra.emplace(DracoPoints::key(w, v), extra);
    }
  }
  return out;
}

/// Adds an attribute with `values` entries of `components` values of type `type` to the mesh;
/// returns its id.
int addDracoAttribute(draco::Mesh& mesh, draco::GeometryAttribute::Type kind, int components,
                      draco::DataType type, std::size_t values, bool identity) {
  draco::GeometryAttribute attribute;
  attribute.Init(kind, nullptr, static_cast<std::uint8_t>(components), type, false,
                 std::int64_t(draco::DataTypeLength(type)) * components, 0);
  return mesh.AddAttribute(attribute, identity, static_cast<std::uint32_t>(values));
}

/// Maps every point to the value of its vertex (values are indexed by vertex).
void mapPointsToVertices(draco::PointAttribute& attribute, const std::vector<std::uint32_t>& vertexOfPoint) {
  attribute.SetExplicitMapping(vertexOfPoint.size());
  for (std::size_t p = 0; p < vertexOfPoint.size(); ++p) {
    attribute.SetPointMapEntry(draco::PointIndex(static_cast<std::uint32_t>(p)),
                               draco::AttributeValueIndex(vertexOfPoint[p]));
  }
}

draco::DataType dracoType(ScalarType type) {
  static const draco::DataType kTypes[] = {draco::DT_INT8,  draco::DT_UINT8,  draco::DT_INT16,
                                           draco::DT_UINT16, draco::DT_INT32, draco::DT_UINT32,
                                           draco::DT_FLOAT32, draco::DT_FLOAT64};
  return kTypes[static_cast<int>(type)];
}

/// The vertex attribute type of a Draco data type; false for 64-bit integers (not kept).
bool scalarTypeOf(draco::DataType type, ScalarType& out) {
  switch (type) {
    case draco::DT_INT8: out = ScalarType::Int8; return true;
    case draco::DT_UINT8: case draco::DT_BOOL: out = ScalarType::UInt8; return true;
    case draco::DT_INT16: out = ScalarType::Int16; return true;
    case draco::DT_UINT16: out = ScalarType::UInt16; return true;
    case draco::DT_INT32: out = ScalarType::Int32; return true;
    case draco::DT_UINT32: out = ScalarType::UInt32; return true;
    case draco::DT_FLOAT32: out = ScalarType::Float32; return true;
    case draco::DT_FLOAT64: out = ScalarType::Float64; return true;
    default: return false;
  }
}

/// Metadata entry of a GENERIC attribute holding the little-endian bytes of a 32-bit integer: its
/// PLY type name ("int" or "uint").
constexpr const char* kBytesOfType = "seamvox_bytes_of";

/// Writes the vertex properties as Draco attributes with one value per vertex, mapped to every
/// point of that vertex: red green blue [alpha] as COLOR, nx ny nz as NORMAL, every other one as
/// a GENERIC attribute whose metadata entry "name" keeps its name.
void addVertexProperties(draco::Mesh& built, const VertexAttributes& attributes,
                         const std::vector<std::uint32_t>& vertexOfPoint, std::uint32_t numVertices) {
  const std::vector<VertexProperty>& properties = attributes.properties;
  std::vector<std::pair<draco::GeometryAttribute::Type, std::vector<std::size_t>>> groups;
  const std::vector<std::size_t> color = detail::colorProperties(attributes);
  const std::vector<std::size_t> normal = detail::normalProperties(attributes);
  if (!color.empty()) groups.emplace_back(draco::GeometryAttribute::COLOR, color);
  if (!normal.empty()) groups.emplace_back(draco::GeometryAttribute::NORMAL, normal);
  for (std::size_t i = 0; i < properties.size(); ++i) {
    const bool grouped = std::find(color.begin(), color.end(), i) != color.end() ||
                         std::find(normal.begin(), normal.end(), i) != normal.end();
    if (!grouped) groups.emplace_back(draco::GeometryAttribute::GENERIC, std::vector<std::size_t>{i});
  }
  for (const auto& [kind, members] : groups) {
    const ScalarType type = properties[members[0]].type;
    const std::size_t width = scalarSize(type);
    // Draco's integer coding tables grow with the value range (a 32-bit range takes gigabytes or
    // fails): 32-bit integers travel as their 4 little-endian bytes, typed in the metadata.
    const bool asBytes = width == 4 && !isFloatingType(type);
    const int id = asBytes ? addDracoAttribute(built, kind, 4, draco::DT_UINT8, numVertices, false)
                           : addDracoAttribute(built, kind, static_cast<int>(members.size()),
                                               dracoType(type), numVertices, false);
    draco::PointAttribute& attribute = *built.attribute(id);
    std::vector<std::uint8_t> value(members.size() * width);
    for (std::uint32_t v = 0; v < numVertices; ++v) {
      for (std::size_t k = 0; k < members.size(); ++k) {
        std::memcpy(value.data() + k * width, properties[members[k]].bytes.data() + std::size_t(v) * width, width);
      }
      attribute.SetAttributeValue(draco::AttributeValueIndex(v), value.data());
    }
    mapPointsToVertices(attribute, vertexOfPoint);
    if (kind == draco::GeometryAttribute::GENERIC) {
      auto metadata = std::make_unique<draco::AttributeMetadata>();
      metadata->AddEntryString("name", properties[members[0]].name);
      if (asBytes) metadata->AddEntryString(kBytesOfType, scalarTypeName(type));
      built.AddAttributeMetadata(id, std::move(metadata));
    }
  }
}

/// A Draco attribute kept as vertex properties (one per component).
struct KeptAttribute {
  const draco::PointAttribute* source;
  std::size_t firstProperty;  ///< it fills properties firstProperty, +1, ... (count of them)
  std::size_t count;
  std::size_t bytes;          ///< of one value (all components)
};

/// Vertex properties for every attribute of the decoded mesh besides positions and texture
/// coordinates: names from the metadata entry "name", else red green blue alpha (COLOR), nx ny nz
/// (NORMAL) or draco_generic_<id>; a name gets _<k> per component when there are several.
std::vector<KeptAttribute> keepAttributes(const draco::Mesh& source, VertexAttributes& attributes,
                                          const std::string& path, const WarningFn& warn) {
  std::vector<KeptAttribute> kept;
  std::string unkept;
  for (int id = 0; id < source.num_attributes(); ++id) {
    const draco::PointAttribute& a = *source.attribute(id);
    const auto kind = a.attribute_type();
    if (kind == draco::GeometryAttribute::POSITION || kind == draco::GeometryAttribute::TEX_COORD) continue;
    ScalarType type;
    const int components = a.num_components();
    if (!scalarTypeOf(a.data_type(), type) || components < 1) {
      unkept += (unkept.empty() ? "attribute " : ", ") + std::to_string(id);
      continue;
    }
    std::string name, bytesOf;
    const draco::AttributeMetadata* metadata = source.GetAttributeMetadataByAttributeId(id);
    if (metadata && metadata->GetEntryString(kBytesOfType, &bytesOf) && a.data_type() == draco::DT_UINT8 &&
        components == 4 && metadata->GetEntryString("name", &name) && (bytesOf == "int" || bytesOf == "uint")) {
      kept.push_back({&a, attributes.properties.size(), 1, 4});
      attributes.add(name, bytesOf == "int" ? ScalarType::Int32 : ScalarType::UInt32, 0);
      continue;
    }
    std::vector<std::string> names;
    if (!(metadata && metadata->GetEntryString("name", &name))) {
      if (kind == draco::GeometryAttribute::COLOR && components <= 4 && !attributes.find("red")) {
        names.assign({"red", "green", "blue", "alpha"});
      } else if (kind == draco::GeometryAttribute::NORMAL && components == 3 && !attributes.find("nx")) {
        names.assign({"nx", "ny", "nz"});
      }
      name = "draco_generic_" + std::to_string(id);
    }
    names.resize(components);
    for (int k = 0; k < components; ++k) {
      if (names[k].empty()) names[k] = components == 1 ? name : name + "_" + std::to_string(k);
    }
    kept.push_back({&a, attributes.properties.size(), std::size_t(components), std::size_t(components) * scalarSize(type)});
    for (const std::string& n : names) attributes.add(n, type, 0);
  }
  if (!unkept.empty()) detail::warn(warn, path + ": not kept (64-bit integer values): Draco " + unkept);
  return kept;
}

/// Vertices of a decoded mesh: one per position value, split where points of one position carry
/// different values of a kept attribute (a crease in the normals, a color seam). Fills
/// vertexOfPoint and, per vertex, a point whose values it takes (or kInvalidId).
struct DracoVertices {
  std::vector<std::uint32_t> vertexOfPoint, pointOfVertex, positionOfVertex;
};

DracoVertices dracoVertices(const draco::Mesh& source, const draco::PointAttribute& position,
                            const std::vector<KeptAttribute>& kept) {
  DracoVertices out;
  out.vertexOfPoint.assign(source.num_points(), kInvalidId);
  out.pointOfVertex.assign(position.size(), kInvalidId);
  out.positionOfVertex.resize(position.size());
  for (std::uint32_t v = 0; v < position.size(); ++v) out.positionOfVertex[v] = v;
  if (kept.empty()) {  // nothing to split by: the vertex of a point is its position value
    for (std::uint32_t p = 0; p < source.num_points(); ++p) {
      out.vertexOfPoint[p] = position.mapped_index(draco::PointIndex(p)).value();
    }
    return out;
  }
  std::vector<std::uint32_t> nextCopy(position.size(), kInvalidId);  // split vertices of a position
  std::vector<std::uint8_t> a, b;
  auto sameValues = [&](std::uint32_t p, std::uint32_t q) {
    for (const KeptAttribute& k : kept) {
      const auto ip = k.source->mapped_index(draco::PointIndex(p)), iq = k.source->mapped_index(draco::PointIndex(q));
      if (ip == iq) continue;
      a.resize(k.bytes);
      b.resize(k.bytes);
      k.source->GetValue(ip, a.data());
      k.source->GetValue(iq, b.data());
      if (a != b) return false;
    }
    return true;
  };
  for (std::uint32_t f = 0; f < source.num_faces(); ++f) {
    for (const draco::PointIndex& point : source.face(draco::FaceIndex(f))) {
      const std::uint32_t p = point.value();
      if (p >= out.vertexOfPoint.size() || out.vertexOfPoint[p] != kInvalidId) continue;
      std::uint32_t v = position.mapped_index(point).value();
      if (v >= position.size()) continue;  // reported by the caller
      for (;;) {
        if (out.pointOfVertex[v] == kInvalidId) out.pointOfVertex[v] = p;
        if (sameValues(out.pointOfVertex[v], p)) break;
        if (nextCopy[v] == kInvalidId) {
          nextCopy[v] = static_cast<std::uint32_t>(out.pointOfVertex.size());
          out.pointOfVertex.push_back(p);
          out.positionOfVertex.push_back(out.positionOfVertex[v]);
          nextCopy.push_back(kInvalidId);
        }
        v = nextCopy[v];
      }
      out.vertexOfPoint[p] = v;
    }
  }
  return out;
}

/// Values of the kept attributes at each vertex's point (zero for a vertex no face uses).
void readVertexValues(const std::vector<KeptAttribute>& kept, const std::vector<std::uint32_t>& pointOfVertex,
                      VertexAttributes& attributes) {
  const std::size_t numVertices = pointOfVertex.size();
  for (VertexProperty& p : attributes.properties) p.bytes.assign(numVertices * scalarSize(p.type), 0);
  std::vector<std::uint8_t> value;
  for (const KeptAttribute& k : kept) {
    const std::size_t components = k.count;
    const std::size_t width = k.bytes / components;
    value.resize(k.bytes);
    for (std::size_t v = 0; v < numVertices; ++v) {
      if (pointOfVertex[v] == kInvalidId) continue;
      k.source->GetValue(k.source->mapped_index(draco::PointIndex(pointOfVertex[v])), value.data());
      for (std::size_t c = 0; c < components; ++c) {
        std::memcpy(attributes.properties[k.firstProperty + c].bytes.data() + v * width, value.data() + c * width, width);
      }
    }
  }
}

/// The Draco mesh of a mesh: points, faces, UVs on the lattice and positions (one entry per
/// vertex, explicitly mapped). Points are set explicitly (no deduplication by value): the
/// encoder's connectivity, taken from the position entries, is the mesh's own. With `owned`
/// (the same mesh, given up by the caller) each array of the mesh is freed once copied.
std::unique_ptr<draco::Mesh> buildDracoMesh(const TriangleMesh& mesh, bool withUV, const UVLattice& lattice,
                                            TriangleMesh* owned) {
  DracoPoints points = dracoPoints(mesh, withUV);
  const std::size_t numPoints = points.vertexOfPoint.size();
  auto built = std::make_unique<draco::Mesh>();
  built->set_num_points(static_cast<std::uint32_t>(numPoints));
  built->SetNumFaces(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(points.point(mesh, 3 * f + k));
    built->SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), face);
  }
  if (owned) std::vector<Triangle>().swap(owned->triangles);
  std::vector<std::uint32_t>().swap(points.pointOfWedge);
  if (withUV) {
    draco::PointAttribute* texcoord = built->attribute(
        addDracoAttribute(*built, draco::GeometryAttribute::TEX_COORD, 2,
                          lattice.bits ? draco::DT_FLOAT32 : draco::DT_FLOAT64, numPoints, true));
    const double scale = lattice.bits ? 1.0 / lattice.step : 0.0;
    for (std::size_t p = 0; p < numPoints; ++p) {
      const Vec2d uv = mesh.cornerUV.wedgeValue(points.wedgeOfPoint[p]);
      const draco::AttributeValueIndex index(static_cast<std::uint32_t>(p));
      if (lattice.bits) {
        // Lattice values: exact in float32 by the choice of the lattice.
        float rounded[2];
        for (int c = 0; c < 2; ++c) rounded[c] = static_cast<float>(std::nearbyint(uv[c] * scale) * lattice.step);
        texcoord->SetAttributeValue(index, rounded);
      } else {
        texcoord->SetAttributeValue(index, uv.data());
      }
    }
    if (owned) owned->cornerUV.clear();
    std::vector<std::uint32_t>().swap(points.wedgeOfPoint);
  }
  // Far from zero (TriangleMesh::origin) the positions are float64 at origin + position.
  const bool shifted = !mesh.origin.isZero(0.0);
  draco::PointAttribute* position = built->attribute(
      addDracoAttribute(*built, draco::GeometryAttribute::POSITION, 3, shifted ? draco::DT_FLOAT64 : draco::DT_FLOAT32,
                        mesh.numVertices(), false));
  for (std::uint32_t v = 0; v < mesh.numVertices(); ++v) {
    if (shifted) {
      const Vec3d world = mesh.origin + mesh.positions[v].cast<double>();
      position->SetAttributeValue(draco::AttributeValueIndex(v), world.data());
    } else {
      position->SetAttributeValue(draco::AttributeValueIndex(v), mesh.positions[v].data());
    }
  }
  const std::uint32_t numVertices = mesh.numVertices();
  if (owned) std::vector<Vec3f>().swap(owned->positions);
  mapPointsToVertices(*position, points.vertexOfPoint);
  addVertexProperties(*built, mesh.attributes, points.vertexOfPoint, numVertices);
  if (owned) owned->attributes = VertexAttributes();
  return built;
}

/// Encodes a Draco mesh (consumed) into file. Speed 5: at 7 the encoder uses less memory (65
/// instead of 84 bytes per face) but no longer keeps vertices with equal UVs apart from their
/// positions' connectivity (the decoded mesh has a vertex per point), see bench/RESULTS.md.
void encodeDraco(AtomicFile& file, std::unique_ptr<draco::Mesh> built, const UVLattice& lattice,
                 const WriteOptions& options) {
  draco::Encoder encoder;
  encoder.SetSpeedOptions(5, 5);
  if (options.dracoPositionBits > 0) {
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.dracoPositionBits);
  }
  if (lattice.bits) {
    // delta = range / (2^bits - 1) = 2^-k exactly: every quantized value is a lattice index.
    const float range = static_cast<float>((std::ldexp(1.0, lattice.quantizationBits) - 1.0) * lattice.step);
    encoder.SetAttributeExplicitQuantization(draco::GeometryAttribute::TEX_COORD,
                                             lattice.quantizationBits, 2, lattice.origin, range);
  }
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*built, &buffer);
  built.reset();  // before the archive is written out
  if (!status.ok()) throw IoError(file.path() + ": Draco encoding failed: " + status.error_msg_string());
  file.write(buffer.data(), buffer.size());
}

/// Checks the options and the size, then builds and encodes (owned: see buildDracoMesh).
void writeDracoMesh(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options, TriangleMesh* owned) {
  const bool withUV = options.writeUV && mesh.hasUV();
  if (mesh.triangles.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw InputError(file.path() + ": too many faces for Draco");
  }
  if (options.dracoPositionBits < 0 || options.dracoPositionBits > 30) {
    throw InputError(file.path() + ": Draco position bits must be between 0 (lossless) and 30");
  }
  const UVLattice lattice = withUV ? chooseUVLattice(mesh, options) : UVLattice{};
  WriteOptions used = options;
  if (!mesh.origin.isZero(0.0) && options.dracoPositionBits > 0) {
    // Draco quantizes float32 positions only; far from zero they are float64, kept lossless.
    detail::warn(options.warn, file.path() + ": the mesh lies far from zero: its positions are written as lossless float64, "
                                     "not quantized to " + std::to_string(options.dracoPositionBits) + " bits");
    used.dracoPositionBits = 0;
  }
  encodeDraco(file, buildDracoMesh(mesh, withUV, lattice, owned), lattice, used);
}

}  // namespace

int dracoUVBitsFor(const TriangleMesh& mesh, const WriteOptions& options) {
  return options.writeUV ? chooseUVLattice(mesh, options).bits : 0;
}

namespace detail {

TriangleMesh readDraco(const std::string& path, const ReadOptions& options) {
  // The decoder needs the whole file in memory: a pipe is read to its end first.
  InputFile in(path, options.pipeWaitSeconds);
  const std::size_t size = in.readToEnd();
  draco::DecoderBuffer buffer;
  buffer.Init(in.data(), size);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) {
    throw InputError(path + ": not a valid Draco mesh: " + decoded.status().error_msg_string());
  }
  const std::unique_ptr<draco::Mesh> source = std::move(decoded).value();

  const draco::PointAttribute* position = source->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (!position || position->num_components() < 3) {
    throw InputError(path + ": the Draco mesh has no 3D POSITION attribute");
  }
  const draco::PointAttribute* texcoord =
      options.readUV ? source->GetNamedAttribute(draco::GeometryAttribute::TEX_COORD) : nullptr;
  if (texcoord && texcoord->num_components() < 2) texcoord = nullptr;
  if (position->size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw InputError(path + ": more vertices than 32-bit ids allow");
  }

  TriangleMesh mesh;
  // Vertices are the distinct position values (split where other attributes differ); points
  // (position + UV pairs) map onto them.
  const std::vector<KeptAttribute> kept = keepAttributes(*source, mesh.attributes, path, options.warn);
  const DracoVertices vertices = dracoVertices(*source, *position, kept);
  if (vertices.pointOfVertex.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw InputError(path + ": more vertices than 32-bit ids allow");
  }
  mesh.positions.resize(vertices.pointOfVertex.size());
  OriginShift shift(options.origin);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    double p[3] = {0.0, 0.0, 0.0};
    if (!position->ConvertValue<double>(draco::AttributeValueIndex(vertices.positionOfVertex[v]), 3, p)) {
      throw InputError(path + ": vertex " + std::to_string(v) + ": unreadable position");
    }
    const Vec3d exact(p[0], p[1], p[2]);
    mesh.positions[v] = shift.relative(exact, exact.cast<float>());
    if (!mesh.positions[v].allFinite()) {
      throw InputError(path + ": vertex " + std::to_string(v) + ": coordinate is NaN or infinite");
    }
  }
  mesh.origin = shift.origin();
  readVertexValues(kept, vertices.pointOfVertex, mesh.attributes);
  mesh.triangles.resize(source->num_faces());
  WedgeMapBuilder uv;
  if (texcoord) uv.reserve(3 * mesh.triangles.size());
  for (std::uint32_t f = 0; f < source->num_faces(); ++f) {
    const draco::Mesh::Face& face = source->face(draco::FaceIndex(f));
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = face[k].value();
      const std::uint32_t v = p < vertices.vertexOfPoint.size() ? vertices.vertexOfPoint[p] : kInvalidId;
      if (v >= mesh.positions.size()) {
        throw InputError(path + ": face " + std::to_string(f) + " refers to a missing vertex");
      }
      mesh.triangles[f][k] = v;
      if (!texcoord) continue;
      double t[2] = {0.0, 0.0};
      if (!texcoord->ConvertValue<double>(texcoord->mapped_index(face[k]), 2, t)) {
        throw InputError(path + ": face " + std::to_string(f) + ": unreadable texture coordinate");
      }
      uv.add(v, Vec2d(t[0], t[1]));
    }
  }
  if (texcoord) mesh.cornerUV = uv.finish();
  return mesh;
}

void writeDraco(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  writeDracoMesh(file, mesh, options, nullptr);
}

void writeDraco(AtomicFile& file, TriangleMesh&& mesh, const WriteOptions& options) {
  writeDracoMesh(file, mesh, options, &mesh);
  mesh = TriangleMesh();
}

}  // namespace detail
}  // namespace seamvox
