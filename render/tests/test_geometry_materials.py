"""Pair split orientation, smooth normals, Beer–Lambert media, scene hints."""

import math
import unittest

import numpy as np

from polyphase_render.geometry import (
    CLOSING,
    INTERFACE,
    WALL,
    corner_normals,
    face_normals,
    phase_volumes,
    split_pairs,
)
from polyphase_render.materials import bsdf_dict, medium_dict, sigma_t
from polyphase_render.ply import OUTSIDE
from polyphase_render.scene import SceneError, parse_scene

from .fixtures import SCENE_TOML, sphere_labels, voxel_mesh


def signed_volume(vertices, faces):
    p = vertices[faces]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0


def scene(extra=""):
    return parse_scene(SCENE_TOML.format(n=8, frames=1, extra=extra))


class SplitTest(unittest.TestCase):
    def setUp(self):
        self.n = 10
        self.labels = sphere_labels(self.n)
        self.mesh = voxel_mesh(self.labels, [0, 0, 0], [1, 1, 1])
        self.scene = scene()

    def test_normals_point_from_interior_to_exterior(self):
        shapes = split_pairs(self.mesh, self.scene, tank=False, smooth=False)
        kinds = {(s.interior, s.exterior): s.kind for s in shapes}
        # blue (ior 1.45, denser by index tie-break) is the interior of the red-blue pair.
        self.assertEqual(kinds, {(1, 0): INTERFACE, (2, 0): INTERFACE, (2, 1): INTERFACE})
        vol = {(s.interior, s.exterior): signed_volume(s.vertices, s.faces) for s in shapes}
        # Divergence theorem: red is bounded by (1,0) outward and (2,1) inward, blue by (2,0)
        # and (2,1) outward; the voxel counts are the exact volumes (fixture is voxel-exact).
        h3 = 1.0 / self.n**3
        self.assertAlmostEqual(vol[(1, 0)] - vol[(2, 1)], (self.labels == 1).sum() * h3, places=12)
        self.assertAlmostEqual(vol[(2, 0)] + vol[(2, 1)], (self.labels == 2).sum() * h3, places=12)

    def test_phase_volumes_by_divergence(self):
        # Voxel-exact fixture: each phase's volume is its voxel count times the voxel volume.
        expected = [(self.labels == p).sum() / self.n**3 for p in range(3)]
        np.testing.assert_allclose(phase_volumes(self.mesh, 3), expected, rtol=0, atol=1e-12)

    def test_boundary_faces(self):
        labels = np.ones((4, 4, 4), dtype=np.int64)
        labels[:, 2:, :] = 0  # red fills the lower half, air the upper half of the domain
        mesh = voxel_mesh(labels, [0, 0, 0], [1, 1, 1])
        plain = {(s.interior, s.exterior, s.kind) for s in split_pairs(mesh, self.scene, False, False)}
        self.assertEqual(plain, {(1, 0, INTERFACE), (1, OUTSIDE, CLOSING)})
        tank = split_pairs(mesh, self.scene, True, False)
        self.assertIn((0, OUTSIDE, WALL), {(s.interior, s.exterior, s.kind) for s in tank})
        closing = [s for s in tank if s.kind == CLOSING][0]
        # The red half-box closed by its boundary faces: volume 1/2 with outward normals.
        red = [s for s in tank if s.kind == INTERFACE][0]
        total = signed_volume(closing.vertices, closing.faces) + signed_volume(red.vertices, red.faces)
        self.assertAlmostEqual(total, 0.5, places=12)

    def test_an_opaque_background_is_closed_on_the_domain_boundary(self):
        # A foam: every phase opaque ("*"), the background a cell like the others. Its faces on
        # the domain boundary must be drawn, or the picture has a hole where it touches a wall.
        labels = np.zeros((4, 4, 4), dtype=np.int64)
        labels[:2] = 1
        labels[:2, :2] = 2
        mesh = voxel_mesh(labels, [0, 0, 0], [1, 1, 1])
        foam = scene('\n[render]\nopaque = ["*"]\n')
        self.assertEqual(foam.opaque_ids(), {0, 1, 2})
        shapes = split_pairs(mesh, foam, False, False)
        self.assertEqual(
            {(s.interior, s.exterior, s.kind) for s in shapes},
            {(0, OUTSIDE, CLOSING), (1, OUTSIDE, CLOSING), (2, OUTSIDE, CLOSING), (1, 0, INTERFACE),
             (2, 0, INTERFACE), (2, 1, INTERFACE)},
        )
        # The closing faces cover the whole boundary of the unit box: 6 faces of area 1, each
        # voxel face two triangles, every one drawn once.
        closing = [s for s in shapes if s.kind == CLOSING]
        area = sum(0.5 * np.linalg.norm(face_normals(s.vertices, s.faces), axis=1).sum() for s in closing)
        self.assertAlmostEqual(area, 6.0, places=12)
        self.assertEqual({bsdf_dict(s, foam)["type"] for s in shapes}, {"roughplastic"})
        # A transparent background is still left open (its boundary is the tank's, if any).
        self.assertNotIn(0, {s.interior for s in split_pairs(mesh, self.scene, False, False)})

    def test_a_cutaway_leaves_out_the_triangles_beyond_its_plane(self):
        cut = scene('\n[render]\nopaque = ["*"]\ncutaway = { point = [0.5, 0.5, 0.5], normal = [0.0, 0.0, 2.0] }\n')
        np.testing.assert_allclose(cut.hints.cutaway[1], [0, 0, 1])
        shapes = split_pairs(self.mesh, cut, False, False)
        whole = split_pairs(self.mesh, scene('\n[render]\nopaque = ["*"]\n'), False, False)
        kept = np.concatenate([s.vertices[s.faces].mean(axis=1) for s in shapes])
        every = np.concatenate([s.vertices[s.faces].mean(axis=1) for s in whole])
        # Exactly the triangles with centroids at z <= 1/2 stay (the voxel mesh has faces on both
        # sides of the plane and on it: faces on the plane are kept).
        self.assertEqual(len(kept), int((every[:, 2] <= 0.5).sum()))
        self.assertTrue(np.all(kept[:, 2] <= 0.5))
        # Opened shells show their inner sides: opaque surfaces become two-sided.
        self.assertEqual(bsdf_dict(shapes[0], cut)["type"], "twosided")
        self.assertEqual(bsdf_dict(shapes[0], cut)["material"]["type"], "roughplastic")
        for bad in ("cutaway = { point = [0, 0, 0] }", "cutaway = { point = [0, 0, 0], normal = [0, 0, 0] }"):
            with self.assertRaises(SceneError):
                scene(f"\n[render]\n{bad}\n")

    def test_corner_normals_keep_creases_and_smooth_curves(self):
        # A cube: every corner normal is its face normal (90 degree creases are kept).
        labels = np.zeros((3, 3, 3), dtype=np.int64)
        labels[1, 1, 1] = 1
        mesh = voxel_mesh(labels, [0, 0, 0], [1, 1, 1])
        shapes = split_pairs(mesh, self.scene, False, True)
        s = [x for x in shapes if x.kind == INTERFACE][0]
        p = s.vertices[s.faces]
        fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        fn /= np.linalg.norm(fn, axis=1)[:, None]
        np.testing.assert_allclose(s.normals.reshape(-1, 3, 3), np.repeat(fn[:, None], 3, axis=1), atol=1e-12)
        # A shallow tent (10 degrees): the ridge vertices get the average of both sides.
        t = math.tan(math.radians(10))
        verts = np.array([[0, 0, 0], [0, 2, 0], [1, 1, -t], [-1, 1, -t]], float)
        tris = np.array([[0, 2, 1], [0, 1, 3]])
        _, _, n = corner_normals(verts, tris, math.cos(math.radians(60)))
        self.assertTrue(np.allclose(n[0], n[3]) and abs(n[0][0]) < 1e-12)


class MaterialTest(unittest.TestCase):
    def test_beer_lambert(self):
        color = (0.85, 0.15, 0.1)
        s = sigma_t(color, 0.2)
        for c, k in zip(color, s):
            self.assertAlmostEqual(math.exp(-k * 0.2), c, places=12)
        m = medium_dict(scene().phases[1], 0.2)
        self.assertAlmostEqual(max(m["sigma_t"]["value"]), 1.0)
        self.assertAlmostEqual(m["scale"], max(s))

    def test_bsdfs(self):
        sc = scene()
        shapes = split_pairs(voxel_mesh(sphere_labels(6), [0, 0, 0], [1, 1, 1]), sc, False, False)
        by = {(s.interior, s.exterior): bsdf_dict(s, sc) for s in shapes}
        self.assertEqual(by[(1, 0)], {"type": "dielectric", "int_ior": 1.33, "ext_ior": 1.0})
        self.assertEqual(by[(2, 1)], {"type": "dielectric", "int_ior": 1.45, "ext_ior": 1.33})
        sc2 = scene('\n[render]\nopaque = ["blue"]\n')
        shapes = split_pairs(voxel_mesh(sphere_labels(6), [0, 0, 0], [1, 1, 1]), sc2, False, False)
        self.assertEqual(bsdf_dict(shapes[-1], sc2)["type"], "roughplastic")

    def test_hints_are_checked(self):
        h = scene('\n[render]\ncamera_origin = [2, 2, 2]\nfov = 40\ntank = true\n').hints
        self.assertEqual(list(h.camera_origin), [2, 2, 2])
        self.assertTrue(h.tank)
        np.testing.assert_allclose(h.up, [0, 1, 0])
        for bad in ("fov = -1", "tank = 3", "opaque = [\"nope\"]", "bogus = 1", "up = [0, 0]"):
            with self.assertRaises(SceneError):
                scene(f"\n[render]\n{bad}\n")

    def test_gravity_sets_up(self):
        self.assertEqual(list(scene("\n[physics]\ngravity = [0.0, 0.0, -9.81]\n").hints.up), [0, 0, 1])


if __name__ == "__main__":
    unittest.main()
