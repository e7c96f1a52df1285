# usage: add_specks.py IN.ply OUT.ply N  -- appends N floating specks (two triangles each, a tiny
# quad about an edge long (bounding-box diagonal / sqrt(faces)), random position and orientation in the bounding box) to a binary
# little-endian PLY with float xyz and uchar/int faces.
import array, math, random, struct, sys

src, dst, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
data = open(src, 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
hdr = data[:end].decode().splitlines()
nv = int([l for l in hdr if l.startswith('element vertex')][0].split()[2])
nf = int([l for l in hdr if l.startswith('element face')][0].split()[2])
V = array.array('f'); V.frombytes(data[end:end + 12 * nv])
lo = [min(V[k::3]) for k in range(3)]; hi = [max(V[k::3]) for k in range(3)]
d = [hi[k] - lo[k] for k in range(3)]
e = math.sqrt(sum(x * x for x in d)) / math.sqrt(nf)
rnd = random.Random(5)
P = array.array('f'); T = bytearray()
def unit(v):
    l = math.sqrt(sum(x * x for x in v)); return [x / l for x in v]
for i in range(n):
    c = [lo[k] - 0.15 * d[k] + rnd.random() * 1.3 * d[k] for k in range(3)]
    a = unit([rnd.gauss(0, 1) for _ in range(3)])
    b = [rnd.gauss(0, 1) for _ in range(3)]
    ab = sum(a[k] * b[k] for k in range(3)); b = unit([b[k] - ab * a[k] for k in range(3)])
    for p in (c, [c[k] + e * a[k] for k in range(3)], [c[k] + e * (a[k] + b[k]) for k in range(3)], [c[k] + e * b[k] for k in range(3)]):
        P.extend(p)
    v = nv + 4 * i
    T += struct.pack('<Biii', 3, v, v + 1, v + 2) + struct.pack('<Biii', 3, v, v + 2, v + 3)
with open(dst, 'wb') as f:
    f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {nv + 4 * n}\nproperty float x\nproperty float y\nproperty float z\nelement face {nf + 2 * n}\nproperty list uchar int vertex_indices\nend_header\n".encode())
    f.write(data[end:end + 12 * nv]); f.write(P.tobytes()); f.write(data[end + 12 * nv:]); f.write(bytes(T))
