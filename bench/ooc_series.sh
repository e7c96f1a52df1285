#!/usr/bin/env bash
# param's time, peak memory and disk traffic against mesh size (issue #17): generated scans
# (`seamvox gen scan`, seed 1) from 1M to 250M faces, one `seamvox param` per size with the
# default memory budget, then a CSV and a markdown table (bench/ooc_series.py) with the slope
# between the two largest sizes extrapolated to 1G faces, and a log-log PNG plot of time and peak
# against faces (bench_scaling_report, built with the project: the runs are linked there as
# scan_L<k>_voxloc128.json, the solver every size above 400K faces runs).
#
#   bash bench/ooc_series.sh [--sizes "1000000 2000000 ..."] [--cache DIR] [--out DIR]
#                            [--seamvox PATH] [--reporter PATH] [--budget SIZE] [--noise A]
#
# --noise A: scan noise (`gen scan --noise A`, every vertex moved up to A mean edge lengths); the
# inputs are then cached as scan_<faces>_noise<A>.ply.
#
# Inputs are cached (DIR/scan_<faces>.ply, about 19 bytes per face); each run's output map is
# removed after the run (it is as large again). Peak = the report's peakResidentBytes (VmHWM) and
# GNU time's maximum resident set, the larger. Resumable: a size whose OUT/runs/<faces>.json
# exists is not run again.
set -uo pipefail
command_line="bash bench/ooc_series.sh $*"
here=$(cd "$(dirname "$0")" && pwd)
sizes="1000000 2000000 5000000 10000000 20000000 50000000 100000000 250000000"
cache=${TMPDIR:-/tmp}/seamvox_series
out=$here/ooc_series
seamvox=$here/../build/seamvox
reporter=$here/../build/bench/bench_scaling_report
budget=""
noise=""
while (($#)); do
  case "$1" in
    --sizes) sizes=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --seamvox) seamvox=$2; shift 2 ;;
    --reporter) reporter=$2; shift 2 ;;
    --budget) budget=$2; shift 2 ;;
    --noise) noise=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
[ -x "$seamvox" ] || { echo "no seamvox at $seamvox (build first, or --seamvox PATH)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "GNU time (/usr/bin/time, Debian package time) is needed" >&2; exit 1; }
mkdir -p "$cache" "$out/runs" || exit 1
budget_args=()
[ -n "$budget" ] && budget_args=(--memory-budget "$budget")
for n in $sizes; do
  input=$cache/scan_$n${noise:+_noise$noise}.ply
  report=$out/runs/$n.json
  [ -f "$report" ] && { echo "$n: done before ($report)"; continue; }
  if [ ! -f "$input" ]; then
    "$seamvox" gen scan --faces "$n" ${noise:+--noise "$noise"} -o "$input" --quiet > /dev/null ||
      { echo "$n: gen failed" >&2; exit 1; }
  fi
  map=$cache/map_$n.ply
  log=$out/runs/$n.log
  /usr/bin/time -v "$seamvox" param "$input" -o "$map" --report "$report.tmp" --quiet "${budget_args[@]}" \
    > "$log" 2> "$out/runs/$n.time"
  rc=$?
  rm -f "$map"
  if [ $rc -ne 0 ]; then
    echo "$n: param exited with $rc (see $log)" >&2
    rm -f "$report.tmp"
    continue
  fi
  mv "$report.tmp" "$report"
  echo "$n: $(grep -E '^path' "$log")"
done
python3 "$here/ooc_series.py" "$out/runs" --csv "$out/series.csv" --md "$out/series.md" --command "$command_line" || exit 1
rm -rf "$out/plot_runs" && mkdir -p "$out/plot_runs" || exit 1
k=0
for n in $(ls "$out/runs" | grep -E '^[0-9]+\.json$' | sed 's/\.json$//' | sort -n); do
  f=$out/runs/$n.json
  ln -s "$(realpath "$f")" "$out/plot_runs/scan_L${k}_voxloc128.json"
  k=$((k + 1))
done
budget_gb=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['memoryBudget'] / 1e9)" "$f")
"$reporter" "$out/plot_runs" --png "$out/series.png" --md "$out/plot_runs/table.md" --csv "$out/plot_runs/table.csv" \
  --limit-gb "$budget_gb" --command "$command_line" > /dev/null || exit 1
rm -rf "$out/plot_runs"
echo "wrote $out/series.csv, $out/series.md, $out/series.png"
