"""Ground truth per frame: depth along the ray, semantic classes and the rain / water / spray / glass masks.

```python
from rain_core.labels import render_label_images, CLASS_IDS, LabelImages
frame = scene.render()
li = render_label_images(scene, frame)   # LabelImages: depth_m (H, W) float32 m, masks {name: (H, W)}
```

* ``classes`` — the stable class ids (CLASS_IDS, table in its docstring) and the class of every mesh vertex.
* ``images`` — LabelImages, the mask names and ids, decoding of the read-back (GL-free).
* ``renderer`` — the GL passes: the opaque meshes redrawn with their classes (depth as ray length, the road's
  water regions from shaders/road/film.glsl), then the effects' ``render_label`` passes (rain streaks, spray,
  glass water) composited as transmittance; read back once. Nothing runs unless labels are asked for.
"""

from rain_core.labels.classes import CLASS_COLORS, CLASS_IDS, CLASS_NAMES, world_classes
from rain_core.labels.images import BLENDED_MASKS, MASK_NAMES, ROAD_WATER_IDS, LabelImages, decode
from rain_core.labels.renderer import (
    LabelRenderer,
    LabelTarget,
    label_renderer,
    release_labels,
    render_label_images,
)

__all__ = ["BLENDED_MASKS", "CLASS_COLORS", "CLASS_IDS", "CLASS_NAMES", "MASK_NAMES", "ROAD_WATER_IDS",
           "LabelImages", "LabelRenderer", "LabelTarget", "decode", "label_renderer", "release_labels",
           "render_label_images", "world_classes"]
