"""Per-frame ground truth on disk (``--labels``): the writer the app records with, and ``load_dataset``.

Layout of a labels folder (``DIR`` itself for ``--record DIR``, ``out.labels/`` beside ``--record out.mp4``)::

    dataset.json        {"format": "rainroad-labels", "version": 1, "size": [W, H], "fps": …,
                         "video": "../out.mp4" or null, "class_ids": {name: id}, "road_water_ids": {name: id},
                         "mask_names": [...]}                   written with the first frame
    labels.jsonl        one JSON object per frame, in order, flushed as each frame is written: Capture.labels
                        (matrices as nested lists, row-major; a non-finite number as null) plus "arrays" (the NPZ
                        file name) and "image" (the PNG file name, or null when the frames are in the video)
    frame_00000.npz     depth_m (H, W) float32 m (inf: sky) and mask_<name> for each mask (Capture.masks)
    frame_00000.png     the picture (--record DIR only; with a video, frame N of the video is frame N here)

A recording cut short keeps every frame whose JSON line was written.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rain_core.session.capture import Capture

FORMAT, VERSION = "rainroad-labels", 1
HEADER, LINES = "dataset.json", "labels.jsonl"
_MATRICES = ("camera_intrinsics", "camera_to_world")


def frame_name(index: int, suffix: str) -> str:
    return f"frame_{index:05d}{suffix}"


def _plain(value):
    """A JSON-safe copy: arrays → lists, NumPy scalars → Python, non-finite floats → None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray | list | tuple):
        return [_plain(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value)]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class DatasetWriter:
    """Writes a labels folder (layout in the module docstring). ``folder`` is created if missing.

    images: write frame_NNNNN.png too (False when the pictures go to a video). video: the video's path, stored
    relative to the folder in dataset.json. Close (or use as a context manager) to flush the last line."""

    def __init__(self, folder: Path | str, fps: float, images: bool = True, video: Path | str | None = None):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.fps, self.images = float(fps), bool(images)
        self.video = None if video is None else Path(video)
        self.count = 0
        self._lines = None

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _header(self, cap: Capture) -> None:
        video = None
        if self.video is not None:
            video = Path(_relative(self.video.resolve(), self.folder.resolve())).as_posix()
        header = {"format": FORMAT, "version": VERSION, "size": list(cap.size), "fps": self.fps, "video": video,
                  "class_ids": cap.labels.get("class_ids", {}), "road_water_ids": cap.labels.get("road_water_ids", {}),
                  "mask_names": sorted(cap.masks)}
        (self.folder / HEADER).write_text(json.dumps(header, indent=1) + "\n")
        self._lines = open(self.folder / LINES, "w", encoding="utf-8")  # noqa: SIM115 (closed in close())

    def add(self, cap: Capture) -> None:
        """Write one frame's arrays, picture (if images) and JSON line."""
        if self._lines is None:
            self._header(cap)
        index = self.count
        arrays = {f"mask_{name}": mask for name, mask in cap.masks.items()}
        if cap.depth_m is not None:
            arrays["depth_m"] = cap.depth_m
        npz = frame_name(index, ".npz")
        np.savez_compressed(self.folder / npz, **arrays)
        image = None
        if self.images:
            from PIL import Image

            image = frame_name(index, ".png")
            Image.fromarray(cap.rgb).save(self.folder / image)
        labels = {k: v for k, v in cap.labels.items() if k not in ("class_ids", "road_water_ids")}
        self._lines.write(json.dumps(_plain({**labels, "arrays": npz, "image": image})) + "\n")
        self._lines.flush()  # a run cut short keeps every line written
        self.count += 1

    def close(self) -> None:
        if self._lines is not None:
            self._lines.close()
            self._lines = None


def _relative(path: Path, start: Path) -> str:
    import os

    return os.path.relpath(path, start)


@dataclass
class Dataset:
    """A labels folder read back: ``header`` (dataset.json), ``records`` (labels.jsonl, one dict a frame).

    ``len(ds)``, ``ds[i]`` → Capture (rgb from the PNG or the video, depth_m, masks, labels with the matrices
    as arrays and the class tables), ``for cap in ds`` in order (a video is decoded once, in order)."""

    folder: Path
    header: dict
    records: list[dict]

    def __len__(self) -> int:
        return len(self.records)

    def labels(self, index: int) -> dict:
        rec = dict(self.records[index])
        for key in _MATRICES:
            if rec.get(key) is not None:
                rec[key] = np.array(rec[key], dtype=np.float64)
        rec["class_ids"] = dict(self.header.get("class_ids", {}))
        rec["road_water_ids"] = dict(self.header.get("road_water_ids", {}))
        return rec

    def arrays(self, index: int) -> tuple[np.ndarray | None, dict[str, np.ndarray]]:
        """(depth_m, masks) of frame ``index``."""
        with np.load(self.folder / self.records[index]["arrays"]) as data:
            masks = {k[len("mask_"):]: data[k] for k in data.files if k.startswith("mask_")}
            depth = data["depth_m"] if "depth_m" in data.files else None
        return depth, masks

    def _capture(self, index: int, rgb: np.ndarray) -> Capture:
        depth, masks = self.arrays(index)
        return Capture(rgb=rgb, depth_m=depth, masks=masks, labels=self.labels(index))

    def video_frames(self):
        """The video's frames as (H, W, 3) uint8, in order (needs PyAV)."""
        import av

        with av.open(str(self.folder / self.header["video"])) as container:
            for frame in container.decode(video=0):
                yield frame.to_ndarray(format="rgb24")

    def __getitem__(self, index: int) -> Capture:
        if not -len(self) <= index < len(self):
            raise IndexError(f"frame index must be in [0, {len(self) - 1}], got {index}")
        index %= len(self)
        image = self.records[index].get("image")
        if image is not None:
            from PIL import Image

            return self._capture(index, np.asarray(Image.open(self.folder / image).convert("RGB")))
        for i, rgb in enumerate(self.video_frames()):
            if i == index:
                return self._capture(index, rgb)
        raise IndexError(f"the video has fewer than {index + 1} frames")

    def __iter__(self):
        if self.records and self.records[0].get("image") is None:
            for index, rgb in zip(range(len(self)), self.video_frames(), strict=False):
                yield self._capture(index, rgb)
        else:
            for index in range(len(self)):
                yield self[index]


def load_dataset(folder: Path | str) -> Dataset:
    """Read a labels folder written by DatasetWriter (``--record … --labels``). A missing or foreign folder
    raises ValueError naming the file; a last line cut off by a crash is skipped."""
    folder = Path(folder)
    try:
        header = json.loads((folder / HEADER).read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"{folder / HEADER}: not a rainroad labels folder ({exc})") from None
    if header.get("format") != FORMAT:
        raise ValueError(f"{folder / HEADER}: format must be {FORMAT!r}, got {header.get('format')!r}")
    records = []
    with open(folder / LINES, encoding="utf-8") as f:
        for line in f:
            try:
                records.append(json.loads(line))
            except ValueError:
                break  # a line cut short by a crash: everything before it is whole
    return Dataset(folder, header, records)
