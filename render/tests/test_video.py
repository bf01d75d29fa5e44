"""The movie encoder: the system's ffmpeg first, else the binary of the imageio-ffmpeg wheel that
requirements.txt installs, so a fresh machine without ffmpeg still writes `movie.mp4`."""

import os
import stat
import subprocess
import sys
import tempfile
import unittest
from unittest import mock

import numpy as np
import matplotlib.image as mpimg

from polyphase_render.video import find_ffmpeg, make_movie

# Three flat frames of an odd size (33 × 21: the encoder pads to 34 × 22 for yuv420p).
COLOURS = [(230, 40, 30), (30, 200, 60), (40, 60, 220)]
WIDTH, HEIGHT = 33, 21


def _no_system_ffmpeg(tmp):
    """Environment patch: PATH holds only an empty folder, as on a machine without ffmpeg."""
    empty = os.path.join(tmp, "empty-bin")
    os.makedirs(empty, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k != "IMAGEIO_FFMPEG_EXE"}
    env["PATH"] = empty
    return mock.patch.dict(os.environ, env, clear=True)


def _write_frames(tmp):
    paths = []
    for i, c in enumerate(COLOURS):
        path = os.path.join(tmp, f"{i:04d}.png")
        mpimg.imsave(path, np.full((HEIGHT, WIDTH, 3), c, dtype=np.uint8))
        paths.append(path)
    return paths


class EncoderChoiceTest(unittest.TestCase):
    def test_system_ffmpeg_comes_first(self):
        with tempfile.TemporaryDirectory() as tmp, _no_system_ffmpeg(tmp):
            fake = os.path.join(os.environ["PATH"], "ffmpeg")
            with open(fake, "w") as f:
                f.write("#!/bin/sh\nexit 0\n")
            os.chmod(fake, os.stat(fake).st_mode | stat.S_IXUSR)
            self.assertEqual(find_ffmpeg(), (fake, "system"))

    def test_without_any_ffmpeg_the_movie_is_skipped_with_a_notice(self):
        notes = []
        with tempfile.TemporaryDirectory() as tmp, _no_system_ffmpeg(tmp):
            # A None entry in sys.modules makes `import imageio_ffmpeg` fail, as if not installed.
            with mock.patch.dict(sys.modules, {"imageio_ffmpeg": None}):
                written = make_movie(_write_frames(tmp), os.path.join(tmp, "m.mp4"), 24, notes.append)
        self.assertFalse(written)
        self.assertEqual(len(notes), 1)
        self.assertIn("apt-get install ffmpeg", notes[0])


class FreshEnvironmentMovieTest(unittest.TestCase):
    def test_wheel_ffmpeg_writes_a_readable_movie(self):
        import imageio_ffmpeg

        with tempfile.TemporaryDirectory() as tmp, _no_system_ffmpeg(tmp):
            exe, source = find_ffmpeg()
            self.assertEqual(source, "imageio-ffmpeg")
            self.assertTrue(os.access(exe, os.X_OK), exe)
            out = os.path.join(tmp, "movie.mp4")
            notes = []
            self.assertTrue(make_movie(_write_frames(tmp), out, 24, notes.append), notes)
            with open(out, "rb") as f:
                self.assertEqual(f.read(12)[4:8], b"ftyp")  # an ISO media (MP4) file
            # ffmpeg itself decodes the file: every frame is there, at the padded size, 34 × 22.
            frames, secs = imageio_ffmpeg.count_frames_and_secs(out)
            self.assertEqual(frames, len(COLOURS))
            self.assertAlmostEqual(secs, len(COLOURS) / 24, delta=0.01)
            raw = subprocess.run(
                [exe, "-loglevel", "error", "-i", out, "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
                capture_output=True, check=True,
            ).stdout
        size = (HEIGHT + 1) * (WIDTH + 1) * 3
        self.assertEqual(len(raw), len(COLOURS) * size)
        decoded = [np.frombuffer(raw[i * size:(i + 1) * size], np.uint8).reshape(HEIGHT + 1, WIDTH + 1, 3)
                   for i in range(len(COLOURS))]
        self.assertEqual(len(decoded), len(COLOURS))
        for img, c in zip(decoded, COLOURS):
            # Flat colours survive H.264 at crf 18 and the yuv420p round trip to within a few
            # levels; 12 of 255 leaves room for the chroma rounding, far below the ~170-level
            # gaps between the three frames' colours.
            centre = img[HEIGHT // 2, WIDTH // 2].astype(int)
            self.assertTrue(np.all(np.abs(centre - np.array(c)) <= 12), (centre, c))


if __name__ == "__main__":
    unittest.main()
