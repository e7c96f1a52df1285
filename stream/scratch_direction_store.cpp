#include "stream/scratch_direction_store.h"

#include <string>

#include "core/system/errors.h"

namespace seamvox {

void ScratchDirectionStore::store(std::vector<Vec3f>& directions) {
  if (held_) throw InputError("direction store: the directions are already stored");
  static_assert(sizeof(Vec3f) == 3 * sizeof(float), "directions are written as 3 plain floats");
  ScratchWriter writer(folder_, "field to disk");
  writer.write(directions.data(), directions.size() * sizeof(Vec3f));
  file_ = writer.finish();
  count_ = directions.size();
  bytesStored_ += file_.bytes;
  held_ = true;
  std::vector<Vec3f>().swap(directions);
}

void ScratchDirectionStore::load(std::vector<Vec3f>& directions) {
  if (!held_) throw InputError("direction store: nothing is stored");
  directions.resize(count_);
  {
    ScratchReader reader(folder_, file_, "field from disk");
    if (count_ > 0 && !reader.read(directions.data(), count_ * sizeof(Vec3f))) {
      throw IoError(file_.path + ": the stored field directions are missing");
    }
  }
  folder_.remove(file_);
  held_ = false;
}

}  // namespace seamvox
