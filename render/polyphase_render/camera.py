"""Camera, lights and ground presets computed from the domain box and the frames' content, each
overridable by the scene's `[render]` hints (issue 5, "scene presets"). Lighting is
environment-free: a constant emitter plus one rectangular area light above the scene."""

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class View:
    """Where the camera is and what it frames."""

    origin: np.ndarray
    target: np.ndarray
    up: np.ndarray
    fov: float  # horizontal, degrees
    radius: float  # half-diagonal of the framed box


def basis(up: np.ndarray):
    """(side, up, front) unit vectors: `front` is the world axis closest to +z orthogonal to up
    (+x when up is along z), so y-up scenes are seen from +z with x to the right."""
    cand = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    front = cand - up * np.dot(cand, up)
    front /= np.linalg.norm(front)
    side = np.cross(up, front)
    return side, up, front


def frame_box(scene, content_lo, content_hi):
    """The box the camera frames: the content's bounding box padded by 5 % (at least a fiftieth
    of the domain), inside the domain; the whole domain for tanks or when there is no content."""
    if scene.hints.tank or content_lo is None:
        return scene.lo.copy(), scene.hi.copy()
    pad = np.maximum(0.05 * (content_hi - content_lo), 0.02 * scene.extent.max())
    return np.maximum(content_lo - pad, scene.lo), np.minimum(content_hi + pad, scene.hi)


def make_view(scene, box_lo, box_hi, aspect: float) -> View:
    """The preset camera: three-quarter view from the front, right and above for 3D scenes,
    straight on along -front for slabs; the framed box's bounding sphere fills the frame."""
    h = scene.hints
    up = h.up
    side, _, front = basis(up)
    target = h.camera_target if h.camera_target is not None else 0.5 * (box_lo + box_hi)
    if scene.slab:
        # A slab is flat: frame its rectangle, not its bounding sphere.
        ext = box_hi - box_lo
        half_w = 0.5 * max(abs(np.dot(ext, side)), abs(np.dot(ext, up)) * aspect) * 1.08
        radius = half_w
        direction = front
    else:
        radius = 0.5 * float(np.linalg.norm(box_hi - box_lo))
        direction = 0.8 * side + 0.55 * up + 1.0 * front
        direction /= np.linalg.norm(direction)
    half_x = math.radians(h.fov) / 2
    half_y = math.atan(math.tan(half_x) / aspect)
    if scene.slab:
        dist = radius / math.tan(half_x)
    else:
        dist = radius / math.sin(min(half_x, half_y)) * 1.02
    origin = h.camera_origin if h.camera_origin is not None else target + dist * direction
    return View(origin, target, up, h.fov, radius)


def _look_at(origin, target, up):
    import mitsuba as mi

    return mi.ScalarTransform4f().look_at(
        origin=[float(c) for c in origin], target=[float(c) for c in target], up=[float(c) for c in up]
    )


def sensor_dict(view: View, width: int, height: int, spp: int) -> dict:
    """Perspective camera with an HDR film (linear RGB)."""
    return {
        "type": "perspective",
        "fov": view.fov,
        "fov_axis": "x",
        "near_clip": max(1e-4, 1e-3 * view.radius),
        "far_clip": 1e4 * view.radius,
        "to_world": _look_at(view.origin, view.target, view.up),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {
            "type": "hdrfilm",
            "width": width,
            "height": height,
            "rfilter": {"type": "gaussian"},
            "pixel_format": "rgb",
        },
    }


def environment(scene, view: View, box_lo, box_hi) -> dict:
    """Lights and ground: constant ambient, a rectangular light above the framed box, and a
    checkered ground plane just below the domain (3D) or a white backdrop behind a slab."""
    import mitsuba as mi

    h = scene.hints
    up = h.up
    side, _, front = basis(up)
    center = 0.5 * (box_lo + box_hi)
    size = max(float(np.linalg.norm(box_hi - box_lo)), 1e-6)
    out = {"ambient": {"type": "constant", "radiance": {"type": "rgb", "value": [h.ambient] * 3}}}
    if h.light > 0:
        # A large, soft light: small bright lights seen through dielectrics make fireflies.
        light_pos = center + up * (1.5 * size) + front * (0.5 * size) + side * (0.3 * size)
        out["key_light"] = {
            "type": "rectangle",
            "to_world": _look_at(light_pos, center, front)
            @ mi.ScalarTransform4f().scale([2.0 * size, 2.0 * size, 1.0]),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [h.light] * 3}},
        }
    if scene.slab:
        depth = float(np.dot(scene.lo - center, front)) - 0.05 * size
        pos = center + front * depth
        out["backdrop"] = {
            "type": "rectangle",
            "to_world": _look_at(pos, pos + front, up) @ mi.ScalarTransform4f().scale([10 * size] * 3),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}},
        }
    elif h.ground:
        floor = float(np.dot(scene.lo, up)) - 1e-3 * size
        pos = center + up * (floor - float(np.dot(center, up)))
        extent = 20.0 * size
        cells = extent / (0.125 * float(scene.extent.max()))
        out["ground"] = {
            "type": "rectangle",
            "to_world": _look_at(pos, pos + up, front) @ mi.ScalarTransform4f().scale([extent] * 3),
            "bsdf": {
                "type": "diffuse",
                "reflectance": {
                    "type": "checkerboard",
                    "color0": {"type": "rgb", "value": [0.75, 0.75, 0.75]},
                    "color1": {"type": "rgb", "value": [0.35, 0.35, 0.38]},
                    "to_uv": mi.ScalarTransform3f().scale([cells, cells]),
                },
            },
        }
    return out
