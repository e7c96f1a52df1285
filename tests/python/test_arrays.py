"""Arrays into seamvox: every accepted dtype and layout gives the same map; every bad array or option
raises seamvox.InputError (a ValueError) naming the problem; library errors keep their messages."""
import numpy as np
import pytest

import seamvox
from conftest import sphere

V0, F0 = sphere(2)


@pytest.fixture(scope="module")
def reference():
    return seamvox.parameterize(V0, F0)


def layouts():
    """(name, V, F) in every accepted dtype and a few memory layouts."""
    wide = np.zeros((len(V0), 7))
    wide[:, ::2][:, :3] = V0  # columns 0, 2, 4 of a wider array: strided rows and columns
    faces_t = np.ascontiguousarray(F0.T).T  # Fortran order
    every_other = np.repeat(F0, 2, axis=0)[::2]  # row stride of two rows
    return [
        ("float32/int32", V0.astype(np.float32), F0.astype(np.int32)),
        ("float64/uint32", V0, F0.astype(np.uint32)),
        ("float64/int64", V0, F0.astype(np.int64)),
        ("strided V, Fortran F", wide[:, 0:6:2], faces_t),
        ("Fortran V, row-strided F", np.asfortranarray(V0), every_other),
        ("big-endian", V0.astype(">f8"), F0.astype(">i4")),
        ("nested lists", V0.tolist(), F0.tolist()),
    ]


@pytest.mark.parametrize("name,V,F", layouts(), ids=[l[0] for l in layouts()])
def test_every_accepted_layout_gives_the_same_map(reference, name, V, F):
    r = seamvox.parameterize(V, F)
    np.testing.assert_array_equal(r.F, reference.F)
    np.testing.assert_array_equal(r.uv, reference.uv)
    verdict = seamvox.check(V, F, r.uv)
    assert verdict["seamless"]


def bad_meshes():
    nan, inf = V0.copy(), V0.copy()
    nan[3, 2] = np.nan
    inf[5, 0] = -np.inf
    huge = V0.copy()
    huge[7, 1] = 1e300
    negative, beyond = F0.copy(), F0.copy()
    negative[2, 1] = -1
    beyond[4, 2] = len(V0)
    return [
        ("V 1-D", V0.ravel(), F0, "V must have shape (n, 3), got (%d,)" % V0.size),
        ("V (n, 2)", V0[:, :2], F0, "V must have shape (n, 3), got (%d, 2)" % len(V0)),
        ("F (m, 4)", V0, np.hstack([F0, F0[:, :1]]), "F must have shape (m, 3), got (%d, 4)" % len(F0)),
        ("F 3-D", V0, F0[:, :, None], "F must have shape (m, 3)"),
        ("V integers", V0.astype(np.int64), F0, "V must hold float32 or float64 values, got int64"),
        ("V strings", [["a", "b", "c"]], F0, "V must hold float32 or float64 values, got str32"),
        ("F floats", V0, F0.astype(np.float64), "F must hold integers (int32, int64, uint32, ...), got float64"),
        ("F negative", V0, negative, "F[2, 1] = -1 is negative"),
        ("F out of range", V0, beyond, "F[4, 2] = %d is out of range: V has %d vertices" % (len(V0), len(V0))),
        ("V NaN", nan, F0, "V[3, 2] is NaN"),
        ("V -inf", inf, F0, "V[5, 0] is -inf"),
        ("V beyond float32", huge, F0, "V[7, 1] is "),
        ("F empty", V0, np.zeros((0, 3), np.int32), "F has no faces"),
        ("V None", None, F0, "V is None"),
        ("F None", V0, None, "F is None"),
    ]


@pytest.mark.parametrize("name,V,F,message", bad_meshes(), ids=[b[0] for b in bad_meshes()])
@pytest.mark.parametrize("call", ["parameterize", "cross_field", "check", "write_mesh"])
def test_every_bad_array_is_a_value_error_naming_it(tmp_path, name, V, F, message, call):
    uv = np.zeros((len(F0), 3, 2))
    calls = {
        "parameterize": lambda: seamvox.parameterize(V, F),
        "cross_field": lambda: seamvox.cross_field(V, F),
        "check": lambda: seamvox.check(V, F, uv),
        "write_mesh": lambda: seamvox.write_mesh(str(tmp_path / "m.ply"), V, F),
    }
    with pytest.raises(ValueError) as error:
        calls[call]()
    assert isinstance(error.value, seamvox.InputError) and isinstance(error.value, seamvox.Error)
    assert message in str(error.value)
    assert not (tmp_path / "m.ply").exists()


def test_bad_uv_and_field_arrays(reference):
    uv = reference.uv
    cases = [
        (lambda: seamvox.check(V0, F0, uv[:-1]), "uv must have shape (m, 3, 2) with m the faces of F, got"),
        (lambda: seamvox.check(V0, F0, uv.reshape(-1, 2)), "uv must have shape (m, 3, 2)"),
        (lambda: seamvox.check(V0, F0, np.where(np.arange(uv.size).reshape(uv.shape) == 7, np.nan, uv)),
         "uv[1, 0, 1] is NaN"),
        (lambda: seamvox.check(V0, F0, uv, field=np.ones((3, 3))), "field must have shape (m, 3)"),
        (lambda: seamvox.parameterize(V0, F0, field=np.ones((len(F0), 2))), "field must have shape (m, 3)"),
        (lambda: seamvox.parameterize(V0, F0, field=np.full((len(F0), 3), np.inf)), "field[0, 0] is inf"),
        (lambda: seamvox.write_mesh("x.ply", V0, F0, uv[:, :, :1]), "uv must have shape (m, 3, 2)"),
    ]
    for call, message in cases:
        with pytest.raises(seamvox.InputError, match=None) as error:
            call()
        assert message in str(error.value)


@pytest.mark.parametrize("options,message", [
    (dict(solver="fast"), "unknown"),
    (dict(grid=100), "grid must be a power of two from 4 to 1024, got 100"),
    (dict(grid=2048), "grid must be a power of two"),
    (dict(cells=0), "cells must be a positive number"),
    (dict(cells=float("nan")), "cells must be a positive number"),
    (dict(edge_length=-1.0), "edge_length must be a positive finite number"),
    (dict(merge_cones=-0.5), "merge_cones must be a number from 0 to 10"),
    (dict(close_holes=-1.0), "close_holes must be a number from 0 to 1000"),
    (dict(field_smoothing=0), "field_smoothing must be an integer from 1 to 64, got 0"),
    (dict(field_smoothing=65), "field_smoothing must be an integer from 1 to 64, got 65"),
    (dict(threads=0), "threads must be a whole number from 1 to 4096, got 0"),
    (dict(threads=2.5), "threads must be a whole number from 1 to 4096, got 2.5"),
    (dict(edge_length="1"), "edge_length must be a positive finite number, got '1'"),
    (dict(edge_length=float("inf")), "edge_length must be a positive finite number, got inf"),
    (dict(field="bogus"), "unknown field method 'bogus'"),
])
def test_bad_options_are_value_errors(options, message):
    with pytest.raises(ValueError) as error:
        seamvox.parameterize(V0, F0, **options)
    assert message in str(error.value)


def test_numpy_scalars_and_path_objects_are_accepted(tmp_path):
    r = seamvox.parameterize(V0, F0, threads=np.int64(1), edge_length=np.float32(0.25), cells=np.float64(10))
    assert r.report["edgeLength"] == 0.25
    seamvox.write_mesh(tmp_path / "m.ply", r.V, r.F, r.uv)
    assert seamvox.check(*seamvox.read_mesh(tmp_path / "m.ply", uv=True))["seamless"]


def test_progress_must_be_callable():
    with pytest.raises(TypeError):
        seamvox.parameterize(V0, F0, progress=3)


def test_library_errors_keep_their_messages(tmp_path):
    missing = str(tmp_path / "missing.ply")
    with pytest.raises(OSError) as error:
        seamvox.read_mesh(missing)
    assert isinstance(error.value, seamvox.IoError) and missing in str(error.value)
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    with pytest.raises(ValueError) as error:
        seamvox.read_mesh(str(bad))
    assert isinstance(error.value, seamvox.InputError) and str(bad) in str(error.value)
    # A flat mesh (all vertices on one point) has no extent for the grid.
    with pytest.raises(seamvox.InputError, match="extent|no valid faces"):
        seamvox.parameterize(np.zeros((3, 3)), [[0, 1, 2]])
    for name, base in [("InputError", ValueError), ("IoError", OSError), ("TopologyError", RuntimeError),
                       ("SolverError", RuntimeError), ("CancelledError", RuntimeError)]:
        assert issubclass(getattr(seamvox, name), base) and issubclass(getattr(seamvox, name), seamvox.Error)
