"""What one frame hands to every effect: the ``Frame`` (simulation inputs), the ``RenderContext`` (GL objects and
camera matrices), the typed ``SharedResources`` effects exchange, and the ``PassStat`` the renderer records.

The world is periodic along Z (``layout.PERIOD_M``). Everything sent to the GPU is in a *wrapped* frame: world z
minus ``shift_z``, a multiple of the period chosen so the camera sits in [0, PERIOD_M). That keeps float32
positions precise however far the car has driven.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import moderngl
import numpy as np

from rain_core.camera import Camera
from rain_core.gfx import frame_block
from rain_core.gfx.linalg import inverse
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import RenderTarget
from rain_core.gfx.uniforms import mat4_bytes
from rain_core.lighting import Lighting


@dataclass
class Frame:
    """Everything the effects see for one frame. Units: s, m, m/s; rain in mm/h inside ``weather``."""

    time_s: float
    dt_s: float
    camera: Camera
    lighting: Lighting
    world: object  # rain_core.world.World
    ego: object | None = None  # rain_core.vehicles.Vehicle
    vehicles: list = field(default_factory=list)  # every vehicle, the ego included
    weather: object | None = None  # rain_core.weather.WeatherState
    settings: object | None = None  # rain_core.settings.Settings
    headlights_on: bool = False
    flash: object | None = None  # rain_core.effects.lightning.storm.FlashView: the flash lit in this frame
    storm: object | None = None  # rain_core.effects.lightning.storm.Storm (read-only for effects: thunder delay)

    @property
    def rain_rate_mm_h(self) -> float:
        return float(getattr(self.weather, "rate_mm_h", 0.0)) if self.weather is not None else 0.0

    def with_camera(self, camera: Camera) -> Frame:
        """This frame seen by ``camera`` (a mirror view's): ``dataclasses.replace(self, camera=camera)`` without its
        walk over the fields, which cost ~6 Python lines a field every frame."""
        return Frame(self.time_s, self.dt_s, camera, self.lighting, self.world, self.ego, self.vehicles, self.weather,
                     self.settings, self.headlights_on, self.flash, self.storm)


@dataclass
class PassStat:
    name: str
    ran: bool
    cpu_ms: float = 0.0
    gpu_ms: float | None = None
    note: str = ""  # e.g. which backend an effect chose


# --- what effects share -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class WaterNormals:
    """The ripple field: ``texture`` RG = slopes (dh/dx, dh/dz), B = height (m, a tyre's trough is negative);
    ``origin_xz_m`` the world (x, z) in m of the centre of texel 0; ``extent_m`` from the first texel centre to the
    last."""

    texture: moderngl.Texture
    origin_xz_m: tuple[float, float]
    extent_m: float


@dataclass(frozen=True)
class RainRings:
    """A tiling normal map of raindrop rings on standing water, ``tile_m`` metres per repeat."""

    texture: moderngl.Texture
    tile_m: float


# (x m, z m world) → standing water depth, mm. It may carry a hashable ``cache_key``: equal keys mean equal depths,
# so a consumer may keep depths it asked for while the key is unchanged.
FilmDepthFn = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass
class SharedResources:
    """The only channel between effects, filled anew every frame in update order (road → spray → ripples → …).

    | field            | producer (stage)   | consumers                  |
    |------------------|--------------------|----------------------------|
    | film_depth_fn    | road (update)      | ripples (update)           |
    | droplet_impacts  | spray, drips       | ripples (update)           |
    | water_normals    | ripples (update)   | road (scene binding)       |
    | rain_rings       | ripples (update)   | road (scene binding)       |

    A field left None means its producer did not run this frame; consumers then fall back (documented there).
    """

    film_depth_fn: FilmDepthFn | None = None
    # (N, 3): x m, z m world, downward momentum kg·m/s of spray parcels that landed in standing water.
    droplet_impacts: np.ndarray | None = None
    water_normals: WaterNormals | None = None
    rain_rings: RainRings | None = None


class FrameUniforms(dict):
    """A dict of frame uniforms that counts its changes (``version``), so a program asking for the frame's
    uniforms again costs one comparison, not a walk over every entry."""

    __slots__ = ("version",)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.version = 0

    def __setitem__(self, key, value):
        self.version += 1
        super().__setitem__(key, value)

    def __delitem__(self, key):
        self.version += 1
        super().__delitem__(key)

    def __ior__(self, other):
        self.version += 1
        return super().__ior__(other)

    def update(self, *args, **kwargs):
        self.version += 1
        super().update(*args, **kwargs)

    def pop(self, *args):
        self.version += 1
        return super().pop(*args)

    def popitem(self):
        self.version += 1
        return super().popitem()

    def setdefault(self, key, default=None):
        self.version += 1
        return super().setdefault(key, default)

    def clear(self):
        self.version += 1
        super().clear()


_LIGHTING_VALUES: list = [None, None]  # [the last Lighting asked about, its uniforms]


def _lighting_values(lighting) -> dict:
    """The sun, sky and exposure uniforms of ``lighting`` (an immutable object, the same one every frame while the
    hour and the overcast stay): made once per lighting, not for every view of every frame."""
    if _LIGHTING_VALUES[0] is not lighting:
        _LIGHTING_VALUES[:] = [lighting, {
            "u_exposure": lighting.exposure,
            "u_night": lighting.night_factor,
            "u_sun_dir": tuple(float(v) for v in lighting.sun_direction),
            "u_sun_illum": tuple(float(v) for v in lighting.sun_illuminance),
            "u_sky_zenith": tuple(float(v) for v in lighting.sky_zenith),
            "u_sky_horizon": tuple(float(v) for v in lighting.sky_horizon),
            "u_ground_albedo": lighting.ground_albedo,
        }]
    return _LIGHTING_VALUES[1]


@dataclass
class RenderContext:
    """What a pass needs to draw: GL objects, the frame, camera matrices in the wrapped frame, the shared value,
    and the per-frame uniforms every program receives (``set_frame_uniforms``).

    Effects may call the renderer's public methods (``rc.renderer.draw_mirror_view``) and never assign to it."""

    ctx: moderngl.Context
    shaders: ShaderLibrary
    frame: Frame
    hdr: RenderTarget
    size: tuple[int, int]
    shift_z: float
    view: np.ndarray
    projection: np.ndarray
    lights: tuple  # packed (pos, dir, color, count) for common/lighting.glsl
    renderer: object  # rain_core.gfx.renderer.Renderer (public methods only)
    shared: SharedResources = field(default_factory=SharedResources)
    # Uniforms beyond the camera and lighting that every program gets: the medium the active effects report
    # (Effect.frame_uniforms) over the clear-air defaults, and the sun shadow map's.
    uniforms: dict = field(default_factory=FrameUniforms)
    active: tuple = ()  # the effects that run this frame
    # The renderer's uniform buffers for the frame block (rain_core.gfx.frame_block): set_frame_uniforms binds one.
    frame_blocks: frame_block.FrameBlocks | None = None
    # The tile size (pixels) of the light grid the renderer builds for this view after its depth pre-pass
    # (gfx/light_grid.py); 0: no grid, every light is visited everywhere (contexts made outside the renderer).
    light_grid_px: int = 0
    # Whether the frame's view is drawn (Renderer.render(frame, draw=False): only the simulations advance).
    drawn: bool = True

    @property
    def view_proj(self) -> np.ndarray:
        """projection @ view, computed once per context (the frame block, the mirrors, the post passes ask)."""
        cached = self.__dict__.get("_vp_cache")
        if cached is None or cached[0] is not self.view or cached[1] is not self.projection:
            product = self.projection @ self.view
            product.flags.writeable = False  # shared by every asker
            cached = self.__dict__["_vp_cache"] = (self.view, self.projection, product)
        return cached[2]

    @property
    def camera_position(self) -> np.ndarray:
        """Camera position (m) in the wrapped frame (read-only; made once per camera and shift: the draw lists,
        the frame block, the shadow and the mirrors ask for it)."""
        return self._camera_cache()[3]

    def _camera_floats(self) -> tuple[float, float, float]:
        """``camera_position`` as a tuple of floats (the frame block's u_camera_pos)."""
        return self._camera_cache()[4]

    def _camera_cache(self) -> tuple:
        camera = self.frame.camera
        cached = self.__dict__.get("_cam_cache")
        if cached is None or cached[0] is not camera or cached[1] is not camera.position or cached[2] != self.shift_z:
            # In floats: x − 0.0 is x (−0.0 included), so only z is subtracted, as the array subtraction would
            position = camera.position
            if type(position) is np.ndarray and position.dtype.kind == "f":
                x, y, z = position.tolist()
            else:
                x, y, z = (float(v) for v in position)
            floats = (x, y, z - float(self.shift_z))
            position = np.array(floats)
            position.flags.writeable = False
            cached = self.__dict__["_cam_cache"] = (camera, camera.position, self.shift_z, position, floats)
        return cached

    def wrap(self, world_points) -> np.ndarray:
        """World positions (…, 3) m → the wrapped frame the GPU uses."""
        out = np.array(world_points, dtype=np.float64, copy=True)
        out[..., 2] -= self.shift_z
        return out

    def _frame_values(self) -> dict:
        """Camera, exposure, sun/sky and light values of this context, computed once (every program of the frame
        gets the same; ``view``/``projection`` replaced means a new context, see dataclasses.replace)."""
        cached = self.__dict__.get("_frame_cache")
        if cached is not None:
            k = cached[0]
            if k[0] is self.view and k[1] is self.projection and k[2] is self.frame and k[3] is self.lights:
                return cached[1]
        key = (self.view, self.projection, self.frame, self.lights)
        values = {
            "u_view_proj": mat4_bytes(self.view_proj),
            "u_camera_pos": self._camera_floats(),
            "u_time": self.frame.time_s,
            **_lighting_values(self.frame.lighting),
            "u_light_count": self.lights[3],
            "u_light_grid_px": self.light_grid_px,
            "u_light_pos": self.lights[0],
            "u_light_dir": self.lights[1],
            "u_light_color": self.lights[2],
        }
        self.__dict__["_frame_cache"] = (key, values)
        return values

    def _frame_state(self) -> tuple[dict, bytes]:
        """(every frame uniform: the frame's own values under ``uniforms``, the frame block's bytes), recomputed
        only when the frame values or an entry of ``uniforms`` changed (compared by identity; a ``FrameUniforms``
        not written since is not walked at all)."""
        base = self._frame_values()
        uniforms = self.uniforms
        cached = self.__dict__.get("_state_cache")
        versioned = type(uniforms) is FrameUniforms
        if versioned and cached is not None and cached[0] is base and cached[4] is uniforms \
                and cached[5] == uniforms.version:
            return cached[2], cached[3]
        items = tuple(uniforms.items())
        if (cached is not None and cached[0] is base and len(cached[1]) == len(items)
                and all(a[0] == b[0] and a[1] is b[1] for a, b in zip(cached[1], items, strict=True))):
            if versioned:  # written again with the same values: the next ask takes the quick path
                self.__dict__["_state_cache"] = (*cached[:4], uniforms, uniforms.version)
            return cached[2], cached[3]
        merged = {**base, **uniforms}  # the frame's own uniforms (medium, shadow) take precedence
        blocks = self.frame_blocks
        data = frame_block.pack(merged) if blocks is None else blocks.pack(merged)
        self.__dict__["_state_cache"] = (base, items, merged, data, uniforms, uniforms.version if versioned else None)
        return merged, data

    def frame_block_bytes(self) -> bytes:
        """The frame block's std140 bytes for this context (packed once while its values stay)."""
        return self._frame_state()[1]

    def set_frame_uniforms(self, program: moderngl.Program, *, bind: bool = True) -> None:
        """Camera, exposure, sun/sky, lights, atmosphere and shadow uniforms, where the program has them: the
        frame block (shaders/common/frame.glsl) is bound, and names the program declares as plain uniforms
        (samplers, names outside the block) are written.

        ``bind=False``: this context's block is bound already (a draw just before bound it and nothing in between
        bound another), so it is not bound again."""
        values, data = self._frame_state()
        blocks = self.frame_blocks
        if blocks is None:
            raise RuntimeError("this RenderContext has no frame_blocks: make it with Renderer.render_context")
        info = blocks.program_info(program)
        if info.has_block and bind:
            blocks.use(data)
        for target, value in info.plain_values(values):
            if isinstance(value, bytes):
                target.write(value)
            elif isinstance(value, np.ndarray):
                target.write(np.ascontiguousarray(value, dtype=np.float32).tobytes())
            else:
                target.value = value

    @property
    def inv_view_proj(self) -> np.ndarray:
        """inverse(projection @ view), computed once per context (sky and depth reconstruction passes)."""
        key = (self.view, self.projection)
        cached = self.__dict__.get("_inv_cache")
        if cached is None or cached[0][0] is not key[0] or cached[0][1] is not key[1]:
            cached = self.__dict__["_inv_cache"] = (key, inverse_view_proj(self.view_proj))
        return cached[1]


# (rows of the view-projection inverted last, its inverse): the road's mirror view and the main view of a frame
# are each other's mirror image about y = 0, and the second inverse is then the first with one row negated.
_LAST_INVERSE: list = [None]
_NEGATE_ROW_1 = np.array([[1.0], [-1.0], [1.0], [1.0]])


def _mirrored_in_y(a: list, b: list) -> bool:
    """Whether 4×4 ``a`` equals ``b`` with its column 1 negated (b @ diag(1, −1, 1, 1)); zeros of either sign
    match."""
    for ra, rb in zip(a, b, strict=True):
        if ra[0] != rb[0] or ra[1] != -rb[1] or ra[2] != rb[2] or ra[3] != rb[3]:
            return False
    return True


def inverse_view_proj(view_proj: np.ndarray) -> np.ndarray:
    """``linalg.inverse(view_proj)``, the same bits, read-only. When ``view_proj`` is the matrix inverted last
    times diag(1, −1, 1, 1) — the road reflection's view is the main view times that mirror — the inverse is the
    last one with row 1 negated, without a second LAPACK call (~50 µs between the frame's GL work): negating a
    column of A negates the same column of its LU factors (the pivots compare magnitudes) and the same row of the
    solution, every rounding being symmetric. tests/gfx/test_linalg.py checks the bits on mirrored cameras."""
    rows = view_proj.tolist()
    last = _LAST_INVERSE[0]
    if last is not None and _mirrored_in_y(rows, last[0]):
        out = last[1] * _NEGATE_ROW_1
    else:
        out = inverse(view_proj)
    out.flags.writeable = False
    _LAST_INVERSE[0] = (rows, out)
    return out
