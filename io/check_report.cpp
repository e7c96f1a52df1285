// The JSON document of a check: seams, flips, collapses, gradient error, the verdict.
#include "io/check_report.h"

#include "core/quality/check.h"
#include "io/json.h"

namespace seamvox {

std::string checkReportJson(const std::string& mesh, const CheckResult& r,
                            const std::function<void(JsonWriter&)>& extra) {
  JsonWriter j;
  j.beginObject();
  j.key("mesh").value(mesh);
  j.key("faces").value(static_cast<std::uint64_t>(r.faces));
  j.key("seamless").value(r.isSeamless).key("tolerance").value(r.tolerance);
  j.key("seamEdges").value(r.seams.seamEdges).key("seamLength").value(r.seams.seamLength);
  j.key("maxSeamResidual").value(r.seams.maxResidual);
  j.key("maxIntegerDistance").value(r.seams.maxIntegerDistance);
  j.key("flipped").value(r.map.flipped).key("flippedFraction").value(r.map.flippedFraction);
  j.key("collapsed").value(r.map.collapsed);
  j.key("stretched").value(r.map.stretched);
  j.key("wound");
  if (r.map.woundCounted) {
    j.value(r.map.wound);
  } else {
    j.null();  // out of core: not counted
  }
  j.key("edgeLength").value(r.map.edgeLength);
  j.key("relativeGradientError");
  if (r.hasField) {
    j.value(r.map.relativeGradientError);
  } else {
    j.null();
  }
  if (extra) extra(j);
  j.endObject();
  return j.str();
}

}  // namespace seamvox
