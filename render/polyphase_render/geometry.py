"""Splits a labeled frame into one triangle set per phase pair (issue 5, "materials from
physics"): every triangle is oriented so that its normal points from the pair's interior phase
to its exterior phase, as Mitsuba's `dielectric` (int_ior behind the normal) and shape media
(`interior` behind the normal) expect. Faces on the domain boundary become closing faces of the
phase inside (so absorbing media stay closed) or tank walls."""

from dataclasses import dataclass
from typing import Optional

import numpy as np

from .ply import OUTSIDE, LabeledMesh

#: Kinds of triangle sets.
INTERFACE, CLOSING, WALL = "interface", "closing", "wall"


@dataclass
class PairShape:
    """Triangles between two phases, normals pointing from `interior` to `exterior`
    (`exterior` is `OUTSIDE` for faces on the domain boundary)."""

    interior: int
    exterior: int
    kind: str
    vertices: np.ndarray  # (K, 3)
    faces: np.ndarray  # (M, 3)
    normals: Optional[np.ndarray]  # (K, 3) shading normals, or None for flat shading


def _rank(phase, scene, opaque):
    """Which phase of a pair is the interior: opaque before liquid, non-background before the
    background, then the denser, then the higher index (deterministic for equal densities)."""
    return (phase in opaque, phase != scene.background, scene.phases[phase].density, phase)


def split_pairs(mesh: LabeledMesh, scene, tank: bool, smooth: bool) -> list:
    """One `PairShape` per (interior, exterior, kind), in sorted order. Background faces on the
    domain boundary are kept as tank walls (`tank`), or as closing faces where the background is
    opaque (a foam's outer cell), and dropped otherwise. With a cut-away, triangles whose
    centroid lies beyond its plane are left out."""
    n_phases = len(scene.phases)
    opaque = scene.opaque_ids()
    front, back = mesh.front, mesh.back
    valid = (front != back) & ((front < n_phases) | (front == OUTSIDE))
    valid &= (back < n_phases) | (back == OUTSIDE)
    valid &= ~((front == OUTSIDE) & (back == OUTSIDE))
    valid &= np.linalg.norm(face_normals(mesh.vertices, mesh.faces), axis=1) > 0
    if scene.hints.cutaway is not None:
        point, normal = scene.hints.cutaway
        centroids = mesh.vertices[mesh.faces].mean(axis=1)
        valid &= (centroids - point) @ normal <= 0
    idx = np.nonzero(valid)[0]
    f, b = front[idx], back[idx]
    interior = np.empty_like(f)
    exterior = np.empty_like(f)
    ranks = {p: _rank(p, scene, opaque) for p in range(n_phases)}
    ranks[OUTSIDE] = (False, False, -np.inf, -1)
    for p in np.unique(np.concatenate([f, b])):
        for q in np.unique(np.concatenate([f, b])):
            sel = (f == p) & (b == q)
            if not np.any(sel):
                continue
            inner, outer = (p, q) if ranks[p] > ranks[q] else (q, p)
            interior[sel] = inner
            exterior[sel] = outer
    shapes = []
    for key in sorted(set(zip(interior.tolist(), exterior.tolist()))):
        inner, outer = key
        if outer == OUTSIDE and inner == scene.background and inner not in opaque:
            if not tank:
                continue
            kind = WALL
        elif outer == OUTSIDE:
            kind = CLOSING
        else:
            kind = INTERFACE
        sel = (interior == inner) & (exterior == outer)
        tris = mesh.faces[idx[sel]].copy()
        # The normal points into `front`; it must point into the exterior.
        flip = f[sel] == inner
        tris[flip] = tris[flip][:, [0, 2, 1]]
        if smooth and kind == INTERFACE:
            verts, faces, normals = corner_normals(mesh.vertices, tris, np.cos(np.radians(60.0)))
        else:
            verts, faces = compact(mesh.vertices, tris)
            normals = None
        shapes.append(PairShape(inner, outer, kind, verts, faces, normals))
    return shapes


def compact(vertices: np.ndarray, tris: np.ndarray):
    """The vertices `tris` uses, and `tris` re-indexed into them."""
    used, inverse = np.unique(tris.ravel(), return_inverse=True)
    return vertices[used], inverse.reshape(tris.shape).astype(np.int64)


def face_normals(vertices: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Area-weighted (length = twice the area) right-hand normals."""
    p = vertices[tris]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def corner_normals(vertices: np.ndarray, tris: np.ndarray, cos_crease: float):
    """Smooth shading normals that keep creases: each triangle corner averages the area-weighted
    normals of the triangles around its vertex that deviate less than the crease angle from its
    own. Returns unwelded vertices (three per triangle), faces and per-corner normals."""
    m = len(tris)
    fn = face_normals(vertices, tris)
    length = np.linalg.norm(fn, axis=1)
    unit = fn / np.where(length > 0, length, 1.0)[:, None]
    corner_vertex = tris.ravel()
    corner_face = np.repeat(np.arange(m), 3)
    order = np.argsort(corner_vertex, kind="stable")
    sorted_vertex = corner_vertex[order]
    _, start, count = np.unique(sorted_vertex, return_index=True, return_counts=True)
    group_start = np.repeat(start, count)
    group_count = np.repeat(count, count)
    # Every ordered pair (corner i, corner j) of corners that share a vertex.
    i_pos = np.repeat(np.arange(len(order)), group_count)
    offsets = np.arange(len(i_pos)) - np.repeat(np.cumsum(group_count) - group_count, group_count)
    j_pos = np.repeat(group_start, group_count) + offsets
    ci, cj = order[i_pos], order[j_pos]
    fi, fj = corner_face[ci], corner_face[cj]
    keep = np.einsum("ij,ij->i", unit[fi], unit[fj]) >= cos_crease
    normals = np.stack(
        [np.bincount(ci[keep], weights=fn[fj[keep], k], minlength=3 * m) for k in range(3)],
        axis=1,
    )
    nlen = np.linalg.norm(normals, axis=1)
    flat = np.repeat(unit, 3, axis=0)
    normals = np.where((nlen > 0)[:, None], normals / np.where(nlen > 0, nlen, 1.0)[:, None], flat)
    verts = vertices[corner_vertex]
    faces = np.arange(3 * m, dtype=np.int64).reshape(m, 3)
    return verts, faces, normals


def phase_volumes(mesh: LabeledMesh, n_phases: int) -> np.ndarray:
    """Volume of each phase by the divergence theorem over its closed boundary: a triangle adds
    its signed tetrahedron volume to `back` (the normal points out of it) and subtracts it
    from `front`."""
    p = mesh.vertices[mesh.faces]
    tet = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0
    vol = np.zeros(n_phases)
    for labels, sign in ((mesh.back, 1.0), (mesh.front, -1.0)):
        ok = labels < n_phases
        vol += sign * np.bincount(labels[ok], weights=tet[ok], minlength=n_phases)[:n_phases]
    return vol
