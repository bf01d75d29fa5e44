"""The contact sheet: every tile's image lands in its own cell, labels above."""

import os
import tempfile
import unittest

import numpy as np

from polyphase_render.sheet import compose, label_px


class SheetTest(unittest.TestCase):
    def test_tiles_keep_their_colours_and_layout(self):
        import matplotlib.image as mpimg

        colours = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
        with tempfile.TemporaryDirectory() as d:
            tiles = []
            for k, c in enumerate(colours):
                path = os.path.join(d, f"{k}.png")
                mpimg.imsave(path, np.tile(np.array(c), (40, 60, 1)))
                tiles.append((path, f"variant-{k}"))
            tiles.append((os.path.join(d, "missing.png"), "variant-3"))
            out = os.path.join(d, "sheet.png")
            compose(tiles, out, "wedge")
            sheet = mpimg.imread(out)[..., :3]
        # Four tiles make a 2 × 2 grid of 60 × 40 images, each under a label band of two lines
        # (the missing tile's label has a second one), below a one-line title.
        band, top = label_px(2), label_px(1) + 6
        self.assertEqual(sheet.shape[:2], (top + 2 * (40 + band), 2 * 60))
        # The centre of each tile is its image's colour (a solid tile, drawn nearest-neighbour
        # at its own size): 0.02 allows the 8-bit PNG round trip (1/255) with margin.
        for k, c in enumerate(colours):
            r, col = divmod(k, 2)
            y = top + r * (40 + band) + band + 20
            x = col * 60 + 30
            np.testing.assert_allclose(sheet[y, x], c, atol=0.02)
        # The missing one is grey.
        np.testing.assert_allclose(sheet[top + 40 + 2 * band + 20, 90], (0.5, 0.5, 0.5), atol=0.02)


if __name__ == "__main__":
    unittest.main()
