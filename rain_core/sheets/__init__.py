"""Contact sheets of rendered frames: ``python -m rain_core.sheets NAME`` runs rain_core/sheets/NAME.py's
``main(argv)``, which renders its frames and writes ``docs/sheets/NAME.png`` (the committed pictures)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

DEFAULT_OUT = Path("docs") / "sheets"


def contact_sheet(images, labels=None, columns: int = 3, pad: int = 4, label_h: int = 16) -> np.ndarray:
    """Tile uint8 (H, W, 3) images (all one size) into a grid with a caption above each; returns uint8 RGB."""
    images = [np.asarray(im, dtype=np.uint8) for im in images]
    if not images:
        raise ValueError("contact_sheet needs at least one image")
    h, w = images[0].shape[:2]
    labels = list(labels or [""] * len(images))
    columns = max(1, min(columns, len(images)))
    rows = (len(images) + columns - 1) // columns
    sheet = Image.new("RGB", (columns * (w + pad) + pad, rows * (h + label_h + pad) + pad), (24, 24, 24))
    draw = ImageDraw.Draw(sheet)
    for i, (im, label) in enumerate(zip(images, labels, strict=True)):
        x = pad + (i % columns) * (w + pad)
        y = pad + (i // columns) * (h + label_h + pad)
        draw.text((x + 2, y + 2), label, fill=(230, 230, 230))
        sheet.paste(Image.fromarray(im[..., :3]), (x, y + label_h))
    return np.asarray(sheet)


def save_sheet(images, labels, name: str, out_dir: Path | str = DEFAULT_OUT, columns: int = 3) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.png"
    Image.fromarray(contact_sheet(images, labels, columns)).save(path)
    return path
