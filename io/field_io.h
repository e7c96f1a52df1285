#pragma once
/// Per-face field files (DESIGN section 4, "Sources of a field"). Two text formats:
/// * `.crossfield` (shared/data/README.md): first line `2 F`, then per face
///   `flag x1 y1 z1 x2 y2 z2` (flag 1 = hard constraint, 0 = free). Only the first vector is
///   used; the second is one of its quarter turns.
/// * plain (seamvox's own; what writeField produces): optional `#` comment lines, an optional
///   header line `1 F`, then one line `x y z` per face in face order (world coordinates; need
///   not be tangent or unit: the importer projects; a zero vector means "no preference").
/// Blank lines and `#` lines are skipped in both. The format is told by the first other line:
/// two integers are a header (`1 F` plain, `2 F` crossfield), three numbers a headerless plain file.
#include <cstdint>
#include <string>
#include <vector>

#include "core/field/field.h"
#include "core/mesh/mesh.h"

namespace seamvox {

class AtomicFile;

/// Reads the per-face vectors of a field file (first vector for `.crossfield`), unprojected.
/// Throws IoError (cannot open) or InputError naming the file and line: a malformed line, a
/// non-finite number, or a face count different from expectedFaces.
std::vector<Vec3d> readFieldVectors(const std::string& path, std::uint32_t expectedFaces);

/// readFieldVectors followed by projectToTangent on mesh (faces in mesh order).
CrossField importField(const std::string& path, const TriangleMesh& mesh);
/// The same for a cleaned mesh whose face f comes from input face faceOrigin[f] (CleanResult):
/// the file holds one vector per input face (inputFaces of them).
CrossField importField(const std::string& path, const TriangleMesh& mesh,
                       const std::vector<FaceId>& faceOrigin, std::uint32_t inputFaces);

/// Writes per-face vectors in the plain format (header `1 F`), atomically. Throws IoError.
void writeField(const std::string& path, const std::vector<Vec3d>& vectors);
/// The same into an open output (e.g. one of an OutputSet); the caller commits.
void writeField(AtomicFile& file, const std::vector<Vec3d>& vectors);
/// The same in pieces, for fields larger than memory: the header for `faces` vectors, then the
/// vectors in face order, count at a time (writeField's bytes once all are appended).
void writeFieldHeader(AtomicFile& file, std::uint64_t faces);
void appendFieldVectors(AtomicFile& file, const Vec3d* vectors, std::size_t count);

}  // namespace seamvox
