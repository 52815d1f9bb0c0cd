"""tridiff.solve and tridiff.solve_diffusion against scipy (solve_banded, lapack ?gtsv) and a
dense numpy solve, on every axis of 1-, 2- and 3-D arrays, every dtype and layout, and every
kind of bad input."""
import numpy as np
import pytest
import scipy.linalg
from scipy.linalg import lapack

import tridiff

DTYPES = [np.float32, np.float64, np.complex64, np.complex128]


def tolerance(dtype, n):
    """Relative error allowed against a float64 reference: a few ulps per row of elimination
    on well-conditioned (diagonally dominant) systems."""
    eps = np.finfo(dtype).eps
    return 50 * eps * max(n, 4)


def random_values(rng, shape, dtype):
    values = rng.uniform(-1, 1, shape)
    if np.issubdtype(dtype, np.complexfloating):
        values = values + 1j * rng.uniform(-1, 1, shape)
    return values.astype(dtype)


def dominant_system(rng, shape, dtype):
    """a, b, c, d with |b| > |a| + |c| + 1 on every row."""
    a = random_values(rng, shape, dtype)
    c = random_values(rng, shape, dtype)
    b = (3 + rng.uniform(0, 1, shape)).astype(dtype)
    d = random_values(rng, shape, dtype)
    return a, b, c, d


def banded_reference(a, b, c, d, axis):
    """Every system along `axis` through scipy.linalg.solve_banded, in complex128/float64."""
    wide = np.complex128 if np.iscomplexobj(d) else np.float64
    a, b, c, d = (np.moveaxis(np.asarray(v, wide), axis, -1) for v in (a, b, c, d))
    n = d.shape[-1]
    x = np.empty_like(d)
    for index in np.ndindex(d.shape[:-1]):
        ab = np.zeros((3, n), wide)
        ab[0, 1:] = c[index][:-1]
        ab[1] = b[index]
        ab[2, :-1] = a[index][1:]
        x[index] = scipy.linalg.solve_banded((1, 1), ab, d[index])
    return np.moveaxis(x, -1, axis)


def relative_error(x, reference):
    scale = max(np.abs(reference).max(), 1e-300)
    return np.abs(x.astype(reference.dtype) - reference).max() / scale


SHAPES = [(1,), (2,), (3,), (17,), (33,), (4, 1), (5, 9), (9, 5), (2, 3, 7), (6, 17, 4)]


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("shape", SHAPES)
def test_every_axis_matches_solve_banded(shape, dtype):
    rng = np.random.default_rng(len(shape) * 100 + shape[-1])
    a, b, c, d = dominant_system(rng, shape, dtype)
    for axis in range(-len(shape), len(shape)):
        x = tridiff.solve(a, b, c, d, axis=axis)
        assert x.dtype == dtype and x.shape == shape
        n = shape[axis]
        assert relative_error(x, banded_reference(a, b, c, d, axis)) <= tolerance(dtype, n)


@pytest.mark.parametrize("method", tridiff.solver_methods)
@pytest.mark.parametrize("n", [1, 2, 3, 15, 16, 17, 65])
def test_every_method_matches_solve_banded(method, n):
    rng = np.random.default_rng(n)
    a, b, c, d = dominant_system(rng, (7, n), np.float64)
    x = tridiff.solve(a, b, c, d, method=method)
    assert relative_error(x, banded_reference(a, b, c, d, -1)) <= tolerance(np.float64, n)


def test_matches_lapack_dgtsv_without_dominance():
    # Not diagonally dominant: auto sends these to partial pivoting, LAPACK's own algorithm.
    rng = np.random.default_rng(7)
    a, c, d = (rng.uniform(-1, 1, (40, 129)) for _ in range(3))
    b = rng.uniform(-0.5, 0.5, (40, 129))
    x = tridiff.solve(a, b, c, d)
    for s in range(40):
        _, _, _, expected, info = lapack.dgtsv(a[s, 1:], b[s], c[s, :-1], d[s])
        assert info == 0
        cond = np.linalg.cond(np.diag(b[s]) + np.diag(a[s, 1:], -1) + np.diag(c[s, :-1], 1))
        assert relative_error(x[s], expected) <= 1e-13 * cond


def test_periodic_matches_dense_solve():
    rng = np.random.default_rng(3)
    n = 11
    a, b, c, d = dominant_system(rng, (4, n), np.float64)
    x = tridiff.solve(a, b, c, d, periodic=True)
    for s in range(4):
        m = np.diag(b[s]) + np.diag(a[s, 1:], -1) + np.diag(c[s, :-1], 1)
        m[0, n - 1], m[n - 1, 0] = a[s, 0], c[s, n - 1]
        assert relative_error(x[s], np.linalg.solve(m, d[s])) <= 1e-13


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("periodic", [False, True])
def test_solve_diffusion_matches_dense_solve(dtype, periodic):
    rng = np.random.default_rng(5)
    real = np.float32 if dtype in (np.float32, np.complex64) else np.float64
    beta = rng.uniform(0.1, 10, (3, 6, 19)).astype(real)
    d = random_values(rng, beta.shape, dtype)
    for axis in range(3):
        x = tridiff.solve_diffusion(beta, d, axis=axis, periodic=periodic)
        bm, dm, xm = (np.moveaxis(v, axis, -1) for v in (beta, d, x))
        n = dm.shape[-1]
        for index in np.ndindex(dm.shape[:-1]):
            link = bm[index].astype(np.float64)
            left = np.concatenate([[link[-1] if periodic else 0], link[:-1]])
            right = link if periodic else np.concatenate([link[:-1], [0]])
            m = np.diag(1 + left + right) - np.diag(link[:-1], 1) - np.diag(link[:-1], -1)
            if periodic:
                m[0, n - 1] -= link[-1]
                m[n - 1, 0] -= link[-1]
            expected = np.linalg.solve(m, dm[index].astype(np.complex128))
            assert relative_error(xm[index], expected) <= tolerance(dtype, n)


def test_fortran_order_and_out_are_used_in_place():
    rng = np.random.default_rng(11)
    a, b, c, d = (np.asfortranarray(v) for v in dominant_system(rng, (20, 30), np.float64))
    expected = banded_reference(a, b, c, d, 0)
    x = tridiff.solve(a, b, c, d, axis=0)
    assert x.flags.f_contiguous and relative_error(x, expected) < 1e-13
    out = np.empty_like(d)
    assert tridiff.solve(a, b, c, d, axis=0, out=out) is out
    assert relative_error(out, expected) < 1e-13
    in_place = d.copy(order="F")
    assert tridiff.solve(a, b, c, in_place, axis=0, out=in_place) is in_place
    assert relative_error(in_place, expected) < 1e-13


def test_strided_views():
    rng = np.random.default_rng(12)
    big = [v for v in dominant_system(rng, (3, 40, 50), np.float64)]
    views = [v[1:, ::3, 1::2] for v in big]
    for axis in range(3):
        expected = banded_reference(*views, axis)
        assert relative_error(tridiff.solve(*views, axis=axis), expected) < 1e-13
        # An out with the inputs' strides: solved where everything lies.
        out_base = np.zeros_like(big[3])
        out = out_base[1:, ::3, 1::2]
        assert tridiff.solve(*views, axis=axis, out=out) is out
        assert relative_error(out, expected) < 1e-13
        assert np.all(out_base[0] == 0)  # nothing written outside the view
    # Reversed (negative strides) and broadcast (stride 0) inputs are copied.
    a, b, c, d = (v[0] for v in big)
    reversed_d = d[:, ::-1]
    constant_b = np.broadcast_to(np.float64(4.0), d.shape)
    expected = banded_reference(a, constant_b, c, reversed_d, 1)
    assert relative_error(tridiff.solve(a, constant_b, c, reversed_d), expected) < 1e-13
    out = np.zeros_like(d)[:, ::-1]
    tridiff.solve(a, constant_b, c, reversed_d, out=out)
    assert relative_error(out, expected) < 1e-13


def test_read_only_inputs_are_accepted_and_read_only_out_refused():
    rng = np.random.default_rng(13)
    arrays = dominant_system(rng, (4, 9), np.float64)
    for v in arrays:
        v.flags.writeable = False
    x = tridiff.solve(*arrays)
    assert relative_error(x, banded_reference(*arrays, -1)) < 1e-13
    with pytest.raises(ValueError, match="'out'.*read-only"):
        tridiff.solve(*arrays, out=arrays[3])


@pytest.mark.parametrize("shape,axis", [((0,), 0), ((0, 5), 1), ((0, 5), 0), ((5, 0), 1),
                                        ((3, 0, 4), 0), ((3, 0, 4), 2)])
def test_zero_size(shape, axis):
    a, b, c, d = (np.zeros(shape) for _ in range(4))
    x = tridiff.solve(a, b, c, d, axis=axis)
    assert x.shape == shape and x.dtype == np.float64
    assert tridiff.solve_diffusion(a, d, axis=axis).shape == shape


def test_lists_are_converted():
    x = tridiff.solve([0.0, 1.0], [4.0, 4.0], [1.0, 0.0], [5.0, 5.0])
    assert np.allclose(x, [1.0, 1.0], rtol=0, atol=1e-15)


def test_wrong_dtypes_are_refused():
    a, b, c, d = dominant_system(np.random.default_rng(1), (3, 5), np.float64)
    with pytest.raises(ValueError, match="argument 'd'.*int64"):
        tridiff.solve(a, b, c, np.ones((3, 5), np.int64))
    with pytest.raises(ValueError, match="argument 'b'.*float32"):
        tridiff.solve(a, b.astype(np.float32), c, d)
    with pytest.raises(ValueError, match="argument 'out'.*float32"):
        tridiff.solve(a, b, c, d, out=np.empty((3, 5), np.float32))
    with pytest.raises(ValueError, match="argument 'beta'"):
        tridiff.solve_diffusion(np.ones((3, 5), np.float32), d)
    with pytest.raises(ValueError, match="argument 'out'"):
        tridiff.solve(a, b, c, d, out=[0.0] * 15)


def test_mismatched_shapes_are_refused():
    a, b, c, d = dominant_system(np.random.default_rng(1), (3, 5), np.float64)
    with pytest.raises(ValueError, match=r"argument 'c'.*\(3, 4\)"):
        tridiff.solve(a, b, c[:, :4], d)
    with pytest.raises(ValueError, match="argument 'out'"):
        tridiff.solve(a, b, c, d, out=np.empty((5, 3)))
    with pytest.raises(ValueError, match="argument 'axis'"):
        tridiff.solve(a, b, c, d, axis=2)
    with pytest.raises(ValueError, match="argument 'd'.*0-dimensional"):
        tridiff.solve(1.0, 1.0, 1.0, 1.0)


def test_bad_options_are_refused():
    a, b, c, d = dominant_system(np.random.default_rng(1), (3, 5), np.float64)
    with pytest.raises(ValueError, match="argument 'method'.*unknown"):
        tridiff.solve(a, b, c, d, method="gauss")
    with pytest.raises(ValueError, match="argument 'threads'"):
        tridiff.solve(a, b, c, d, threads=-1)
    with pytest.raises(ValueError, match="argument 'out'.*overlaps 'a'"):
        tridiff.solve(a, b, c, d, out=a)


def test_nan_names_argument_system_and_row():
    a, b, c, d = dominant_system(np.random.default_rng(2), (4, 6, 9), np.float64)
    d[2, 3, 5] = np.nan
    with pytest.raises(ValueError) as caught:
        tridiff.solve(a, b, c, d, axis=2)
    error = caught.value
    assert (error.argument, error.system, error.row) == ("d", (2, 3), 5)
    assert "argument 'd', system (2, 3), row 5" in str(error)
    # Along the middle axis: the system is (2, 5), its row 3.
    with pytest.raises(ValueError) as caught:
        tridiff.solve(a, b, c, d, axis=1)
    assert (caught.value.system, caught.value.row) == ((2, 5), 3)
    b[1, 1, 1] = np.inf
    with pytest.raises(ValueError, match="argument 'b', system"):
        tridiff.solve(a, b, c, np.zeros_like(d), axis=2)


def test_singular_system_is_a_lin_alg_error():
    rng = np.random.default_rng(4)
    a, b, c, d = dominant_system(rng, (5, 8), np.float64)
    a[3], b[3], c[3] = 0, 0, 0  # system 3 is the zero matrix
    with pytest.raises(np.linalg.LinAlgError) as caught:
        tridiff.solve(a, b, c, d)
    assert isinstance(caught.value, tridiff.LinAlgError)
    assert caught.value.system == (3,)
    assert "system 3" in str(caught.value)
    with pytest.raises(tridiff.LinAlgError):  # every method, pivoting included
        tridiff.solve(a, b, c, d, method="pivoting")
    # The in-place solve leaves d as it was.
    kept = d.copy()
    with pytest.raises(tridiff.LinAlgError):
        tridiff.solve(a, b, c, d, out=d)
    assert np.array_equal(d[3], kept[3])


def test_pivot_free_method_refuses_unsafe_matrix():
    a = np.array([0.0, 1.0, 1.0])
    b = np.array([0.1, 0.1, 0.1])
    c = np.array([1.0, 1.0, 0.0])
    with pytest.raises(tridiff.LinAlgError, match="not diagonally dominant.*method='pivoting'"):
        tridiff.solve(a, b, c, np.ones(3), method="thomas")
    x = tridiff.solve(a, b, c, np.ones(3))  # auto pivots
    assert relative_error(x, banded_reference(a, b, c, np.ones(3), 0)) < 1e-14


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_info_reports_each_system_and_solves_the_others(axis):
    """info=True: a status per system in the batch shape, nothing raised for a bad system, the
    good ones solved (against solve_banded)."""
    rng = np.random.default_rng(7)
    shape = (6, 7, 9)
    a, b, c, d = dominant_system(rng, shape, np.float64)
    a, b, c, d = (np.moveaxis(v, -1, axis) for v in (a, b, c, d))
    singular = (1, 2)  # batch index; the equations run along `axis`
    not_finite = (4, 5)
    view = lambda v, index: np.moveaxis(v, axis, -1)[index]  # noqa: E731 (one system)
    for v in (a, b, c):
        view(v, singular)[:] = 0  # the zero matrix: Thomas stops at its first row
    view(d, not_finite)[3] = np.inf
    x, info = tridiff.solve(a, b, c, d, axis=axis, info=True)
    expected = np.zeros(shape[:2], np.int64)
    expected[singular] = 1  # breakdown at row 0, reported 1-based as LAPACK does
    expected[not_finite] = -4  # d
    assert info.dtype == np.int64 and info.shape == shape[:2]
    assert np.array_equal(info, expected)
    good = np.ones(shape[:2], bool)
    good[singular] = good[not_finite] = False
    xs, ds = np.moveaxis(x, axis, -1), np.moveaxis(d, axis, -1)
    reference = banded_reference(*(np.moveaxis(v, axis, -1)[good] for v in (a, b, c)),
                                 ds[good], axis=-1)
    assert relative_error(xs[good], reference) < tolerance(np.float64, shape[2])


def test_info_of_solve_diffusion_names_a_negative_beta():
    beta = np.full((5, 12), 0.5)
    d = np.ones((5, 12))
    beta[2, 4] = -1.0
    x, info = tridiff.solve_diffusion(beta, d, info=True)
    assert np.array_equal(info, [0, 0, -5, 0, 0])
    assert np.allclose(x[[0, 1, 3, 4]], 1.0)  # rhs = 1 is a fixed point of the diffusion
    without = tridiff.solve_diffusion(beta[[0, 1, 3, 4]], d[[0, 1, 3, 4]])
    assert np.array_equal(x[[0, 1, 3, 4]], without)
