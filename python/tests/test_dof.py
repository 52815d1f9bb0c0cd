"""tridiff.dof: the circle of confusion against the thin-lens formula computed here, and the
invariant that an image entirely in focus comes back unchanged, for every method."""
import numpy as np
import pytest

import tridiff

METHODS = [m["name"] for m in tridiff.dof_methods()]
KEEPS_SHARP = {m["name"]: m["keeps_sharp"] for m in tridiff.dof_methods()}


def thin_lens_coc(depth, focus, f_number, focal_length, sensor_width, width, max_coc):
    """Seed 000 eq. 3.2: c = A f (d - d_f) / (d (d_f - f)) on the sensor, A = f / N, in pixels,
    signed (negative in front of the focus), clamped to max_coc. Lengths in mm."""
    f, d, df = focal_length, depth * 1000.0, focus * 1000.0
    sensor = (f / f_number) * f * (d - df) / (d * (df - f))
    return np.clip(sensor * width / sensor_width, -max_coc, max_coc)


def scene(height=40, width=56, channels=3):
    rng = np.random.default_rng(5)
    color = rng.random((height, width, channels), dtype=np.float32)
    depth = np.linspace(1.0, 10.0, width, dtype=np.float32)[None, :].repeat(height, 0)
    return color, depth


def test_coc_is_the_thin_lens():
    color, depth = scene()
    lens = dict(focus=2.5, f_number=2.0, focal_length=85.0, sensor_width=36.0, max_coc=12.0)
    image, coc = tridiff.dof(color, depth, return_coc=True, **lens)
    assert image.shape == color.shape and image.dtype == np.float32
    assert coc.shape == depth.shape
    expected = thin_lens_coc(depth.astype(np.float64), width=color.shape[1], **lens)
    assert np.abs(coc - expected).max() <= 1e-4 * 12.0
    assert coc.min() < 0 < coc.max()


@pytest.mark.parametrize("method", METHODS)
def test_in_focus_image_is_unchanged(method):
    color, _ = scene()
    depth = np.full(color.shape[:2], 3.0, np.float32)  # every pixel at the focus distance
    image = tridiff.dof(color, depth, focus=3.0, method=method)
    # Bit for bit where the method promises it; else within the 8-bit registers of the IPF
    # hardware model (half a step of 1/255).
    tolerance = 0 if KEEPS_SHARP[method] else 0.5 / 255 + 1e-6
    assert np.abs(image - color).max() <= tolerance


@pytest.mark.parametrize("method", METHODS)
def test_out_of_focus_blurs_and_keeps_the_mean(method):
    color, depth = scene()
    grey = color.mean(axis=2, keepdims=True).repeat(3, axis=2)  # any channel count works
    image = tridiff.dof(grey, depth, focus=1.5, method=method, focal_length=135.0, f_number=1.4,
                        max_coc=8.0)
    # Blurred: the far half (large CoC) loses most of its pixel-to-pixel variation.
    far = slice(color.shape[1] // 2, None)
    assert np.abs(np.diff(image[:, far], axis=1)).mean() < 0.7 * np.abs(
        np.diff(grey[:, far], axis=1)).mean()
    assert np.all(np.isfinite(image))
    assert abs(image.mean() - grey.mean()) < 0.05


def test_grey_float64_inputs():
    color, depth = scene(channels=1)
    image = tridiff.dof(color[:, :, 0].astype(np.float64), depth.astype(np.float64), focus=2.0)
    assert image.shape == depth.shape and image.dtype == np.float32


def test_bad_arguments_are_value_errors():
    color, depth = scene()
    with pytest.raises(ValueError, match="argument 'depth'.*sizes differ"):
        tridiff.dof(color, depth[:, :-1])
    with pytest.raises(ValueError, match="argument 'focal_length'"):
        tridiff.dof(color, depth, focal_length=-50.0)
    with pytest.raises(ValueError, match="argument 'focus'"):
        tridiff.dof(color, depth, focus=0.01)
    with pytest.raises(ValueError, match="argument 'method'.*unknown"):
        tridiff.dof(color, depth, method="tilt-shift")
    bad_depth = depth.copy()
    bad_depth[3, 4] = np.nan
    with pytest.raises(ValueError, match="argument 'depth'"):
        tridiff.dof(color, bad_depth)
    with pytest.raises(ValueError, match="argument 'color'.*dtype"):
        tridiff.dof(color.astype(np.uint8), depth)
