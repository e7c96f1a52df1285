#!/usr/bin/env python3
"""The default solver against hat and voxloc (issue #15: the default never slower than 1.1x the
faster of the two; gradient error within 1.1x of hat's).

    python3 bench/default_solver.py SEAMVOX DATA_DIR OUT_DIR [--hat-max-faces N]

Inputs: every shared mesh in DATA_DIR, fertility and armadillo subdivided around the hat/voxloc
crossover (1-2 levels), and generated scans of 200K-2M faces, clean and with noise 0.25. Per input,
back to back: `param --solver hat`, `param --solver voxloc`, `param` (the default), one run each,
default options otherwise; runs under a second are the fastest of three. Time and peak are the
report's (`seconds.total`, `peakResidentBytes`). The last column: feature curves each solver held
on iso-lines (the default finds creases on CAD-like meshes; only the hat solver aligns them).
Prints a markdown table (ratio = default / faster of hat and voxloc) to stdout; reports and
generated inputs stay in OUT_DIR (inputs are reused when present).
"""
import json
import os
import subprocess
import sys


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def inputs(seamvox, data, out):
    found = []
    for name in sorted(os.listdir(data)):
        stem, ext = os.path.splitext(name)
        if ext in (".off", ".obj", ".ply"):
            found.append((stem, os.path.join(data, name)))
    made = os.path.join(out, "inputs")
    os.makedirs(made, exist_ok=True)
    for stem, levels in (("fertility", (1, 2, 3, 4)), ("armadillo", (1, 2))):
        source = dict(found).get(stem)
        if not source:
            continue
        for level in levels:
            path = os.path.join(made, f"{stem}_L{level}.ply")
            if not os.path.exists(path):
                run([seamvox, "subdivide", source, "--levels", str(level), "-o", path])
            found.append((f"{stem} x{4 ** level}", path))
    for faces in (200000, 400000, 1000000, 2000000):
        for noise in ("0", "0.25"):
            path = os.path.join(made, f"scan_{faces}_n{noise}.ply")
            if not os.path.exists(path):
                run([seamvox, "gen", "scan", "--faces", str(faces), "--noise", noise, "-o", path, "--quiet"])
            found.append((f"scan {faces // 1000}K" + (f" noise {noise}" if noise != "0" else ""), path))
    return found


def param(seamvox, mesh, solver, out, tag):
    report = os.path.join(out, "runs", f"{tag}_{solver or 'default'}.json")
    os.makedirs(os.path.dirname(report), exist_ok=True)
    cmd = [seamvox, "param", mesh, "-o", os.path.join(out, "map.ply"), "--report", report, "--quiet"]
    if solver:
        cmd += ["--solver", solver]
    best = None
    for _ in range(3):  # runs under a second: the fastest of three (the machine's noise)
        try:
            run(cmd)
        except subprocess.CalledProcessError:
            return best
        with open(report) as f:
            r = json.load(f)
        if best is None or r["seconds"]["total"] < best["seconds"]["total"]:
            best = r
        if best["seconds"]["total"] >= 1.0:
            break
    return best


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    seamvox, data, out = sys.argv[1:4]
    hat_max = int(sys.argv[sys.argv.index("--hat-max-faces") + 1]) if "--hat-max-faces" in sys.argv else 2500000
    os.makedirs(out, exist_ok=True)
    print("| input | faces | hat s / MiB | voxloc s / MiB | default: picks, s / MiB | default / faster "
          "| L2 default / hat | feature curves aligned: hat / voxloc |")
    print("|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for name, path in inputs(seamvox, data, out):
        tag = name.replace(" ", "_")
        results = {}
        for solver in ("hat", "voxloc", None):
            r = param(seamvox, path, solver, out, tag)
            if r and solver == "hat" and r["faces"] > hat_max:
                r = None
            results[solver] = r
        cells = []
        for solver in ("hat", "voxloc"):
            r = results[solver]
            cells.append(f"{r['seconds']['total']:.2f} / {r['peakResidentBytes'] / 2**20:.0f}" if r else "-")
        d = results[None]
        if not d:
            print(f"| {name} | - | {cells[0]} | {cells[1]} | failed | - | - |")
            continue
        faster = min(r["seconds"]["total"] for r in (results["hat"], results["voxloc"]) if r)
        ratio = d["seconds"]["total"] / faster
        worst = max(worst, ratio)
        hat = results["hat"]
        l2 = (f"{d['quality']['relativeGradientError'] / hat['quality']['relativeGradientError']:.3f}"
              if hat else "-")
        aligned = " / ".join(str(results[s]["featureCurves"]["aligned"]) if results[s] else "-"
                             for s in ("hat", "voxloc"))
        print(f"| {name} | {d['faces']:,} | {cells[0]} | {cells[1]} | {d['solverUsed']}, "
              f"{d['seconds']['total']:.2f} / {d['peakResidentBytes'] / 2**20:.0f} | {ratio:.2f} | {l2} "
              f"| {aligned} |", flush=True)
    print(f"\nworst default / faster: {worst:.2f}")


if __name__ == "__main__":
    main()
