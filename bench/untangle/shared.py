#!/usr/bin/env python3
"""Foldover repair and quads on the shared meshes: per mesh and solver, `param --quads` with the
repair and `param --no-untangle`, one Markdown row each (flips, of them folded in 3D, L2 gradient
error before / after and its ratio, quad validity). Usage: shared.py SEAMVOX DATA OUT [SOLVER...]"""
import json, os, subprocess, sys

MESHES = ["3holes.off", "bumpy.off", "spot.obj", "lilium.obj", "fertility.off", "bunny.off",
          "rocker-arm.obj", "camelhead.off", "cheburashka.off", "armadillo.obj"]


def run(seamvox, args):
    done = subprocess.run([seamvox] + args + ["--quiet"], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(args)} failed: {done.stdout}{done.stderr}")
    return done.stdout


def main():
    seamvox, data, out = sys.argv[1:4]
    solvers = sys.argv[4:] or ["auto", "hat"]
    os.makedirs(out, exist_ok=True)
    print("| mesh | solver | flips before / after (folded in 3D) | relocated | L2 unrepaired / repaired (ratio) | quads | valid |")
    print("|---|---|---|---|---|---|---|")
    for name in MESHES:
        mesh = os.path.join(data, name)
        if not os.path.exists(mesh):
            print(f"| {name} | absent |")
            continue
        stem = os.path.join(out, name.split(".")[0])
        for solver in solvers:
            base = ["param", mesh, "--solver", solver]
            run(seamvox, base + ["-o", f"{stem}-{solver}-raw.ply", "--no-untangle", "--report", f"{stem}-{solver}-raw.json"])
            text = run(seamvox, base + ["-o", f"{stem}-{solver}.ply", "--report", f"{stem}-{solver}.json",
                                        "--quads", f"{stem}-{solver}-q.obj"])
            raw = json.load(open(f"{stem}-{solver}-raw.json"))["quality"]
            rep = json.load(open(f"{stem}-{solver}.json"))
            q, u = rep["quality"], rep["untangle"]
            quads = next((l for l in text.splitlines() if l.startswith("quads ->")), "")
            valid = next((l for l in text.splitlines() if l.startswith("validation:")), "")
            extraction = next((l for l in text.splitlines() if l.startswith("extraction:")), "")
            share = quads.split("(")[1].split(" quads")[0] if "(" in quads else "?"
            figures = {k: extraction.split(k + " ")[1].split(",")[0].split(";")[0] for k in ("untraced", "open faces")}
            if "twice" in valid:
                figures["faces through a vertex twice"] = valid.split("twice ")[1].split(";")[0]
            figures["non-manifold edges"] = valid.split("non-manifold edges ")[1].split(",")[0]
            ok = "yes" if valid.startswith("validation: valid") else "no (" + ", ".join(
                f"{k} {n}" for k, n in figures.items() if n != "0") + ")"
            l2a, l2b = raw["relativeGradientError"], q["relativeGradientError"]
            print(f"| {name} | {rep['solverUsed']} | {raw['flipped']} / {q['flipped']} ({q['flippedFolded']}) | "
                  f"{u['relocatedVertices']} | {l2a:.4f} / {l2b:.4f} ({l2b / l2a:.3f}) | {share} | {ok} |", flush=True)


if __name__ == "__main__":
    main()
