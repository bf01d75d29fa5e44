"""PLY reading (layout, every malformation named) and frame selection."""

import os
import tempfile
import unittest

import numpy as np

from polyphase_render.frames import RangeError, parse_range, select
from polyphase_render.ply import PlyError, read_ply, write_ply

from .fixtures import sphere_labels, voxel_mesh


class PlyTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.tmp.name, "0000.ply")
        self.mesh = voxel_mesh(sphere_labels(6), [0, 0, 0], [1, 1, 1])
        write_ply(self.path, self.mesh)

    def tearDown(self):
        self.tmp.cleanup()

    def test_round_trip_is_exact(self):
        m = read_ply(self.path)
        np.testing.assert_array_equal(m.vertices, self.mesh.vertices)
        np.testing.assert_array_equal(m.faces, self.mesh.faces)
        np.testing.assert_array_equal(m.front, self.mesh.front)
        np.testing.assert_array_equal(m.back, self.mesh.back)

    def _corrupt(self, data):
        with open(self.path, "wb") as f:
            f.write(data)

    def test_malformed_files_are_named(self):
        with open(self.path, "rb") as f:
            good = f.read()
        cases = {
            "truncated": good[: len(good) - 5],
            "trailing garbage": good + b"xx",
            "no PLY header": b"\x00\x01garbage",
            "bad header line": good.replace(b"property double z", b"property float z"),
        }
        for reason, data in cases.items():
            self._corrupt(data)
            with self.assertRaises(PlyError) as cm:
                read_ply(self.path)
            self.assertIn(reason, str(cm.exception))
        with self.assertRaises(PlyError) as cm:
            read_ply(os.path.join(self.tmp.name, "absent.ply"))
        self.assertIn("cannot read", str(cm.exception))

    def test_index_out_of_range_is_named(self):
        self.mesh.faces[0, 0] = len(self.mesh.vertices)
        write_ply(self.path, self.mesh)
        with self.assertRaises(PlyError) as cm:
            read_ply(self.path)
        self.assertIn("out of range", str(cm.exception))


class FramesTest(unittest.TestCase):
    def test_ranges(self):
        self.assertIsNone(parse_range("all"))
        self.assertEqual(parse_range("3"), [3])
        self.assertEqual(parse_range("0-2,5, 7-8"), [0, 1, 2, 5, 7, 8])
        for bad in ("x", "3-1", "1-", "-2"):
            with self.assertRaises(RangeError):
                parse_range(bad)

    def test_missing_frames_are_listed(self):
        found = {0: "a", 2: "c"}
        self.assertEqual(select(found, None, 3), ([0, 2], [1, 3]))
        self.assertEqual(select(found, [2], 3), ([2], []))
        self.assertEqual(select(found, None, None), ([0, 2], [1]))


if __name__ == "__main__":
    unittest.main()
