// Defaults and validation of the grid spacing h.
#include "core/pipeline/grid_spacing.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/system/errors.h"

namespace seamvox {

namespace {

std::string numberText(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

}  // namespace

void GridSpacing::validate() const {
  if (edgeLength != 0.0 && cells != 0.0) {
    throw InputError("give either an edge length or a cell count for the grid spacing, not both");
  }
  if (edgeLength != 0.0 && !(edgeLength > 0.0 && std::isfinite(edgeLength))) {
    throw InputError("the grid spacing (edge length) must be a positive finite number, not " +
                     numberText(edgeLength));
  }
  if (cells != 0.0 && !(cells > 0.0 && cells <= kMaxCells)) {
    throw InputError("the cell count on the diagonal must be a number in (0, " + numberText(kMaxCells) +
                     "], not " + numberText(cells));
  }
}

double GridSpacing::spacing(double diagonal) const {
  validate();
  if (!(diagonal > 0.0) || !std::isfinite(diagonal)) {
    throw InputError("the mesh has zero or non-finite extent (bounding-box diagonal " + numberText(diagonal) + ")");
  }
  const double h = edgeLength > 0.0 ? edgeLength : diagonal / (cells > 0.0 ? cells : kDefaultCells);
  if (!(h > 0.0) || !std::isfinite(h) || diagonal / h > kMaxCells) {
    throw InputError("grid spacing " + numberText(h) + " gives more than " + numberText(kMaxCells) +
                     " cells on the mesh's diagonal " + numberText(diagonal));
  }
  return h;
}

}  // namespace seamvox
