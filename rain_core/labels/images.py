"""The label images of one frame (``LabelImages``) and their decoding from the GL read-back. GL-free."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rain_core.labels.classes import CLASS_IDS

# What render_label_images can produce besides the depth, and the effect pass behind each blended mask.
MASK_NAMES = ("rain", "glass_water", "road_water", "spray", "class")
BLENDED_MASKS = ("rain", "spray", "glass_water")  # drawn by the effects (render_label), in the mask texture's R, G, B
ROAD_WATER_IDS: dict[str, int] = {"dry": 0, "wet": 1, "drenched": 2, "puddle": 3, "not_road": 255}
# The geometry texture is cleared to this where no opaque surface is: no distance, sky, not road.
CLEAR_GEOMETRY = (-1.0, float(CLASS_IDS["sky"]), float(ROAD_WATER_IDS["not_road"]), 0.0)


@dataclass
class LabelImages:
    """Ground truth of one rendered frame, top row first, the frame's size (H, W).

    ``depth_m``: float32 metres along the view ray from the camera to the first opaque surface (inf for sky;
    transparent things — rain, spray, the windshield — are not surfaces). ``masks`` holds the ones asked for:
    ``"rain"`` float32 0..1, the rain streaks' coverage (their opacity composited along the ray);
    ``"spray"`` float32 0..1, spray opacity along the ray; ``"glass_water"`` float32 0..1, water on the windshield
    as seen (0 outside the glass; all 0 outside the car); ``"road_water"`` uint8 ROAD_WATER_IDS (0 dry, 1 wet,
    2 drenched, 3 puddle, 255 not road); ``"class"`` uint8 CLASS_IDS. ``class_ids`` is the id table."""

    depth_m: np.ndarray
    masks: dict[str, np.ndarray]
    class_ids: dict[str, int] = field(default_factory=lambda: dict(CLASS_IDS))

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) in pixels."""
        return self.depth_m.shape[1], self.depth_m.shape[0]


def check_mask_names(masks) -> tuple[str, ...]:
    """The mask names asked for (None: all of MASK_NAMES); an unknown name → ValueError naming the allowed ones."""
    if masks is None:
        return MASK_NAMES
    names = (masks,) if isinstance(masks, str) else tuple(masks)
    unknown = [n for n in names if n not in MASK_NAMES]
    if unknown:
        raise ValueError(f"masks: unknown name(s) {unknown!r}; allowed: {', '.join(MASK_NAMES)}")
    return names


def decode(geometry: np.ndarray, blended: np.ndarray | None, names) -> LabelImages:
    """LabelImages from the read-back: ``geometry`` (H, W, 4) float32 (ray length m or −1, class, road region, 0)
    and ``blended`` (H, W, 4) float32 transmittances (rain, spray, glass water, 1) or None when no blended mask
    was drawn; both bottom row first, as GL reads them."""
    geometry = geometry[::-1]
    dist = geometry[..., 0]
    depth = np.where(dist >= 0.0, dist, np.inf).astype(np.float32)
    masks: dict[str, np.ndarray] = {}
    for name in names:
        if name == "class":
            masks[name] = np.rint(geometry[..., 1]).astype(np.uint8)
        elif name == "road_water":
            masks[name] = np.rint(geometry[..., 2]).astype(np.uint8)
        else:
            channel = BLENDED_MASKS.index(name)
            if blended is None:
                masks[name] = np.zeros(dist.shape, np.float32)
            else:
                masks[name] = np.clip(1.0 - blended[::-1, :, channel], 0.0, 1.0).astype(np.float32)
    return LabelImages(depth, masks)
