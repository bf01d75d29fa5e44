"""The camera's framing of a run: every frame's liquids, kept in `render/framing.json` and
recomputed when a frame is rewritten."""

import json
import os
import tempfile
import unittest

import numpy as np

from polyphase_render.frames import frames_on_disk
from polyphase_render.pipeline import _framing
from polyphase_render.ply import write_ply
from polyphase_render.scene import load_scene

from .fixtures import make_run, sphere_labels, voxel_mesh


class FramingTest(unittest.TestCase):
    def test_box_spans_every_frame_and_the_cache_follows_the_frames(self):
        with tempfile.TemporaryDirectory() as d:
            make_run(d, n=12, frames=2)
            scene_path = os.path.join(d, "scene.toml")
            scene = load_scene(scene_path)
            found = frames_on_disk(os.path.join(d, "frames"))
            lo, hi, liquid = _framing(d, scene_path, scene, found)
            # The sphere (radius 0.3 at x = 0.5, painted on 1/12 voxels) moves 0.1 in x over
            # the run: the box spans the first frame's left side and the last one's right.
            self.assertLess(lo[0], 0.5 - 0.3 + 1 / 12)
            self.assertGreater(hi[0], 0.6 + 0.3 - 1 / 12)
            self.assertGreater(liquid, 0.0)
            # A second call reads the kept result: marked so it can be told apart.
            cache = os.path.join(d, "render", "framing.json")
            with open(cache) as f:
                kept = json.load(f)
            kept["liquid"] = -1.0
            with open(cache, "w") as f:
                json.dump(kept, f)
            self.assertEqual(_framing(d, scene_path, scene, found)[2], -1.0)
            # Rewriting a frame (the sphere 0.2 further right: it reaches the domain's right
            # side) invalidates it.
            frame = os.path.join(d, "frames", "0002.ply")
            write_ply(frame, voxel_mesh(sphere_labels(12, shift=0.3), [0, 0, 0], [1, 1, 1]))
            st = os.stat(frame)
            os.utime(frame, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
            lo2, hi2, liquid2 = _framing(d, scene_path, scene, found)
            self.assertEqual(liquid2, liquid)
            self.assertGreater(hi2[0], hi[0])
            np.testing.assert_array_equal(lo2, lo)


if __name__ == "__main__":
    unittest.main()
