#!/usr/bin/env bash
# Runs a seamvox binary on the 7 shared meshes of the before/after tables (bench/RESULTS.md):
# `field` (auto and proxy: JSON and the field file) and `param` with hat and voxloc (JSON report).
# Usage: run_shared.sh SEAMVOX DATA_DIR OUT_DIR. Compare two OUT_DIRs with compare_shared.py.
set -euo pipefail
bin=$1 data=$2 out=$3
mkdir -p "$out"
for m in 3holes.off bunny.off camelhead.off cheburashka.off spot.obj rocker-arm.obj bumpy.off; do
  n=${m%.*}
  for method in auto proxy; do
    "$bin" field "$data/$m" -o "$out/$n.$method.field" --field "$method" --json --quiet \
      --cones "$out/$n.$method.cones.obj" > "$out/$n.$method.field.json"
  done
  for solver in hat voxloc; do
    "$bin" param "$data/$m" -o "$out/$n.$solver.obj" --solver "$solver" --report "$out/$n.$solver.json" --quiet
  done
done
