#!/usr/bin/env python3
"""The default `param` on real meshes at scan size, with and without scan noise (issue #15's
targets: noisy <= 60 s and <= 2 GB with no stage above a quarter of the total, clean <= 45 s and
<= 1.8 GB; flipped faces <= 0.01% and at most 1% of the vertices refined in the hat basis on both;
a noisy input's cones before merging within 1.5x of its clean one's, when that ran first).
The wound column counts vertices the map winds around twice (a fold no flipped face shows); the
issue sets no target for it.

    python3 bench/real_scans.py SEAMVOX DATA_DIR OUT_DIR [--noise A] [--noise-tangential F]
                                [--noise-scale local] [--no-check] [--only NAME,...]
                                [--param "OPTIONS"]

Inputs, made once in OUT_DIR/inputs and reused: the shared armadillo subdivided 4 times (L4, 22.1M
faces), fertility 5 times (9.2M), camelhead 5 times (23.2M, one boundary loop) and a generated
20M-face scan, each as it is and with noise A (default 0.25 mean edge lengths, seed 1;
`subdivide --noise`, `gen scan --noise`; with --noise-tangential F its part across the normal
scaled by F, 0: a range scanner's depth noise, label "noise A tF"; with --noise-scale local A is in
each vertex's own mean edge length, label "noise A local"). One `param X -o OUT_DIR/map.ply --report R.json` per
input, default options, then `seamvox check` on the written map (its verdict must be param's).
With --param the OPTIONS (e.g. "--field-smoothing 8") go to every param run, clean and noisy.
Prints a markdown table; the last column lists the targets a row misses. Peak = the report's
peakResidentBytes (VmHWM). Reports stay in OUT_DIR/runs.
"""
import json
import os
import subprocess
import sys

MESHES = (("armadillo", "armadillo.obj", 4), ("fertility", "fertility.off", 5), ("camelhead", "camelhead.off", 5))


def run(cmd, check=True):
    return subprocess.run(cmd, check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def inputs(seamvox, data, out, noise, tangential, only, scale="mean"):
    made = os.path.join(out, "inputs")
    os.makedirs(made, exist_ok=True)
    found = []
    for stem, name, levels in MESHES:
        source = os.path.join(data, name)
        if not os.path.exists(source):
            print(f"skipped {stem}: {source} is missing", file=sys.stderr)
            continue
        for a in ("0", noise):
            label = f"{stem} L{levels}" + (f" noise {a}{suffix(a, tangential, scale=scale)}" if a != "0" else "")
            path = os.path.join(made, f"{stem}_L{levels}_n{a}{suffix(a, tangential, '_t', scale)}.ply")
            if only and label not in only:
                continue
            if not os.path.exists(path):
                run([seamvox, "subdivide", source, "--levels", str(levels), "--noise", a,
                     "--noise-tangential", tangential, "--noise-scale", scale, "-o", path, "--quiet"])
            found.append((label, path))
    for a in ("0", noise):
        label = "scan 20M" + (f" noise {a}{suffix(a, tangential, scale=scale)}" if a != "0" else "")
        path = os.path.join(made, f"scan_20M_n{a}{suffix(a, tangential, '_t', scale)}.ply")
        if only and label not in only:
            continue
        if not os.path.exists(path):
            run([seamvox, "gen", "scan", "--faces", "20000000", "--noise", a, "--noise-tangential", tangential,
                 "--noise-scale", scale, "-o", path, "--quiet"])
        found.append((label, path))
    return found


def suffix(amplitude, tangential, sep=" t", scale="mean"):
    # Noise with its default tangential share and scale keeps the plain label and file name.
    if amplitude == "0":
        return ""
    local = "" if scale == "mean" else (" local" if sep == " t" else "_local")
    return ("" if float(tangential) == 1.0 else f"{sep}{tangential}") + local


def misses(r, noisy, checked, clean_cones=None):
    q, rf = r["quality"], r.get("refine", {})
    total = r["seconds"]["total"]
    out = []
    if noisy and clean_cones and r["conesBeforeMerge"] > 1.5 * clean_cones:
        out.append(f"raw cones {r['conesBeforeMerge'] / clean_cones:.1f}x the clean {clean_cones}")
    if total > (60 if noisy else 45):
        out.append(f"time > {60 if noisy else 45} s")
    if r["peakResidentBytes"] > (2.0e9 if noisy else 1.8e9):
        out.append(f"peak > {2.0 if noisy else 1.8} GB")
    if not q["seamless"]:
        out.append("not seamless")
    if checked is not None and checked != q["seamless"]:
        out.append("check disagrees")
    if q["flipped"] > 1e-4 * r["faces"]:
        out.append("flips > 0.01%")
    if rf.get("refinedFractionOffIslands", 0.0) > 0.01:
        out.append("refined > 1%")
    stage = max(r["stages"], key=lambda s: s["seconds"])
    if noisy and stage["seconds"] > total / 4:  # the issue asks it of the noisy scans
        out.append(f"{stage['name']} > 1/4")
    return out


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    seamvox, data, out = sys.argv[1:4]
    noise = sys.argv[sys.argv.index("--noise") + 1] if "--noise" in sys.argv else "0.25"
    tangential = sys.argv[sys.argv.index("--noise-tangential") + 1] if "--noise-tangential" in sys.argv else "1"
    only = sys.argv[sys.argv.index("--only") + 1].split(",") if "--only" in sys.argv else None
    scale = sys.argv[sys.argv.index("--noise-scale") + 1] if "--noise-scale" in sys.argv else "mean"
    check = "--no-check" not in sys.argv
    extra = sys.argv[sys.argv.index("--param") + 1].split() if "--param" in sys.argv else []
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    print("| input | faces | time s | peak MiB | cones (before merging) | hat-refined | flips before repair "
          "-> after | stretched | wound | gradient error | largest stage | check | misses |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    clean_cones = {}  # raw cones of each clean input, for its noisy row (issue #15: within 1.5x)
    for label, path in inputs(seamvox, data, out, noise, tangential, only, scale):
        tag = label.replace(" ", "_")
        report = os.path.join(out, "runs", f"{tag}.json")
        mapped = os.path.join(out, "map.ply")
        done = run([seamvox, "param", path, "-o", mapped, "--report", report, "--quiet"] + extra, check=False)
        if done.returncode != 0:
            print(f"| {label} | - | failed (exit {done.returncode}) | | | | | | | | | | |", flush=True)
            continue
        with open(report) as f:
            r = json.load(f)
        checked = None
        if check:
            verdict = run([seamvox, "check", mapped], check=False).returncode
            checked = verdict == 0 if verdict in (0, 5) else None
        os.remove(mapped)
        base = label.split(" noise")[0]
        if "noise" not in label:
            clean_cones[base] = r["conesBeforeMerge"]
        q, rf, u = r["quality"], r.get("refine", {}), r.get("untangle", {})
        stage = max(r["stages"], key=lambda s: s["seconds"])
        share = stage["seconds"] / r["seconds"]["total"]
        print(f"| {label} | {r['faces']:,} | {r['seconds']['total']:.1f} | {r['peakResidentBytes'] / 2**20:,.0f} "
              f"| {r['cones']} ({r['conesBeforeMerge']}) | {100 * rf.get('refinedFractionOffIslands', 0.0):.3f}% "
              f"| {u.get('flippedBefore', 0):,} -> {q['flipped']:,} | {q['stretched']} "
              f"| {'-' if q.get('wound') is None else q['wound']} "
              f"| {q['relativeGradientError']:.4f} | {stage['name']} {stage['seconds']:.1f} s ({100 * share:.0f}%) "
              f"| {'-' if checked is None else ('seamless' if checked else 'NOT seamless')} "
              f"| {', '.join(misses(r, 'noise' in label, checked, clean_cones.get(base))) or 'none'} |", flush=True)


if __name__ == "__main__":
    main()
