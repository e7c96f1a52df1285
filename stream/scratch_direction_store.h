#pragma once
/// DirectionStore in a scratch folder: the field's directions go to one scratch file by plain
/// writes through a buffer and come back by plain reads; the file is removed once read. Memory:
/// the buffer (1 MiB), not the directions.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/pipeline/parameterize.h"
#include "stream/scratch_folder.h"

namespace seamvox {

class ScratchDirectionStore : public DirectionStore {
 public:
  explicit ScratchDirectionStore(ScratchFolder& folder) : folder_(folder) {}
  /// IoError naming the folder and the bytes needed when the disk is full.
  void store(std::vector<Vec3f>& directions) override;
  /// IoError when the file does not give back what was stored.
  void load(std::vector<Vec3f>& directions) override;
  std::uint64_t bytesStored() const { return bytesStored_; }  ///< in all, over every store

 private:
  ScratchFolder& folder_;
  ScratchFile file_;
  std::size_t count_ = 0;
  bool held_ = false;
  std::uint64_t bytesStored_ = 0;
};

}  // namespace seamvox
