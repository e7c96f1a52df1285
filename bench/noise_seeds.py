#!/usr/bin/env python3
"""`param` on every shared mesh at 1.5-6M faces, as it is and with scan noise of two seeds, under
one or more option sets: what a change of defaults does beyond the few full-size inputs of
bench/real_scans.py (cone passes, flips, gradient error, time).

    python3 bench/noise_seeds.py SEAMVOX DATA_DIR OUT_DIR [--faces N] [--seeds S,...]
                                 [--noise A] [--only STEM,...] [--param "OPTIONS"]...

Inputs, made once in OUT_DIR/inputs and reused: each shared mesh subdivided by the fewest levels
that give it N faces or more (default 1,500,000), clean and with `--noise A` (default 0.25 mean
edge lengths) for each seed (default 1,2). Each `--param` adds an option set (none: the defaults
only); each input runs `param X -o OUT_DIR/map.ply --report R.json` once per set, the sets
alternating, and `seamvox check` reads the map (its verdict must be param's). Prints a markdown
table, one row per input and set; reports stay in OUT_DIR/runs.
"""
import json
import os
import subprocess
import sys

MESHES = ("armadillo.obj", "bumpy.off", "bunny.off", "camelhead.off", "cheburashka.off", "fertility.off",
          "lilium.obj", "rocker-arm.obj", "spot.obj", "3holes.off")


def run(cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def option(name, default):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def faces_of(seamvox, path):
    info = json.loads(run([seamvox, "info", path, "--json"]).stdout)
    return int(info["faces"])


def inputs(seamvox, data, out, target, seeds, noise, only):
    made = os.path.join(out, "inputs")
    os.makedirs(made, exist_ok=True)
    found = []
    for name in MESHES:
        stem = name.split(".")[0]
        source = os.path.join(data, name)
        if (only and stem not in only) or not os.path.exists(source):
            continue
        faces, levels = faces_of(seamvox, source), 0
        while faces * 4 ** levels < target:
            levels += 1
        for seed in ["0"] + seeds:
            label = f"{stem} L{levels}" + (f" noise {noise} seed {seed}" if seed != "0" else "")
            path = os.path.join(made, f"{stem}_L{levels}_s{seed}.ply")
            if not os.path.exists(path):
                cmd = [seamvox, "subdivide", source, "--levels", str(levels), "-o", path, "--quiet"]
                if seed != "0":
                    cmd += ["--noise", noise, "--seed", seed]
                run(cmd)
            found.append((label, path))
    return found


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    seamvox, data, out = sys.argv[1:4]
    target = int(option("--faces", "1500000"))
    seeds = option("--seeds", "1,2").split(",")
    noise = option("--noise", "0.25")
    only = option("--only", "").split(",") if "--only" in sys.argv else None
    sets = [sys.argv[i + 1] for i, a in enumerate(sys.argv) if a == "--param"] or [""]
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    print("| input | faces | options | time s | passes (kept) | pairs merged in map | cones (before merging) "
          "| flips before -> after | gradient error | check |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, path in inputs(seamvox, data, out, target, seeds, noise, only):
        for k, extra in enumerate(sets):
            report = os.path.join(out, "runs", f"{os.path.basename(path)[:-4]}_{k}.json")
            mapped = os.path.join(out, "map.ply")
            done = run([seamvox, "param", path, "-o", mapped, "--report", report, "--quiet"] + extra.split(),
                       check=False)
            if done.returncode != 0:
                print(f"| {label} | - | {extra or 'default'} | failed (exit {done.returncode}) | | | | | | |", flush=True)
                continue
            with open(report) as f:
                r = json.load(f)
            verdict = run([seamvox, "check", mapped], check=False).returncode
            os.remove(mapped)
            q, u = r["quality"], r.get("untangle", {})
            agree = "seamless" if verdict == 0 else "NOT seamless" if verdict == 5 else f"exit {verdict}"
            if (verdict == 0) != bool(q["seamless"]):
                agree += " (param disagrees)"
            print(f"| {label} | {r['faces']:,} | {extra or 'default'} | {r['seconds']['total']:.1f} "
                  f"| {r['conePasses']} ({r['conePassKept']}) | {r.get('conePairsMergedInMap', 0)} "
                  f"| {r['cones']} ({r['conesBeforeMerge']}) | {u.get('flippedBefore', 0):,} -> {q['flipped']:,} "
                  f"| {q['relativeGradientError']:.4f} | {agree} |", flush=True)


if __name__ == "__main__":
    main()
