#include "core/system/progress.h"

#include <string>

#include "core/system/errors.h"

namespace seamvox {

void reportProgress(const ProgressFn& fn, const char* stage, double fraction) {
  if (fn && !fn(stage, fraction)) throw CancelledError(std::string("cancelled during ") + stage);
}

}  // namespace seamvox
