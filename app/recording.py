"""Screenshots and numbered PNG sequences."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image


def save_png(image: np.ndarray, path: Path | str) -> Path:
    """Write a uint8 (H, W, 3) image; creates the parent folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(path)
    return path


class Recorder:
    """Writes frame_00000.png, frame_00001.png, … into a folder (created if missing)."""

    def __init__(self, folder: Path | str):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.count = 0

    def add(self, image: np.ndarray) -> Path:
        path = save_png(image, self.folder / f"frame_{self.count:05d}.png")
        self.count += 1
        return path
