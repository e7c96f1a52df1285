"""seamvox.parameterize, check, cross_field, read_mesh and write_mesh on meshes generated with numpy:
the map is seamless with integer translations, obeys Poincare-Hopf, and is the command's map."""
import json

import numpy as np
import pytest

import seamvox
from conftest import bumpy_patch, euler_characteristic, sphere, torus

MESHES = {"torus": torus, "sphere": sphere, "patch": bumpy_patch}


def flatten(d, prefix=""):
    """Keys of a nested report as dotted paths (list items by position)."""
    out = {}
    items = d.items() if isinstance(d, dict) else enumerate(d)
    for k, v in items:
        key = f"{prefix}{k}"
        if isinstance(v, (dict, list)) and v:
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


@pytest.mark.parametrize("name", MESHES)
def test_round_trip_from_arrays_is_seamless(name):
    V, F = MESHES[name]()
    r = seamvox.parameterize(V, F)
    # A clean input is its own cleaned mesh: same faces, positions at float32 precision.
    np.testing.assert_array_equal(r.F, F)
    np.testing.assert_allclose(r.V, V.astype(np.float32), rtol=0, atol=0)
    assert r.uv.shape == (len(F), 3, 2) and r.uv.dtype == np.float64
    assert r.quality["seamless"] and r.quality["flipped"] == 0
    assert r.quality["maxSeamResidual"] <= 1e-6 and r.quality["maxIntegerDistance"] <= 1e-6
    # The check finds the seams from the uv alone: seamless, integer translations, no flips.
    verdict = seamvox.check(r.V, r.F, r.uv)
    assert verdict["seamless"] and verdict["seamEdges"] > 0
    assert verdict["maxSeamResidual"] <= 1e-6 and verdict["maxIntegerDistance"] <= 1e-6
    assert verdict["flipped"] == 0 and verdict["faces"] == len(F)
    # Poincare-Hopf on closed meshes: cone indices (quarter turns) sum to 4 chi.
    chi = euler_characteristic(V, F)
    assert r.cones.shape[1] == 2 and np.all(r.cones[:, 1] != 0)
    assert np.all((r.cones[:, 0] >= 0) & (r.cones[:, 0] < len(r.V)))
    if name != "patch":
        assert r.cones[:, 1].sum() == 4 * chi
    # The report says the same as the result.
    assert r.report["faces"] == len(F) and r.report["cones"] == len(r.cones)
    assert r.report["seams"] == r.seams and r.report["quality"] == r.quality
    assert r.report["input"] == "<arrays>"


def test_a_mesh_far_from_zero_is_mapped_as_near_it(tmp_path):
    # A georeferenced scan (UTM metres): float32 positions there would be 0.25-0.5 apart. The same
    # torus on a 2^-10 lattice near zero and moved by whole units maps the same, and the result and
    # the written file keep the far positions exactly.
    V, F = torus()
    V = np.round(V * 1024) / 1024
    V -= np.round(V[0])
    offset = np.array([512000.0, 4123000.0, 100.0])
    near = seamvox.parameterize(V, F)
    far = seamvox.parameterize(V + offset, F)
    np.testing.assert_array_equal(far.V, near.V + offset)
    np.testing.assert_array_equal(far.uv, near.uv)
    assert far.quality["seamless"] and far.report["cones"] == near.report["cones"]
    path = str(tmp_path / "far.ply")
    seamvox.write_mesh(path, far.V, far.F, far.uv)
    V2, F2, uv2 = seamvox.read_mesh(path, uv=True)
    np.testing.assert_array_equal(V2, far.V)
    np.testing.assert_array_equal(uv2, far.uv)


def test_a_moved_map_is_not_seamless():
    V, F = torus()
    r = seamvox.parameterize(V, F)
    uv = r.uv.copy()
    uv[0, 0] += 0.25  # one corner off: its edges no longer match across their seams or neighbours
    verdict = seamvox.check(r.V, r.F, uv)
    assert not verdict["seamless"] and verdict["maxSeamResidual"] > 0.1


def test_same_map_as_the_command(tmp_path, seamvox_command):
    V, F = torus(30, 14)
    mesh, out, report = tmp_path / "in.ply", tmp_path / "out.ply", tmp_path / "report.json"
    seamvox.write_mesh(str(mesh), V, F)
    r = seamvox.parameterize(*seamvox.read_mesh(str(mesh)))
    # The command with the module's BLAS kernels (it would pick others where OpenBLAS fell back
    # to generic ones): the same arithmetic, so the same figures to the last digit.
    seamvox_command("param", str(mesh), "-o", str(out), "--report", str(report), "--quiet",
                    blas_core=r.report.get("blasCore"))
    V2, F2, uv2 = seamvox.read_mesh(str(out), uv=True)
    np.testing.assert_array_equal(r.F, F2)
    np.testing.assert_array_equal(r.V, V2)
    np.testing.assert_allclose(r.uv, uv2, rtol=0, atol=1e-9)
    command = json.loads(report.read_text())
    for key in ("cones", "seams", "faces", "vertices", "conesBeforeMerge", "conePasses", "solverUsed",
                "edgeLength", "wedges", "quality"):
        assert r.report[key] == command[key], key
    # Same keys (the command's stages add read and write, and it reports its memory budget; the
    # file names differ).
    mine, theirs = flatten(r.report), flatten(command)
    budget = {"path", "memoryBudget", "estimatedBytes", "fieldBytesOnDisk"}
    assert {k for k in theirs if not k.startswith(("stages.", "seconds.")) and k not in budget} <= set(mine)


def test_close_holes_is_the_commands(tmp_path, seamvox_command):
    """close_holes=2 closes what `param --close-holes 2` closes; the default, like the command's
    without --quads, closes none."""
    V, F = sphere(4)
    F = np.array([f for k, f in enumerate(F) if k % 41 != 20])  # scattered one-triangle holes
    mesh, out, report = tmp_path / "in.ply", tmp_path / "out.ply", tmp_path / "report.json"
    seamvox.write_mesh(str(mesh), V, F)
    seamvox_command("param", str(mesh), "-o", str(out), "--report", str(report), "--quiet", "--close-holes", "2",
                    "--cells", "25")
    closed = seamvox.parameterize(*seamvox.read_mesh(str(mesh)), close_holes=2, cells=25)
    command = json.loads(report.read_text())
    assert closed.report["system"]["holesCappedForField"] == command["system"]["holesCappedForField"] > 0
    assert closed.report["cones"] == command["cones"]
    assert len(closed.F) == len(F)  # the caps are gone from the output
    assert seamvox.parameterize(V, F, cells=25).report["system"]["holesCappedForField"] == 0


def test_cross_field_is_the_field_commands(tmp_path, seamvox_command):
    V, F = sphere(3)
    mesh, field, cones = tmp_path / "in.off", tmp_path / "f.field", tmp_path / "cones.obj"
    seamvox.write_mesh(str(mesh), V, F)
    seamvox_command("field", str(mesh), "-o", str(field), "--cones", str(cones), "--quiet")
    fr = seamvox.cross_field(V, F)
    rows = [w for w in (line.split() for line in field.read_text().splitlines() if not line.startswith("#"))
            if len(w) == 3]
    np.testing.assert_allclose(fr.field, np.array(rows, float), rtol=0, atol=1e-6)
    listed = [line.split() for line in cones.read_text().splitlines() if line.startswith("# cone vertex")]
    np.testing.assert_array_equal(fr.cones, [[int(w[3]), int(w[5])] for w in listed])
    assert fr.cones[:, 1].sum() == 4 * euler_characteristic(V, F)
    assert np.allclose(np.linalg.norm(fr.field, axis=1), 1.0, atol=1e-6)
    # Tangent: each direction lies in its face's plane.
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    assert np.abs(np.einsum("ij,ij->i", n, fr.field)).max() < 1e-5


def test_field_smoothing_is_the_commands(tmp_path, seamvox_command):
    """field_smoothing=N reads the field on the surface `--field-smoothing N` does: the same field as
    `seamvox field`, another one than the default's, and parameterize's report says the steps."""
    V, F = sphere(3)
    rng = np.random.default_rng(5)
    V = V + rng.uniform(-0.01, 0.01, V.shape)  # some noise, so the smoothing matters
    mesh, field = tmp_path / "in.off", tmp_path / "f.field"
    seamvox.write_mesh(str(mesh), V, F)
    seamvox_command("field", str(mesh), "-o", str(field), "--quiet", "--field-smoothing", "8")
    V, F = seamvox.read_mesh(str(mesh))
    fr = seamvox.cross_field(V, F, field_smoothing=8)
    rows = [w for w in (line.split() for line in field.read_text().splitlines() if not line.startswith("#"))
            if len(w) == 3]
    np.testing.assert_allclose(fr.field, np.array(rows, float), rtol=0, atol=1e-6)
    assert np.abs(fr.field - seamvox.cross_field(V, F).field).max() > 1e-3
    r = seamvox.parameterize(V, F, field_smoothing=8)
    assert r.report["fieldSmoothing"] == 8 and r.quality["seamless"]
    assert seamvox.parameterize(V, F).report["fieldSmoothing"] == 3
    with pytest.raises(ValueError, match="field_smoothing has no effect with a field array"):
        seamvox.parameterize(V, F, field=fr.field, field_smoothing=8)


def plane_with_crumpled_fine_patch(seed=1):
    """A coarse 40 x 40 plane of unit cells and, beside it, a patch 4 across in cells of 1/16 whose
    inner vertices move up to 0.3 along z: noise on a part tessellated far finer than the rest."""
    def grid(n, step, x0, jitter, rng):
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        inner = ((i > 0) & (i < n) & (j > 0) & (j < n)).ravel()  # the border stays straight
        V = np.stack([x0 + step * i.ravel(), step * j.ravel(), inner * rng.uniform(-jitter, jitter, i.size)], axis=1)
        k = (i[:-1, :-1] * (n + 1) + j[:-1, :-1]).ravel()
        F = np.concatenate([np.stack([k, k + n + 1, k + n + 2], 1), np.stack([k, k + n + 2, k + 1], 1)])
        return V, F
    rng = np.random.default_rng(seed)
    Vc, Fc = grid(40, 1.0, 0.0, 0.0, rng)
    Vf, Ff = grid(64, 1.0 / 16, 50.0, 0.3, rng)
    return np.concatenate([Vc, Vf]), np.concatenate([Fc, Ff + len(Vc)])


def test_rough_spots_are_the_commands(tmp_path, seamvox_command):
    """rough_spots (default True) smooths the crumpled patch of the field's surface within h as
    `seamvox field` and `param` do: the same cones as the command, fewer than without, and the
    report says it; rough_spots=False is `--no-rough-spots`."""
    V, F = plane_with_crumpled_fine_patch()
    mesh, cones = tmp_path / "in.ply", tmp_path / "cones.obj"
    seamvox.write_mesh(str(mesh), V, F)
    V, F = seamvox.read_mesh(str(mesh))
    for rough, flag in ((True, []), (False, ["--no-rough-spots"])):
        seamvox_command("field", str(mesh), "-o", str(tmp_path / "f.field"), "--quiet", "--edge-length", "2",
                        "--merge-cones", "0", "--cones", str(cones), *flag)
        listed = [line.split() for line in cones.read_text().splitlines() if line.startswith("# cone vertex")]
        fr = seamvox.cross_field(V, F, edge_length=2, merge_cones=0, rough_spots=rough)
        expected = np.array([[int(w[3]), int(w[5])] for w in listed], dtype=np.int64).reshape(-1, 2)
        np.testing.assert_array_equal(fr.cones.reshape(-1, 2), expected)
    smoothed = seamvox.parameterize(V, F, edge_length=2, merge_cones=0, solver="hat")
    plain = seamvox.parameterize(V, F, edge_length=2, merge_cones=0, solver="hat", rough_spots=False)
    assert smoothed.report["roughSpots"] is True and plain.report["roughSpots"] is False
    assert smoothed.report["fieldSolve"]["roughVertices"] > 100
    assert plain.report["fieldSolve"]["roughVertices"] == 0
    assert 5 * smoothed.report["conesBeforeMerge"] <= plain.report["conesBeforeMerge"]
    assert smoothed.quality["seamless"] and plain.quality["seamless"]


def test_a_given_field_drives_the_map():
    V, F = torus()
    fr = seamvox.cross_field(V, F)
    r = seamvox.parameterize(V, F, field=fr.field)
    assert r.report["field"] == "array" and r.report["fieldMethod"] == "file"
    assert r.quality["seamless"]
    np.testing.assert_allclose(r.uv, seamvox.parameterize(V, F).uv, rtol=0, atol=1e-6)
    verdict = seamvox.check(r.V, r.F, r.uv, field=fr.field, edge_length=r.report["edgeLength"])
    assert verdict["relativeGradientError"] == pytest.approx(r.quality["relativeGradientError"], abs=1e-6)


@pytest.mark.parametrize("solver", ["hat", "vox", "voxloc"])
def test_every_solver_is_seamless(solver):
    V, F = sphere(3)
    r = seamvox.parameterize(V, F, solver=solver, grid=32, cells=20, threads=1)
    assert r.report["solverUsed"] == solver and r.report["solver"] == solver
    assert r.quality["seamless"] and seamvox.check(r.V, r.F, r.uv)["seamless"]


def test_grid_spacing_follows_cells_and_edge_length():
    V, F = sphere(3)
    diagonal = np.linalg.norm(V.max(0) - V.min(0))
    assert seamvox.parameterize(V, F, cells=10).report["edgeLength"] == pytest.approx(diagonal / 10, rel=1e-6)
    assert seamvox.parameterize(V, F, edge_length=0.5).report["edgeLength"] == 0.5


@pytest.mark.parametrize("suffix", ["ply", "obj", "drc"])
def test_write_and_read_keep_the_mesh_and_map(tmp_path, suffix):
    V, F = sphere(2)
    r = seamvox.parameterize(V, F)
    path = str(tmp_path / f"m.{suffix}")
    seamvox.write_mesh(path, r.V, r.F, r.uv)
    V2, F2, uv2 = seamvox.read_mesh(path, uv=True)
    assert F2.shape == r.F.shape and uv2.shape == r.uv.shape
    if suffix != "drc":  # Draco orders vertices and faces its own way
        np.testing.assert_array_equal(F2, r.F)
        np.testing.assert_array_equal(V2, r.V)
        np.testing.assert_allclose(uv2, r.uv, rtol=0, atol=1e-12)
    # Draco keeps UVs on a 2^-14 lattice, so integer translations and the seams stay exact.
    assert seamvox.check(V2, F2, uv2)["seamless"]
    V3, F3 = seamvox.read_mesh(path)
    np.testing.assert_array_equal(F3, F2)
    assert seamvox.read_mesh(str(tmp_path / f"m.{suffix}"), uv=True)[2] is not None
    seamvox.write_mesh(str(tmp_path / "plain.ply"), V, F)
    assert seamvox.read_mesh(str(tmp_path / "plain.ply"), uv=True)[2] is None


def test_version_is_the_projects():
    import pathlib
    import re
    cmake = (pathlib.Path(__file__).resolve().parents[2] / "CMakeLists.txt").read_text()
    assert seamvox.__version__ == re.search(r"project\(seamvox VERSION ([0-9.]+)", cmake).group(1)
