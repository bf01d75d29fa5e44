"""Contact sheet of a wedge: one rendered frame per variant, each labeled with its settings
(`polyphase render WEDGE_DIR` writes `WEDGE_DIR/sheet.png`).

`python -m polyphase_render.sheet OUT.png --title TEXT IMAGE LABEL [IMAGE LABEL ...]`
"""

import argparse
import math
import os
import sys


LINE_PX = 13
"""Height of one label line in pixels (a 9-point font at 100 dpi is 12.5 pixels)."""


def label_px(lines: int) -> int:
    """Height of a label band of `lines` lines."""
    return 4 + LINE_PX * lines


def compose(tiles, out_path, title=""):
    """Writes a grid of the (image path, label) `tiles`, about square, each label (lines split
    at newlines) above its image, shrunk to the tile's width; a missing image leaves its tile
    grey, labeled "(not rendered)"."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt
    import numpy as np

    if not tiles:
        raise ValueError("a contact sheet needs at least one tile")
    images = [mpimg.imread(p) if os.path.isfile(p) else None for p, _ in tiles]
    labels = [lab if im is not None else f"{lab}\n(not rendered)" for (_, lab), im in zip(tiles, images)]
    shape = next((im.shape for im in images if im is not None), (240, 320, 3))
    h, w = shape[0], shape[1]
    cols = math.ceil(math.sqrt(len(tiles)))
    rows = math.ceil(len(tiles) / cols)
    band = label_px(max(len(lab.split("\n")) for lab in labels))
    title_px, dpi = (label_px(1) + 6 if title else 0), 100
    total_h = rows * (h + band) + title_px
    fig = plt.figure(figsize=(cols * w / dpi, total_h / dpi), dpi=dpi)

    def fit(text, width_px):
        # A character of a DejaVu font is about 0.6 of its size wide; 9 points at most.
        chars = max(len(line) for line in text.split("\n"))
        return min(9.0, width_px / (0.6 * max(chars, 1)) * 72 / dpi)

    if title:
        fig.text(0.5, 1 - 4 / total_h, title, ha="center", va="top", fontsize=fit(title, cols * w))
    for k, (im, label) in enumerate(zip(images, labels)):
        r, c = divmod(k, cols)
        bottom = total_h - title_px - (r + 1) * (h + band)
        ax = fig.add_axes([c / cols, bottom / total_h, 1 / cols, h / total_h])
        ax.set_axis_off()
        ax.imshow(np.full((h, w, 3), 0.5) if im is None else im, interpolation="nearest")
        ax.text(0.5, 1.0 + 2 / h, label, transform=ax.transAxes, ha="center", va="bottom",
                fontsize=fit(label, w - 4), linespacing=1.0)
    tmp = out_path + ".tmp.png"
    fig.savefig(tmp, dpi=dpi, facecolor="white", metadata={"Software": None})
    plt.close(fig)
    os.replace(tmp, out_path)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="polyphase_render.sheet", description=__doc__.splitlines()[0])
    p.add_argument("out", help="the sheet's PNG path")
    p.add_argument("--title", default="")
    p.add_argument("tiles", nargs="+", help="IMAGE LABEL pairs")
    a = p.parse_args(sys.argv[1:] if argv is None else argv)
    if len(a.tiles) % 2:
        p.error("tiles come in IMAGE LABEL pairs")
    tiles = list(zip(a.tiles[0::2], a.tiles[1::2]))
    try:
        compose(tiles, a.out, a.title)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
