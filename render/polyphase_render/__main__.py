"""`python -m polyphase_render DIR [options]`: render a polyphase run folder (issue 5)."""

import argparse
import sys

from .frames import RangeError, parse_range
from .pipeline import Options, RunFolderError, run
from .scene import SceneError


def parse_args(argv):
    """Command-line options -> `Options`."""
    p = argparse.ArgumentParser(
        prog="polyphase render",
        description="Render a polyphase run folder with Mitsuba 3: DIR/render/NNNN.exr, NNNN.png, "
        "movie.mp4 and plots of stats.jsonl in DIR/plots.",
    )
    p.add_argument("dir", help="run folder written by `polyphase run`")
    p.add_argument("--frames", default="all", help="frames to render: all (default), N, A-B, or a comma list")
    p.add_argument("--width", type=int, default=640, help="image width in pixels (default 640)")
    p.add_argument("--height", type=int, default=480, help="image height in pixels (default 480)")
    p.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    p.add_argument("--variant", default="auto", help="Mitsuba variant: auto (llvm_ad_rgb if it works, else scalar_rgb), scalar_rgb, llvm_ad_rgb")
    p.add_argument("--no-movie", action="store_true", help="do not assemble movie.mp4")
    p.add_argument("--no-plots", action="store_true", help="do not plot stats.jsonl")
    p.add_argument("--only-missing", action="store_true", help="render only the frames whose EXR or PNG is missing; keep the others (for the movie)")
    p.add_argument("--vol", type=int, default=0, metavar="N", help="also export per-phase occupancy grids as Mitsuba .vol files, N voxels along the longest axis")
    p.add_argument("--volume", action="store_true", help="render the phases voxelised (.vol grids, --vol voxels, default 64) as coloured smoke into DIR/render/volume, for debugging")
    tank = p.add_mutually_exclusive_group()
    tank.add_argument("--tank", dest="tank", action="store_const", const=True, help="draw the domain walls as glass")
    tank.add_argument("--no-tank", dest="tank", action="store_const", const=False, help="do not draw the domain walls")
    a = p.parse_args(argv)
    for name in ("width", "height", "spp"):
        if getattr(a, name) < 1:
            p.error(f"--{name} must be at least 1")
    if a.vol < 0:
        p.error("--vol must be positive")
    try:
        frames = parse_range(a.frames)
    except RangeError as e:
        p.error(str(e))
    return Options(
        run_dir=a.dir, frames=frames, width=a.width, height=a.height, spp=a.spp, variant=a.variant,
        movie=not a.no_movie, plots=not a.no_plots, vol=a.vol, volume=a.volume, tank=a.tank,
        only_missing=a.only_missing,
    )


def main(argv=None) -> int:
    """Entry point; returns the exit status."""
    opts = parse_args(sys.argv[1:] if argv is None else argv)

    def log(text):
        print(text, file=sys.stderr, flush=True)

    try:
        return run(opts, log)
    except (RunFolderError, SceneError, ValueError) as e:
        log(f"error: {e}")
        return 2
    except ImportError as e:
        log(f"error: {e}; the render environment looks broken: delete render/.venv to reinstall it")
        return 2
    except KeyboardInterrupt:
        log("interrupted")
        return 130


if __name__ == "__main__":
    sys.exit(main())
