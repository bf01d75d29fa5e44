"""Voxel grids of a frame as Mitsuba `.vol` files (issue 5, "volume rendering option"): the
program writes no phase grids yet (OpenVDB output comes with issue 4), so the phase of every
voxel centre is recovered from the labeled mesh by casting axis-parallel rays (scan conversion
along x) and the occupancy χ of each non-background phase is written as a float32 grid.

VOL version 3 layout (little endian): b"VOL", version byte 3, int32 encoding (1 = float32),
int32 xres, yres, zres, int32 channels, float32 bounding box (xmin, ymin, zmin, xmax, ymax,
zmax), then the values with x varying fastest, then y, then z."""

import os
import struct

import numpy as np

from .ply import OUTSIDE


def write_vol(path, data: np.ndarray, lo, hi) -> None:
    """Writes `data` indexed [x, y, z] or [x, y, z, channel] as a float32 VOL v3 file."""
    grid = np.asarray(data, dtype="<f4")
    if grid.ndim == 3:
        grid = grid[..., None]
    nx, ny, nz, nc = grid.shape
    header = b"VOL" + bytes([3]) + struct.pack("<5i", 1, nx, ny, nz, nc)
    header += struct.pack("<6f", *[float(c) for c in lo], *[float(c) for c in hi])
    tmp = str(path) + ".tmp"
    with open(tmp, "wb") as f:
        f.write(header)
        # x fastest: memory order [z][y][x][c].
        f.write(np.ascontiguousarray(grid.transpose(2, 1, 0, 3)).tobytes())
    os.replace(tmp, path)


def read_vol(path):
    """(data [x, y, z, channel], lo, hi) of a float32 VOL v3 file (for tests and debugging)."""
    with open(path, "rb") as f:
        raw = f.read()
    if raw[:3] != b"VOL" or raw[3] != 3:
        raise ValueError(f"{path}: not a VOL version 3 file")
    enc, nx, ny, nz, nc = struct.unpack_from("<5i", raw, 4)
    if enc != 1:
        raise ValueError(f"{path}: encoding {enc} is not float32")
    box = struct.unpack_from("<6f", raw, 24)
    data = np.frombuffer(raw, dtype="<f4", offset=48, count=nx * ny * nz * nc)
    return data.reshape(nz, ny, nx, nc).transpose(2, 1, 0, 3), np.array(box[:3]), np.array(box[3:])


def grid_shape(lo, hi, longest: int):
    """Voxel counts with `longest` voxels along the longest axis and cubic voxels."""
    ext = np.asarray(hi, float) - np.asarray(lo, float)
    h = ext.max() / longest
    return tuple(int(max(1, round(e / h))) for e in ext)


def voxel_phases(mesh, lo, hi, shape, fill: int) -> np.ndarray:
    """Phase id of every voxel centre: for each (y, z) column the mesh crossings along +x are
    sorted, and a centre takes the phase on the -x side of the next crossing after it (the +x
    side of the last one beyond). Columns without crossings take `fill`."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    nx, ny, nz = shape
    h = (hi - lo) / np.array(shape)
    # Sample columns are nudged off the lattice by an irrational fraction of a voxel so that
    # no column passes exactly through a mesh edge or vertex.
    jitter = np.array([0.0, np.sqrt(2) - 1.4, np.sqrt(3) - 1.7]) * 1e-3
    p = mesh.vertices[mesh.faces]  # (M, 3, 3)
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    # Candidate (triangle, j, k) pairs from each triangle's (y, z) bounding box.
    def index_range(axis):
        t_lo = (np.minimum(np.minimum(a[:, axis], b[:, axis]), c[:, axis]) - lo[axis]) / h[axis] - 0.5 - jitter[axis]
        t_hi = (np.maximum(np.maximum(a[:, axis], b[:, axis]), c[:, axis]) - lo[axis]) / h[axis] - 0.5 - jitter[axis]
        i0 = np.clip(np.ceil(t_lo), 0, shape[axis]).astype(np.int64)
        i1 = np.clip(np.floor(t_hi), -1, shape[axis] - 1).astype(np.int64)
        return i0, np.maximum(i1 - i0 + 1, 0)

    j0, nj = index_range(1)
    k0, nk = index_range(2)
    count = nj * nk
    tri = np.repeat(np.arange(len(p)), count)
    local = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    j = j0[tri] + local % np.maximum(nj[tri], 1)
    k = k0[tri] + local // np.maximum(nj[tri], 1)
    y = lo[1] + (j + 0.5 + jitter[1]) * h[1]
    z = lo[2] + (k + 0.5 + jitter[2]) * h[2]
    # 2D barycentric coordinates in the (y, z) projection.
    ay, az = a[tri, 1], a[tri, 2]
    by, bz = b[tri, 1], b[tri, 2]
    cy, cz = c[tri, 1], c[tri, 2]
    det = (by - ay) * (cz - az) - (cy - ay) * (bz - az)
    ok = det != 0
    safe = np.where(ok, det, 1.0)
    u = ((y - ay) * (cz - az) - (cy - ay) * (z - az)) / safe
    v = ((by - ay) * (z - az) - (y - ay) * (bz - az)) / safe
    ok &= (u >= 0) & (v >= 0) & (u + v <= 1)
    tri, j, k, u, v, det = tri[ok], j[ok], k[ok], u[ok], v[ok], det[ok]
    x = a[tri, 0] + u * (b[tri, 0] - a[tri, 0]) + v * (c[tri, 0] - a[tri, 0])
    # The normal's x component has the sign of det ((b-a) x (c-a)).x; a normal along +x points
    # into `front`, so the -x side holds `back`.
    minus_side = np.where(det > 0, mesh.back[tri], mesh.front[tri])
    plus_side = np.where(det > 0, mesh.front[tri], mesh.back[tri])
    column = j * nz + k
    order = np.lexsort((x, column))
    column, x, minus_side, plus_side = column[order], x[order], minus_side[order], plus_side[order]
    out = np.full((nx, ny, nz), fill, dtype=np.int64)
    xs = lo[0] + (np.arange(nx) + 0.5) * h[0]
    starts = np.searchsorted(column, np.arange(ny * nz), side="left")
    ends = np.searchsorted(column, np.arange(ny * nz), side="right")
    for col in np.nonzero(ends > starts)[0]:
        s, e = starts[col], ends[col]
        nxt = np.searchsorted(x[s:e], xs, side="right")
        phases = np.where(nxt < e - s, minus_side[s:e][np.minimum(nxt, e - s - 1)], plus_side[e - 1])
        out[:, col // nz, col % nz] = phases
    out[out == OUTSIDE] = fill
    return out


def occupancy(mesh, scene, longest: int, supersample: int = 2) -> np.ndarray:
    """Volume fraction of every phase per voxel, [x, y, z, phase]: the phase of
    `supersample`³ sub-voxel centres per voxel, averaged (smooth edges for rendering)."""
    shape = grid_shape(scene.lo, scene.hi, longest)
    fine = tuple(n * supersample for n in shape)
    ids = voxel_phases(mesh, scene.lo, scene.hi, fine, scene.background)
    n = len(scene.phases)
    one_hot = np.zeros(fine + (n,), dtype=np.float32)
    np.put_along_axis(one_hot, ids[..., None], 1.0, axis=3)
    s = supersample
    return one_hot.reshape(shape[0], s, shape[1], s, shape[2], s, n).mean(axis=(1, 3, 5))


def export_frame(mesh, scene, longest: int, out_dir, frame: int) -> list:
    """Writes `NNNN_<phase>.vol` (volume fraction χ in [0, 1]) for every non-background phase
    present; returns the paths."""
    os.makedirs(out_dir, exist_ok=True)
    chi = occupancy(mesh, scene, longest)
    paths = []
    for i, phase in enumerate(scene.phases):
        if i == scene.background or not np.any(chi[..., i] > 0):
            continue
        path = os.path.join(out_dir, f"{frame:04d}_{phase.name}.vol")
        write_vol(path, chi[..., i], scene.lo, scene.hi)
        paths.append(path)
    return paths


def volume_shapes(mesh, scene, longest: int, out_dir, frame: int, density: float) -> dict:
    """A smoke-like debug view of a frame: the domain box holding a heterogeneous medium whose
    extinction is the non-background volume fraction times `density` (per metre) and whose
    albedo is the phase colours mixed by volume fraction. Writes the two grids it uses."""
    import mitsuba as mi

    os.makedirs(out_dir, exist_ok=True)
    chi = occupancy(mesh, scene, longest)
    liquid = 1.0 - chi[..., scene.background]
    colors = np.array([p.color for p in scene.phases], dtype=np.float32)
    colors[scene.background] = 0.0
    albedo = np.einsum("xyzp,pc->xyzc", chi, colors) / np.maximum(liquid, 1e-6)[..., None]
    sigma_path = os.path.join(out_dir, f"{frame:04d}_density.vol")
    albedo_path = os.path.join(out_dir, f"{frame:04d}_albedo.vol")
    write_vol(sigma_path, liquid, scene.lo, scene.hi)
    write_vol(albedo_path, np.clip(albedo, 0.0, 1.0), scene.lo, scene.hi)
    lo = [float(c) for c in scene.lo]
    ext = [float(c) for c in scene.extent]
    grid_to_world = mi.ScalarTransform4f().translate(lo) @ mi.ScalarTransform4f().scale(ext)
    center = [float(c) for c in scene.center]
    medium = {
        "type": "heterogeneous",
        "sigma_t": {"type": "gridvolume", "filename": sigma_path, "to_world": grid_to_world},
        "albedo": {"type": "gridvolume", "filename": albedo_path, "to_world": grid_to_world},
        "scale": density,
    }
    return {
        "volume": {
            "type": "cube",
            "to_world": mi.ScalarTransform4f().translate(center)
            @ mi.ScalarTransform4f().scale([0.5 * e for e in ext]),
            "bsdf": {"type": "null"},
            "interior": medium,
        }
    }
