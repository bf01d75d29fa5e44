"""Image outputs: the linear render as OpenEXR and a tone-mapped 8-bit sRGB PNG."""

import numpy as np


def tonemap(linear: np.ndarray, exposure: float = 1.0, white: float = 4.0) -> np.ndarray:
    """Extended Reinhard on each channel (values at `white` map to 1), then the sRGB transfer
    curve, as 8-bit. Non-finite pixels become black."""
    x = np.nan_to_num(np.asarray(linear, dtype=np.float64)[..., :3], nan=0.0, posinf=white, neginf=0.0)
    x = np.maximum(x * exposure, 0.0)
    y = x * (1.0 + x / (white * white)) / (1.0 + x)
    y = np.clip(y, 0.0, 1.0)
    srgb = np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1.0 / 2.4) - 0.055)
    return np.round(srgb * 255.0).astype(np.uint8)


def write_outputs(linear: np.ndarray, exr_path, png_path) -> None:
    """Writes `exr_path` (float32 linear RGB) and `png_path` (tone-mapped) atomically."""
    import os

    import mitsuba as mi

    rgb = np.ascontiguousarray(np.asarray(linear, dtype=np.float32)[..., :3])
    for path, bitmap in (
        (exr_path, mi.Bitmap(rgb, mi.Bitmap.PixelFormat.RGB)),
        (png_path, mi.Bitmap(tonemap(rgb), mi.Bitmap.PixelFormat.RGB)),
    ):
        tmp = str(path) + ".tmp" + os.path.splitext(str(path))[1]
        bitmap.write(tmp)
        os.replace(tmp, path)
