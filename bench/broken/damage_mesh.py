# Damaged variants of a mesh, the defects real scans and their repairs have (OBJ in, OBJ out;
# seeded; sizes relative to the bounding-box diagonal D):
#   holes       faces within 0.02 D of 20 random centres removed
#   dups        2% of the faces repeated, half of them reversed
#   flipped     5% of the faces reversed
#   fins        50 edges given a third face
#   bowties     30 vertices given a face that touches them from outside
#   islands     2000 tiny triangles and pairs scattered near the surface
#   degenerate  1% faces with a repeated vertex, 1% collinear slivers on existing edges
#   split       10% of the faces given their own vertices (cracks)
#   moebius     a Moebius strip beside the mesh
# usage: python3 damage_mesh.py IN.obj OUT.obj KIND SEED
import random, sys, math
src, out, kind, seed = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
rng = random.Random(seed)
V, F = [], []
for line in open(src):
    p = line.split()
    if not p: continue
    if p[0] == 'v': V.append([float(x) for x in p[1:4]])
    elif p[0] == 'f': F.append([int(x.split('/')[0]) - 1 for x in p[1:]])
F = [f for f in F if len(f) == 3]
n = len(F)
lo = [min(p[k] for p in V) for k in range(3)]; hi = [max(p[k] for p in V) for k in range(3)]
D = math.dist(lo, hi)
def cen(f): return [sum(V[v][k] for v in f) / 3 for k in range(3)]
if kind == 'holes':   # remove faces near 20 random centres
    for _ in range(20):
        c = cen(F[rng.randrange(len(F))])
        F = [f for f in F if math.dist(cen(f), c) > 0.02 * D]
elif kind == 'dups':  # 2% duplicated faces, some reversed
    for _ in range(n // 50):
        f = F[rng.randrange(n)]; F.append(f[:] if rng.random() < 0.5 else f[::-1])
elif kind == 'flipped':  # 5% faces reversed
    for i in rng.sample(range(n), n // 20): F[i] = F[i][::-1]
elif kind == 'fins':  # 50 fins: a third face on an edge
    for _ in range(50):
        f = F[rng.randrange(n)]; a, b = f[0], f[1]
        c = cen(f); V.append([c[0] + 0.01 * D, c[1] + 0.01 * D, c[2] + 0.02 * D]); F.append([a, b, len(V) - 1])
elif kind == 'bowties':  # 30 cones of faces touching a vertex from outside
    for _ in range(30):
        v = F[rng.randrange(n)][0]; p = V[v]
        V.append([p[0] + 0.02 * D, p[1], p[2] + 0.01 * D]); V.append([p[0], p[1] + 0.02 * D, p[2] + 0.01 * D])
        F.append([v, len(V) - 2, len(V) - 1])
elif kind == 'islands':  # 2000 tiny disconnected triangles and pairs
    for _ in range(2000):
        p = V[rng.randrange(len(V))]; b = len(V)
        V += [[p[0] + rng.uniform(-.005, .005) * D, p[1] + rng.uniform(-.005, .005) * D, p[2] + rng.uniform(-.005, .005) * D] for _ in range(4)]
        F.append([b, b + 1, b + 2])
        if rng.random() < 0.5: F.append([b + 2, b + 1, b + 3])
elif kind == 'degenerate':  # repeated vertices, zero-area slivers, collinear faces
    for _ in range(n // 100):
        f = F[rng.randrange(n)]; F.append([f[0], f[0], f[1]])
    for _ in range(n // 100):
        f = F[rng.randrange(n)]; a, b = V[f[0]], V[f[1]]
        V.append([(a[k] + b[k]) / 2 for k in range(3)]); F.append([f[0], len(V) - 1, f[1]])
elif kind == 'split':  # 10% of faces get their own copies of their vertices (cracks)
    for i in rng.sample(range(n), n // 10):
        b = len(V); V += [V[v][:] for v in F[i]]; F[i] = [b, b + 1, b + 2]
elif kind == 'moebius':  # a Moebius strip island
    m = 24; b = len(V)
    for i in range(m):
        t = 2 * math.pi * i / m
        for s in (-0.05, 0.05):
            V.append([hi[0] + 0.4 * D + D * (0.3 + s * math.cos(t / 2)) * math.cos(t), lo[1] + D * (0.3 + s * math.cos(t / 2)) * math.sin(t), lo[2] + D * s * math.sin(t / 2)])
    for i in range(m):
        a0, a1 = b + 2 * i, b + 2 * i + 1
        j = (i + 1) % m
        c0, c1 = (b + 2 * j, b + 2 * j + 1) if j else (b + 1, b)
        F.append([a0, a1, c1]); F.append([a0, c1, c0])
with open(out, 'w') as o:
    for p in V: o.write('v %.9g %.9g %.9g\n' % tuple(p))
    for f in F: o.write('f %d %d %d\n' % (f[0] + 1, f[1] + 1, f[2] + 1))
