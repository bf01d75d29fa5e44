"""Movie assembly with ffmpeg: H.264, yuv420p, sizes padded to even numbers as yuv420p requires.
The system's ffmpeg (Debian package `ffmpeg`) comes first; without it, the binary that the
`imageio-ffmpeg` wheel in requirements.txt ships, so a fresh machine writes the movie too."""

import os
import shutil
import subprocess
import tempfile


def find_ffmpeg():
    """(path, source) of the ffmpeg to use: `ffmpeg` on PATH first, else the imageio-ffmpeg
    wheel's own binary; (None, reason) when neither is there."""
    system = shutil.which("ffmpeg")
    if system is not None:
        return system, "system"
    try:
        import imageio_ffmpeg

        return imageio_ffmpeg.get_ffmpeg_exe(), "imageio-ffmpeg"
    except (ImportError, RuntimeError) as e:
        return None, f"no ffmpeg on PATH and none from imageio-ffmpeg ({e})"


def make_movie(pngs: list, out_path, fps: int, notice) -> bool:
    """Encodes the PNGs in order into `out_path`; returns whether a movie was written."""
    ffmpeg, source = find_ffmpeg()
    if ffmpeg is None:
        notice(f"note: movie skipped: {source} (install it, e.g. `apt-get install ffmpeg`)")
        return False
    if len(pngs) < 2:
        notice("note: fewer than two frames rendered, movie skipped")
        return False
    with tempfile.TemporaryDirectory(prefix="polyphase-movie-") as tmp:
        # Frames may have gaps (bad or missing ones): number the good ones contiguously.
        for i, png in enumerate(pngs):
            os.symlink(os.path.abspath(png), os.path.join(tmp, f"{i:06d}.png"))
        tmp_out = str(out_path) + ".tmp.mp4"
        cmd = [
            ffmpeg, "-y", "-loglevel", "error", "-framerate", str(fps),
            "-i", os.path.join(tmp, "%06d.png"),
            "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart",
            tmp_out,
        ]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            last = (r.stderr.strip().splitlines() or ["unknown error"])[-1]
            notice(f"warning: ffmpeg ({source}) failed, movie skipped: {last}")
            if os.path.exists(tmp_out):
                os.remove(tmp_out)
            return False
        os.replace(tmp_out, out_path)
    return True
