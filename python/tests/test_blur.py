"""tridiff.blur against scipy.ndimage.gaussian_filter in double precision: every registered
method within its stated error bound, on every border it supports (scipy's modes: replicate =
nearest, mirror = reflect, zero = constant 0, periodic = wrap)."""
import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

import tridiff

SCIPY_MODE = {"replicate": "nearest", "mirror": "reflect", "zero": "constant", "periodic": "wrap"}
METHODS = tridiff.blur_methods()


def exact_gaussian(image, sigma, border):
    """The sampled Gaussian in float64, its tails kept to 10 sigma (below 1e-20)."""
    sigmas = (sigma, sigma) + (0,) * (image.ndim - 2)
    return gaussian_filter(image.astype(np.float64), sigmas, mode=SCIPY_MODE[border], truncate=10)


def sigmas_of(method):
    """Both ends of the method's range where they are small enough for a quick test, and one
    between them."""
    low, high = method["min_sigma"], min(method["max_sigma"], 5.0)
    return sorted({low, (low + high) / 2, high})


@pytest.mark.parametrize("method", METHODS, ids=[m["name"] for m in METHODS])
def test_every_method_within_its_stated_bound(method):
    rng = np.random.default_rng(1)
    image = rng.random((61, 43, 3), dtype=np.float32)  # odd sizes: no tile or lane fits
    for sigma in sigmas_of(method):
        for border in method["borders"]:
            result = tridiff.blur(image, sigma, method=method["name"], border=border)
            assert result.dtype == np.float32 and result.shape == image.shape
            error = np.abs(result - exact_gaussian(image, sigma, border)).max()
            assert error <= method["max_error"], (method["name"], sigma, border, error)


@pytest.mark.parametrize("sigma", [0.5, 2.0, 3.5, 8.0, 20.0])
@pytest.mark.parametrize("border", ["replicate", "mirror", "zero", "periodic"])
def test_auto_within_max_error(sigma, border):
    rng = np.random.default_rng(2)
    image = rng.random((96, 80, 3), dtype=np.float32)
    result = tridiff.blur(image, sigma, border=border)
    assert np.abs(result - exact_gaussian(image, sigma, border)).max() <= 1e-3
    exact = tridiff.blur(image, sigma, border=border, max_error=2e-6)
    assert np.abs(exact - exact_gaussian(image, sigma, border)).max() <= 2e-6


def test_grey_float64_and_strided_images():
    rng = np.random.default_rng(3)
    grey = rng.random((50, 70))  # float64, converted once
    result = tridiff.blur(grey, 3.0, method="separable")
    assert result.shape == grey.shape and result.dtype == np.float32
    assert np.abs(result - exact_gaussian(grey, 3.0, "replicate")).max() <= 2e-6
    # A channels-first array seen as height x width x channels, and a cropped, strided view.
    planar = rng.random((4, 40, 30), dtype=np.float32)
    view = planar.transpose(1, 2, 0)[::2, 3:]
    result = tridiff.blur(view, 1.5, method="separable")
    assert np.abs(result - exact_gaussian(view, 1.5, "replicate")).max() <= 2e-6
    read_only = planar[0].copy()
    read_only.flags.writeable = False
    tridiff.blur(read_only, 1.0, method="separable")


def test_tiny_and_zero_size_images():
    one = np.full((1, 1, 3), 0.5, np.float32)
    assert np.allclose(tridiff.blur(one, 2.0, method="separable"), 0.5, atol=2e-6)
    assert tridiff.blur(np.zeros((0, 5, 3), np.float32), 2.0).shape == (0, 5, 3)


def test_bad_arguments_are_value_errors():
    image = np.zeros((8, 8, 3), np.float32)
    with pytest.raises(ValueError, match="argument 'method'.*unknown blur method"):
        tridiff.blur(image, 2.0, method="bilateral")
    with pytest.raises(ValueError, match="argument 'sigma'.*outside"):
        tridiff.blur(image, 100.0, method="gaussian-fir")
    with pytest.raises(ValueError, match="argument 'border'.*not supported"):
        tridiff.blur(image, 4.0, method="box", border="mirror")
    with pytest.raises(ValueError, match="argument 'border'.*unknown"):
        tridiff.blur(image, 2.0, method="separable", border="wrap")
    with pytest.raises(ValueError, match="argument 'image'.*dtype"):
        tridiff.blur(image.astype(np.int32), 2.0)
    with pytest.raises(ValueError, match="argument 'image'.*shape"):
        tridiff.blur(np.zeros(8, np.float32), 2.0)
    with pytest.raises(ValueError, match="argument 'method'"):
        tridiff.blur(image, -1.0)  # auto: no method takes it
    with pytest.raises(ValueError, match="argument 'sigma'"):
        tridiff.blur(image, float("nan"), method="separable")
