#include "core/quads/checked.h"

#include "core/system/errors.h"

namespace seamvox {

QuadRun extractCheckedQuads(const std::string& name, const TriangleMesh& mesh, const Topology& topology,
                            std::int64_t scale, const ProgressFn& progress) {
  if (!mesh.hasUV()) throw InputError(name + ": has no texture coordinates; run seamvox param first");
  QuadRun run;
  run.seams = measureSeamsFromUV(mesh, topology, mesh.cornerUV);
  const SeamQuality& seams = run.seams;
  if (!seams.isSeamless(kQuadSeamTolerance)) {
    throw InputError(name + ": the map is not seamless (seam residual " + std::to_string(seams.maxResidual) +
                     ", translations " + std::to_string(seams.maxIntegerDistance) +
                     " from integers, at the edge of corner " + std::to_string(seams.worstEdgeCorner) +
                     "); quads needs the integer-grid map of seamvox param");
  }
  QuadOptions options;
  options.scale = scale;
  options.progress = progress;
  try {
    run.quads = extractQuads(mesh, topology, options);
  } catch (...) {
    rethrowWithContext(name);
  }
  if (run.quads.stats.seamEdgesOffScale > 0) {
    // A seam maps u = K m onto u' = +-K m + t: the coarse lines continue only when K divides t.
    // Rounding makes t any integer, so this holds only for maps rounded to multiples of K.
    throw InputError(name + ": " + std::to_string(run.quads.stats.seamEdgesOffScale) +
                     " seam translations are no multiples of --scale " + std::to_string(scale) +
                     " (seam edges), so iso-lines every " + std::to_string(scale) +
                     " units would not continue across the seams: seamvox param rounds translations to "
                     "any integers; for a coarser quad mesh, map with an edge length " + std::to_string(scale) +
                     " times larger (--edge-length, --cells) and extract without --scale");
  }
  run.check = validateQuads(run.quads, computeComponents(topology));
  return run;
}

}  // namespace seamvox
