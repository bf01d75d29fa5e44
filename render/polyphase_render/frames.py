"""Which frames of a run folder to render: the `--frames` range syntax, the frames present on
disk, and the ones that are expected but missing."""

import os
import re


class RangeError(ValueError):
    """A `--frames` value that cannot be parsed."""


def parse_range(text: str):
    """`all` -> None; otherwise a sorted list from comma-separated `N` or `A-B` (inclusive)."""
    text = text.strip()
    if text in ("", "all"):
        return None
    out = set()
    for item in text.split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", item)
        if not m:
            raise RangeError(f"bad frame range {item.strip()!r} (use e.g. 0-10,12)")
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) is not None else a
        if b < a:
            raise RangeError(f"bad frame range {item.strip()!r}: end before start")
        out.update(range(a, b + 1))
    return sorted(out)


def frames_on_disk(frames_dir) -> dict:
    """Frame number -> path of every `NNNN.ply` in `frames_dir`."""
    found = {}
    try:
        names = os.listdir(frames_dir)
    except OSError:
        return found
    for name in names:
        m = re.fullmatch(r"(\d+)\.ply", name)
        if m:
            found[int(m.group(1))] = os.path.join(frames_dir, name)
    return found


def select(found: dict, requested, expected_last):
    """(to_render, missing): the requested frames (default: 0 up to the last expected or found
    frame) that exist, and those that do not."""
    if requested is None:
        last = max([expected_last if expected_last is not None else -1] + list(found))
        requested = list(range(0, last + 1))
    present = [n for n in requested if n in found]
    missing = [n for n in requested if n not in found]
    return present, missing
