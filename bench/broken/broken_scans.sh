#!/bin/bash
# Damaged variants of the shared meshes (damage_mesh.py) through param with quads, check and
# render: one line per variant with the exit codes, both verdicts, flips before/after the repair,
# the quad mesh's validation and the wound vertices param and check count. Usage: bash bench/broken/broken_scans.sh [OUTDIR]
# OOC_BUDGET=700M: param out of core within that budget (no quads: not out of core) and check
# within it.
set -u
here=$(cd "$(dirname "$0")" && pwd)
S=${SEAMVOX:-$here/../../build/seamvox}
D=${SEAMVOX_DATA:-$here/../../../shared/data}
W=${1:-/tmp/seamvox-broken}
mkdir -p "$W" && cd "$W" || exit 1
[ -d "$D" ] || { echo "no shared meshes in $D"; exit 1; }
for m in bunny.off camelhead.off fertility.off spot.obj rocker-arm.obj cheburashka.off 3holes.off armadillo.obj; do
  b=${m%.*}
  [ -f $b.obj ] || "$S" convert "$D/$m" $b.obj --quiet > /dev/null 2>&1
  for k in holes dups flipped fins bowties islands degenerate split moebius; do
    x=$b-$k
    python3 "$here/damage_mesh.py" $b.obj $x.obj $k 7
    rm -f $x-o.ply $x-q.obj $x.json
    if [ -n "${OOC_BUDGET:-}" ]; then
      rm -rf scratch && mkdir scratch
      "$S" param $x.obj -o $x-o.ply --report $x.json --out-of-core --memory-budget $OOC_BUDGET --scratch scratch \
        --quiet > $x.log 2>&1; rc=$?
      "$S" check $x-o.ply --memory-budget $OOC_BUDGET --scratch scratch > $x.check 2>&1; rc2=$?
    else
      "$S" param $x.obj -o $x-o.ply --quads $x-q.obj --report $x.json --quiet > $x.log 2>&1; rc=$?
      "$S" check $x-o.ply > $x.check 2>&1; rc2=$?
    fi
    "$S" render $x-o.ply -o $x.png --seams --cones --quiet > $x.render 2>&1; rc3=$?
    seam=$(grep -oE "(NOT )?seamless" $x.log | tail -1)
    flips=$(grep -oE "flipped [0-9]+ -> [0-9]+" $x.log | tail -1)
    valid=$(grep -oE "validation: (NOT )?valid" $x.log | tail -1)
    # wound vertices as param counted them (its path) and as check counts them on the file
    wound="$(grep -oE "wound [0-9]+" $x.log | tail -1 | cut -d' ' -f2)/$(grep -oE "^wound [0-9]+" $x.check | cut -d' ' -f2)"
    echo "$x param=$rc check=$rc2 render=$rc3 [$seam] [$(tail -1 $x.check)] [$flips] [$valid] wound=$wound output=$([ -f $x-o.ply ] && echo yes || echo no)"
  done
done
