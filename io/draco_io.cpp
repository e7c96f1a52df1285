// Draco (.drc): not supported yet; reading and writing say so.
#include "core/errors.h"
#include "io/detail_mesh_io.h"

namespace seamvox::detail {

TriangleMesh readDraco(const std::string& path, const ReadOptions&) {
  throw IoError(path + ": reading Draco (.drc) files is not supported yet; use PLY, OBJ or OFF");
}

void writeDraco(AtomicFile& file, const TriangleMesh&, const WriteOptions&) {
  throw IoError(file.path() + ": writing Draco (.drc) files is not supported yet; use PLY, OBJ or OFF");
}

}  // namespace seamvox::detail
