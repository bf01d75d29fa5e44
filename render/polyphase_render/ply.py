"""Reader for the labeled PLY frames written by `polyphase run` (binary little endian, double
vertices, uchar/uint triangle lists, ushort `front`/`back` phase labels). Every malformation is
reported as a `PlyError` with a one-line reason, so a bad frame can be named and skipped."""

from dataclasses import dataclass

import numpy as np

#: Label of the pseudo-phase beyond the domain boundary (faces closing the mesh).
OUTSIDE = 65535

_EXPECTED = [
    "ply",
    "format binary_little_endian 1.0",
    None,  # element vertex N
    "property double x",
    "property double y",
    "property double z",
    None,  # element face M
    "property list uchar uint vertex_indices",
    "property ushort front",
    "property ushort back",
    "end_header",
]


class PlyError(Exception):
    """A frame file that is missing, truncated or not in the labeled-mesh layout."""


@dataclass
class LabeledMesh:
    """Triangles with the phase on each side: `front` is the phase the right-hand normal points
    into, `back` the other side."""

    vertices: np.ndarray  # (N, 3) float64
    faces: np.ndarray  # (M, 3) int64
    front: np.ndarray  # (M,) int64
    back: np.ndarray  # (M,) int64


def read_ply(path) -> LabeledMesh:
    """Reads one frame; raises `PlyError` naming what is wrong."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise PlyError(f"cannot read: {e.strerror or e}") from None
    end = data.find(b"end_header\n")
    if end < 0:
        raise PlyError("no PLY header (end_header missing)")
    try:
        header = data[:end].decode("ascii").split("\n") + ["end_header"]
    except UnicodeDecodeError:
        raise PlyError("header is not ASCII") from None
    lines = [ln.strip() for ln in header if ln.strip() and not ln.startswith("comment")]
    if len(lines) != len(_EXPECTED):
        raise PlyError(f"unexpected header ({len(lines)} lines, expected {len(_EXPECTED)})")
    counts = []
    for got, want in zip(lines, _EXPECTED):
        if want is None:
            parts = got.split()
            if len(parts) != 3 or parts[0] != "element" or not parts[2].isdigit():
                raise PlyError(f"bad header line {got!r}")
            counts.append(int(parts[2]))
        elif got != want:
            raise PlyError(f"bad header line {got!r} (expected {want!r})")
    n, m = counts
    body = memoryview(data)[end + len("end_header\n"):]
    vsize = 24 * n
    fsize = 17 * m  # uchar count, 3 uint indices, 2 ushort labels
    if len(body) < vsize + fsize:
        raise PlyError(f"truncated: {len(body)} body bytes, expected {vsize + fsize}")
    if len(body) > vsize + fsize:
        raise PlyError(f"{len(body) - vsize - fsize} bytes of trailing garbage")
    vertices = np.frombuffer(body[:vsize], dtype="<f8").reshape(n, 3).astype(np.float64)
    ftype = np.dtype([("k", "u1"), ("i", "<u4", (3,)), ("front", "<u2"), ("back", "<u2")])
    rec = np.frombuffer(body[vsize:vsize + fsize], dtype=ftype)
    if m and np.any(rec["k"] != 3):
        raise PlyError("a face is not a triangle")
    faces = rec["i"].astype(np.int64)
    if m and faces.max() >= n:
        raise PlyError(f"face index {int(faces.max())} out of range ({n} vertices)")
    if not np.all(np.isfinite(vertices)):
        raise PlyError("non-finite vertex coordinates")
    return LabeledMesh(vertices, faces, rec["front"].astype(np.int64), rec["back"].astype(np.int64))


def write_ply(path, mesh: LabeledMesh) -> None:
    """Writes a mesh in the same layout (used by tests and fixtures)."""
    n, m = len(mesh.vertices), len(mesh.faces)
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment polyphase labeled mesh\n"
        f"element vertex {n}\nproperty double x\nproperty double y\nproperty double z\n"
        f"element face {m}\nproperty list uchar uint vertex_indices\n"
        "property ushort front\nproperty ushort back\nend_header\n"
    )
    ftype = np.dtype([("k", "u1"), ("i", "<u4", (3,)), ("front", "<u2"), ("back", "<u2")])
    rec = np.zeros(m, dtype=ftype)
    rec["k"] = 3
    rec["i"] = mesh.faces
    rec["front"] = mesh.front
    rec["back"] = mesh.back
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.asarray(mesh.vertices, dtype="<f8").tobytes())
        f.write(rec.tobytes())
