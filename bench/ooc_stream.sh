#!/usr/bin/env bash
# gen, convert and info above the memory budget (issue 17): time, peak resident memory and scratch
# traffic per size, one run at a time, each also in memory when the machine holds it.
#
#   bash bench/ooc_stream.sh [--faces 10000000,50000000,100000000] [--budgets 1G] [--dir /tmp/ooc2-bench]
#                            [--build build] [--in-memory]
#
# Per size: gen scan (out of core), convert PLY -> OBJ and OBJ -> PLY (out of core), info --weld
# (out of core where the estimate exceeds the budget), once per budget of --budgets (e.g. 1G,64M);
# with --in-memory also with --memory-budget 16G. Prints one markdown row per
# run (command, wall s, peak MiB from /usr/bin/time, the command's own path line) and removes the
# meshes of a size before the next.
set -euo pipefail
cd "$(dirname "$0")/.."
faces=10000000,50000000,100000000
budgets=1G
dir=${TMPDIR:-/tmp}/ooc2-bench
build=build
in_memory=0
while [ $# -gt 0 ]; do
  case "$1" in
    --faces) faces=$2; shift 2 ;;
    --budgets) budgets=$2; shift 2 ;;
    --dir) dir=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --in-memory) in_memory=1; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$dir"
seamvox=$(pwd)/$build/seamvox

run() {  # run BUDGET ARGS...: one markdown row
  local b=$1
  shift
  local log=$dir/run.log time=$dir/run.time
  /usr/bin/time -f "%e %M" -o "$time" "$seamvox" "$@" --memory-budget "$b" --scratch "$dir" > "$log" 2>&1
  read -r wall kb < "$time"
  local path
  path=$(grep -h "^path " "$log" | tail -1)
  printf '| `seamvox %s --memory-budget %s` | %s | %d | %s |\n' "$*" "$b" "$wall" $((kb / 1024)) "$path"
}

echo "| command | wall s | peak MiB | path |"
echo "|---|---|---|---|"
IFS=, read -ra sizes <<< "$faces"
for n in "${sizes[@]}"; do
  ply=$dir/scan$n.ply obj=$dir/scan$n.obj back=$dir/back$n.ply
  for b in ${budgets//,/ } $([ "$in_memory" = 1 ] && echo 16G); do
    run "$b" gen scan --faces "$n" -o "$ply" --quiet
    run "$b" convert "$ply" "$obj"
    run "$b" convert "$obj" "$back"
    run "$b" info "$ply" --weld --quiet
    rm -f "$obj" "$back"
  done
  rm -f "$ply"
done
