"""seamvox.quads on maps made by seamvox.parameterize: an oriented closed quad mesh with the input's
Euler characteristic and about area / h^2 faces, the same mesh and report as `seamvox quads`, the
command's errors for bad maps and scales, and progress, cancel and Ctrl-C as in parameterize."""
import json
import os
import signal
import time

import numpy as np
import pytest

import seamvox
from conftest import euler_characteristic, sphere, torus

MESHES = {"torus": torus, "sphere": sphere}
SECTIONS = ("map", "extraction", "quadMesh", "validation")  # the report's figures (not names, times)


@pytest.fixture(scope="module", params=sorted(MESHES))
def mapped(request):
    """(name, input V, input F, parameterize's result) of a closed mesh."""
    V, F = MESHES[request.param]()
    return request.param, V, F, seamvox.parameterize(V, F)


def all_faces(Q):
    return [list(f) for f in Q.faces] + [list(p) for p in Q.polygons]


def uv_area(uv):
    a, b = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    return 0.5 * np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def read_obj_polygons(path):
    """Positions and faces (0-based lists) of the command's OBJ quad mesh."""
    V, faces = [], []
    for line in open(path):
        if line.startswith("v "):
            V.append([float(x) for x in line.split()[1:]])
        elif line.startswith("f "):
            faces.append([int(x) - 1 for x in line.split()[1:]])
    return np.array(V), faces


def test_round_trip_is_a_valid_closed_quad_mesh(mapped):
    name, V, F, r = mapped
    Q = seamvox.quads(r.V, r.F, r.uv)
    assert Q.valid and Q.report["validation"]["valid"]
    assert Q.V.dtype == np.float64 and Q.V.shape[1] == 3
    assert Q.faces.dtype == np.int64 and Q.faces.shape[1] == 4
    assert all(p.dtype == np.int64 and p.ndim == 1 and len(p) != 4 for p in Q.polygons)
    faces = all_faces(Q)
    # Every vertex used, no face visits a vertex twice, vertices on the surface's bounding box.
    used = np.concatenate([Q.faces.ravel()] + list(Q.polygons))
    assert used.min() >= 0 and used.max() < len(Q.V) and len(np.unique(used)) == len(Q.V)
    assert all(len(set(f)) == len(f) for f in faces)
    assert np.all(Q.V >= V.min(0) - 1e-9) and np.all(Q.V <= V.max(0) + 1e-9)
    # Oriented and closed: every directed edge once, with its reverse in another face.
    directed = {(f[i], f[(i + 1) % len(f)]) for f in faces for i in range(len(f))}
    assert len(directed) == sum(len(f) for f in faces)
    assert all((b, a) in directed for a, b in directed)
    # Same Euler characteristic as the input (torus 0, sphere 2).
    edges = len(directed) // 2
    assert len(Q.V) - edges + len(faces) == euler_characteristic(V, F)
    # One face per unit of uv area (exact but for cells cut by cones), about area / h^2.
    assert abs(len(faces) - uv_area(r.uv)) <= 0.01 * len(faces)
    P = r.V[r.F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum()
    assert abs(len(faces) - area / r.report["edgeLength"] ** 2) <= 0.1 * len(faces)
    assert Q.quad_fraction > 0.99 and len(Q.polygons) <= len(r.cones)
    # The report says the same as the result.
    mesh = Q.report["quadMesh"]
    assert mesh["vertices"] == len(Q.V) and mesh["faces"] == len(faces) and mesh["edges"] == edges
    assert mesh["quads"] == len(Q.faces) and mesh["quadFraction"] == Q.quad_fraction
    assert mesh["triangles"] + mesh["pentagons"] + mesh["otherFaces"] == len(Q.polygons)
    assert Q.report["input"] == "<arrays>" and Q.report["scale"] == 1 and Q.report["map"]["faces"] == len(r.F)
    assert [s["name"] for s in Q.report["stages"]] == ["clean", "quads"]


def test_same_mesh_and_report_as_the_command(mapped, tmp_path, seamvox_command):
    name, V, F, r = mapped
    path, out, report = tmp_path / "map.ply", tmp_path / "quads.obj", tmp_path / "report.json"
    seamvox.write_mesh(str(path), r.V, r.F, r.uv)
    seamvox_command("quads", str(path), "-o", str(out), "--report", str(report), "--quiet")
    command = json.loads(report.read_text())
    Vc, faces = read_obj_polygons(out)
    Q = seamvox.quads(*seamvox.read_mesh(str(path), uv=True))
    np.testing.assert_array_equal(Q.faces, [f for f in faces if len(f) == 4])
    assert [list(p) for p in Q.polygons] == [f for f in faces if len(f) != 4]
    np.testing.assert_allclose(Q.V, Vc, rtol=1e-8, atol=1e-12)
    for section in SECTIONS:
        assert Q.report[section] == command[section], section
    assert set(Q.report) == set(command)
    # The map in memory (not rounded through a file) gives the same counts.
    assert seamvox.quads(r.V, r.F, r.uv).report["quadMesh"] == command["quadMesh"]


@pytest.fixture(scope="module")
def torus_map():
    V, F = torus(30, 14)
    r = seamvox.parameterize(V, F)
    return r.V, r.F, r.uv


def same_error_as_the_command(tmp_path, seamvox_command, V, F, uv, *args, **kwargs):
    """quads(V, F, uv, **kwargs) and `seamvox quads` on the same map raise the same message (but
    for the name, <arrays> or the file); returns it."""
    path = tmp_path / "map.ply"
    seamvox.write_mesh(str(path), V, F, uv)
    with pytest.raises(seamvox.InputError) as error:
        seamvox.quads(V, F, uv, **kwargs)
    message = str(error.value)
    assert message.startswith("<arrays>: ") and isinstance(error.value, ValueError)
    done = seamvox_command("quads", str(path), "-o", str(tmp_path / "q.obj"), "--quiet", *args, fails=True)
    assert message.replace("<arrays>", str(path)) in done.stderr, (message, done.stderr)
    assert not (tmp_path / "q.obj").exists()
    return message


def test_a_map_without_uv_is_refused_as_by_the_command(torus_map, tmp_path, seamvox_command):
    V, F, _ = torus_map
    message = same_error_as_the_command(tmp_path, seamvox_command, V, F, None)
    assert message == "<arrays>: has no texture coordinates; run seamvox param first"


def test_a_map_that_is_not_seamless_is_refused_as_by_the_command(torus_map, tmp_path, seamvox_command):
    V, F, uv = torus_map
    uv = uv.copy()
    uv[0, 0] += 0.25  # one corner off: its edges no longer match across their seams or neighbours
    message = same_error_as_the_command(tmp_path, seamvox_command, V, F, uv)
    assert "the map is not seamless" in message
    off_grid = 1.5 * torus_map[2]  # seams still match, but odd translations are half a unit off
    assert "not seamless" in str(pytest.raises(seamvox.InputError, seamvox.quads, V, F, off_grid).value)


def test_scale_two_is_refused_as_by_the_command(torus_map, tmp_path, seamvox_command):
    V, F, uv = torus_map
    message = same_error_as_the_command(tmp_path, seamvox_command, V, F, uv, "--scale", "2", scale=2)
    assert "seam translations are no multiples of --scale 2" in message


def test_scale_two_of_a_doubled_map_is_the_map_and_the_command_accepts_it(torus_map, tmp_path, seamvox_command):
    V, F, uv = torus_map
    Q = seamvox.quads(V, F, uv)
    doubled = 2 * uv  # every translation even, the same iso-lines every 2 units
    Q2 = seamvox.quads(V, F, doubled, scale=np.int64(2))
    assert Q2.valid and Q2.report["scale"] == 2
    assert Q2.report["quadMesh"] == Q.report["quadMesh"]
    np.testing.assert_array_equal(Q2.faces, Q.faces)
    np.testing.assert_allclose(Q2.V, Q.V, rtol=0, atol=1e-6)  # snapped at 2^-20 units
    path, report = tmp_path / "doubled.ply", tmp_path / "report.json"
    seamvox.write_mesh(str(path), V, F, doubled)
    seamvox_command("quads", str(path), "-o", str(tmp_path / "q.ply"), "--scale", "2", "--report", str(report))
    assert json.loads(report.read_text())["quadMesh"] == Q2.report["quadMesh"]
    fine = seamvox.quads(V, F, doubled)  # unit cells: four per cell of the doubled map
    assert fine.valid and abs(fine.report["quadMesh"]["faces"] - 4 * len(all_faces(Q))) <= 0.01 * len(fine.faces)


def test_weld_joins_a_map_split_into_separate_triangles(torus_map):
    V, F, uv = torus_map
    split_V, split_F = V[F].reshape(-1, 3), np.arange(3 * len(F)).reshape(-1, 3)
    welded = seamvox.quads(split_V, split_F, uv, weld=True)
    assert welded.valid and welded.report["quadMesh"] == seamvox.quads(V, F, uv).report["quadMesh"]
    apart = seamvox.quads(split_V, split_F, uv)  # every triangle a disk, cut into cells
    assert apart.valid and apart.report["quadMesh"]["boundaryLoops"] == len(F)
    assert apart.report["validation"]["componentsChecked"] == len(F)


@pytest.mark.parametrize("scale", [0, -1, 2.0, 2.5, True, "2", None, (1 << 20) + 1])
def test_a_scale_that_is_no_whole_number_in_range_is_refused(torus_map, scale):
    with pytest.raises(seamvox.InputError, match=r"scale must be a whole number from 1 to 1048576, got "):
        seamvox.quads(*torus_map, scale=scale)


def test_bad_uv_arrays_are_refused_naming_uv(torus_map):
    V, F, uv = torus_map
    for bad in (uv[:, :, 0], uv[:-1], uv.astype(np.int32)):
        with pytest.raises(seamvox.InputError, match="uv"):
            seamvox.quads(V, F, bad)
    nan = uv.copy()
    nan[3, 1, 0] = np.nan
    with pytest.raises(seamvox.InputError, match="uv"):
        seamvox.quads(V, F, nan)


def test_progress_cancel_and_exceptions_stop_the_extraction(torus_map):
    calls = []
    seamvox.quads(*torus_map, progress=lambda stage, f: calls.append((stage, f)))
    assert ("quads", 1.0) in calls and all(0.0 <= f <= 1.0 for _, f in calls)
    stopped = []

    def refuse(stage, fraction):
        stopped.append(stage)
        return stage != "quads"

    with pytest.raises(seamvox.CancelledError):
        seamvox.quads(*torus_map, progress=refuse)
    assert stopped.count("quads") == 1, "progress is not called again once it said False"

    def fail(stage, fraction):
        raise KeyError(stage)

    with pytest.raises(KeyError):
        seamvox.quads(*torus_map, progress=fail)
    assert seamvox.quads(*torus_map).valid, "the module works after a cancel"


def test_sigint_stops_the_extraction_with_keyboard_interrupt(torus_map):
    seen = []

    def progress(stage, fraction):
        seen.append(stage)
        if seen.count("quads") == 1 and stage == "quads":
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.3)  # releases the GIL: the waiting thread sees the signal and cancels

    with pytest.raises(KeyboardInterrupt):
        seamvox.quads(*torus_map, progress=progress)
    assert seen.count("quads") == 1, "the extraction stopped at its next report"
    assert seamvox.quads(*torus_map).valid
