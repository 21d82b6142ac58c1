"""The scripting API of issue 15: ``Session`` (a street in rain, stepped in seconds, captured with ground
truth), ``Weather`` (the weather in physical units, mapped onto the settings), ``Capture`` (one frame) and the
per-frame labels on disk (``DatasetWriter``, ``load_dataset``).

* ``weather`` — the Weather spec and its settings paths (GL-free).
* ``capture`` — Capture and the camera geometry of the labels: intrinsics, camera_to_world (GL-free).
* ``session`` — Session (imports the renderer only when a Session is made).
* ``dataset`` — the labels folder's layout, writer and loader (GL-free).
"""

from rain_core.session.capture import Capture, camera_intrinsics, camera_to_world, project
from rain_core.session.dataset import Dataset, DatasetWriter, load_dataset
from rain_core.session.session import CAMERAS, Session
from rain_core.session.weather import Weather

__all__ = ["CAMERAS", "Capture", "Dataset", "DatasetWriter", "Session", "Weather", "camera_intrinsics",
           "camera_to_world", "load_dataset", "project"]
