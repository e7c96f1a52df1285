#!/usr/bin/env bash
# One checkerboard picture per solver (hat, vox, voxloc) per mesh, like the paper's Figure 7,
# written to bench/pictures/<mesh>_<solver>.png together with each run's JSON report.
#   bash bench/pictures.sh [DATA_DIR] [GRID]
# Needs a build (bash tools/setup.sh). DATA_DIR defaults to ../shared/data.
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-../shared/data}
grid=${2:-128}
out=bench/pictures
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for mesh in fertility.off bunny.off camelhead.off armadillo.obj; do
  [ -f "$data/$mesh" ] || { echo "skipping $mesh: not in $data" >&2; continue; }
  name=${mesh%.*}
  for solver in hat vox voxloc; do
    ./build/seamvox param "$data/$mesh" -o "$work/$name.ply" --solver "$solver" --grid "$grid" \
      --quiet --report "$out/${name}_$solver.json" | grep -E "seam residual|WARNING" | sed "s/^/$name $solver: /"
    ./build/seamvox render "$work/$name.ply" -o "$out/${name}_$solver.png" --size 512x512 \
      --checker 1 --seams --cones --quiet > /dev/null
  done
done
