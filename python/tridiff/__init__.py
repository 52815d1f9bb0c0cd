"""tridiff: tridiagonal solvers, Gaussian blurs and depth of field on numpy arrays.

    import numpy as np, tridiff
    x = tridiff.solve(a, b, c, d)            # a[i] x[i-1] + b[i] x[i] + c[i] x[i+1] = d[i]
    f = tridiff.factor(a, b, c); x = f.solve(d)   # factor once, solve many
    y = tridiff.blur(image, 8.0)             # H x W x C float32, within 1e-3 of the Gaussian

The work is done by the C++ libraries (tridiff._tridiff, built with pybind11); this file only
re-exports them and picks the blur method for method="auto".
"""
from . import _tridiff
from ._tridiff import (Factors, LinAlgError, dof, factor, factor_diffusion, solve,
                       solve_diffusion, solver_methods)

__all__ = [
    "Factors", "LinAlgError", "blur", "blur_methods", "dof", "dof_methods", "factor",
    "factor_diffusion", "solve", "solve_diffusion", "solver_methods", "auto_blur_method",
]

# method="auto": the first of these whose stated error bound (BlurMethod::max_error) is within
# max_error and that takes the sigma and the border. Ordered by time on a 4096^2 RGB float
# image, 2 threads (bench/bench_python.py): the truncated Gaussian for small sigma, the
# decimated recursive Gaussian from sigma 4, the full-resolution recursive one between them
# and for the zero border, then the exact convolutions (separable for small sigma, FFT almost
# flat in sigma) for the rest.
_AUTO_ORDER = ("gaussian-fir", "iir-decimated", "iir-deriche", "separable", "fft")
_AUTO_SEPARABLE_MAX_SIGMA = 4.0


def blur_methods():
    """Every registered blur method, as a list of dicts: name, summary, exact, max_error (the
    stated bound: max |result - exact Gaussian| on images in [0, 1]), min_sigma, max_sigma,
    borders, cost."""
    return _tridiff._blur_methods()


def dof_methods():
    """Every registered depth-of-field method, as a list of dicts: name, summary,
    blurs_foreground, honours_layers, keeps_sharp (a sharp pixel that no nearer blur covers
    keeps its value bit for bit), cost."""
    return _tridiff._dof_methods()


def auto_blur_method(sigma, border="replicate", max_error=1e-3):
    """The method blur(method="auto") runs: the fastest whose stated error bound is at most
    max_error and that takes sigma and border. ValueError if none does."""
    methods = {m["name"]: m for m in _tridiff._blur_methods()}
    for name in _AUTO_ORDER:
        m = methods.get(name)
        if m is None or m["max_error"] > max_error or border not in m["borders"]:
            continue
        if not m["min_sigma"] <= sigma <= m["max_sigma"]:
            continue
        if name == "separable" and sigma > _AUTO_SEPARABLE_MAX_SIGMA and "fft" in methods:
            continue
        return name
    err = ValueError(f"tridiff: argument 'method': no method takes sigma {sigma} with border "
                     f"'{border}' within max_error {max_error} (see blur_methods())")
    err.argument = "method"
    raise err


def blur(image, sigma, method="auto", border="replicate", threads=0, max_error=1e-3):
    """Gaussian blur of an image (height x width [x channels], float32; float64 converted
    once). Returns float32 of the image's shape.

    sigma: the Gaussian's standard deviation in pixels.
    method: "auto" (the fastest method whose stated error bound against the exact Gaussian,
        on images in [0, 1], is at most max_error: see auto_blur_method) or a name from
        blur_methods(). Pass max_error=2e-6 for an exact convolution.
    border: "replicate", "mirror", "zero" or "periodic", as the method supports.
    threads: 0 for all cores.

    Raises ValueError naming the argument at fault. The GIL is released during the work.
    """
    if method == "auto":
        method = auto_blur_method(sigma, border, max_error)
    return _tridiff._blur(image, sigma, method, border, threads)
