"""Outputs that need no renderer run: tone mapping, plots, `.vol` export, progress text."""

import io
import os
import tempfile
import unittest

import numpy as np

from polyphase_render.image import tonemap
from polyphase_render.plots import measurements, plot_all, read_stats
from polyphase_render.progress import Progress
from polyphase_render.scene import load_scene
from polyphase_render.vol import export_frame, grid_shape, read_vol, voxel_phases, write_vol

from .fixtures import make_run, sphere_labels, voxel_mesh


class ToneMapTest(unittest.TestCase):
    def test_range_and_monotone(self):
        x = np.linspace(0, 10, 101)[:, None, None] * np.ones((1, 1, 3))
        y = tonemap(x)[:, 0, 0].astype(int)
        self.assertEqual(y[0], 0)
        self.assertTrue(np.all(np.diff(y) >= 0))
        # The white point (4.0) maps to full white.
        self.assertEqual(tonemap(np.full((1, 1, 3), 4.0))[0, 0, 0], 255)
        self.assertEqual(tonemap(np.full((1, 1, 3), np.nan))[0, 0, 0], 0)


class PlotTest(unittest.TestCase):
    def test_plots_from_stats(self):
        with tempfile.TemporaryDirectory() as tmp:
            root = make_run(os.path.join(tmp, "run"), n=6, frames=3)
            with open(os.path.join(root, "stats.jsonl"), "a") as f:
                f.write("not json\n")
            lines, summary, bad = read_stats(os.path.join(root, "stats.jsonl"))
            self.assertEqual((len(lines), summary, bad), (4, {"frames": 3}, 1))
            series = measurements(lines)
            self.assertEqual(list(series), ["surge_front"])
            # The fixture writes 0.2 + 0.1 k: equal to the float the same expression gives.
            self.assertEqual(series["surge_front"][1], [0.2 + 0.1 * k for k in range(4)])
            written = plot_all(os.path.join(root, "stats.jsonl"), os.path.join(root, "plots"),
                               load_scene(os.path.join(root, "scene.toml")))
            names = sorted(os.path.basename(p) for p in written)
            self.assertEqual(names, ["measurements.png", "timings.png", "volumes.png"])
            for p in written:
                with open(p, "rb") as f:
                    self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")


class VolTest(unittest.TestCase):
    def test_voxelisation_recovers_the_labels(self):
        # The fixture mesh is the boundary of a voxel labeling: voxelising it at the same
        # resolution (and at twice the resolution) must give the labels back exactly.
        labels = sphere_labels(12)
        mesh = voxel_mesh(labels, [0, 0, 0], [1, 1, 1])
        np.testing.assert_array_equal(voxel_phases(mesh, [0, 0, 0], [1, 1, 1], (12, 12, 12), 0), labels)
        fine = labels.repeat(2, 0).repeat(2, 1).repeat(2, 2)
        np.testing.assert_array_equal(voxel_phases(mesh, [0, 0, 0], [1, 1, 1], (24, 24, 24), 0), fine)

    def test_exported_fractions_sum_to_the_phase_volumes(self):
        labels = sphere_labels(8)
        mesh = voxel_mesh(labels, [0, 0, 0], [1, 1, 1])
        with tempfile.TemporaryDirectory() as tmp:
            root = make_run(os.path.join(tmp, "run"), n=8, frames=0)
            scene = load_scene(os.path.join(root, "scene.toml"))
            paths = export_frame(mesh, scene, 8, os.path.join(tmp, "vol"), 3)
            self.assertEqual([os.path.basename(p) for p in paths], ["0003_red.vol", "0003_blue.vol"])
            for phase, path in zip((1, 2), paths):
                chi, _, _ = read_vol(path)
                # Voxel-exact fixture at the same resolution: fractions are exactly 0 or 1.
                np.testing.assert_array_equal(chi[..., 0], (labels == phase).astype(np.float32))

    def test_vol_file_round_trip_and_header(self):
        data = np.random.default_rng(1).random((3, 4, 5)).astype(np.float32)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "g.vol")
            write_vol(path, data, [0, 0, 0], [1, 2, 3])
            with open(path, "rb") as f:
                raw = f.read()
            self.assertEqual(raw[:4], b"VOL\x03")
            self.assertEqual(len(raw), 48 + 4 * data.size)
            back, lo, hi = read_vol(path)
            np.testing.assert_array_equal(back[..., 0], data)
            self.assertEqual(list(hi), [1, 2, 3])
            # x varies fastest in the file.
            self.assertEqual(np.frombuffer(raw[48:56], "<f4").tolist(), [data[0, 0, 0], data[1, 0, 0]])
        self.assertEqual(grid_shape([0, 0, 0], [2, 1, 0.5], 8), (8, 4, 2))

    def test_mitsuba_reads_the_grid(self):
        import mitsuba as mi

        mi.set_variant("scalar_rgb")
        data = np.zeros((4, 4, 4), np.float32)
        data[1, 2, 3] = 1.0
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "g.vol")
            write_vol(path, data, [0, 0, 0], [1, 1, 1])
            grid = mi.VolumeGrid(path)
            self.assertEqual(list(grid.size()), [4, 4, 4])
            self.assertEqual(grid.max(), 1.0)
            # VolumeGrid is indexed [z, y, x].
            self.assertEqual(np.array(grid).reshape(4, 4, 4)[3, 2, 1], 1.0)


class ProgressTest(unittest.TestCase):
    def test_counts_and_eta(self):
        out = io.StringIO()
        p = Progress(4, stream=out)
        p.step("frame 0000")
        p.step("frame 0001")
        lines = out.getvalue().splitlines()
        self.assertEqual(len(lines), 2)
        self.assertIn("2/4 frames", lines[1])
        self.assertIn("ETA", lines[1])


if __name__ == "__main__":
    unittest.main()
