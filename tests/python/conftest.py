"""Shared pieces of the Python module's tests: meshes generated with numpy, the seamvox command."""
import os
import subprocess

import numpy as np
import pytest


def torus(n=40, m=20, R=2.0, r=1.0):
    """Closed torus (genus 1, chi 0) of 2 n m faces, counter-clockwise seen from outside."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = 2 * np.pi * i / n, 2 * np.pi * j / m
    V = np.stack([(R + r * np.cos(b)) * np.cos(a), (R + r * np.cos(b)) * np.sin(a), r * np.sin(b)], -1)
    idx = lambda x, y: (x % n) * m + (y % m)
    x, y = i.ravel(), j.ravel()
    F = np.concatenate([np.stack([idx(x, y), idx(x + 1, y), idx(x + 1, y + 1)], 1),
                        np.stack([idx(x, y), idx(x + 1, y + 1), idx(x, y + 1)], 1)])
    return V.reshape(-1, 3), F


def sphere(levels=3):
    """Icosphere (chi 2): 20 * 4**levels faces."""
    t = (1 + 5 ** 0.5) / 2
    V = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    F = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(levels):
        mid, out = {}, []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = V[a] + V[b]
                V.append(p / np.linalg.norm(p))
                mid[key] = len(V) - 1
            return mid[key]

        for a, b, c in F:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        F = out
    return np.array(V), np.array(F)


def bumpy_patch(n=24):
    """An open square patch (a disk, chi 1) with a bump: 2 n^2 faces."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    x, y = i / n, j / n
    V = np.stack([x, y, 0.3 * np.exp(-20 * ((x - 0.5) ** 2 + (y - 0.5) ** 2))], -1).reshape(-1, 3)
    idx = lambda a, b: a * (n + 1) + b
    a, b = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a, b = a.ravel(), b.ravel()
    F = np.concatenate([np.stack([idx(a, b), idx(a + 1, b), idx(a + 1, b + 1)], 1),
                        np.stack([idx(a, b), idx(a + 1, b + 1), idx(a, b + 1)], 1)])
    return V, F


def euler_characteristic(V, F):
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return len(np.unique(F)) - len(np.unique(edges, axis=0)) + len(F)


@pytest.fixture
def seamvox_command():
    """Runs the seamvox binary of this build (SEAMVOX_BINARY, set by ctest): its stdout, or with
    fails=True the CompletedProcess of a run that must fail."""
    binary = os.environ.get("SEAMVOX_BINARY")
    if not binary or not os.path.exists(binary):
        pytest.skip("SEAMVOX_BINARY does not name the seamvox command (ctest sets it)")

    def run(*args, fails=False, blas_core=None):
        # blas_core: the OpenBLAS kernels to run with (the command picks its own otherwise).
        env = dict(os.environ, OPENBLAS_CORETYPE=blas_core) if blas_core else None
        done = subprocess.run([binary, *args], capture_output=True, text=True, timeout=120, env=env)
        assert (done.returncode != 0) == fails, done.stdout + done.stderr
        return done if fails else done.stdout

    return run
