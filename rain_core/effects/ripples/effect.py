"""The ripples effect: drives the ripple field with the frame (the ego car's window, the wheels, the rain, the
spray's droplets) and publishes the water's slopes and the far puddles' ring map for the road."""

from __future__ import annotations

from rain_core.effects.ripples.backend import make_field
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.rain_tiles import RainRippleTexture
from rain_core.effects.ripples.textures import RippleTextures
from rain_core.effects.ripples.wheels import WheelBatch, WheelSweep, wheel_rows
from rain_core.effects.ripples.window import window_centre_xz
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import RainRings
from rain_core.gfx.shaders import ShaderLibrary


class RipplesEffect(Effect):
    """Interactive water (DESIGN §3): wakes of every wheel in the window and raindrop rings on the simulated field
    ahead of the ego car (``window_centre``: the window reaches from behind the car, or the chase camera, to
    ~20 m ahead, where the driver sees the wakes of the cars in front), plus the tiled rain-ring map for puddles
    beyond it.

    It only runs where there is standing water (flood levels above 0) — a dry or merely wet road costs nothing —
    and the solver itself sleeps once the water has settled. It reads the road's ``rc.shared.film_depth_fn``
    (None: the road is off, the water stays flat) and the spray's ``rc.shared.droplet_impacts``, and publishes
    ``rc.shared.water_normals`` (the field's slopes) and, while it rains, ``rc.shared.rain_rings`` (the tiled
    map) for the road's water shading. Settings: ``settings.ripples`` and ``settings.quality.ripple_grid``.

    ``backend`` (one of ``BACKENDS``, default "auto": timed at start-up) is read when the field is built, on the
    first active frame and whenever the grid settings change."""

    name = "ripples"
    # update simulates (CPU only, with the NumPy solvers); upload writes their height into its texture before the
    # frame's first draw (gfx/effect.py); prepare publishes the field to GL. On llvmpipe a draw leaves Python's
    # caches cold for whatever follows it, so the frame runs every effect's CPU update first: with the normals
    # pass and the ring map drawn here in update, the rainfall's and the windshield's updates after it cost ~130
    # and ~150 µs more a frame.
    stages = ("upload", "prepare")

    def __init__(self, ctx, settings=None, *, seed: int = 0, shaders=None):
        self.ctx = ctx
        self.seed = int(seed)
        self.backend = "auto"
        self._owns_shaders = shaders is None and ctx is not None  # a library of our own: ours to release
        self.shaders = shaders if shaders is not None or ctx is None else ShaderLibrary(ctx)
        self.field: RippleField | None = None
        self.textures: RippleTextures | None = None
        self._config = None
        self.rain_tiles = RainRippleTexture(ctx, seed=self.seed, shaders=self.shaders) if ctx is not None else None
        self.last_report: dict = {}
        self._to_publish: tuple[float, float] | None = None  # (time s, rain mm/h) of the frame update stepped

    def _ensure_field(self, settings) -> RippleField:
        r = settings.ripples
        config = (settings.quality.ripple_grid, r.extent_m, r.speed_m_s, r.damping_per_s)
        if config != self._config:
            self._release_field()
            n, extent, speed, damping = config
            self.field = make_field(self.ctx, n=n, extent_m=extent, speed_m_s=speed, damping_per_s=damping,
                                    backend=self.backend, seed=self.seed, shaders=self.shaders)
            if self.ctx is not None:
                self.textures = RippleTextures(self.ctx, self.field, self.shaders)
            self._config = config
        self.field.wake_gain = r.wheel_strength
        self.field.rain_gain = r.rain_strength
        return self.field

    def active(self, frame) -> bool:
        settings, weather = frame.settings, frame.weather
        if settings is None or weather is None or not settings.ripples.enabled:
            return False
        return max(weather.cracks, weather.puddles) > 0.0

    def wheel_batch(self, frame, field: RippleField) -> WheelBatch:
        """The wheels whose contact path this frame may touch the window, as one ``WheelBatch`` (world m, m/s;
        film depths left to the road's function)."""
        ox, oz = field.origin_xz
        reach = field.extent_m
        rows = []
        for vehicle in frame.vehicles:
            # Cheap reject on the body position first: wheels lie within a few metres of it.
            x, z = float(vehicle.position[0]), float(vehicle.position[2])
            if ox - 20.0 < x < ox + reach + 20.0 and oz - 20.0 < z < oz + reach + 20.0:
                rows += wheel_rows(vehicle)
        # One array for all wheels (a few vehicles, 4 wheels each: Python floats cost less than NumPy per vehicle),
        # checked here once: the field's update then trusts it.
        return WheelBatch.from_rows(rows)

    @staticmethod
    def window_centre(frame, field: RippleField) -> tuple[float, float] | None:
        """World (x, z) in m where the window is centred this frame (None: no ego car, keep the window): ahead
        of the ego car along its heading, by ``window.window_offset_m`` for the frame's camera (driver's seat: the
        window reaches ~21 m ahead, so the wakes of the cars ahead are simulated where the driver sees them;
        chase: from behind the camera over the car to ~16 m ahead)."""
        ego = frame.ego
        if ego is None:
            return None
        heading = ego.forward()
        camera = frame.camera
        return window_centre_xz((ego.position[0], ego.position[2]), (heading[0], heading[2]), field.extent_m,
                                None if camera is None else camera.position,
                                # basis()[2] alone, without the right and up axes' cross products
                                None if camera is None else camera.forward_axis(),
                                car_half_length_m=0.5 * float(ego.spec.length_m),
                                margin_m=field.recenter_margin_cells * field.cell_m)

    def wheel_sweeps(self, frame, field: RippleField) -> list[WheelSweep]:
        """``wheel_batch`` as a list of ``WheelSweep`` (one per wheel)."""
        batch = self.wheel_batch(frame, field)
        return [WheelSweep(tuple(batch.p0_xz[i]), tuple(batch.p1_xz[i]), float(batch.speed_m_s[i]),
                           float(batch.tire_width_m[i])) for i in range(len(batch))]

    def update(self, frame, rc) -> None:
        self._to_publish = None
        field = self._ensure_field(frame.settings)
        film_fn = rc.shared.film_depth_fn
        if film_fn is None:  # the road effect is off: keep the water flat rather than guessing where it is
            return
        center = self.window_centre(frame, field)
        rate = frame.rain_rate_mm_h
        # Rain, wakes and the spray's droplets reach the solver as one batch (one draw on the GPU backend).
        self.last_report = field.update(frame.dt_s, center_xz=center, rate_mm_h=rate,
                                        wheels=self.wheel_batch(frame, field), film_depth_fn=film_fn,
                                        impacts=rc.shared.droplet_impacts)
        self._to_publish = (frame.time_s, rate)

    def render(self, stage: str, rc) -> None:
        """upload: the NumPy solvers' height into its texture. prepare: the field's textures (the height, uploaded
        here if upload was not asked, or the GPU solver's state; the normals pass) and, while it rains, the ring
        map, published on ``rc.shared`` for the road's scene pass."""
        if self._to_publish is None:
            return
        if stage == "upload":
            if self.textures is not None:
                self.textures.upload()
            return
        if stage != "prepare":
            return
        time_s, rate = self._to_publish
        self._to_publish = None
        if self.textures is not None:
            rc.shared.water_normals = self.textures.water_normals()
        if rate > 0.0 and self.rain_tiles is not None:
            self.rain_tiles.render(time_s, rate)
            rc.shared.rain_rings = RainRings(self.rain_tiles.texture, self.rain_tiles.tile_m)

    def describe(self) -> str:
        if self.field is None:
            return ""
        state = "asleep" if self.field.asleep else f"{self.last_report.get('substeps', 0)} sub-steps"
        return f"{self.field.backend} {self.field.n}², {state}"

    def _release_field(self) -> None:
        if self.textures is not None:
            self.textures.release()
            self.textures = None
        if self.field is not None:
            self.field.release()
            self.field = None

    def release(self) -> None:
        """Free the field's and the ring map's GL objects, and the programs when the shader library is our own
        (a shared library's owner releases it)."""
        self._release_field()
        self._config = None
        if self.rain_tiles is not None:
            self.rain_tiles.release()
            self.rain_tiles = None
        if self._owns_shaders:
            self.shaders.release()
            self._owns_shaders = False
