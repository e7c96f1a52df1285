#!/usr/bin/env bash
# Hat against voxloc on one mesh, in one invocation, alternating: K pairs (hat, then voxloc), each
# run a separate `seamvox param` process with a JSON report. Prints each run's total time and peak
# resident memory, each pair's ratios (hat / voxloc) and their medians, as a markdown table.
# On a shared machine the speed varies by 20% or more from one minute to the next (two scaling
# studies of the same code measured voxloc at 19.6 and 24.6 s on one mesh): alternating the
# solvers and taking the median of several pairs keeps the ratio from resting on one run.
#
#   bash bench/pairs.sh MESH [--field FILE] [--pairs K] [--grid G] [--build DIR] [--out DIR]
#
# Defaults: 3 pairs, grid 128, build ./build, reports in /tmp/seamvox_pairs. --field passes a
# field file to both solvers (the scaling study's inherited field), else `--field auto`.
set -u
mesh=${1:-}
[ -n "$mesh" ] && [ "${mesh#-}" = "$mesh" ] || { echo "usage: bash bench/pairs.sh MESH [--field FILE] [--pairs K] [--grid G] [--build DIR] [--out DIR]" >&2; exit 2; }
shift
field=auto pairs=3 grid=128 build=build out=/tmp/seamvox_pairs
while (($#)); do
  case "$1" in
    --field) field=$2; shift 2 ;;
    --pairs) pairs=$2; shift 2 ;;
    --grid) grid=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "pairs.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ $pairs =~ ^[1-9][0-9]*$ && $grid =~ ^[0-9]+$ ]] || { echo "pairs.sh: --pairs and --grid take whole numbers" >&2; exit 2; }
[ -f "$mesh" ] || { echo "pairs.sh: $mesh not found" >&2; exit 1; }
[ -x "$build/seamvox" ] || { echo "pairs.sh: $build/seamvox missing (bash tools/setup.sh)" >&2; exit 1; }
mkdir -p "$out" || exit 1

json_number() {  # json_number FILE KEY: the first "KEY": <number> in FILE
  sed -n "s/^ *\"$2\": *\(-\{0,1\}[0-9][0-9.eE+-]*\).*/\1/p" "$1" | head -1
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "| pair | hat total | hat peak | voxloc$grid total | voxloc$grid peak | time ratio | memory ratio |"
echo "|---|---|---|---|---|---|---|"
: > "$out/ratios"
for ((k = 1; k <= pairs; ++k)); do
  row="| $k"
  for solver in hat voxloc; do
    report=$out/${solver}_$k.json
    "$build/seamvox" param "$mesh" -o "$out/out.ply" --solver "$solver" --grid "$grid" --field "$field" \
      --quiet --report "$report" > "$out/${solver}_$k.log" 2>&1 ||
      { cat "$out/${solver}_$k.log" >&2; echo "pairs.sh: $solver run $k failed" >&2; exit 1; }
    total=$(json_number "$report" total)
    peak=$(json_number "$report" peakResidentBytes)
    eval "${solver}_total=$total ${solver}_peak=$peak"
    row="$row | $(awk -v t="$total" 'BEGIN { printf "%.1f s", t }') | $(awk -v b="$peak" 'BEGIN { printf "%.2f GB", b / 1e9 }')"
  done
  time_ratio=$(awk -v a="$hat_total" -v b="$voxloc_total" 'BEGIN { printf "%.2f", a / b }')
  memory_ratio=$(awk -v a="$hat_peak" -v b="$voxloc_peak" 'BEGIN { printf "%.2f", a / b }')
  echo "$time_ratio $memory_ratio" >> "$out/ratios"
  echo "$row | ${time_ratio}x | ${memory_ratio}x |"
done
rm -f "$out/out.ply"
echo
echo "median over $pairs pairs: time $(cut -d' ' -f1 "$out/ratios" | median)x, memory $(cut -d' ' -f2 "$out/ratios" | median)x (hat / voxloc$grid)"
