"""tridiff.factor, tridiff.factor_diffusion and Factors.solve against independent references:
scipy's solve_banded, LAPACK ?gttrf/?gttrs through scipy, dense numpy solves of A, A^T and A^H,
and the exact 1-norm condition number; every axis of 1-, 2- and 3-D arrays, every dtype and
layout, and the bad inputs."""
import numpy as np
import pytest
from scipy.linalg import lapack

import tridiff
from test_solve import (DTYPES, SHAPES, banded_reference, dominant_system, random_values,
                        relative_error, tolerance)


def dense(a, b, c):
    """The matrix of one system (1-D a, b, c) in complex128 or float64."""
    wide = np.complex128 if np.iscomplexobj(b) else np.float64
    a, b, c = (np.asarray(v, wide) for v in (a, b, c))
    return np.diag(b) + np.diag(a[1:], -1) + np.diag(c[:-1], 1)


def per_system(axis, *arrays):
    """(index, the systems' 1-D slices) for every system along `axis`."""
    moved = [np.moveaxis(v, axis, -1) for v in arrays]
    for index in np.ndindex(moved[0].shape[:-1]):
        yield index, [v[index] for v in moved]


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("shape", SHAPES)
def test_every_axis_matches_solve_banded(shape, dtype):
    rng = np.random.default_rng(len(shape) * 10 + shape[0])
    a, b, c, d = dominant_system(rng, shape, dtype)
    second = random_values(rng, shape, dtype)
    for axis in range(-len(shape), len(shape)):
        factors = tridiff.factor(a, b, c, axis=axis)
        assert factors.shape == shape and factors.dtype == dtype
        assert factors.axis == axis % len(shape)
        assert not factors.pivoted.any()  # dominant (in modulus, for complex): no pivoting
        n = shape[axis]
        for rhs in (d, second):  # factored once, solved twice
            x = factors.solve(rhs)
            assert x.dtype == dtype and x.shape == shape
            assert relative_error(x, banded_reference(a, b, c, rhs, axis)) <= tolerance(dtype, n)


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
@pytest.mark.parametrize("trans", ["N", "T", "C", 0, 1, 2])
def test_transposed_solves_match_dense_solve(dtype, trans):
    rng = np.random.default_rng(3)
    shape = (5, 13)
    a, b, c, d = dominant_system(rng, shape, dtype)
    b[1] *= 0.05  # system 1 is not dominant: factored with pivoting
    factors = tridiff.factor(a, b, c)
    assert factors.pivoted.tolist() == [True] * 5  # pivoting is chosen per chunk of systems
    x = factors.solve(d, trans=trans)
    op = {"N": lambda m: m, "T": np.transpose, "C": lambda m: m.conj().T}[
        "NTC"[trans] if isinstance(trans, int) else trans]
    for index, (sa, sb, sc, sd) in per_system(-1, a, b, c, d):
        m = dense(sa, sb, sc)
        expected = np.linalg.solve(op(m), sd)
        bound = 1e-14 * np.linalg.cond(m, 1)
        assert relative_error(x[index], expected) <= bound


def test_pivoting_factors_match_lapack_gttrf_gttrs():
    rng = np.random.default_rng(8)
    a, c, d = (rng.uniform(-1, 1, (70, 65)) for _ in range(3))
    b = rng.uniform(-0.5, 0.5, (70, 65))  # far from dominant
    for method in ("auto", "pivoting"):
        factors = tridiff.factor(a, b, c, method=method)
        assert factors.pivoted.all()
        x = factors.solve(d)
        for s in range(70):
            *lu, info = lapack.dgttrf(a[s, 1:], b[s], c[s, :-1])
            assert info == 0
            expected, info = lapack.dgttrs(*lu, d[s])
            assert info == 0
            cond = np.linalg.cond(dense(a[s], b[s], c[s]), 1)
            assert relative_error(x[s], expected) <= 1e-14 * cond
    with pytest.raises(tridiff.LinAlgError, match="use method='pivoting' or method='auto'") as caught:
        tridiff.factor(a, b, c, method="no-pivoting")
    assert caught.value.system == (0,)


def test_rcond_bounds_the_exact_condition_number():
    rng = np.random.default_rng(9)
    a, b, c, _ = dominant_system(rng, (4, 6, 21), np.float64)
    b[1, 2] = rng.uniform(-0.3, 0.3, 21)  # one ill-conditioned, pivoted system
    for axis in (0, 2):
        factors = tridiff.factor(a, b, c, axis=axis)
        rcond = factors.rcond()
        assert rcond.dtype == np.float64
        assert rcond.shape == tuple(s for k, s in enumerate(b.shape) if k != axis)
        for index, (sa, sb, sc) in per_system(axis, a, b, c):
            exact = 1 / np.linalg.cond(dense(sa, sb, sc), 1)
            # The estimate of ||A^-1||_1 never exceeds it (Hager-Higham), and is rarely far.
            assert exact * (1 - 1e-12) <= rcond[index] <= 10 * exact
    assert tridiff.factor(a.astype(np.float32), b.astype(np.float32),
                          c.astype(np.float32)).rcond().dtype == np.float32


@pytest.mark.parametrize("dtype", DTYPES)
def test_factor_diffusion_matches_dense_solve(dtype):
    rng = np.random.default_rng(5)
    real = np.float32 if dtype in (np.float32, np.complex64) else np.float64
    beta = rng.uniform(0.1, 10, (3, 6, 19)).astype(real)
    d = random_values(rng, beta.shape, dtype)
    for axis in range(3):
        factors = tridiff.factor_diffusion(beta, axis=axis, dtype=dtype)
        assert factors.dtype == dtype
        x = factors.solve(d)
        assert np.allclose(x, tridiff.solve_diffusion(beta, d, axis=axis),
                           rtol=0, atol=tolerance(dtype, 19) * np.abs(x).max())
        for index, (link, rhs) in per_system(axis, beta.astype(np.float64), d):
            off = link[:-1]
            m = np.diag(1 + np.concatenate([[0], off]) + np.concatenate([off, [0]]))
            m -= np.diag(off, 1) + np.diag(off, -1)
            expected = np.linalg.solve(m, rhs.astype(np.complex128))
            assert relative_error(np.moveaxis(x, axis, -1)[index], expected) <= tolerance(dtype, 19)


def test_layouts_in_place_and_copies():
    rng = np.random.default_rng(11)
    a, b, c, d = (np.asfortranarray(v) for v in dominant_system(rng, (20, 30), np.float64))
    expected = banded_reference(a, b, c, d, 0)
    factors = tridiff.factor(a, b, c, axis=0)
    # A right-hand side in the coefficients' order: solved where it lies, in place too.
    in_place = d.copy(order="F")
    assert factors.solve(in_place, out=in_place) is in_place
    assert relative_error(in_place, expected) < 1e-13
    # Another order, a strided view, a read-only array: copied, same answer.
    assert relative_error(factors.solve(np.ascontiguousarray(d)), expected) < 1e-13
    wide = np.zeros((20, 60))
    wide[:, ::2] = d
    assert relative_error(factors.solve(wide[:, ::2]), expected) < 1e-13
    out = np.zeros((20, 60))[:, ::2]
    assert factors.solve(d, out=out) is out and relative_error(out, expected) < 1e-13
    frozen = d.copy()
    frozen.flags.writeable = False
    assert relative_error(factors.solve(frozen), expected) < 1e-13
    # Strided coefficients are copied once, at factoring.
    big = dominant_system(rng, (3, 40, 50), np.float64)
    views = [v[1:, ::3, 1::2] for v in big]
    for axis in range(3):
        x = tridiff.factor(*views[:3], axis=axis).solve(views[3])
        assert relative_error(x, banded_reference(*views, axis)) < 1e-13


@pytest.mark.parametrize("shape,axis", [((0,), 0), ((0, 5), 1), ((0, 5), 0), ((3, 0, 4), 2)])
def test_zero_size(shape, axis):
    zeros = np.zeros(shape)
    factors = tridiff.factor(zeros, zeros, zeros, axis=axis)
    assert factors.solve(zeros).shape == shape
    batch = tuple(s for k, s in enumerate(shape) if k != axis)
    assert factors.pivoted.shape == batch and not factors.pivoted.any()
    assert factors.rcond().shape == batch and np.all(factors.rcond() == 1)  # as ?gtcon, n = 0
    assert tridiff.factor_diffusion(zeros, axis=axis).solve(zeros).shape == shape


def test_bad_input_is_named():
    rng = np.random.default_rng(2)
    a, b, c, d = dominant_system(rng, (4, 6, 9), np.float64)
    factors = tridiff.factor(a, b, c, axis=1)
    bad = d.copy()
    bad[2, 5, 3] = np.nan
    with pytest.raises(ValueError) as caught:
        factors.solve(bad)
    assert (caught.value.argument, caught.value.system, caught.value.row) == ("d", (2, 3), 5)
    with pytest.raises(ValueError, match=r"argument 'd'.*\(4, 9, 6\)"):
        factors.solve(np.ones((4, 9, 6)))
    with pytest.raises(ValueError, match="argument 'd'.*float32; the factors are float64"):
        factors.solve(d.astype(np.float32))
    with pytest.raises(ValueError, match="argument 'out'.*read-only"):
        frozen = np.empty_like(d)
        frozen.flags.writeable = False
        factors.solve(d, out=frozen)
    with pytest.raises(ValueError, match="argument 'trans'"):
        factors.solve(d, trans="X")
    with pytest.raises(ValueError, match="argument 'threads'"):
        factors.solve(d, threads=-1)
    b_nan = b.copy()
    b_nan[1, 4, 7] = np.inf
    with pytest.raises(ValueError) as caught:
        tridiff.factor(a, b_nan, c, axis=2)
    assert (caught.value.argument, caught.value.system, caught.value.row) == ("b", (1, 4), 7)
    with pytest.raises(ValueError, match="argument 'method'"):
        tridiff.factor(a, b, c, method="thomas")
    with pytest.raises(ValueError, match="argument 'c'"):
        tridiff.factor(a, b, c[:, :, :8])
    with pytest.raises(ValueError, match="argument 'a'.*float32"):
        tridiff.factor(a.astype(np.float32), b, c)
    with pytest.raises(ValueError, match="argument 'beta'"):
        tridiff.factor_diffusion(np.ones((3, 5)), dtype=np.complex64)
    with pytest.raises(ValueError, match="argument 'dtype': int32 is not one of"):
        tridiff.factor_diffusion(np.ones((3, 5)), dtype=np.int32)
    with pytest.raises(ValueError, match="argument 'beta'"):
        tridiff.factor_diffusion(-np.ones((3, 5)))


def test_singular_system_is_a_lin_alg_error():
    rng = np.random.default_rng(4)
    a, b, c, _ = dominant_system(rng, (5, 8), np.float64)
    a[3], b[3], c[3] = 0, 0, 0
    with pytest.raises(tridiff.LinAlgError) as caught:
        tridiff.factor(a, b, c)
    assert caught.value.system == (3,) and "singular" in str(caught.value)
