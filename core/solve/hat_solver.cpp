#include "core/solve/hat_solver.h"

#include <algorithm>
#include <chrono>

#include "core/basis/basis.h"
#include "core/solve/evaluate.h"
#include "core/basis/reduce.h"
#include "core/system/stopwatch.h"

namespace seamvox {

ParamResult parameterizeMesh(const TriangleMesh& mesh, const Topology& topology,
                             const CrossField& field, const CutResult& cut,
                             const ParamOptions& options) {
  ParamResult out;
  auto start = std::chrono::steady_clock::now();
  HatBasisOptions basisOptions;
  basisOptions.edgeLength = options.edgeLength;
  basisOptions.coneWeightRadius = options.coneWeightRadius;
  const HatBasis basis(mesh, topology, field, cut, basisOptions);
  out.basisFunctions = basis.numBasisFunctions();
  out.domains = basis.numDomains();
  out.seamAdjacencies = static_cast<std::uint32_t>(basis.adjacencies().size());
  out.secondsBasis = secondsSince(start);

  start = std::chrono::steady_clock::now();
  ReduceOptions reduceOptions;
  reduceOptions.progress = options.progress;
  const Reduction reduction = reduceBasis(basis, reduceOptions);
  out.translationConstraints = static_cast<std::uint32_t>(reduction.cycleConstraints.size());
  out.secondsReduce = secondsSince(start);

  RoundOptions roundOptions;
  roundOptions.greedy = options.greedyRounding;
  roundOptions.progress = options.progress;
  storeSeamlessSolution(basis, reduction, solveSeamless(basis, reduction, roundOptions), topology, cut, out);
  return out;
}

void storeSeamlessSolution(const Basis& basis, const Reduction& reduction, SeamlessSolution solution,
                           const Topology& topology, const CutResult& cut, ParamResult& out) {
  out.stats = solution.stats;
  out.translations = std::move(solution.translations);
  const auto start = std::chrono::steady_clock::now();
  out.cornerUV = buildCutWedges(topology, cut);
  evaluateMap(basis, reduction, solution.unknowns, out.cornerUV);
  out.secondsEvaluate = secondsSince(start);
}

std::vector<GaussVector> seamCycleConstraints(const TriangleMesh& mesh, const Topology& topology,
                                              const CrossField& field, const CutResult& cut,
                                              double edgeLength) {
  HatBasisOptions options;
  options.edgeLength = edgeLength;
  for (const SeamCurve& seam : cut.seams) {
    for (CornerId c : seam.corners) {
      for (CornerId end : {nextCorner(c), prevCorner(c)}) {
        topology.forEachCornerAround(topology.vertex(end),
                                     [&](CornerId around) { options.faces.push_back(around / 3); });
      }
    }
  }
  if (options.faces.empty()) return {};  // an empty subset would mean the whole mesh
  std::sort(options.faces.begin(), options.faces.end());
  options.faces.erase(std::unique(options.faces.begin(), options.faces.end()), options.faces.end());
  const HatBasis basis(mesh, topology, field, cut, options);
  return reduceBasis(basis).cycleConstraints;
}

}  // namespace seamvox
