#!/usr/bin/env bash
# The scaling study (issue #7): hat vs vox vs voxloc on fertility subdivided 1-to-4 (9K to 9.2M
# faces) and armadillo subdivided (86K to 22M faces), one process per run, then the CSV, the
# markdown section of bench/RESULTS.md and a log-log plot of total time and peak RSS against faces.
#
#   bash bench/scaling.sh [--max-faces N] [--out DIR] [--cache DIR] [--build DIR] [--data DIR]
#                         [--meshes fertility,armadillo] [--solvers hat,vox64,vox128,voxloc64,voxloc128]
#                         [--field inherit|auto|smooth|proxy] [--mem-gb G] [--timeout S] [--no-build]
#                         [--no-results] [--max-level K]
#
# --max-level K keeps subdivision levels 0..K (0: the meshes as they are; see the shared-mesh table
# in bench/RESULTS.md).
# Defaults: every size (hours of CPU), out bench/scaling, inputs cached in /tmp/seamvox_scaling,
# build ./build (the script builds the targets seamvox and bench_scaling_report there first).
# Field (--field inherit, the default): the smoothest cross field of the base mesh, computed once
# (`seamvox field`) and carried to the subdivided faces (`seamvox subdivide --field`; children are
# coplanar with their parent), so every solver and every size of a mesh solves for the same field
# and cones. --field auto|smooth|proxy instead passes that value to every `seamvox param` run.
# Each run is `seamvox param CACHED.ply --solver S --grid G --report R.json` under a memory limit
# (default 20 GB = 20e9 bytes, every solver: a watchdog kills the run when its resident set
# exceeds it; an address-space limit 10% higher is the backstop) and a timeout (default 7200 s).
# Hat stops for a mesh after a failed run, or when its last peak RSS scaled by n log n (the fill
# of a nested-dissection factor of a surface mesh) exceeds the limit. Failed and skipped runs are recorded as rows. Resumable: a run whose file
# OUT/runs/<mesh>_L<level>_<solver>.json exists is not run again (delete the file to redo it;
# use another --out for another --field or --mem-gb).
# Outputs: OUT/runs/*.json (+ .time, logs/), OUT/scaling.csv, OUT/scaling.md, OUT/scaling.png,
# and the block between the scaling.sh markers in bench/RESULTS.md (unless --no-results).
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

command_line="bash bench/scaling.sh $*"
max_faces=100000000
max_level_opt=99
out=bench/scaling
cache=${TMPDIR:-/tmp}/seamvox_scaling
build=build
data=../shared/data
meshes=fertility,armadillo
solvers=hat,vox64,vox128,voxloc64,voxloc128
field_mode=inherit
mem_gb=20
timeout_s=7200
do_build=1
do_results=1
capped=0
while (($#)); do
  case "$1" in
    --max-faces) max_faces=$2; capped=1; shift 2 ;;
    --max-level) max_level_opt=$2; capped=1; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --cache) cache=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --data) data=$2; shift 2 ;;
    --meshes) meshes=$2; shift 2 ;;
    --solvers) solvers=$2; shift 2 ;;
    --field) field_mode=$2; shift 2 ;;
    --mem-gb) mem_gb=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --no-build) do_build=0; shift ;;
    --no-results) do_results=0; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "scaling.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$field_mode" in inherit|auto|smooth|proxy) ;; *) echo "scaling.sh: --field must be inherit, auto, smooth or proxy" >&2; exit 2 ;; esac
[[ $max_faces =~ ^[0-9]+$ && $timeout_s =~ ^[0-9]+$ && $mem_gb =~ ^[0-9]+(\.[0-9]+)?$ ]] ||
  { echo "scaling.sh: --max-faces and --timeout take whole numbers, --mem-gb a number" >&2; exit 2; }

seamvox=$build/seamvox
reporter=$build/bench/bench_scaling_report
mkdir -p "$out/runs" "$out/logs" "$cache" || exit 1
if ((do_build)); then
  [ -f "$build/CMakeCache.txt" ] || cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null || exit 1
  echo "building seamvox and bench_scaling_report in $build"
  cmake --build "$build" -j2 --target seamvox bench_scaling_report > "$cache/build.log" 2>&1 ||
    { tail -20 "$cache/build.log"; echo "scaling.sh: build failed (log: $cache/build.log)" >&2; exit 1; }
fi
for exe in "$seamvox" "$reporter"; do
  [ -x "$exe" ] || { echo "scaling.sh: $exe missing: build it (cmake --build $build --target seamvox bench_scaling_report)" >&2; exit 1; }
done
"$reporter" --self-check > /dev/null || { echo "scaling.sh: $reporter --self-check failed" >&2; exit 1; }
if [ "$field_mode" != inherit ] && ! "$seamvox" param --help 2>&1 | grep -q -- "--field $field_mode"; then
  echo "scaling.sh: this seamvox param has no --field $field_mode" >&2; exit 2
fi
mem_bytes=$(awk -v g="$mem_gb" 'BEGIN { printf "%.0f", g * 1e9 }')
# Backstop for allocations faster than the watchdog: an address-space limit 10% (at least 1 GB)
# above the resident limit. (OpenBLAS retries a failed buffer allocation forever, so a run that
# hits this limit inside a factorization ends at the timeout, not with an error.)
as_bytes=$(awk -v b="$mem_bytes" 'BEGIN { printf "%.0f", (b * 0.1 > 1e9) ? b * 1.1 : b + 1e9 }')
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# ---- small helpers --------------------------------------------------------------------------
calc() { awk "BEGIN { printf \"%.6g\", $1 }"; }
short() { awk "BEGIN { printf \"%.3g\", $1 }"; }  # 3 significant digits, for messages
commas() { echo "$1" | sed -e ':a' -e 's/\([0-9]\)\([0-9]\{3\}\)\($\|,\)/\1,\2\3/' -e 'ta'; }
duration() {  # seconds -> 1h02m / 3m05s / 12s
  awk -v s="$1" 'BEGIN { s = int(s + 0.5); if (s >= 3600) printf "%dh%02dm", s / 3600, (s % 3600) / 60;
    else if (s >= 60) printf "%dm%02ds", s / 60, s % 60; else printf "%ds", s }'
}
json_number() {  # json_number FILE KEY [OBJECT]: first "KEY": <number> in FILE (or in "OBJECT": {...})
  if [ -n "${3:-}" ]; then sed -n "/^ *\"$3\": {/,/}/p" "$1"; else cat "$1"; fi |
    sed -n "s/^ *\"$2\": *\(-\{0,1\}[0-9][0-9.eE+-]*\).*/\1/p" | head -1
}
json_escape() { printf '%s' "$1" | tr -d '\000-\037' | sed 's/\\/\\\\/g; s/"/\\"/g'; }
mesh_file() {
  case "$1" in
    fertility) echo "$data/fertility.off" ;;
    armadillo) echo "$data/armadillo.obj" ;;
    *) for e in ply obj off; do [ -f "$data/$1.$e" ] && { echo "$data/$1.$e"; return; }; done; echo "$data/$1" ;;
  esac
}
solver_args() {
  case "$1" in
    hat) echo "--solver hat" ;;
    vox[0-9]*) echo "--solver vox --grid ${1#vox}" ;;
    voxloc[0-9]*) echo "--solver voxloc --grid ${1#voxloc}" ;;
    *) return 1 ;;
  esac
}
IFS=, read -r -a mesh_list <<< "$meshes"
IFS=, read -r -a solver_list <<< "$solvers"
for s in "${solver_list[@]}"; do
  solver_args "$s" > /dev/null || { echo "scaling.sh: unknown solver '$s' (hat, voxN, voxlocN)" >&2; exit 2; }
done

# ---- inputs: base field, subdivided meshes and their fields ------------------------------------
declare -A level_faces  # "mesh level" -> faces
declare -A max_level
echo "== inputs (cache $cache)"
for mesh in "${mesh_list[@]}"; do
  src=$(mesh_file "$mesh")
  [ -f "$src" ] || { echo "scaling.sh: $src not found (--data DIR)" >&2; exit 1; }
  base_field=$cache/${mesh}.base.field
  if [ "$field_mode" = inherit ] && [ ! -f "$base_field" ]; then
    echo "$mesh: smoothest field of the base mesh -> $base_field"
    "$seamvox" field "$src" -o "$base_field" --quiet > "$tmp/field.log" 2>&1 ||
      { cat "$tmp/field.log"; echo "scaling.sh: seamvox field failed on $src" >&2; exit 1; }
  fi
  level=0
  while ((level <= max_level_opt)); do
    stem=$cache/${mesh}_L$level
    if [ ! -f "$stem.faces" ] || { [ "$field_mode" = inherit ] && [ ! -f "$stem.field" ]; }; then
      # Stop before building a level that would exceed --max-faces (known from the level below).
      if ((level > 0)) && (( level_faces["$mesh $((level - 1))"] * 4 > max_faces )); then break; fi
      start=$(date +%s.%N)
      field_args=()
      [ "$field_mode" = inherit ] && field_args=(--field "$base_field" --field-out "$stem.field")
      "$seamvox" subdivide "$src" --levels "$level" -o "$stem.ply" "${field_args[@]}" --quiet > "$tmp/sub.log" 2>&1 ||
        { cat "$tmp/sub.log"; echo "scaling.sh: seamvox subdivide failed on $src" >&2; exit 1; }
      faces=$(sed -n 's/^wrote .*: \([0-9]*\) faces.*/\1/p' "$tmp/sub.log" | head -1)
      [ -n "$faces" ] || { cat "$tmp/sub.log"; echo "scaling.sh: cannot read the face count" >&2; exit 1; }
      echo "$faces" > "$stem.faces"
      echo "$mesh L$level: $(commas "$faces") faces ($(duration "$(calc "$(date +%s.%N) - $start")"))"
    fi
    faces=$(cat "$stem.faces")
    if ((faces > max_faces)); then
      ((level == 0)) && echo "$mesh: base mesh has $(commas "$faces") faces > --max-faces; skipped"
      break
    fi
    level_faces["$mesh $level"]=$faces
    max_level[$mesh]=$level
    level=$((level + 1))
  done
done

# ---- the plan and its ETA -------------------------------------------------------------------
plan=()
for mesh in "${mesh_list[@]}"; do
  [ -n "${max_level[$mesh]:-}" ] || continue
  for ((level = 0; level <= max_level[$mesh]; ++level)); do
    for s in "${solver_list[@]}"; do plan+=("$mesh $level $s"); done
  done
done
declare -A known previous  # "mesh solver" -> "faces seconds" of the last and the one before
exponent() { [ "$1" = hat ] && echo 1.5 || echo 1.0; }
predict() {  # predict MESH SOLVER FACES -> seconds, or empty when nothing is known yet
  # Two runs of this mesh and solver: hat by their power law (exponent in [1, 2]), the voxel
  # solvers linearly (a fixed grid cost plus a per-face cost). One run: n^1.5 (hat) or n.
  # None: the same solver on another mesh, scaled by faces.
  local k=${known["$1 $2"]:-} p=${previous["$1 $2"]:-}
  if [ -n "$k" ] && [ -n "$p" ]; then
    set -- "$1" "$2" "$3" $p $k
    if [ "$2" = hat ]; then
      calc "$7 * ($3 / $6) ^ (($5 > 0 && $7 > $5) ? (log($7 / $5) / log($6 / $4) > 2 ? 2 : (log($7 / $5) / log($6 / $4) < 1 ? 1 : log($7 / $5) / log($6 / $4))) : 1)"
    else
      calc "$7 + (($7 > $5) ? ($7 - $5) / ($6 - $4) : 0) * ($3 - $6)"
    fi
    return 0
  fi
  k=${k:-${known["* $2"]:-}}
  [ -n "$k" ] || return 0
  set -- "$1" "$2" "$3" $k
  calc "$5 * ($3 / $4) ^ $(exponent "$2")"
}
remember() {  # remember MESH SOLVER FACES SECONDS (in increasing faces)
  [ -n "${known["$1 $2"]:-}" ] && previous["$1 $2"]=${known["$1 $2"]}
  known["$1 $2"]="$3 $4"
  known["* $2"]="$3 $4"
}
eta_from() {  # eta_from INDEX: predicted seconds of plan[INDEX..], "+" when some are unknown
  local total=0 unknown="" i p
  for ((i = $1; i < ${#plan[@]}; ++i)); do
    read -r m l s <<< "${plan[$i]}"
    [ -f "$out/runs/${m}_L${l}_$s.json" ] && continue
    p=$(predict "$m" "$s" "${level_faces["$m $l"]}")
    if [ -n "$p" ]; then total=$(calc "$total + $p"); else unknown="+"; fi
  done
  echo "$(duration "$total")$unknown"
}

descendants() {  # a process and all its descendants
  local c
  echo "$1"
  for c in $(cat /proc/"$1"/task/*/children 2> /dev/null); do descendants "$c"; done
}
watch_rss() {  # watch_rss PID LIMIT FLAGFILE: SIGKILLs the tree of PID when its RSS exceeds LIMIT
  # bytes (writing the RSS to FLAGFILE); writes the largest RSS seen to FLAGFILE.max at the end.
  local pids total p kb max=0
  while kill -0 "$1" 2> /dev/null; do
    pids=$(descendants "$1")
    total=0
    for p in $pids; do
      kb=$(awk '/^VmRSS/ { print $2 }' /proc/"$p"/status 2> /dev/null)
      total=$((total + ${kb:-0} * 1024))
    done
    ((total > max)) && max=$total
    if ((total > $2)); then
      echo "$total" > "$3"
      # shellcheck disable=SC2086
      kill -KILL $(echo "$pids" | tail -n +2) 2> /dev/null
      break
    fi
    sleep 0.5
  done
  echo "$max" > "$3.max"
}
declare -A hat_peak hat_faces hat_stop
write_stub() {  # write_stub FILE STATUS REASON FACES [WALL] [PEAK]
  {
    printf '{\n  "status": "%s",\n  "reason": "%s",\n  "faces": %s' "$2" "$(json_escape "$3")" "$4"
    [ -n "${5:-}" ] && printf ',\n  "wallSeconds": %s' "$5"
    [ -n "${6:-}" ] && printf ',\n  "peakResidentBytes": %s' "$6"
    printf '\n}\n'
  } > "$1.tmp" && mv "$1.tmp" "$1"
}

echo "== ${#plan[@]} runs (memory limit $mem_gb GB resident, timeout $timeout_s s, field: $field_mode); results in $out"
study_start=$(date +%s)
for ((i = 0; i < ${#plan[@]}; ++i)); do
  read -r mesh level s <<< "${plan[$i]}"
  faces=${level_faces["$mesh $level"]}
  stem=${mesh}_L${level}_$s
  report=$out/runs/$stem.json
  tag="[$((i + 1))/${#plan[@]}] $mesh L$level ($(commas "$faces") faces) $s"
  if [ -f "$report" ]; then
    if grep -q '"status"' "$report"; then
      echo "$tag: recorded earlier as $(sed -n 's/.*"status": "\(.*\)".*/\1/p' "$report")"
      [ "$s" = hat ] && hat_stop[$mesh]="hat did not finish at $(commas "$faces") faces"
    else
      t=$(json_number "$report" total seconds)
      remember "$mesh" "$s" "$faces" "$t"
      if [ "$s" = hat ]; then hat_peak[$mesh]=$(json_number "$report" peakResidentBytes); hat_faces[$mesh]=$faces; fi
      echo "$tag: done earlier ($(duration "$t"))"
    fi
    continue
  fi
  if [ "$s" = hat ]; then
    if [ -n "${hat_stop[$mesh]:-}" ]; then
      write_stub "$report" skipped "${hat_stop[$mesh]}" "$faces"
      echo "$tag: skipped (${hat_stop[$mesh]})"
      continue
    fi
    if [ -n "${hat_peak[$mesh]:-}" ]; then
      predicted=$(calc "${hat_peak[$mesh]} * ($faces / ${hat_faces[$mesh]}) * log($faces) / log(${hat_faces[$mesh]})")
      if awk "BEGIN { exit !($predicted > $mem_bytes) }"; then
        hat_stop[$mesh]="predicted peak $(short "$predicted / 1e9") GB (n log n from $(short "${hat_peak[$mesh]} / 1e9") GB at $(commas "${hat_faces[$mesh]}") faces) > $mem_gb GB"
        write_stub "$report" skipped "${hat_stop[$mesh]}" "$faces"
        echo "$tag: skipped (${hat_stop[$mesh]})"
        continue
      fi
    fi
  fi
  p=$(predict "$mesh" "$s" "$faces")
  expected=unknown
  [ -n "$p" ] && expected="~$(duration "$p")"
  echo "$tag: running (expected $expected; ETA of the rest $(eta_from "$i"); elapsed $(duration $(($(date +%s) - study_start))))"
  field_arg=$field_mode
  [ "$field_mode" = inherit ] && field_arg=$cache/${mesh}_L$level.field
  rm -f "$tmp/report.json" "$tmp/time" "$tmp/oom" "$tmp/oom.max"
  rc=0
  # shellcheck disable=SC2046
  /usr/bin/time -f "%e %M" -o "$tmp/time" \
    timeout --kill-after=60 "$timeout_s" prlimit --as="$as_bytes" -- \
    "$seamvox" param "$cache/${mesh}_L$level.ply" -o "$tmp/out.ply" $(solver_args "$s") \
    --field "$field_arg" --report "$tmp/report.json" --quiet > "$out/logs/$stem.log" 2>&1 &
  run_pid=$!
  watch_rss "$run_pid" "$mem_bytes" "$tmp/oom" &
  watch_pid=$!
  wait "$run_pid" || rc=$?
  wait "$watch_pid" 2> /dev/null
  rm -f "$tmp/out.ply"
  read -r wall maxrss_kb < <(tail -1 "$tmp/time" 2>/dev/null) || true
  wall=${wall:-0}
  maxrss=$(( ${maxrss_kb:-0} * 1024 ))
  seen=$(cat "$tmp/oom.max" 2> /dev/null)
  ((${seen:-0} > maxrss)) && maxrss=$seen
  if ((rc == 0)) && [ -f "$tmp/report.json" ]; then
    echo "wallSeconds=$wall maxRssBytes=$maxrss" > "$out/runs/$stem.time"
    mv "$tmp/report.json" "$report"
    t=$(json_number "$report" total seconds)
    peak=$(json_number "$report" peakResidentBytes)
    remember "$mesh" "$s" "$faces" "$t"
    if [ "$s" = hat ]; then hat_peak[$mesh]=$peak; hat_faces[$mesh]=$faces; fi
    echo "  done: total $(awk "BEGIN { printf \"%.2f s (wall $wall s), peak %.1f MB, L2 %.4f\", $t, $peak / 1e6, $(json_number "$report" relativeGradientError quality) }"), flipped $(json_number "$report" flipped quality), $(grep -q '"seamless": true' "$report" && echo seamless || echo NOT seamless)$(grep -q '"fallbackReason"' "$report" && echo ", FELL BACK to hat")"
  else
    if [ -f "$tmp/oom" ]; then
      reason="out of memory (resident set above $mem_gb GB: $(short "$(cat "$tmp/oom") / 1e9") GB; killed)"
    elif ((rc == 124 || rc == 137)); then
      reason="timeout after $timeout_s s"
    elif ((rc == 3)) || grep -qiE "out of memory|bad_alloc|cannot allocate" "$out/logs/$stem.log"; then
      reason="out of memory (address space above $(short "$as_bytes / 1e9") GB)"
    else
      reason="exit code $rc: $(grep -v '^ *$' "$out/logs/$stem.log" | tail -1 | cut -c1-200)"
    fi
    write_stub "$report" failed "$reason" "$faces" "$wall" "$maxrss"
    [ "$s" = hat ] && hat_stop[$mesh]="hat failed at a smaller size ($reason)"
    echo "  FAILED: $reason (wall $wall s, peak $(short "$maxrss / 1e6") MB; log $out/logs/$stem.log)"
  fi
done
echo "== study time $(duration $(($(date +%s) - study_start)))"

# ---- report -------------------------------------------------------------------------------------
png_link=$(realpath -m --relative-to="$repo/bench" "$out/scaling.png")
"$reporter" "$out/runs" --csv "$out/scaling.csv" --md "$tmp/table.md" --png "$out/scaling.png" \
  --png-link "$png_link" --limit-gb "$mem_gb" --command "$command_line" || exit 1
{
  echo "Generated $(date -u +%Y-%m-%d) on $(nproc) cores, $(awk '/MemTotal/ { printf "%.0f GB", $2 / 1e6 }' /proc/meminfo) RAM"\
       "(load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)). Field: $(
         [ "$field_mode" = inherit ] && echo "the base mesh's smoothest field, inherited by the subdivided faces (the same for every solver and size)" || echo "--field $field_mode")."\
       "Memory limit $mem_gb GB resident (watchdog; every run), timeout $timeout_s s; peak RSS is VmHWM; MB and GB are 10^6 and 10^9 bytes."\
       "Times: total is the whole \`seamvox param\` process (read to write); solves = first solve + rounding + second solve."
  ((capped)) && ((max_faces < 20000000 || max_level_opt < 4)) && echo "" &&
    echo "**Small run (--max-faces $max_faces, --max-level $max_level_opt): a test of the driver, not the study.**"
  echo ""
  cat "$tmp/table.md"
} > "$out/scaling.md"
echo "wrote $out/scaling.csv, $out/scaling.md, $out/scaling.png"
results=bench/RESULTS.md
if ((do_results)); then
  begin='<!-- scaling.sh:begin -->'
  end='<!-- scaling.sh:end -->'
  if grep -qF "$begin" "$results" && grep -qF "$end" "$results"; then
    awk -v begin="$begin" -v end="$end" -v body="$out/scaling.md" '
      $0 == begin { print; while ((getline line < body) > 0) print line; skip = 1; next }
      $0 == end { skip = 0 }
      !skip { print }' "$results" > "$tmp/results.md" && cp "$tmp/results.md" "$results"
    echo "updated the scaling block of $results"
  else
    echo "no '$begin' ... '$end' block in $results: paste $out/scaling.md there"
  fi
fi
