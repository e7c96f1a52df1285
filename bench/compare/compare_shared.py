#!/usr/bin/env python3
"""Compares two run_shared.sh outputs: field cones (with indices), field files (largest angle
between the crosses of a face, in radians, modulo quarter turns), and the param figures (cones,
seams, flips, L2 gradient error, seamless) and output OBJ files (byte for byte). Prints one line per mesh and run; exit 1 on a change
beyond the tolerance (--tol, relative, for the float figures)."""
import json, math, sys, pathlib, argparse

p = argparse.ArgumentParser()
p.add_argument("before"); p.add_argument("after"); p.add_argument("--tol", type=float, default=1e-12)
a = p.parse_args()
A, B = pathlib.Path(a.before), pathlib.Path(a.after)
bad = 0

def cones(path):  # "# cone vertex V index4 K" lines
    return [tuple(l.split()[3:6:2]) for l in open(path) if l.startswith("# cone vertex")]

def vectors(path):
    lines = open(path).read().split("\n")
    return [tuple(map(float, l.split())) for l in lines[1:] if l.strip()]

def cross_angle(u, v):  # angle between two crosses in one tangent plane (mod pi/2)
    d = sum(x * y for x, y in zip(u, v))
    nu = math.sqrt(sum(x * x for x in u)); nv = math.sqrt(sum(x * x for x in v))
    if nu == 0 or nv == 0: return 0.0 if nu == nv else math.pi
    c = max(-1.0, min(1.0, d / (nu * nv)))
    ang = math.acos(c) % (math.pi / 2)
    return min(ang, math.pi / 2 - ang)

for f in sorted(A.glob("*.field.json")):
    name = f.name[: -len(".field.json")]
    ja, jb = json.load(open(f)), json.load(open(B / f.name))
    keys = ["cones", "conesBeforeMerge", "indexSum4", "seams", "seamEdges", "cutEdges", "conesByIndex4"]
    diff = [k for k in keys if ja.get(k) != jb.get(k)]
    ca, cb = cones(A / f"{name}.cones.obj"), cones(B / f"{name}.cones.obj")
    va, vb = vectors(A / f"{name}.field"), vectors(B / f"{name}.field")
    same_file = (A / f"{name}.field").read_bytes() == (B / f"{name}.field").read_bytes()
    worst = max((cross_angle(u, v) for u, v in zip(va, vb)), default=0.0) if not same_file else 0.0
    ok = not diff and ca == cb and len(va) == len(vb)
    bad += not ok
    print(f"field {name:22s} cones {jb['cones']:4d} (before merge {jb['conesBeforeMerge']:4d}) "
          f"cone list+indices {'same' if ca == cb else 'DIFFERENT'}; field file "
          f"{'identical' if same_file else f'max cross angle change {worst:.3g} rad'}"
          + (f"; CHANGED {diff}" if diff else ""))

def uvs(path):
    return [tuple(map(float, l.split()[1:3])) for l in open(path) if l.startswith("vt ")]

def fig(r):
    q = r["quality"]
    return {"cones": r.get("cones"), "seams": r.get("seams"), "flipped": q["flipped"],
            "collapsed": q["collapsed"], "L2": q["relativeGradientError"], "seamless": q["seamless"]}

for f in sorted(A.glob("*.json")):
    if f.name.endswith(".field.json"): continue
    fa, fb = fig(json.load(open(f))), fig(json.load(open(B / f.name)))
    changed = []
    for k in fa:
        x, y = fa[k], fb[k]
        if isinstance(x, float) and isinstance(y, float):
            if abs(x - y) > a.tol * max(abs(x), abs(y), 1e-300): changed.append(f"{k} {x!r} -> {y!r}")
        elif x != y: changed.append(f"{k} {x} -> {y}")
    same_map = (A / f"{f.stem}.obj").read_bytes() == (B / f"{f.stem}.obj").read_bytes()
    if not same_map:
        uva, uvb = uvs(A / f"{f.stem}.obj"), uvs(B / f"{f.stem}.obj")
        same_map = f"{len(uva)} vs {len(uvb)} vt" if len(uva) != len(uvb) else max(
            (abs(x - y) for p, q in zip(uva, uvb) for x, y in zip(p, q)), default=0.0)
    bad += bool(changed)
    print(f"param {f.stem:22s} cones {fb['cones']} seams {fb['seams']} flipped {fb['flipped']} "
          f"L2 {fb['L2']:.6f} seamless {fb['seamless']}: " + ("same" if not changed else "CHANGED " + "; ".join(changed))
          + ("" if same_map is True else f" (output OBJ differs: max |vt change| {same_map})"))
sys.exit(1 if bad else 0)
