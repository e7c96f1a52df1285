"""Other file variants of a binary little-endian PLY mesh (float x y z, uchar/int triangles), as
scanners and survey tools write them, for the STL and far-from-zero figures in RESULTS.md:

  python3 bench/formats/variants.py stl IN.ply OUT.stl              # binary STL, header "solid ..."
  python3 bench/formats/variants.py far IN.ply OUT.ply X,Y,Z [S]     # scaled by S, moved by (X, Y, Z): double x y z

Needs numpy (Debian python3-numpy)."""
import sys

import numpy as np


def read_ply(path):
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            line = f.readline()
            if not line:
                sys.exit(f"{path}: no end_header")
            header += line
        text = header.decode()
        if "binary_little_endian" not in text or "property float x" not in text:
            sys.exit(f"{path}: expected a binary little-endian PLY with float x y z")
        nv = int(text.split("element vertex ")[1].split()[0])
        nf = int(text.split("element face ")[1].split()[0])
        V = np.fromfile(f, dtype="<f4", count=3 * nv).reshape(nv, 3)
        F = np.fromfile(f, dtype=np.dtype([("n", "u1"), ("i", "<i4", (3,))]), count=nf)
        if nf and not np.all(F["n"] == 3):
            sys.exit(f"{path}: expected triangles only")
        return V, F["i"]


def write_stl(path, V, F):
    facets = np.zeros(len(F), dtype=np.dtype([("n", "<f4", (3,)), ("v", "<f4", (9,)), ("a", "<u2")]))
    facets["v"] = V[F].reshape(len(F), 9)
    with open(path, "wb") as f:
        f.write(b"solid written as binary STL".ljust(80, b" "))
        f.write(np.uint32(len(F)).tobytes())
        facets.tofile(f)


def write_far(path, V, F, offset, scale):
    W = V.astype("<f8") * scale + offset
    faces = np.zeros(len(F), dtype=np.dtype([("n", "u1"), ("i", "<i4", (3,))]))
    faces["n"] = 3
    faces["i"] = F
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
                 "property double z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(V), len(F))).encode())
        W.tofile(f)
        faces.tofile(f)


if __name__ == "__main__":
    if len(sys.argv) < 4 or sys.argv[1] not in ("stl", "far") or (sys.argv[1] == "far" and len(sys.argv) not in (5, 6)):
        sys.exit(__doc__)
    V, F = read_ply(sys.argv[2])
    if sys.argv[1] == "stl":
        write_stl(sys.argv[3], V, F)
    else:
        scale = float(sys.argv[5]) if len(sys.argv) == 6 else 1.0
        write_far(sys.argv[3], V, F, np.array([float(x) for x in sys.argv[4].split(",")]), scale)
