"""A contact sheet of a dataset's RGB images: view 0 of every sample, in sample order, in a
grid of `--columns` cells of `--cell` pixels (the size a README reader sees them at).

    python python/examples/gallery.py out/outdoor docs/outdoor_gallery.png --columns 8 \
        --order 0,1,2,3,4,5,6,14,7,8,9,10,11,12,13,14:1

Samples beyond a full row fill the next; an empty cell stays white.
"""

import argparse
from pathlib import Path

from PIL import Image


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--columns", type=int, default=8)
    parser.add_argument("--cell", type=int, default=320)
    parser.add_argument("--order", type=str, default="",
                        help="cells in grid order, comma-separated: a sample index (its view 0) "
                             "or sample:view (default: view 0 of every sample)")
    args = parser.parse_args()
    images = sorted(args.dataset.glob("samples/*/*_00.rgb.png"))
    if args.order:
        def path(cell: str) -> Path:
            sample, _, view = cell.partition(":")
            s = int(sample)
            return args.dataset / f"samples/{s // 1000:04}/{s:06}_{int(view or 0):02}.rgb.png"
        images = [path(cell) for cell in args.order.split(",")]
    rows = (len(images) + args.columns - 1) // args.columns
    sheet = Image.new("RGB", (args.columns * args.cell, rows * args.cell), "white")
    for k, path in enumerate(images):
        cell = Image.open(path).convert("RGB").resize((args.cell, args.cell), Image.LANCZOS)
        sheet.paste(cell, ((k % args.columns) * args.cell, (k // args.columns) * args.cell))
    sheet.save(args.out, optimize=True)


if __name__ == "__main__":
    main()
