"""The render command: validates the run folder, renders the chosen frames to
`DIR/render/NNNN.exr` and `NNNN.png`, then the movie and the plots. Bad or missing frames are
skipped, named at the end, and make the exit status 1; everything good is still rendered."""

import os
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import frames as frames_mod
from .ply import PlyError, read_ply
from .progress import Progress
from .scene import load_scene


class RunFolderError(Exception):
    """The run folder cannot be rendered at all."""


@dataclass
class Options:
    """What `python -m polyphase_render` was asked to do."""

    run_dir: str
    frames: Optional[list] = None  # None: all
    width: int = 640
    height: int = 480
    spp: int = 64
    variant: str = "auto"
    movie: bool = True
    plots: bool = True
    vol: int = 0  # 0: no .vol export, else voxels along the longest axis
    volume: bool = False  # render the voxelised phases as a coloured smoke instead of surfaces
    tank: Optional[bool] = None  # None: from the scene's hints
    only_missing: bool = False  # keep frames whose EXR and PNG exist (a farmed render's finish)


def _bad_text(bad) -> str:
    return "; ".join(f"{name}: {why}" for name, why in bad)


def run(opts: Options, log) -> int:
    """Renders; returns the exit status (0 all good, 1 some frames bad or missing)."""
    root = opts.run_dir
    if not os.path.isdir(root):
        raise RunFolderError(f"run folder {root} does not exist")
    scene_path = os.path.join(root, "scene.toml")
    if not os.path.isfile(scene_path):
        raise RunFolderError(f"{scene_path} is missing (not a polyphase run folder?)")
    scene = load_scene(scene_path)
    if opts.tank is not None:
        scene.hints.tank = opts.tank
    expected_last = _expected_last(scene_path)
    found = frames_mod.frames_on_disk(os.path.join(root, "frames"))
    present, missing = frames_mod.select(found, opts.frames, expected_last)
    bad = [(f"frames/{n:04d}.ply", "missing") for n in missing]

    # The selected frames are read once up front to validate them; the camera is framed (and
    # the absorption sized) on every frame of the run, so a frame rendered alone (a farmed
    # frame range) is the same image as in a render of the whole run.
    good = []
    for n in present:
        try:
            read_ply(found[n])
        except PlyError as e:
            bad.append((f"frames/{n:04d}.ply", str(e)))
            continue
        good.append(n)
    lo, hi, liquid = _framing(root, scene_path, scene, found)
    if not good:
        msg = "no frame could be read"
        raise RunFolderError(f"{msg}: {_bad_text(bad)}" if bad else f"{msg}: {root}/frames has no NNNN.ply")

    from . import variant as variant_mod

    chosen = variant_mod.choose(opts.variant, log)
    import mitsuba as mi

    from . import build, camera
    from .image import write_outputs

    out_dir = os.path.join(root, "render", "volume") if opts.volume else os.path.join(root, "render")
    os.makedirs(out_dir, exist_ok=True)
    box_lo, box_hi = camera.frame_box(scene, lo, hi)
    view = camera.make_view(scene, box_lo, box_hi, opts.width / opts.height)
    length = scene.absorption_length(liquid)
    log(
        f"rendering {len(good)} frame(s) of {scene.name} at {opts.width}x{opts.height}, "
        f"{opts.spp} spp, {chosen} -> {out_dir}"
    )
    bar = Progress(len(good))
    pngs, render_secs = [], []
    for n in good:
        label = f"frame {n:04d}"
        exr = os.path.join(out_dir, f"{n:04d}.exr")
        png = os.path.join(out_dir, f"{n:04d}.png")
        if opts.only_missing and os.path.isfile(exr) and os.path.isfile(png):
            pngs.append(png)
            bar.step(label + " kept")
            continue
        try:
            mesh = read_ply(found[n])
            t0 = time.monotonic()
            if opts.volume:
                from .vol import volume_shapes

                d = build.base_dict(scene, view, box_lo, box_hi, opts.width, opts.height, opts.spp)
                # Optical depth about 3 across a liquid body of the absorption length.
                d.update(volume_shapes(mesh, scene, opts.vol or 64, os.path.join(out_dir, "grids"), n, 3.0 / length))
            else:
                d = build.scene_dict(
                    mesh, scene, view, box_lo, box_hi, opts.width, opts.height, opts.spp, length
                )
            mscene = mi.load_dict(d)
            img = np.array(mi.render(mscene, spp=opts.spp))
            render_secs.append(time.monotonic() - t0)
            write_outputs(img, exr, png)
            pngs.append(png)
        except (PlyError, RuntimeError, OSError, ValueError) as e:
            bad.append((f"frames/{n:04d}.ply", f"render failed: {str(e).splitlines()[0][:200]}"))
            label += " FAILED"
        bar.step(label)

    if opts.movie:
        from .video import make_movie

        if make_movie(pngs, os.path.join(out_dir, "movie.mp4"), scene.hints.fps, log):
            log(f"movie: {os.path.join(out_dir, 'movie.mp4')}")
    if opts.plots:
        _plots(root, scene, log)
    if opts.vol and not opts.volume:
        from .vol import export_frame

        vol_dir = os.path.join(out_dir, "vol")
        for n in good:
            try:
                export_frame(read_ply(found[n]), scene, opts.vol, vol_dir, n)
            except (PlyError, OSError, ValueError) as e:
                bad.append((f"frames/{n:04d}.ply", f"vol export failed: {e}"))
        log(f"vol grids: {vol_dir}")

    if render_secs:
        log(
            f"rendered {len(render_secs)} frame(s) in {bar.elapsed():.1f} s "
            f"({sum(render_secs) / len(render_secs):.2f} s per frame, {chosen})"
        )
    if bad:
        log(f"error: {len(bad)} frame(s) not rendered: {_bad_text(sorted(bad))}")
        return 1
    return 0


def _framing(root, scene_path, scene, found):
    """(lo, hi, liquid): the box of every frame's liquids and the mean liquid phase volume of
    the first readable frame. Reading every frame costs each task of a farmed render as much
    as the whole run, so the result is kept in `DIR/render/framing.json`, keyed by the size
    and modification time of `scene.toml` and of every frame (any rewrite recomputes it)."""
    import json

    from .build import content_box
    from .geometry import phase_volumes

    def stamp(path):
        st = os.stat(path)
        return [st.st_size, st.st_mtime_ns]

    key = [stamp(scene_path)] + [[n] + stamp(found[n]) for n in sorted(found)]
    cache = os.path.join(root, "render", "framing.json")
    try:
        with open(cache) as f:
            kept = json.load(f)
        if kept["key"] == key:
            box = [None if v is None else np.array(v) for v in (kept["lo"], kept["hi"])]
            return box[0], box[1], kept["liquid"]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    lo, hi, liquid = None, None, None
    for n in sorted(found):
        try:
            mesh = read_ply(found[n])
        except PlyError:
            continue
        if liquid is None:
            vols = [v for i, v in enumerate(phase_volumes(mesh, len(scene.phases)))
                    if i != scene.background and i not in scene.opaque_ids() and v > 0]
            liquid = float(np.mean(vols)) if vols else None
        clo, chi = content_box(mesh, scene)
        if clo is not None:
            lo = clo if lo is None else np.minimum(lo, clo)
            hi = chi if hi is None else np.maximum(hi, chi)
    kept = {"key": key, "liquid": liquid,
            "lo": None if lo is None else lo.tolist(), "hi": None if hi is None else hi.tolist()}
    try:
        os.makedirs(os.path.dirname(cache), exist_ok=True)
        tmp = cache + ".tmp" + str(os.getpid())
        with open(tmp, "w") as f:
            json.dump(kept, f)
        os.replace(tmp, cache)
    except OSError:
        pass  # an unwritable cache only costs the next render the reading
    return lo, hi, liquid


def _expected_last(scene_path):
    """Last frame number the scene promises (`time.frames`), if it says."""
    import tomllib

    try:
        with open(scene_path, "rb") as f:
            n = tomllib.load(f).get("time", {}).get("frames")
        return int(n) if isinstance(n, int) and n >= 0 else None
    except (OSError, ValueError):
        return None


def _plots(root, scene, log):
    stats = os.path.join(root, "stats.jsonl")
    if not os.path.isfile(stats):
        log("note: no stats.jsonl, plots skipped")
        return
    from .plots import StatsError, plot_all

    try:
        written = plot_all(stats, os.path.join(root, "plots"), scene)
    except StatsError as e:
        log(f"warning: plots skipped: {e}")
        return
    if written:
        log(f"plots: {', '.join(os.path.relpath(p, root) for p in written)}")
