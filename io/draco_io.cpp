// Draco (.drc) reading and writing. Positions are float32 and UVs float64 per corner, both
// stored without quantization: seam checks need UVs exact to 1e-6 on values of thousands, which
// even 30-bit quantization does not give. Draco merges vertices with equal positions.
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>

#include <cmath>
#include <limits>

#include "core/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {

TriangleMesh readDraco(const std::string& path, const ReadOptions& options) {
  InputFile in(path);  // missing file / folder errors, and the size
  if (!in.ensure(static_cast<std::size_t>(in.size()))) throw IoError(path + ": read failed");
  draco::DecoderBuffer buffer;
  buffer.Init(in.data(), static_cast<std::size_t>(in.size()));
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
  // Vertices are the distinct position values; points (position + UV pairs) map onto them.
  mesh.positions.resize(position->size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    float p[3];
    position->ConvertValue<float>(draco::AttributeValueIndex(static_cast<std::uint32_t>(v)), 3, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw InputError(path + ": vertex " + std::to_string(v) + ": coordinate is NaN or infinite");
    }
    mesh.positions[v] = Vec3f(p[0], p[1], p[2]);
  }
  mesh.triangles.resize(source->num_faces());
  if (texcoord) mesh.cornerUV.resize(3 * mesh.triangles.size());
  for (std::uint32_t f = 0; f < source->num_faces(); ++f) {
    const draco::Mesh::Face& face = source->face(draco::FaceIndex(f));
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = position->mapped_index(face[k]).value();
      if (v >= mesh.positions.size()) {
        throw InputError(path + ": face " + std::to_string(f) + " refers to a missing vertex");
      }
      mesh.triangles[f][k] = v;
      if (!texcoord) continue;
      double t[2];
      texcoord->ConvertValue<double>(texcoord->mapped_index(face[k]), 2, t);
      mesh.cornerUV[3 * f + k] = Vec2d(t[0], t[1]);
    }
  }
  return mesh;
}

void writeDraco(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options) {
  const bool withUV = options.writeUV && mesh.hasUV();
  if (mesh.triangles.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw InputError(file.path() + ": too many faces for Draco");
  }
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(static_cast<int>(mesh.triangles.size()));
  const int position = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  const int texcoord =
      withUV ? builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT64) : -1;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const draco::FaceIndex face(static_cast<std::uint32_t>(f));
    builder.SetAttributeValuesForFace(position, face, mesh.positions[t[0]].data(),
                                      mesh.positions[t[1]].data(), mesh.positions[t[2]].data());
    if (withUV) {
      builder.SetAttributeValuesForFace(texcoord, face, mesh.cornerUV[3 * f].data(),
                                        mesh.cornerUV[3 * f + 1].data(), mesh.cornerUV[3 * f + 2].data());
    }
  }
  const std::unique_ptr<draco::Mesh> built = builder.Finalize();
  if (!built) throw InputError(file.path() + ": Draco could not build the mesh");

  draco::Encoder encoder;
  encoder.SetSpeedOptions(5, 5);  // no quantization is set: attributes are stored losslessly
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*built, &buffer);
  if (!status.ok()) throw IoError(file.path() + ": Draco encoding failed: " + status.error_msg_string());
  file.write(buffer.data(), buffer.size());
}

}  // namespace seamvox::detail
