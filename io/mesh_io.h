#pragma once
/// Reading and writing triangle meshes: PLY (ascii, binary little/big endian, faces and
/// tristrips), OBJ, OFF, Draco, and reading STL (binary and ASCII; its per-corner vertices
/// welded at equal positions), with per-vertex properties (TriangleMesh::attributes) where the
/// format holds them. Errors name the file, the line or element, and the problem.
/// Inputs are regular files or pipes (a named FIFO, /dev/stdin when piped: read as a stream; a
/// Draco file is buffered whole, up to 4 GiB); folders, devices and sockets are refused. Text
/// files may start with a UTF-8 byte order mark and end lines in LF, CRLF or CR alone.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "stream/mesh_stream.h"

namespace seamvox {

class AtomicFile;

enum class MeshFormat { Unknown, Ply, Obj, Off, Draco, Stl };
/// Format from the file extension (case-insensitive): .ply .obj .off .drc .stl.
MeshFormat formatFromPath(const std::string& path);
/// The formats meshes are written in (all but STL, which holds no texture coordinates).
bool isWritableFormat(MeshFormat format);

/// Receives one line naming a file and what of it a reader or writer cannot keep.
using WarningFn = std::function<void(const std::string&)>;

struct ReadOptions {
  /// Also read per-corner texture coordinates (OBJ vt, PLY face texcoord). Off: they are ignored.
  bool readUV = false;
  /// Triangles per chunk handed out by the stream.
  std::size_t chunkTriangles = 1u << 18;
  /// A pipe is opened without blocking; reading fails (IoError) when no writer sends data or
  /// closes it within this time, instead of waiting forever in open().
  double pipeWaitSeconds = 10.0;
  /// The origin positions are kept relative to (TriangleMesh::origin) instead of the one the first
  /// vertex decides: tiles of one site read about one origin weld exactly.
  std::optional<Vec3d> origin;
  /// Told what is read but not kept (PLY face properties other than vertex_indices and texcoord,
  /// list properties of vertices, other elements; Draco attributes of 64-bit types). Empty:
  /// printed on stderr.
  WarningFn warn;
};

/// Opens a mesh file as a chunked stream. The format is detected from the extension and checked
/// against the content. Throws IoError (cannot open, unknown format) or InputError.
std::unique_ptr<MeshStream> openMeshStream(const std::string& path, const ReadOptions& options = {});

/// Reads a whole mesh. Throws InputError for an empty mesh (no faces), indices out of range and
/// NaN/inf coordinates, naming the file and the element.
TriangleMesh readMesh(const std::string& path, const ReadOptions& options = {});
/// The same from a stream already opened (openMeshStream), e.g. after its header was looked at.
TriangleMesh readMesh(MeshStream& stream);

struct WriteOptions {
  /// Write per-corner UVs when the mesh has them (OBJ vt per corner, PLY face "texcoord" list).
  bool writeUV = true;
  /// PLY: binary little endian (default) or ascii.
  bool binary = true;
  /// Draco: UVs are rounded to a grid of step 2^-dracoUVBits (grid units) whose origin is an
  /// integer, so integer seam translations stay exact and rotations by quarter turns map the grid
  /// onto itself: a seamless map stays seamless (the default 14 moves a corner by at most 4.4e-5).
  /// 0, or a map whose UV range does not fit 24-bit exact floats at this step: lossless float64.
  int dracoUVBits = 14;
  /// Draco: position quantization bits over the bounding box, 1..30; 0 = lossless float32.
  int dracoPositionBits = 0;
  /// Told which vertex properties the format cannot hold (OBJ: all but red, green, blue written
  /// as `v x y z r g b` in [0, 1]; OFF: all), in one line naming the output. Empty: printed on
  /// stderr.
  WarningFn warn;
};

/// Vertex properties of the mesh a file of this format cannot hold (empty for PLY and Draco).
std::vector<std::string> droppedVertexProperties(const TriangleMesh& mesh, MeshFormat format);

/// The UV step exponent a Draco write of this mesh uses with these options (0 = lossless).
int dracoUVBitsFor(const TriangleMesh& mesh, const WriteOptions& options);

/// Writes a mesh; the format comes from the extension. The file is written to a temporary file
/// in the same folder and renamed into place, so a failure never leaves a half-written output.
void writeMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options = {});
/// The same into an open output (e.g. one of an OutputSet), format from file.path(); the
/// caller commits.
void writeMesh(AtomicFile& file, const TriangleMesh& mesh, const WriteOptions& options = {});
/// The same, consuming the mesh: a Draco write frees the mesh's arrays as its own copy takes
/// them, so the encoder's memory comes on top of that copy only (bench/RESULTS.md); the other
/// formats write, then free.
void writeMesh(AtomicFile& file, TriangleMesh&& mesh, const WriteOptions& options = {});

}  // namespace seamvox
