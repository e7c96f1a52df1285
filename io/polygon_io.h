#pragma once
/// Polygon meshes (quad meshes of `seamvox quads`) in OBJ (`v`, `f`) and PLY (binary little
/// endian: float x y z, faces as `list uchar int vertex_indices`); OBJ read back for `render`.
#include <string>

#include "core/quads/extract.h"

namespace seamvox {

class AtomicFile;

/// Writes the mesh into an open output (e.g. one of an OutputSet); the format comes from
/// file.path(): .obj or .ply (InputError otherwise, or for a face of more than 255 vertices in PLY).
void writePolygonMesh(AtomicFile& file, const PolygonMesh& mesh);

/// Reads the `v` and `f` lines of an OBJ file (other lines are skipped; `f` corners may carry
/// `/vt/vn` parts and negative indices). Throws IoError when it cannot be opened, InputError
/// naming the file and line for a malformed number, a face of fewer than 3 corners or an index
/// out of range.
PolygonMesh readPolygonObj(const std::string& path);

}  // namespace seamvox
