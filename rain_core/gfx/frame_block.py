"""The frame block: the uniforms every program of a frame shares, in one uniform buffer (shaders/common/frame.glsl).

Camera, exposure, time, sun and sky, the rain medium, the sun shadow and the lights used to be written into
every program that drew (about 25 uniform writes, 1.7 KB, per program and pass). They are now packed once per
view (std140, ``pack``) and written into a uniform buffer that every program reads at binding point
``BINDING``; ``FrameBlocks.use`` binds the buffer holding a view's bytes (the main view and the road's mirror
view alternate within a frame, so a few buffers are kept and only a view whose bytes changed is rewritten).
"""

from __future__ import annotations

import struct

import numpy as np

BINDING = 0  # the uniform-buffer binding point of FrameBlock
BLOCK_NAME = "FrameBlock"
MAX_LIGHTS = 32  # shaders/common/frame.glsl

# name → (offset in 4-byte words, words, kind), std140, in the order of shaders/common/frame.glsl.
# kind "f": floats (a number or a sequence), "i": one int32, "b": raw bytes (column-major mat4, packed lights).
FRAME_BLOCK_LAYOUT: dict[str, tuple[int, int, str]] = {
    "u_view_proj": (0, 16, "b"),
    "u_shadow_matrix": (16, 16, "b"),
    "u_camera_pos": (32, 3, "f"), "u_exposure": (35, 1, "f"),
    "u_sun_dir": (36, 3, "f"), "u_time": (39, 1, "f"),
    "u_sun_illum": (40, 3, "f"), "u_night": (43, 1, "f"),
    "u_sky_zenith": (44, 3, "f"), "u_ground_albedo": (47, 1, "f"),
    "u_sky_horizon": (48, 3, "f"), "u_extinction_per_m": (51, 1, "f"),
    "u_airlight": (52, 3, "f"), "u_medium_extinction_per_m": (55, 1, "f"),
    "u_airlight_sun": (56, 3, "f"), "u_phase_g": (59, 1, "f"),
    "u_airlight_sun_dir": (60, 3, "f"), "u_phase_back_g": (63, 1, "f"),
    "u_shadow_params": (64, 3, "f"), "u_phase_back_weight": (67, 1, "f"),
    # without FRAME_OWN_LIGHTS (a program with its own light list stops here: 272 bytes)
    "u_light_count": (68, 1, "i"), "u_light_grid_px": (69, 1, "i"),
    "u_light_pos": (72, 4 * MAX_LIGHTS, "b"),
    "u_light_dir": (72 + 4 * MAX_LIGHTS, 4 * MAX_LIGHTS, "b"),
    "u_light_color": (72 + 8 * MAX_LIGHTS, 4 * MAX_LIGHTS, "b"),
}
BLOCK_WORDS = 72 + 12 * MAX_LIGHTS
BLOCK_BYTES = 4 * BLOCK_WORDS  # 1824
BLOCK_BYTES_OWN_LIGHTS = 4 * 68  # 272


_FLOATS = {count: struct.Struct(f"={count}f") for count in {c for _, c, k in FRAME_BLOCK_LAYOUT.values() if k == "f"}}
_INT = struct.Struct("=i")


def pack(values: dict) -> bytes:
    """The std140 bytes of the frame block for ``values`` (uniform name → value, as ``set_uniform`` takes them;
    names outside the block are ignored, members without a value are 0)."""
    # struct into one bytearray: the same float32 bytes as NumPy's assignment (round to nearest), a few µs
    # instead of ~25 small NumPy calls; anything struct refuses (an overflow, a numpy-only shape) takes NumPy's path.
    out = bytearray(BLOCK_BYTES)
    for name, value in values.items():
        slot = FRAME_BLOCK_LAYOUT.get(name)
        if slot is not None:
            _pack_slot(out, name, slot, value)
    return bytes(out)


def pack_changes(values: dict, previous: dict | None, previous_data: bytes | None) -> bytes:
    """``pack(values)``, made from ``previous_data`` (= ``pack(previous)``) by packing again only the entries
    whose value is not the same object as in ``previous``: the road's mirror view differs from the main view in
    its camera and lights alone. Entries are compared by identity (a value must not be changed in place); with
    other names than ``previous`` it packs everything."""
    if previous is None or previous_data is None or values.keys() != previous.keys():
        return pack(values)
    out = bytearray(previous_data)
    for name, value in values.items():
        if value is not previous[name]:
            slot = FRAME_BLOCK_LAYOUT.get(name)
            if slot is not None:
                if slot[2] == "b":  # shorter bytes leave the rest of the slot 0, as in a fresh block
                    out[4 * slot[0]:4 * (slot[0] + slot[1])] = bytes(4 * slot[1])
                _pack_slot(out, name, slot, value)
    return bytes(out)


def _pack_slot(out: bytearray, name: str, slot: tuple[int, int, str], value) -> None:
    offset, count, kind = slot
    at = 4 * offset
    if kind == "b":
        data = value if isinstance(value, bytes | bytearray) else np.ascontiguousarray(value, np.float32).tobytes()
        if len(data) % 4:
            raise ValueError(f"{name}: {len(data)} bytes is not a whole number of float32 words")
        n = 4 * min(len(data) // 4, count)
        out[at:at + n] = data[:n]
    elif kind == "i":
        _INT.pack_into(out, at, int(value))
    else:
        try:
            if hasattr(value, "__len__"):
                _FLOATS[count].pack_into(out, at, *value)
            else:  # a number fills every word, as NumPy broadcasts it
                _FLOATS[count].pack_into(out, at, *((value,) * count))
        except (struct.error, OverflowError, TypeError):
            np.frombuffer(out, np.float32)[offset:offset + count] = value


def unpack(data: bytes) -> dict:
    """The values of a frame block's bytes by name: floats, tuples of floats, an int; the light arrays as
    (MAX_LIGHTS, 4) float32 arrays, the matrices as column-major (4, 4) (for tests and debugging)."""
    words = np.frombuffer(bytes(data), np.float32)
    out: dict = {}
    for name, (offset, count, kind) in FRAME_BLOCK_LAYOUT.items():
        if offset + count > words.size:
            continue
        chunk = words[offset:offset + count]
        if kind == "i":
            out[name] = int(chunk.view(np.int32)[0])
        elif kind == "b":
            out[name] = chunk.reshape(-1, 4).copy()
        else:
            out[name] = float(chunk[0]) if count == 1 else tuple(float(v) for v in chunk)
    return out


class _ProgramInfo:
    """Per program: whether it reads the frame block, and which frame names it declares as plain uniforms."""

    __slots__ = ("program", "has_block", "plain", "_last", "_keys", "_names", "_keys_of")

    def __init__(self, program, keys_of=tuple):
        self.program = program
        block = program.get(BLOCK_NAME, None)
        self.has_block = block is not None
        if block is not None:
            block.binding = BINDING  # the default too; set once so a program never depends on it
        self.plain: dict[str, object] = {}  # name → moderngl Uniform or None, filled as names are asked for
        self._last = (None, ())  # (values dict, its (uniform, value) pairs this program declares as plain)
        self._keys_of = keys_of  # values dict → tuple of its names (FrameBlocks.keys_of: one tuple for all programs)
        self._keys: tuple = ()
        self._names: tuple = ()  # (uniform, name) of those keys that this program declares as plain

    def plain_values(self, values: dict) -> tuple:
        """(uniform, value) for the names of ``values`` this program declares outside the block; kept while the
        same dict object is asked for again (a view's values are one dict until they change)."""
        last = self._last
        if last[0] is values:
            return last[1]
        # A new dict every frame: its names are the same tuple object as last time unless they changed (the
        # shadow's come and go with the sun), and most programs declare none of them plainly.
        keys = self._keys_of(values)
        if keys is not self._keys:
            if keys != self._keys:
                self._names = tuple((u, n) for u, n in ((self.uniform(n), n) for n in keys) if u is not None)
            self._keys = keys
        names = self._names
        pairs = tuple((u, values[n]) for u, n in names) if names else ()
        self._last = (values, pairs)
        return pairs

    def uniform(self, name: str):
        try:
            return self.plain[name]
        except KeyError:
            found = self.plain[name] = self.program.get(name, None)
            return found


class FrameBlocks:
    """A few uniform buffers holding frame blocks; ``use(data)`` binds one holding ``data`` (rewriting the least
    recently used one if none does). Owned by the renderer: ``release()`` frees the buffers."""

    def __init__(self, ctx, slots: int = 3):
        self.ctx = ctx
        self._buffers = [ctx.buffer(reserve=BLOCK_BYTES) for _ in range(slots)]
        self._contents: list[bytes | None] = [None] * slots
        self._order = list(range(slots))  # least recently used first
        self._programs: dict[int, _ProgramInfo] = {}
        self._last = 0
        self._packed: tuple[dict, bytes] | None = None  # (values, bytes) packed last: pack() starts from them
        self._keys: list[tuple] = [(None, ())]  # (values dict, tuple of its names), the two asked for last

    def pack(self, values: dict) -> bytes:
        """``frame_block.pack(values)``, made from the values packed last (``pack_changes``)."""
        previous = self._packed
        data = pack_changes(values, *(previous or (None, None)))
        self._packed = (values, data)
        return data

    def program_info(self, program) -> _ProgramInfo:
        info = self._programs.get(program.glo)
        if info is None or info.program is not program:  # a released program's GL name may be reused
            info = self._programs[program.glo] = _ProgramInfo(program, self.keys_of)
        return info

    def keys_of(self, values: dict) -> tuple:
        """``tuple(values)``, the same tuple object as for the values asked for before while the names stay: each
        program then knows its plain names unchanged by one identity test. The main view's and the road's mirror
        view's dicts alternate within a frame: the last two are kept."""
        cache = self._keys
        for known, keys in cache:
            if known is values:
                return keys
        keys = tuple(values)
        for _, known_keys in cache:
            if known_keys == keys:
                keys = known_keys
                break
        self._keys = [(values, keys), cache[0]]
        return keys

    def use(self, data: bytes) -> None:
        """Bind (at ``BINDING``) a buffer whose contents are ``data``. Bound every call: other renderers on the
        same context bind their own."""
        contents = self._contents
        index = self._last
        if contents and contents[index] is data:  # a view's bytes are one object: the programs after its first
            self._buffers[index].bind_to_uniform_block(BINDING)
            return
        for index in self._order[::-1]:  # most recent first: usually the first compare matches
            if contents[index] == data:
                break
        else:
            index = self._order[0]
            self._buffers[index].write(data)
            contents[index] = data
        if self._order[-1] != index:
            self._order.remove(index)
            self._order.append(index)
        self._buffers[index].bind_to_uniform_block(BINDING)
        self._last = index

    def read_bound(self) -> bytes:
        """The bytes of the buffer this object bound last, read back from the GPU (for tests)."""
        return self._buffers[self._last].read()

    def release(self) -> None:
        for buffer in self._buffers:
            buffer.release()
        self._buffers = []
        self._contents = []
        self._order = []
        self._programs.clear()
        self._packed = None
