"""Many calls leave no trace: reference counts of the arguments unchanged, no growth of
Python-traced memory (tracemalloc: numpy's buffers included) or of the resident set (the
library's own buffers), on the success paths and on the error paths. One thread: on a loaded
machine a team of two waits for a core at every call, which only makes the loop slow."""
import gc
import sys
import tracemalloc

import numpy as np
import pytest

import tridiff

CALLS = 2000  # solves; the image functions, 100 times slower, run one call in IMAGE_EVERY
IMAGE_EVERY = 20


def resident_bytes():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4096


def system(rng):
    shape = (8, 33)
    return (rng.uniform(-1, 1, shape), 4 + rng.uniform(0, 1, shape), rng.uniform(-1, 1, shape),
            rng.uniform(-1, 1, shape))


def singular_call(a, b, c, d):
    zero = np.zeros_like(b)
    with pytest.raises(tridiff.LinAlgError):
        tridiff.solve(a, zero, c, d, method="pivoting", threads=1)


def nan_call(a, b, c, d):
    bad = d.copy()
    bad[3, 7] = np.nan
    with pytest.raises(ValueError):
        tridiff.solve(a, b, c, bad, threads=1)


def calls(a, b, c, d, out, image, depth, with_images=True):
    """One of everything the module does, including its error paths."""
    tridiff.solve(a, b, c, d, threads=1)
    tridiff.solve(a, b, c, d, out=out, threads=1)
    tridiff.solve(a[:, ::2], b[:, ::2], c[:, ::2], d[:, ::2], axis=0, threads=1)  # copies inside
    tridiff.solve_diffusion(np.abs(a), d.astype(np.complex128), threads=1)
    singular_call(a, b, c, d)
    nan_call(a, b, c, d)
    with pytest.raises(ValueError):
        tridiff.solve(a, b, c, d.astype(np.float32), threads=1)
    factors = tridiff.factor(a, b, c, threads=1)
    factors.solve(d, out=out, threads=1)
    factors.solve(d, trans="T", threads=1)
    factors.rcond(threads=1)
    with pytest.raises(tridiff.LinAlgError):
        tridiff.factor(a, np.zeros_like(b), c, method="pivoting", threads=1)
    with pytest.raises(ValueError):
        factors.solve(d[:, :5], threads=1)
    if not with_images:
        return
    tridiff.blur(image, 2.0, threads=1)
    with pytest.raises(ValueError):
        tridiff.blur(image, 2.0, method="unknown")
    tridiff.dof(image, depth, focus=2.0, return_coc=True, threads=1)


def test_no_growth_in_references_or_memory():
    rng = np.random.default_rng(1)
    a, b, c, d = system(rng)
    out = np.empty_like(d)
    image = rng.random((24, 20, 3), dtype=np.float32)
    depth = np.linspace(1, 5, 24 * 20, dtype=np.float32).reshape(24, 20)
    arguments = (a, b, c, d, out, image, depth)
    for _ in range(50):  # warm up: thread pools, per-thread scratch, caches
        calls(*arguments)
    gc.collect()
    references = [sys.getrefcount(v) for v in arguments]
    tracemalloc.start()
    traced_before, _ = tracemalloc.get_traced_memory()
    resident_before = resident_bytes()
    for k in range(CALLS):
        calls(*arguments, with_images=k % IMAGE_EVERY == 0)
    gc.collect()
    traced_after, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    resident_after = resident_bytes()
    assert [sys.getrefcount(v) for v in arguments] == references
    # A leak of one small array per call would be CALLS x >= 1 KiB.
    assert traced_after - traced_before < 256 * 1024
    assert resident_after - resident_before < 16 * 1024 * 1024
