"""Mitsuba materials derived from the phases' physics (issue 5): a `dielectric` between two
phases with their indices of refraction (a `null` BSDF where they are equal, so the boundary
only switches media), a homogeneous purely absorbing medium per liquid whose transmittance over
the scene's absorption length equals the phase colour (Beer–Lambert), and a rough plastic for
phases the scene marks opaque (two-sided under a cut-away)."""

import math

from .geometry import WALL
from .ply import OUTSIDE

#: Transmittance per channel is clamped to this range so that no channel is fully black or
#: fully clear (sigma_t stays finite and positive).
_T_MIN, _T_MAX = 0.02, 0.98
#: Index of refraction of the tank's glass walls.
GLASS_IOR = 1.5


def sigma_t(color, length: float):
    """Extinction per channel such that exp(-sigma_t * length) equals the colour (Beer–Lambert)."""
    return [-math.log(min(max(c, _T_MIN), _T_MAX)) / length for c in color]


def medium_dict(phase, length: float) -> dict:
    """A homogeneous, purely absorbing medium for a liquid phase. Mitsuba bounds RGB values to
    [0, 1], so the extinction is written as a normalised colour times `scale`."""
    s = sigma_t(phase.color, length)
    peak = max(s)
    return {
        "type": "homogeneous",
        "albedo": 0.0,
        "sigma_t": {"type": "rgb", "value": [c / peak for c in s]},
        "scale": peak,
    }


def has_medium(phase_id: int, scene) -> bool:
    """Liquids carry a medium; the background and opaque phases do not."""
    return phase_id != scene.background and phase_id not in scene.opaque_ids()


def ior_of(phase_id: int, scene) -> float:
    """Index of refraction; beyond the domain boundary (`OUTSIDE`) it is air's."""
    return 1.0 if phase_id == OUTSIDE else scene.phases[phase_id].ior


def bsdf_dict(shape, scene) -> dict:
    """The BSDF of one pair shape (normals point interior to exterior)."""
    if shape.kind == WALL:
        return {"type": "thindielectric", "int_ior": GLASS_IOR, "ext_ior": 1.0}
    inner = scene.phases[shape.interior]
    outer_ior = ior_of(shape.exterior, scene)
    if shape.interior in scene.opaque_ids():
        plastic = {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": 0.15,
            "diffuse_reflectance": {"type": "rgb", "value": [min(max(c, 0.0), 1.0) for c in inner.color]},
            "int_ior": 1.49,
            "ext_ior": outer_ior,
        }
        # A cut-away opens shells toward the camera: their inner sides must show too.
        if scene.hints.cutaway is not None:
            return {"type": "twosided", "material": plastic}
        return plastic
    if abs(inner.ior - outer_ior) < 1e-9:
        return {"type": "null"}
    return {"type": "dielectric", "int_ior": inner.ior, "ext_ior": outer_ior}
