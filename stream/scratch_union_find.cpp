#include "stream/scratch_union_find.h"

#include "core/system/errors.h"

namespace seamvox {

ScratchLinks::ScratchLinks(ScratchFolder& folder, std::uint64_t n, std::uint64_t memoryBytes, const std::string& stage,
                           bool parities)
    : links_(folder, n, memoryBytes, stage), distanceMask_(parities ? 0x7fffffffu : 0xffffffffu) {
  if (parities && n > 0x80000000u) {
    throw InputError("a mesh of " + std::to_string(n) + " faces: more than 2^31, which orienting its faces supports");
  }
}

}  // namespace seamvox
