#include "io/chunked_mesh_writer.h"

#include <string>
#include <vector>

#include "core/system/errors.h"
#include "io/detail_mesh_io.h"
#include "stream/paged_reader.h"

namespace seamvox {

using detail::OutputBuffer;

namespace {

constexpr std::size_t kScratchBufferBytes = std::size_t(1) << 20;

/// A body waiting in a scratch file: formatted into a buffer, written through a ScratchWriter.
struct ScratchBody {
  ScratchBody(ScratchFolder& folder, const char* stage)
      : writer(folder, stage, 1 << 16),
        out([this](const char* data, std::size_t n) { writer.write(data, n); }, kScratchBufferBytes) {}
  ScratchWriter writer;
  OutputBuffer out;
};

/// Appends a finished scratch file to the output.
void copyInto(AtomicFile& file, ScratchFolder& folder, const ScratchFile& body) {
  ScratchReader reader(folder, body, "write", kScratchBufferBytes);
  std::vector<char> block(kScratchBufferBytes);
  for (std::size_t n; (n = reader.readUpTo(block.data(), block.size())) > 0;) file.write(block.data(), n);
  folder.remove(body);
}

}  // namespace

struct ChunkedMeshWriter::State {
  AtomicFile& file;
  ChunkedMeshLayout layout;
  WriteOptions options;
  ScratchFolder* scratch = nullptr;
  MeshFormat format = MeshFormat::Unknown;
  bool withUV = false;
  OutputBuffer direct;
  std::unique_ptr<ScratchBody> vertexBody, faceBody, texcoordBody;  // null: straight into the file
  std::uint64_t vertices = 0, faces = 0;
  // OBJ with UVs: every vertex's first (u, v) and its vt number plus one (0: no corner yet). With
  // the counts known, a ScratchArray within layout.memoryBytes (on disk beyond); else growing.
  struct FirstCorner {
    double u = 0.0, v = 0.0;
    std::uint32_t texcoord = 0, unused = 0;
  };
  std::vector<FirstCorner> firstGrowing;
  std::unique_ptr<ScratchArray<FirstCorner>> firstCounted;
  std::uint32_t texcoords = 0;
  bool uvDecided = false;  ///< counts known: from the layout; else by the first triangles

  void decideUV(bool chunkHasUV) {
    uvDecided = true;
    withUV = options.writeUV && chunkHasUV && format != MeshFormat::Off;
    if (!withUV || format != MeshFormat::Obj) return;
    texcoordBody = std::make_unique<ScratchBody>(*scratch, "write");
    firstGrowing.resize(vertices);
  }
  FirstCorner firstCorner(VertexId v) { return firstCounted ? firstCounted->get(v) : firstGrowing[v]; }
  void setFirstCorner(VertexId v, const FirstCorner& first) {
    if (firstCounted) {
      firstCounted->set(v, first);
    } else {
      firstGrowing[v] = first;
    }
  }

  State(AtomicFile& f, ChunkedMeshLayout l, const WriteOptions& o, ScratchFolder* s)
      : file(f), layout(std::move(l)), options(o), scratch(s), format(formatFromPath(f.path())), direct(f) {}

  OutputBuffer& vertexOut() { return vertexBody ? vertexBody->out : direct; }
  OutputBuffer& faceOut() { return faceBody ? faceBody->out : direct; }

  void writeObjCornersWithUV(const MeshChunk& chunk) {
    for (std::size_t f = 0; f < chunk.triangles.size(); ++f) {
      std::uint32_t texcoord[3];
      for (int k = 0; k < 3; ++k) {
        const VertexId v = chunk.triangles[f][k];
        const Vec2d& uv = chunk.cornerUV[3 * f + k];
        if (v >= vertices) {
          throw InputError(file.path() + ": cannot write face " + std::to_string(faces + f) + " before its vertex " +
                           std::to_string(v) + ": OBJ with texture coordinates is written out of core only from " +
                           "inputs that give vertices before the faces using them");
        }
        const FirstCorner first = firstCorner(v);
        if (first.texcoord != 0 && uv == Vec2d(first.u, first.v)) {
          texcoord[k] = first.texcoord - 1;
          continue;
        }
        if (first.texcoord == 0) setFirstCorner(v, {uv.x(), uv.y(), texcoords + 1});
        detail::putObjTexcoord(texcoordBody->out, uv);
        texcoord[k] = texcoords++;
      }
      detail::putObjFace(faceBody->out, chunk.triangles[f], texcoord);
    }
  }
};

ChunkedMeshWriter::ChunkedMeshWriter(AtomicFile& file, ChunkedMeshLayout layout, const WriteOptions& options,
                                     ScratchFolder* scratch)
    : state_(std::make_unique<State>(file, std::move(layout), options, scratch)) {
  State& s = *state_;
  const std::string& path = file.path();
  if (s.format == MeshFormat::Stl) {
    throw InputError(path + ": STL is read, not written (it holds no texture coordinates): write PLY, OBJ or OFF");
  }
  if (s.format == MeshFormat::Draco || s.format == MeshFormat::Unknown) {
    throw InputError(path + ": Draco encodes a whole mesh at once and cannot be written chunk by chunk; "
                     "write PLY, OBJ or OFF instead (or raise --memory-budget)");
  }
  s.withUV = options.writeUV && s.layout.hasUV && s.format != MeshFormat::Off;
  s.uvDecided = s.layout.countsKnown;
  TriangleMesh names;
  names.attributes = s.layout.attributes.emptyCopy();
  const std::vector<std::string> dropped = droppedVertexProperties(names, s.format);
  if (!dropped.empty()) {
    std::string list;
    for (const std::string& name : dropped) list += (list.empty() ? "" : ", ") + name;
    detail::warn(options.warn, path + ": the format cannot hold the vertex properties " + list + ": they are not written");
  }
  if (!scratch && (!s.layout.countsKnown || (s.format == MeshFormat::Obj && s.withUV))) {
    throw InputError(path + ": a chunked write without known counts, or of OBJ with UVs, needs a scratch folder");
  }
  if (s.format == MeshFormat::Obj) {
    s.direct.put("# written by seamvox\n");
    if (!s.layout.countsKnown || s.withUV) s.faceBody = std::make_unique<ScratchBody>(*scratch, "write");
    if (s.layout.countsKnown && s.withUV) {
      s.texcoordBody = std::make_unique<ScratchBody>(*scratch, "write");
      s.firstCounted = std::make_unique<ScratchArray<State::FirstCorner>>(*scratch, s.layout.vertices,
                                                                          s.layout.memoryBytes, "write");
    }
    return;
  }
  if (s.layout.countsKnown) {
    if (s.format == MeshFormat::Ply) {
      detail::putPlyHeader(s.direct, s.layout.vertices, s.layout.faces, s.layout.attributes, s.withUV, options.binary, s.layout.origin);
    } else {
      detail::putOffHeader(s.direct, s.layout.vertices, s.layout.faces);
    }
    return;
  }
  s.vertexBody = std::make_unique<ScratchBody>(*scratch, "write");
  s.faceBody = std::make_unique<ScratchBody>(*scratch, "write");
}

ChunkedMeshWriter::~ChunkedMeshWriter() = default;

void ChunkedMeshWriter::write(const MeshChunk& chunk) {
  State& s = *state_;
  if (!chunk.positions.empty()) {
    if (s.faces > 0 && !s.faceBody && !s.vertexBody) {
      throw InputError(s.file.path() + ": vertices after faces in a write whose faces go straight to the file");
    }
    const std::vector<VertexProperty>& expected = s.layout.attributes.properties;
    const std::vector<VertexProperty>& given = chunk.attributes.properties;
    bool sameLayout = expected.size() == given.size();
    for (std::size_t i = 0; sameLayout && i < given.size(); ++i) {
      sameLayout = expected[i].name == given[i].name && expected[i].type == given[i].type;
    }
    if (!sameLayout) {
      throw InputError(s.file.path() + ": vertices with the properties " + chunk.attributes.describe() +
                       " in a mesh written with " + s.layout.attributes.describe());
    }
    // Headers written at the end take the origin of the stream's positions (a reader's chunks).
    if (!s.layout.countsKnown && s.vertices == 0) s.layout.origin = chunk.origin;
    const std::size_t n = chunk.positions.size();
    switch (s.format) {
      case MeshFormat::Ply:
        detail::putPlyVertices(s.vertexOut(), chunk.positions, chunk.attributes, 0, n, s.options.binary, s.layout.origin);
        break;
      case MeshFormat::Off: detail::putOffVertices(s.vertexOut(), chunk.positions.data(), n, s.layout.origin); break;
      default: detail::putObjVertices(s.vertexOut(), chunk.positions, chunk.attributes, 0, n, s.layout.origin); break;
    }
    s.vertices += n;
    if (s.firstCounted && s.vertices > s.layout.vertices) {
      throw InputError(s.file.path() + ": more vertices (" + std::to_string(s.vertices) + ") than announced (" +
                       std::to_string(s.layout.vertices) + ")");
    }
    if (s.texcoordBody && !s.firstCounted) s.firstGrowing.resize(s.vertices);
  }
  if (chunk.triangles.empty()) return;
  if (!s.uvDecided) s.decideUV(!chunk.cornerUV.empty());
  if (s.withUV && chunk.cornerUV.size() != 3 * chunk.triangles.size()) {
    throw InputError(s.file.path() + ": triangles without texture coordinates in a mesh written with them");
  }
  const std::size_t n = chunk.triangles.size();
  switch (s.format) {
    case MeshFormat::Ply:
      detail::putPlyFaces(s.faceOut(), chunk.triangles.data(), s.withUV ? chunk.cornerUV.data() : nullptr, n,
                          s.options.binary);
      break;
    case MeshFormat::Off: detail::putOffFaces(s.faceOut(), chunk.triangles.data(), n); break;
    default:
      if (s.withUV) {
        s.writeObjCornersWithUV(chunk);
      } else {
        detail::putObjFaces(s.faceOut(), chunk.triangles.data(), n);
      }
      break;
  }
  s.faces += n;
}

void ChunkedMeshWriter::finish() {
  State& s = *state_;
  if (s.layout.countsKnown && (s.vertices != s.layout.vertices || s.faces != s.layout.faces)) {
    throw InputError(s.file.path() + ": " + std::to_string(s.vertices) + " vertices and " + std::to_string(s.faces) +
                     " faces written where " + std::to_string(s.layout.vertices) + " and " +
                     std::to_string(s.layout.faces) + " were announced");
  }
  if (s.vertexBody) {
    if (s.format == MeshFormat::Ply) {
      detail::putPlyHeader(s.direct, s.vertices, s.faces, s.layout.attributes, s.withUV, s.options.binary, s.layout.origin);
    } else {
      detail::putOffHeader(s.direct, s.vertices, s.faces);
    }
  }
  s.direct.flush();
  for (ScratchBody* body : {s.vertexBody.get(), s.texcoordBody.get(), s.faceBody.get()}) {
    if (!body) continue;
    body->out.flush();
    copyInto(s.file, *s.scratch, body->writer.finish());
  }
}

std::uint64_t ChunkedMeshWriter::vertices() const { return state_->vertices; }
std::uint64_t ChunkedMeshWriter::faces() const { return state_->faces; }

}  // namespace seamvox
