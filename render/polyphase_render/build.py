"""Assembles the Mitsuba scene of one frame: pair shapes as in-memory `mi.Mesh`es with their
BSDFs and media, camera, lights and ground. Mitsuba takes one BSDF per shape, so the split into
phase pairs is what gives every interface its own material."""

import numpy as np

from . import camera, materials
from .geometry import split_pairs
from .ply import OUTSIDE


def integrator_dict(max_depth: int = 48) -> dict:
    """Volumetric path tracer with spectral MIS (`volpathmis`): the liquids' absorption differs
    strongly between channels, where plain `volpath` samples one channel's distances and shows
    coloured speckle. Nested dielectrics need many bounces."""
    return {"type": "volpathmis", "max_depth": max_depth, "rr_depth": max_depth}


def _mesh(name, shape, props):
    import mitsuba as mi

    has_normals = shape.normals is not None
    mesh = mi.Mesh(name, len(shape.vertices), len(shape.faces), props, has_vertex_normals=has_normals)
    params = mi.traverse(mesh)
    pos_t, face_t = type(params["vertex_positions"]), type(params["faces"])
    params["vertex_positions"] = pos_t(np.ascontiguousarray(shape.vertices, dtype=np.float32).ravel())
    params["faces"] = face_t(np.ascontiguousarray(shape.faces, dtype=np.uint32).ravel())
    if has_normals:
        params["vertex_normals"] = pos_t(np.ascontiguousarray(shape.normals, dtype=np.float32).ravel())
    params.update()
    return mesh


class MediaCache:
    """One medium object per liquid phase, shared by every shape that bounds it."""

    def __init__(self, scene, length: float):
        self.scene = scene
        self.length = length
        self.cache = {}

    def get(self, phase_id):
        """The medium of `phase_id`, or None for the background, opaque phases and `OUTSIDE`."""
        import mitsuba as mi

        if phase_id == OUTSIDE or not materials.has_medium(phase_id, self.scene):
            return None
        if phase_id not in self.cache:
            self.cache[phase_id] = mi.load_dict(
                materials.medium_dict(self.scene.phases[phase_id], self.length)
            )
        return self.cache[phase_id]


def shapes_dict(mesh, scene, tank: bool, absorption_length: float) -> dict:
    """Mitsuba shape objects of one frame, keyed by a name that says which pair they bound."""
    import mitsuba as mi

    media = MediaCache(scene, absorption_length)
    out = {}
    for k, shape in enumerate(split_pairs(mesh, scene, tank, scene.hints.smooth)):
        props = mi.Properties()
        props["bsdf"] = mi.load_dict(materials.bsdf_dict(shape, scene))
        inner = media.get(shape.interior)
        outer = media.get(shape.exterior)
        if inner is not None:
            props["interior"] = inner
        if outer is not None:
            props["exterior"] = outer
        ext = "outside" if shape.exterior == OUTSIDE else scene.phases[shape.exterior].name
        name = f"{k:03d}_{shape.kind}_{scene.phases[shape.interior].name}_{ext}"
        out[name] = _mesh(name, shape, props)
    return out


def content_box(mesh, scene):
    """Bounding box of the vertices of faces that touch a non-background phase, or (None, None)."""
    bg = scene.background
    touch = ((mesh.front != bg) & (mesh.front != OUTSIDE)) | ((mesh.back != bg) & (mesh.back != OUTSIDE))
    if not np.any(touch):
        return None, None
    v = mesh.vertices[np.unique(mesh.faces[touch].ravel())]
    return v.min(axis=0), v.max(axis=0)


def base_dict(scene, view, box_lo, box_hi, width, height, spp) -> dict:
    """Integrator, camera, lights and ground: everything of a frame but its liquids."""
    d = {
        "type": "scene",
        "integrator": integrator_dict(),
        "sensor": camera.sensor_dict(view, width, height, spp),
    }
    d.update(camera.environment(scene, view, box_lo, box_hi))
    return d


def scene_dict(mesh, scene, view, box_lo, box_hi, width, height, spp, absorption_length) -> dict:
    """The whole Mitsuba scene description of one frame (ready for `mi.load_dict`)."""
    d = base_dict(scene, view, box_lo, box_hi, width, height, spp)
    d.update(shapes_dict(mesh, scene, scene.hints.tank, absorption_length))
    return d
