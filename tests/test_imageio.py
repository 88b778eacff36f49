"""
The sRGB transfer function of the previews and the explorer's colour picker
(mi_brdfs.imageio): both directions against Mitsuba's own conversion of an 8-bit sRGB bitmap.
"""

import mitsuba as mi
import numpy as np

from mi_brdfs.imageio import from_srgb8, to_srgb8


def _mitsuba_linear(values: np.ndarray) -> np.ndarray:
    """Mitsuba's linear values of 8-bit sRGB ``values`` (a bitmap marked sRGB, converted)."""
    bitmap = mi.Bitmap(np.repeat(values.astype(np.uint8)[:, None, None], 3, axis=2),
                       mi.Bitmap.PixelFormat.RGB)
    assert bitmap.srgb_gamma()
    linear = bitmap.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    return np.array(linear)[:, 0, 0]


def test01_srgb_both_ways_as_mitsuba_converts(variant_scalar_rgb):
    """Every 8-bit value: from_srgb8 is Mitsuba's linear value (to float32 rounding), and
    to_srgb8 takes it back to the same 8 bits."""
    values = np.arange(256)
    linear = from_srgb8(values)
    np.testing.assert_allclose(linear, _mitsuba_linear(values), rtol=2e-6, atol=1e-7)
    back = to_srgb8(linear.reshape(-1, 1, 1).astype(np.float32))[:, 0, 0]
    np.testing.assert_array_equal(back, values)
