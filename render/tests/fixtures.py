"""Synthetic run folders for the tests: phases painted on a voxel lattice, every face between
two differently labeled voxels (and between a voxel and the domain boundary) written as two
labeled triangles, in the exact PLY layout of `polyphase run`."""

import json
import os

import numpy as np

from polyphase_render.ply import OUTSIDE, LabeledMesh, write_ply

SCENE_TOML = """name = "fixture"
description = "two-liquid sphere for render tests"
resolution = {n}
background = "air"

[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]

[time]
end = 1.0
frames = {frames}

[velocity]
field = "still"

[[phases]]
name = "air"
density = 1.2
viscosity = 1.8e-5
color = [0.9, 0.95, 1.0]
ior = 1.0

[[phases]]
name = "red"
color = [0.85, 0.15, 0.1]
ior = 1.33

[[phases]]
name = "blue"
color = [0.1, 0.3, 0.85]
ior = 1.45
{extra}"""


def voxel_mesh(labels: np.ndarray, lo, hi) -> LabeledMesh:
    """Labeled boundary mesh of a voxel labeling (cells of equal size spanning lo..hi)."""
    n = np.array(labels.shape)
    h = (np.asarray(hi, float) - np.asarray(lo, float)) / n
    padded = np.full(tuple(n + 2), OUTSIDE, dtype=np.int64)
    padded[1:-1, 1:-1, 1:-1] = labels
    vid = lambda i, j, k: (i * (n[1] + 1) + j) * (n[2] + 1) + k  # noqa: E731
    faces, front, back = [], [], []
    for axis in range(3):
        a = np.moveaxis(padded, axis, 0)
        lower, upper = a[:-1], a[1:]
        # Only interior cells in the other two axes.
        lower, upper = lower[:, 1:-1, 1:-1], upper[:, 1:-1, 1:-1]
        p, q, r = np.nonzero(lower != upper)
        both_out = (lower[p, q, r] == OUTSIDE) & (upper[p, q, r] == OUTSIDE)
        p, q, r = p[~both_out], q[~both_out], r[~both_out]
        corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
        ids = []
        for cq, cr in corners:
            idx = [None, None, None]
            idx[axis] = p
            others = [d for d in range(3) if d != axis]
            idx[others[0]] = q + cq
            idx[others[1]] = r + cr
            ids.append(vid(*idx))
        ids = np.stack(ids, axis=1)
        # (others[0], others[1], axis) is right-handed for axis 0 and 2 (x: y,z; z: x,y) and
        # left-handed for axis 1 (y: x,z): flip so every normal points along +axis.
        if axis == 1:
            ids = ids[:, ::-1]
        faces += [ids[:, [0, 1, 2]], ids[:, [0, 2, 3]]]
        f = upper[p, q, r]
        b = lower[p, q, r]
        front += [f, f]
        back += [b, b]
    gi, gj, gk = np.meshgrid(*(np.arange(m + 1) for m in n), indexing="ij")
    verts = np.stack([gi, gj, gk], axis=-1).reshape(-1, 3) * h + np.asarray(lo, float)
    faces = np.concatenate(faces)
    used, inv = np.unique(faces.ravel(), return_inverse=True)
    return LabeledMesh(verts[used], inv.reshape(-1, 3), np.concatenate(front), np.concatenate(back))


def sphere_labels(n: int, center=(0.5, 0.5, 0.5), radius=0.3, shift=0.0) -> np.ndarray:
    """A sphere of `red` with its upper half (y > centre) `blue`, in `air`."""
    c = (np.arange(n) + 0.5) / n
    x, y, z = np.meshgrid(c, c, c, indexing="ij")
    cx, cy, cz = center
    cx += shift
    inside = (x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2 < radius**2
    labels = np.zeros((n, n, n), dtype=np.int64)
    labels[inside] = 1
    labels[inside & (y > cy)] = 2
    return labels


def make_run(root, n: int = 12, frames: int = 1, extra: str = "") -> str:
    """Writes a run folder with `frames + 1` frames of a sphere moving along x and a stats file."""
    os.makedirs(os.path.join(root, "frames"), exist_ok=True)
    with open(os.path.join(root, "scene.toml"), "w") as f:
        f.write(SCENE_TOML.format(n=n, frames=frames, extra=extra))
    with open(os.path.join(root, "stats.jsonl"), "w") as f:
        for k in range(frames + 1):
            labels = sphere_labels(n, shift=0.1 * k / max(frames, 1))
            write_ply(os.path.join(root, "frames", f"{k:04d}.ply"), voxel_mesh(labels, [0, 0, 0], [1, 1, 1]))
            vols = {name: float((labels == i).sum()) / n**3 for i, name in enumerate(["air", "red", "blue"])}
            line = {"frame": k, "time": k / max(frames, 1), "steps": 1, "phase_volumes": vols,
                    "timings": {"advect": 0.01, "write": 0.001}, "surge_front": 0.2 + 0.1 * k}
            f.write(json.dumps(line) + "\n")
        f.write(json.dumps({"summary": {"frames": frames}}) + "\n")
    return root
