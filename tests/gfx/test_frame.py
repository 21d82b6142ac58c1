"""Frame: a mirror view's frame is the frame with another camera and every other field as it was."""

from __future__ import annotations

import dataclasses

from rain_core.gfx.frame import Frame


def test_with_camera_is_dataclasses_replace():
    # A distinct object in every field: a field with_camera forgot (or one added to Frame since) would differ.
    values = {f.name: object() for f in dataclasses.fields(Frame)}
    frame = Frame(**values)
    camera = object()
    got, expected = frame.with_camera(camera), dataclasses.replace(frame, camera=camera)
    assert type(got) is Frame and got is not frame
    for f in dataclasses.fields(Frame):
        assert getattr(got, f.name) is getattr(expected, f.name), f.name
    assert frame.camera is values["camera"]  # the frame itself is unchanged
