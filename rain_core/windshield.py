"""The driver's windshield (DESIGN §3 "Windshield", issue 8): drops that gather, slide with the airflow,
merge and trail, a water film, wipers that push water, and the refraction of the street through it all.

Where the water lives (the bookkeeping)
---------------------------------------
All water mass is on the CPU, in float64, in three places:

* **drops** — objects with position (s, t) m on the glass, velocity m/s and mass kg (``WindshieldSim``);
* **the film** — a coarse FILM_CELLS × FILM_CELLS grid over the glass's UV square holding kg per cell: mist
  (arrivals too small to be objects), impact satellites, wet trails, wiper residue and wiper leakage;
* **the wiper beads** — kg per radial bin along each blade, the water a blade pushes in front of it.

Four counters (kg) close the balance exactly: ``arrived − wiped − shed − evaporated = on the glass``
(``mass_on_glass()``; ``balance_error_kg()`` is the difference, float64 rounding only). *Wiped*: water a blade
pushes off the glass (past an edge, or shed at the end of a stroke); *shed*: drops that run or are blown off
an edge of the glass; *evaporated*: from the film and, very slowly, from drops.

The GPU water texture is a *rendering* of that state plus purely visual detail: drops are splatted into a
height texture each frame, and a high-resolution film texture carries what the coarse grid cannot (streaks of
wiper residue, wet trail lines, splash speckle, the slow beading of a thin film). Each frame that texture is
rescaled so that its local mean over a coarse cell equals the CPU film there (its mipmap at the coarse level
is the cell mean), so the picture never shows water the bookkeeping does not have.

The glass
---------
``GlassGeometry`` wraps ``car_mesh.windshield_frame``: a trapezoid of height H (m, along the glass) whose
width shrinks linearly from the bottom to the top, bulged outward by ``sag``. Coordinates: s (m) to the car's
right, t (m) up the glass; UV: u = s/width(t) + ½, v = t/H (the mesh's UV). Gravity along the glass follows
the real curved surface (a drop near the edge of the bulge slides outward a little).

Drop physics (per drop, vectorised; float64)
--------------------------------------------
A drop on glass is a spherical cap of contact radius a with contact angle θ = CONTACT_ANGLE_DEG: volume
k_V·a³, height a·tan(θ/2). Forces along the glass:

* gravity, m·g projected on the (curved) surface;
* air drag ½·ρ_air·C_d·A·|u|·u, A the cap's frontal area, u the air velocity at the drop's top inside
  a laminar boundary layer (Pohlhausen profile, δ = 5·√(ν·x/U)), minus the drop's own velocity. The air over
  the glass is the car's relative wind: the headwind turns to run up the glass, slow near the cowl
  (stagnation) and faster towards the roof, spreading outwards towards the A-pillars; a crosswind adds a
  sideways flow;
* contact-line pinning (Furmidge): F = γ·2a·Δcosθ. A drop at rest stays put while the other forces are weaker
  (small drops stick; large ones run), a moving drop feels KINETIC_PIN × that against its motion;
* viscous resistance in the moving drop, linear in its speed (implicit, stable for any step).

Since drag on a cap in the boundary layer grows faster with size than its weight, large drops start to climb
first; see ``airflow_onset_speed_m_s`` for the car speed at which a drop of a given size creeps up the glass.

Arrivals come at ``physics.flux_on_surface_per_s`` for the glass's normal and velocity through the rain and
wind, with diameters drawn from the *flux-weighted* Marshall–Palmer law (the distribution in the air times
each size's closing speed on the glass), none under a roof (``world.occluder_height``). A fast impact
splashes: a fraction of the drop (rising with the normal impact speed) spreads as satellite mist into the film
around it.

Merging uses a uniform spatial grid (plus a coarser one for the few large drops) and the closest approach of
the two drops' motions within the step, so fast drops cannot tunnel; touching drops join (mass, momentum and
centre of mass conserved; chains resolve as connected components). A running drop sweeps up the film in its
path and leaves a trail: a thin wet line (film) and, every few radii, a small droplet.

GPU and rendering: see ``WindshieldEffect``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import moderngl
import numpy as np

from rain_core import physics
from rain_core.car_mesh import windshield_frame, windshield_surface
from rain_core.gl import ShaderLibrary, float_target
from rain_core.renderer import Effect
from rain_core.vehicles import CAR_SPEC, VehicleSpec
from rain_core.wipers import (
    SENSOR_CENTRE_FRACTION,
    SENSOR_SIZE_M,
    StrokeSegment,
    WiperController,
    tandem_blades,
)

# --- physical constants ------------------------------------------------------------------------------------
RHO_W = physics.RHO_WATER  # kg/m³
RHO_AIR = 1.2  # kg/m³
NU_AIR = 1.5e-5  # m²/s, kinematic viscosity of air
MU_W = 1.0e-3  # Pa·s, water
GAMMA_W = 0.072  # N/m, surface tension of water
G = 9.81  # m/s²

# --- drop model --------------------------------------------------------------------------------------------
CONTACT_ANGLE_DEG = 50.0  # clean automotive glass, 40–60°
_HALF = math.radians(CONTACT_ANGLE_DEG) / 2.0
HEIGHT_PER_RADIUS = math.tan(_HALF)  # cap height / contact radius
VOLUME_PER_RADIUS3 = math.pi * HEIGHT_PER_RADIUS * (3.0 + HEIGHT_PER_RADIUS**2) / 6.0  # cap volume / a³
_THETA = math.radians(CONTACT_ANGLE_DEG)
_R_CAP = 1.0 / math.sin(_THETA)  # sphere radius / a
FRONTAL_PER_RADIUS2 = _R_CAP**2 * (_THETA - math.sin(_THETA) * math.cos(_THETA))  # circular-segment area / a²
# Contact-angle hysteresis cos θr − cos θa. 0.25 makes drops of contact radius ≳ 3 mm (≈ 20 µL, a 3.4 mm
# raindrop's volume) slide down a 60°-raked glass — single raindrops stick, merged ones run.
HYSTERESIS = 0.25
KINETIC_PIN = 0.8  # sliding resistance / static pinning: drops stick-slip rather than glide
# Viscous resistance of a sliding drop, F = c·μ·a·v, dominated by the wedge at its contact line: c ≈
# 6·ln(a/ℓ)/θ ≈ 100 (Cox–Voinov, ℓ ~ 1 nm). Down a 60° glass a 4 mm drop then slides at ~0.15 m/s and a
# 6 mm one at ~0.7 m/s.
VISCOUS_C = 100.0
# Drag coefficient of a sessile cap in shear flow (more than a free sphere's ~0.5). With the boundary layer
# below, a drop at mid-glass starts to climb at ~110 km/h (2 mm contact radius), ~85 km/h (3 mm) and
# ~65 km/h (5 mm): small drops stay put at any speed, large ones stream up.
DRAG_CD = 1.2
BL_RUN_UP_M = 0.2  # boundary-layer run from the stagnation line at the cowl to the glass's lower edge
FLOW_AT_BOTTOM = 0.3  # air speed over the glass / headwind: low near the cowl (stagnation) …
FLOW_AT_TOP = 1.0  # … accelerating to the free stream at the roof
FLOW_SPREAD = 0.35  # outward flow towards the A-pillars at the glass's side edges, / the upward flow
CROSSWIND_GAIN = 0.6  # sideways air speed over the glass / crosswind

D_OBJECT_MM = 0.5  # arrivals smaller than this (after splashing) join the film: sub-pixel at 1080p
M_OBJECT_MIN = RHO_W * math.pi / 6.0 * (D_OBJECT_MM * 1e-3) ** 3  # kg
SPLASH_SPEED_M_S = (3.0, 25.0)  # normal impact speed where splashing starts / reaches SPLASH_MAX
SPLASH_MAX = 0.7  # most of a drop that can splash into satellite mist
TRAIL_SPACING_RADII = 3.0  # a running drop drops a droplet every this many of its radii
TRAIL_FRACTION = 0.02  # of the drop's mass, per trail droplet
TRAIL_PARENT_MIN = 25.0 * M_OBJECT_MIN  # drops lighter than this leave no droplets (only the wet line)
TRAIL_FILM_M = 0.3e-6  # thickness of the wet line a running drop leaves (m)
V_STOP_M_S = 1e-3

# --- film --------------------------------------------------------------------------------------------------
FILM_CELLS = 64  # the CPU film grid is FILM_CELLS × FILM_CELLS over the glass's UV square
BEAD_THRESHOLD_M = 8e-6  # a film thicker than this (m, cell mean) beads up into a drop
BEAD_KEEP = 0.25  # the film left in a cell that beaded, × the threshold
# Evaporation of thin water, kg/m²/s at rest, × (1 + U/EVAP_AIR_M_S) with U the air speed over the glass:
# a 0.1 µm wiper streak dries in ~10 s parked and in ~1 s at motorway speed.
FILM_EVAP_KG_M2_S = 1e-5
EVAP_AIR_M_S = 2.0
# Diffusion-limited evaporation of a sessile drop, dm/dt = −k·a (k = 4·D_v·Δc in humid rain air): hours.
DROP_EVAP_KG_M_S = 1.7e-7

# --- wipers ------------------------------------------------------------------------------------------------
BEAD_BINS = 24  # radial bins of the water a blade pushes
RESIDUE_M = 0.1e-6  # film left behind a new, wet blade (m); × (1 + 4·wear)
# Water a blade can push per metre of its length before it leaks past the rubber: a bead ~2 mm across.
BEAD_CAPACITY_KG_M = 3e-3
END_LEAVE_FRACTION = 0.35  # of the bead, left as a row of drops where a stroke ends; the rest sheds
BLADE_HALF_WIDTH_M = 0.006  # the rubber's reach either side of its line

MAX_SUBSTEP_S = 1.0 / 30.0
MAX_FRAME_DT_S = 0.25
_D_GRID_MM = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 512)
_V_GRID_M_S = np.asarray(physics.terminal_velocity(_D_GRID_MM), dtype=np.float64)


def _norm(v: np.ndarray) -> np.ndarray:
    """Lengths of (n, 2) vectors (np.linalg.norm is ~20× slower on this shape)."""
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1])


def drop_radius(mass_kg) -> np.ndarray:
    """Contact radius (m) of a drop of the given mass (kg) sitting on the glass as a spherical cap."""
    return np.cbrt(np.asarray(mass_kg, dtype=np.float64) / (RHO_W * VOLUME_PER_RADIUS3))


def drop_mass(radius_m) -> np.ndarray:
    """Mass (kg) of a cap of contact radius ``radius_m`` (m)."""
    return RHO_W * VOLUME_PER_RADIUS3 * np.asarray(radius_m, dtype=np.float64) ** 3


# --- glass --------------------------------------------------------------------------------------------------
class GlassGeometry:
    """The windshield as a trapezoid in its own frame (see the module docstring). Lengths in m."""

    def __init__(self, spec: VehicleSpec = CAR_SPEC):
        f = windshield_frame(spec)
        self.spec = spec
        self.width_bottom = float(f["width_m"])
        self.width_top = float(f["top_width_m"])
        self.height = float(f["height_m"])
        self.sag = float(f["sag_m"])
        self.rake = float(f["rake_rad"])
        self.bottom_center = np.asarray(f["bottom_center"], dtype=np.float64)
        self.up = np.asarray(f["up_along_glass"], dtype=np.float64)
        self.right = np.asarray(f["right"], dtype=np.float64)
        self.normal = np.asarray(f["normal"], dtype=np.float64)
        self.area_m2 = 0.5 * (self.width_bottom + self.width_top) * self.height
        self._dw = (self.width_top - self.width_bottom) / self.height  # d width / d t

    def width(self, t) -> np.ndarray:
        """Glass width (m) at height t (m) up the glass."""
        return self.width_bottom + self._dw * np.asarray(t, dtype=np.float64)

    def to_uv(self, st) -> np.ndarray:
        st = np.asarray(st, dtype=np.float64)
        return np.stack([st[..., 0] / self.width(st[..., 1]) + 0.5, st[..., 1] / self.height], axis=-1)

    def from_uv(self, uv) -> np.ndarray:
        uv = np.asarray(uv, dtype=np.float64)
        t = uv[..., 1] * self.height
        return np.stack([(uv[..., 0] - 0.5) * self.width(t), t], axis=-1)

    def contains(self, st) -> np.ndarray:
        st = np.asarray(st, dtype=np.float64)
        t = st[..., 1]
        return (t >= 0.0) & (t <= self.height) & (np.abs(st[..., 0]) <= 0.5 * self.width(t))

    def local_points(self, st) -> np.ndarray:
        """Car-local positions (m) of glass points, the bulge included."""
        uv = self.to_uv(st)
        st = np.asarray(st, dtype=np.float64)
        bulge = self.sag * (1.0 - (2.0 * uv[..., 0] - 1.0) ** 2) * (1.0 - (2.0 * uv[..., 1] - 1.0) ** 2)
        return (
            self.bottom_center
            + st[..., 1:2] * self.up
            + st[..., 0:1] * self.right
            + bulge[..., None] * self.normal
        )

    def gravity(self, st) -> np.ndarray:
        """Acceleration of gravity along the curved glass, (…, 2) m/s² in (s, t) (the car is level)."""
        st = np.asarray(st, dtype=np.float64)
        s, t = st[..., 0], st[..., 1]
        w = self.width(t)
        u = s / w + 0.5
        v = t / self.height
        bu, bv = 1.0 - (2.0 * u - 1.0) ** 2, 1.0 - (2.0 * v - 1.0) ** 2
        dbu_du, dbv_dv = -4.0 * (2.0 * u - 1.0), -4.0 * (2.0 * v - 1.0)
        du_dt = -s * self._dw / (w * w)
        ny = self.normal[1]
        dy_ds = self.sag * ny * dbu_du / w * bv
        dy_dt = self.up[1] + self.sag * ny * (dbu_du * du_dt * bv + bu * dbv_dv / self.height)
        return np.stack([-G * dy_ds, -G * dy_dt], axis=-1)

    def sample_uniform(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """n points (s, t) m uniformly distributed over the glass area."""
        u1, u2 = rng.random(n), rng.random(n)
        w0, dw, h = self.width_bottom, self._dw * self.height, self.height
        # Inverse CDF of the density ∝ width(t): solve w0·x + dw·x²/2 = q·(w0 + dw/2), x = t/H.
        q = u1 * (w0 + 0.5 * dw)
        x = 2.0 * q / (w0 + np.sqrt(w0 * w0 + 2.0 * dw * q)) if dw != 0 else q / w0
        t = np.clip(x, 0.0, 1.0) * h
        return np.stack([(u2 - 0.5) * self.width(t), t], axis=-1)

    def cells(self, n: int = FILM_CELLS) -> tuple[np.ndarray, np.ndarray]:
        """Centres (n, n, 2) (s, t) m and areas (n, n) m² of the film grid's cells; index [iv, iu]."""
        c = (np.arange(n) + 0.5) / n
        uu, vv = np.meshgrid(c, c)
        centres = self.from_uv(np.stack([uu, vv], axis=-1))
        areas = self.width(centres[..., 1]) / n * (self.height / n)
        return centres, areas

    def cell_index(self, st, n: int = FILM_CELLS) -> np.ndarray:
        """Flat film-cell index (iv·n + iu) of points (…, 2) (s, t) m; points on the edge go to the edge
        cell."""
        uv = self.to_uv(st)
        iu = np.minimum(
            np.maximum((uv[..., 0] * n).astype(np.int64), 0), n - 1
        )  # np.clip is slow on small arrays
        iv = np.minimum(np.maximum((uv[..., 1] * n).astype(np.int64), 0), n - 1)
        return iv * n + iu


# --- inputs -------------------------------------------------------------------------------------------------
@dataclass
class GlassInputs:
    """What the glass sees this frame. rate_mm_h: rain rate (mm/h); car_velocity_m_s and wind_m_s: world (3,)
    m/s; car_rotation: (3, 3) car-local → world; sheltered: a roof over the glass stops the rain; drop_scale:
    arrivals × this; wiper settings: mode, interval_s, low/high cycles per minute, auto sensitivity, blade
    wear."""

    rate_mm_h: float = 0.0
    car_velocity_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    wind_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    car_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    sheltered: bool = False
    drop_scale: float = 1.0
    drop_budget: int = 6000
    wiper_mode: str = "off"
    wiper_interval_s: float = 4.0
    wiper_low_cpm: float = 45.0
    wiper_high_cpm: float = 70.0
    wiper_sensitivity: float = 1.0
    blade_wear: float = 0.2

    @classmethod
    def for_speed(cls, speed_kmh: float, rate_mm_h: float, **kwargs) -> GlassInputs:
        """A car driving straight along −Z at speed_kmh (km/h) in rain of rate_mm_h (mm/h), no wind."""
        return cls(rate_mm_h=rate_mm_h, car_velocity_m_s=np.array([0.0, 0.0, -speed_kmh / 3.6]), **kwargs)

    def relative_air_local(self) -> np.ndarray:
        """Air velocity relative to the car, in the car's local frame (m/s): +z is a headwind."""
        rel = np.asarray(self.wind_m_s, float) - np.asarray(self.car_velocity_m_s, float)
        return np.asarray(self.car_rotation, float).T @ rel


def airflow_onset_speed_m_s(radius_m: float, t_m: float | None = None, spec: VehicleSpec = CAR_SPEC) -> float:
    """Car speed (m/s, still air) at which a drop of contact radius ``radius_m`` (m), at rest at height t_m
    (m;
    default mid-glass) on the centre line, starts to creep up the glass (bisection on the force balance)."""
    glass = GlassGeometry(spec)
    t = 0.5 * glass.height if t_m is None else float(t_m)
    st = np.array([[0.0, t]])
    m = float(drop_mass(radius_m))

    def up_force(v: float) -> float:
        air = _air_velocity(glass, st, np.array([0.0, 0.0, v]))
        f = m * glass.gravity(st)[0] + _drag(glass, st, np.array([radius_m]), air, np.zeros((1, 2)))[0]
        pin = GAMMA_W * 2.0 * radius_m * HYSTERESIS
        return f[1] - pin

    lo, hi = 0.0, 150.0
    if up_force(hi) <= 0:
        return math.inf
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if up_force(mid) <= 0 else (lo, mid)
    return hi


def _air_velocity(glass: GlassGeometry, st: np.ndarray, air_local: np.ndarray) -> np.ndarray:
    """Air velocity just outside the boundary layer over the glass, (n, 2) m/s in (s, t)."""
    head, cross = float(air_local[2]), float(air_local[0])
    t = st[:, 1]
    frac = np.clip(t / glass.height, 0.0, 1.0)
    if head >= 0.0:
        up = head * (FLOW_AT_BOTTOM + (FLOW_AT_TOP - FLOW_AT_BOTTOM) * frac)
    else:  # tailwind or reversing: a weak, separated flow down the glass
        up = np.full_like(t, head * FLOW_AT_BOTTOM)
    side = np.abs(up) * FLOW_SPREAD * (2.0 * st[:, 0] / glass.width(t)) + CROSSWIND_GAIN * cross
    return np.stack([side, up], axis=-1)


def _drag(
    glass: GlassGeometry, st: np.ndarray, radius: np.ndarray, air: np.ndarray, vel: np.ndarray
) -> np.ndarray:
    """Aerodynamic force (n, 2) N on caps of contact radius ``radius`` (m) moving at ``vel`` in the air
    ``air``."""
    speed = _norm(air)
    delta = 5.0 * np.sqrt(NU_AIR * (BL_RUN_UP_M + np.maximum(st[:, 1], 0.0)) / np.maximum(speed, 1e-3))
    eta = np.clip(HEIGHT_PER_RADIUS * radius / delta, 0.0, 1.0)
    profile = 1.5 * eta - 0.5 * eta**3  # Pohlhausen's cubic boundary-layer profile u/U
    rel = air * profile[:, None] - vel
    rel_speed = _norm(rel)
    coef = 0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2 * radius**2 * rel_speed
    return coef[:, None] * rel


# --- spatial grid -------------------------------------------------------------------------------------------
GRID_CELL_M = (
    4e-3  # fine merge-test grid; the drop arrays are kept sorted by this grid's cell of their centre
)
COARSE_CELL_M = 3.2e-2  # coarse grid for large or fast drops
_GRID_ORIGIN = np.array([-1.0, -0.2])  # m; the grids span 2 m × 1.6 m of glass coordinates


def _grid_shape(cell: float) -> tuple[int, int]:
    return int(math.ceil(2.0 / cell)), int(math.ceil(1.6 / cell))


def _grid_keys(points: np.ndarray, cell: float = GRID_CELL_M) -> np.ndarray:
    """Cell key (row-major over (s, t)) of points (n, 2) m in a grid of ``cell`` m; off-grid points clip."""
    n0, n1 = _grid_shape(cell)
    k0 = np.minimum(np.maximum(((points[:, 0] - _GRID_ORIGIN[0]) / cell).astype(np.int64), 0), n0 - 1)
    k1 = np.minimum(np.maximum(((points[:, 1] - _GRID_ORIGIN[1]) / cell).astype(np.int64), 0), n1 - 1)
    return k0 * n1 + k1


def _box_keys(points: np.ndarray, half: np.ndarray, ids: np.ndarray, cell: float) -> tuple[np.ndarray, ...]:
    """(cell key, id) entries for every cell of ``cell`` m that the box points ± half (m) touches."""
    n0, n1 = _grid_shape(cell)
    top = np.array([n0 - 1, n1 - 1])
    lo = np.minimum(
        np.maximum(np.floor((points - half[:, None] - _GRID_ORIGIN) / cell).astype(np.int64), 0), top
    )
    hi = np.minimum(
        np.maximum(np.floor((points + half[:, None] - _GRID_ORIGIN) / cell).astype(np.int64), 0), top
    )
    w0 = hi[:, 0] - lo[:, 0] + 1
    w1 = hi[:, 1] - lo[:, 1] + 1
    counts = w0 * w1
    total = int(counts.sum())
    owner = np.repeat(np.arange(len(ids)), counts)
    within = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    d0, d1 = np.divmod(within, w1[owner])
    return (lo[owner, 0] + d0) * n1 + lo[owner, 1] + d1, ids[owner]


def _match(
    t_keys: np.ndarray, t_ids: np.ndarray, q_keys: np.ndarray, q_ids: np.ndarray
) -> tuple[np.ndarray, ...]:
    """All (query id, target id) pairs that share a cell key."""
    if len(t_keys) == 0 or len(q_keys) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.argsort(t_keys, kind="stable")  # cheap: the entries come nearly sorted
    sorted_keys, t_ids = t_keys[order], t_ids[order]
    first = np.searchsorted(sorted_keys, q_keys, "left")
    c = np.searchsorted(sorted_keys, q_keys, "right") - first
    has = c > 0
    c, q_ids, first = c[has], q_ids[has], first[has]
    total = int(c.sum())
    if total == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    base = np.repeat(first - (np.cumsum(c) - c), c)
    return np.repeat(q_ids, c), t_ids[base + np.arange(total)]


def _grid_pairs(points: np.ndarray, reach: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs (i, j), i ≠ j, at least one of them ``active`` (bool mask), that include every such
    pair with |p_i − p_j| ≤ reach_i + reach_j (m). Pairs may repeat. No all-pairs test and no per-drop loop:

    * small points (reach ≤ half a fine cell) sit in the fine grid by their centre; each active small point
      looks up the fine cells of its box widened by half a cell (≤ 3 × 3 cells), which must hold the centre of
      any small point it can touch;
    * large or fast points sit in the coarse grid in every cell their box p ± reach touches; every point looks
      up the coarse cells of its own box widened by half a fine cell, which must meet the box of any large
      point it can touch. Pairs with neither point active are dropped.
    """
    n = len(points)
    if n < 2 or not active.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    half = 0.5 * GRID_CELL_M
    big = reach > half
    small_ids = np.flatnonzero(~big)
    keys = _grid_keys(points[small_ids])
    q = np.flatnonzero(active & ~big)
    qk, qi = _box_keys(points[q], reach[q] + half, q, GRID_CELL_M)
    i1, j1 = _match(keys, small_ids, qk, qi)
    if not big.any():
        keep = i1 != j1
        return i1[keep], j1[keep]
    big_ids = np.flatnonzero(big)
    bk, bi = _box_keys(points[big_ids], reach[big_ids], big_ids, COARSE_CELL_M)
    everyone = np.arange(n)
    qk, qi = _box_keys(points, reach + half, everyone, COARSE_CELL_M)
    i2, j2 = _match(bk, bi, qk, qi)
    either = active[i2] | active[j2]
    i, j = np.concatenate([i1, i2[either]]), np.concatenate([j1, j2[either]])
    keep = i != j
    return i[keep], j[keep]


def _components(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected-component label (the smallest member index) of each of n nodes joined by edges (i, j)."""
    labels = np.arange(n)
    for _ in range(64):
        lo = np.minimum(labels[i], labels[j])
        new = labels.copy()
        np.minimum.at(new, i, lo)
        np.minimum.at(new, j, lo)
        new = new[new]  # pointer jumping: chains collapse in O(log) rounds
        if np.array_equal(new, labels):
            break
        labels = new
    return labels


# --- the simulation -----------------------------------------------------------------------------------------
class WindshieldSim:
    """Water on the windshield: drops, film, wiper beads and the wipers themselves (CPU, float64, NumPy).

    ``step(dt_s, inputs)`` advances by dt_s seconds (sub-stepped at MAX_SUBSTEP_S; clamped to MAX_FRAME_DT_S).
    State: ``pos`` (n, 2) (s, t) m, ``vel`` (n, 2) m/s, ``mass`` (n,) kg; ``film`` (FILM_CELLS, FILM_CELLS) kg
    per cell ([iv, iu]); ``beads`` (2, BEAD_BINS) kg; counters ``arrived``, ``wiped``, ``shed``,
    ``evaporated`` (kg). Same seed and inputs → the same state (``np.random.Generator`` seeded once).
    """

    def __init__(self, spec: VehicleSpec = CAR_SPEC, seed: int = 0):
        self.glass = GlassGeometry(spec)
        self.rng = np.random.default_rng(seed)
        self.blades = tandem_blades(self.glass.width_bottom, self.glass.width_top, self.glass.height)
        self.wipers = WiperController()
        self.pos = np.zeros((0, 2))
        self.vel = np.zeros((0, 2))
        self.mass = np.zeros(0)
        self.trail = np.zeros(0)  # distance run since the last trail droplet (m)
        self.fresh = np.zeros(0, bool)  # born, grown or merged since the last merge test
        self.cell_centres, self.cell_areas = self.glass.cells(FILM_CELLS)
        self.film = np.zeros((FILM_CELLS, FILM_CELLS))
        self.beads = np.zeros((len(self.blades), BEAD_BINS))
        self.arrived = self.wiped = self.shed = self.evaporated = 0.0
        self.time_s = 0.0
        self.arrival_count = 0
        self._areas_flat = self.cell_areas.ravel()
        flat_centres = self.cell_centres.reshape(-1, 2)
        self._cell_polar = []
        for blade in self.blades:
            rel = flat_centres - np.asarray(blade.pivot)
            self._cell_polar.append((np.hypot(rel[:, 0], rel[:, 1]), np.arctan2(rel[:, 1], rel[:, 0])))
        sc = np.array(SENSOR_CENTRE_FRACTION) * (self.glass.width_bottom, self.glass.height)
        self.sensor_lo = sc - 0.5 * np.array(SENSOR_SIZE_M)
        self.sensor_hi = sc + 0.5 * np.array(SENSOR_SIZE_M)
        inside = np.all((flat_centres >= self.sensor_lo) & (flat_centres <= self.sensor_hi), axis=1)
        self._sensor_cells = np.flatnonzero(inside)
        self._sensor_cell_area = float(self._areas_flat[self._sensor_cells].sum())
        self.sensor_kg_m2 = 0.0
        self._bead_mass = RHO_W * BEAD_THRESHOLD_M * self._areas_flat
        self._rate_cache: tuple | None = None
        self._n0_cache: tuple = (None, 0.0, None)
        self.merges = 0
        self._budget = 6000
        self._reset_frame_records()

    # --- queries --------------------------------------------------------------------------------------------
    @property
    def count(self) -> int:
        return len(self.mass)

    def radius(self) -> np.ndarray:
        return drop_radius(self.mass)

    def mass_on_glass(self) -> float:
        """Water on the glass (kg): drops + film + the wiper beads."""
        return float(self.mass.sum() + self.film.sum() + self.beads.sum())

    def balance_error_kg(self) -> float:
        """arrived − wiped − shed − evaporated − on the glass (kg); 0 up to float64 rounding."""
        return self.arrived - self.wiped - self.shed - self.evaporated - self.mass_on_glass()

    def film_thickness_m(self) -> np.ndarray:
        """Mean film thickness per cell (m), (FILM_CELLS, FILM_CELLS) indexed [iv, iu]."""
        return self.film / (RHO_W * self.cell_areas)

    def has_water(self) -> bool:
        return self.count > 0 or bool(self.film.any()) or bool(self.beads.any())

    def sensor_reading(self) -> float:
        """Water on the rain-sensor patch, kg/m² (drops whose centres lie in it, plus its film cells)."""
        area = float(np.prod(self.sensor_hi - self.sensor_lo))
        inside = np.all((self.pos >= self.sensor_lo) & (self.pos <= self.sensor_hi), axis=1)
        drops = float(self.mass[inside].sum()) / area
        film = float(self.film.ravel()[self._sensor_cells].sum()) / max(self._sensor_cell_area, 1e-12)
        return drops + film

    def blade_angles(self) -> list[float]:
        """Each blade's angle now (rad)."""
        return [float(b.angle(self.wipers.progress)) for b in self.blades]

    # --- arrivals -------------------------------------------------------------------------------------------
    def arrival_rate_per_s(self, inputs: GlassInputs) -> tuple[float, np.ndarray, np.ndarray]:
        """Arrivals on the glass: (drops per second, closing speed (m/s) and the flux-weighted size CDF for
        each diameter of _D_GRID_MM). The count is ``physics.flux_on_surface_per_s`` for the glass's world
        normal and velocity, by the trapezoid rule on the diameter grid (within 1e-4), × ``drop_scale``."""
        zeros = np.zeros_like(_D_GRID_MM)
        if inputs.rate_mm_h <= 0.0 or inputs.sheltered or inputs.drop_scale <= 0.0:
            return 0.0, zeros, zeros
        rot = np.asarray(inputs.car_rotation, float)
        n_world = rot @ self.glass.normal
        vs = np.asarray(inputs.car_velocity_m_s, float)
        wind = np.asarray(inputs.wind_m_s, float).copy()
        wind[1] = 0.0
        a = float((wind - vs) @ n_world)
        closing = np.maximum(_V_GRID_M_S * n_world[1] - a, 0.0)  # −u·n̂ per diameter, as in physics
        if self._n0_cache[0] != inputs.rate_mm_h:
            shape = np.exp(-physics.mp_slope_per_mm(inputs.rate_mm_h) * _D_GRID_MM)
            self._n0_cache = (inputs.rate_mm_h, float(physics.effective_n0(inputs.rate_mm_h)), shape)
        _, n0, shape = self._n0_cache
        pdf = shape * closing
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(_D_GRID_MM))])
        flux = self.glass.area_m2 * n0 * float(cdf[-1])
        return flux * inputs.drop_scale, closing, cdf

    def _sample_arrivals(self, n: int, closing: np.ndarray, cdf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """n diameters (mm) from the flux-weighted law N(D)·closing(D), and their impact speeds (m/s)."""
        d = np.interp(self.rng.random(n) * cdf[-1], cdf, _D_GRID_MM)
        return d, np.interp(d, _D_GRID_MM, closing)

    def _arrive(self, h: float, arrivals: tuple, inputs: GlassInputs) -> None:
        rate_per_s, closing, cdf = arrivals
        n = int(self.rng.poisson(rate_per_s * h)) if rate_per_s > 0 else 0
        if n == 0:
            return
        d_mm, u_n = self._sample_arrivals(n, closing, cdf)
        m = RHO_W * math.pi / 6.0 * (d_mm * 1e-3) ** 3
        st = self.glass.sample_uniform(n, self.rng)
        self.arrived += float(m.sum())
        self.arrival_count += n
        lo, hi = SPLASH_SPEED_M_S
        splash = np.clip((u_n - lo) / (hi - lo), 0.0, 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        is_obj = keep >= M_OBJECT_MIN
        cells = self.glass.cell_index(st)
        room = max(int(inputs.drop_budget) - self.count, 0)
        joined = np.zeros(n, bool)
        if int(is_obj.sum()) > room:
            # A full glass: the surplus lands on (joins) a drop already in its cell, or else the film.
            over = np.flatnonzero(is_obj)[room:]
            is_obj[over] = False
            joined[over] = self._give_to_drops(cells[over], keep[over])
        to_film = m - np.where(is_obj | joined, keep, 0.0)
        np.add.at(self.film.ravel(), cells, to_film)
        splash_r = drop_radius(np.where(is_obj, keep, m)) * (1.5 + 4.0 * splash)
        self._impacts.append(np.column_stack([st, splash_r, to_film / (RHO_W * math.pi * splash_r**2)]))
        self._append(st[is_obj], np.zeros((int(is_obj.sum()), 2)), keep[is_obj])

    def _give_to_drops(self, cells: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """Add each mass (kg) to a random drop of its film cell; returns which ones found a drop."""
        placed = np.zeros(len(cells), bool)
        if self.count == 0 or len(cells) == 0:
            return placed
        drop_cells = self.glass.cell_index(self.pos)
        counts = np.bincount(drop_cells, minlength=FILM_CELLS * FILM_CELLS)
        starts = np.cumsum(counts) - counts
        order = np.argsort(drop_cells, kind="stable")
        c = counts[cells]
        placed = c > 0
        if placed.any():
            pick = order[starts[cells[placed]] + self.rng.integers(0, c[placed])]
            np.add.at(self.mass, pick, mass[placed])
            self.fresh[pick] = True
        return placed

    def _append(self, pos: np.ndarray, vel: np.ndarray, mass: np.ndarray) -> None:
        if len(mass) == 0:
            return
        self.pos = np.concatenate([self.pos, pos])
        self.vel = np.concatenate([self.vel, vel])
        self.mass = np.concatenate([self.mass, mass])
        self.trail = np.concatenate([self.trail, np.zeros(len(mass))])
        self.fresh = np.concatenate([self.fresh, np.ones(len(mass), bool)])

    def _sort_drops(self) -> None:
        """Keep the drop arrays in merge-grid cell order, so the next grid sort finds them nearly sorted."""
        if self.count < 2:
            return
        keys = _grid_keys(self.pos)
        if np.all(keys[1:] >= keys[:-1]):
            return
        order = np.argsort(keys, kind="stable")
        self.pos, self.vel, self.mass = self.pos[order], self.vel[order], self.mass[order]
        self.trail, self.fresh = self.trail[order], self.fresh[order]

    def _keep(self, keep: np.ndarray) -> None:
        self.pos, self.vel, self.mass, self.trail = (
            self.pos[keep],
            self.vel[keep],
            self.mass[keep],
            self.trail[keep],
        )
        self.fresh = self.fresh[keep]

    # --- motion ---------------------------------------------------------------------------------------------
    def _move(self, h: float, air_local: np.ndarray, inputs: GlassInputs) -> tuple[np.ndarray, np.ndarray]:
        """Forces, pinning, viscous sliding; returns (start positions, displacements) for the merge test."""
        n = self.count
        if n == 0:
            return np.zeros((0, 2)), np.zeros((0, 2))
        a = self.radius()
        m = self.mass
        air = _air_velocity(self.glass, self.pos, air_local)
        force = m[:, None] * self.glass.gravity(self.pos) + _drag(self.glass, self.pos, a, air, self.vel)
        fmag = _norm(force)
        pin = GAMMA_W * 2.0 * a * HYSTERESIS
        speed = _norm(self.vel)
        moving = speed > 0.0
        starting = ~moving & (fmag > pin)
        direction = np.where(
            moving[:, None],
            self.vel / np.maximum(speed, 1e-300)[:, None],
            force / np.maximum(fmag, 1e-300)[:, None],
        )
        acc = (force - KINETIC_PIN * pin[:, None] * direction) / m[:, None]
        k_visc = VISCOUS_C * MU_W * a / m
        vnew = (self.vel + h * acc) / (1.0 + h * k_visc)[:, None]
        reversed_ = moving & (np.einsum("ij,ij->i", vnew, self.vel) <= 0.0)
        creeping = moving & (_norm(vnew) < V_STOP_M_S) & (fmag < pin)
        stopped = (~moving & ~starting) | reversed_ | creeping
        vnew[stopped] = 0.0
        disp = h * vnew
        start = self.pos.copy()
        self.pos = start + disp
        self.vel = vnew
        # Slow evaporation of the drops themselves (hours for a millimetre drop; kept for the balance).
        air_speed = np.sqrt(air[:, 0] ** 2 + air[:, 1] ** 2)
        loss = np.minimum(DROP_EVAP_KG_M_S * a * np.sqrt(1.0 + air_speed / EVAP_AIR_M_S) * h, self.mass)
        self.mass = self.mass - loss
        self.evaporated += float(loss.sum())
        step_len = np.sqrt(disp[:, 0] ** 2 + disp[:, 1] ** 2)
        run = step_len > 0.0
        if run.any():
            self._sweep_film_and_trail(h, run, start, disp, step_len, a, inputs)
        return start, disp

    def _sweep_film_and_trail(self, h, run, start, disp, step_len, a, inputs: GlassInputs) -> None:
        """Running drops take up the film in their path, lay a thin wet line and drop trail droplets."""
        idx = np.flatnonzero(run)
        mid = start[idx] + 0.5 * disp[idx]
        inside = self.glass.contains(mid)
        idx, mid = idx[inside], mid[inside]
        if len(idx) == 0:
            return
        cells = self.glass.cell_index(mid)
        flat = self.film.ravel()
        swept_area = 2.0 * a[idx] * step_len[idx]
        frac = swept_area / self._areas_flat[cells]
        total = np.bincount(cells, weights=frac, minlength=flat.size)
        scale = np.where(total > 1.0, 1.0 / np.maximum(total, 1e-300), 1.0)
        take = flat[cells] * frac * scale[cells]
        np.subtract.at(flat, cells, take)
        np.maximum(flat, 0.0, out=flat)
        wet = np.minimum(RHO_W * TRAIL_FILM_M * swept_area, 0.1 * self.mass[idx])
        np.add.at(flat, cells, wet)
        self.mass[idx] += take - wet
        self._trails.append(np.column_stack([start[idx], start[idx] + disp[idx], a[idx]]))
        # Trail droplets: one every TRAIL_SPACING_RADII radii of run, behind the drop, from heavy drops only.
        self.trail[idx] += step_len[idx]
        spacing = TRAIL_SPACING_RADII * a[idx]
        k = np.minimum(np.floor(self.trail[idx] / spacing), 4).astype(np.int64)
        k[self.mass[idx] < TRAIL_PARENT_MIN] = 0
        self.trail[idx] -= k * spacing
        self.trail[idx] = np.minimum(self.trail[idx], spacing)
        total_k = int(k.sum())
        if total_k == 0:
            return
        parent = np.repeat(idx, k)
        within = np.arange(total_k) - np.repeat(np.cumsum(k) - k, k)
        # Behind the drop on the path it ran, clear of it (so they do not join again at once).
        end = start[parent] + disp[parent]
        back = -disp[parent] / step_len[parent][:, None]
        a_p = a[parent]
        where = end + back * ((1.3 + TRAIL_SPACING_RADII * within) * a_p)[:, None]
        ok = self.glass.contains(where)
        parent, where = parent[ok], where[ok]
        m_t = TRAIL_FRACTION * self.mass[parent]
        np.subtract.at(self.mass, parent, m_t)
        room = max(int(inputs.drop_budget) - self.count, 0)
        as_drop = np.zeros(len(m_t), bool)
        as_drop[:room] = m_t[:room] >= M_OBJECT_MIN
        np.add.at(self.film.ravel(), self.glass.cell_index(where[~as_drop]), m_t[~as_drop])
        self._append(where[as_drop], np.zeros((int(as_drop.sum()), 2)), m_t[as_drop])

    # --- merging --------------------------------------------------------------------------------------------
    def _merge(self, start: np.ndarray, disp: np.ndarray) -> None:
        """Join drops that touched during the step (closest approach of their motions ≤ sum of radii).

        Only drops that moved, grew or were born can start touching, so only they are looked up in the grid;
        a merged drop counts as new in the next sub-step (it may now reach a neighbour)."""
        n = self.count
        if n < 2:
            self.fresh = np.zeros(n, bool)
            return
        born = np.zeros(n, bool)
        if len(start) < n:  # trail droplets born during the step: tested from the next sub-step on
            born[len(start) :] = True
            start = np.concatenate([start, self.pos[len(start) :]])
            disp = np.concatenate([disp, np.zeros((n - len(disp), 2))])
        moved = (disp[:, 0] != 0.0) | (disp[:, 1] != 0.0)
        active = (moved | self.fresh) & ~born
        self.fresh = born.copy()
        if not active.any():
            return
        a = self.radius()
        mid = start + 0.5 * disp
        reach = a + 0.5 * np.sqrt(disp[:, 0] ** 2 + disp[:, 1] ** 2)
        i, j = _grid_pairs(mid, reach, active)
        if born.any():
            keep = ~(born[i] | born[j])
            i, j = i[keep], j[keep]
        if len(i) == 0:
            return
        p = start[i] - start[j]
        d = disp[i] - disp[j]
        dd = np.einsum("ij,ij->i", d, d)
        tau = np.clip(-np.einsum("ij,ij->i", p, d) / np.maximum(dd, 1e-300), 0.0, 1.0)
        q = p + tau[:, None] * d
        touch = np.einsum("ij,ij->i", q, q) <= (a[i] + a[j]) ** 2
        if not touch.any():
            return
        labels = _components(n, i[touch], j[touch])
        roots, inv, sizes = np.unique(labels, return_inverse=True, return_counts=True)
        if len(roots) == n:
            return
        mass = np.bincount(inv, weights=self.mass)
        pos = np.stack([np.bincount(inv, weights=self.mass * self.pos[:, k]) for k in range(2)], axis=1)
        vel = np.stack([np.bincount(inv, weights=self.mass * self.vel[:, k]) for k in range(2)], axis=1)
        trail = np.bincount(inv, weights=self.mass * self.trail)
        self.pos = pos / mass[:, None]
        self.vel = vel / mass[:, None]
        self.trail = trail / mass
        self.mass = mass
        self.fresh = (sizes > 1) | (np.bincount(inv, weights=self.fresh.astype(float)) > 0)
        self.merges += n - len(roots)

    # --- wipers ---------------------------------------------------------------------------------------------
    def _sweep(self, seg: StrokeSegment, wear: float) -> None:
        for b, blade in enumerate(self.blades):
            ta, tb = float(blade.angle(seg.p_start)), float(blade.angle(seg.p_end))
            if ta != tb:
                self._sweep_blade(b, blade, ta, tb, wear)
                self._sweep_ranges[b][0] = min(self._sweep_ranges[b][0], ta, tb)
                self._sweep_ranges[b][1] = max(self._sweep_ranges[b][1], ta, tb)
            self._bead_off_glass(b, blade, tb)
        if seg.event is not None:
            for b, blade in enumerate(self.blades):
                self._end_of_stroke(b, blade, float(blade.angle(seg.p_end)), seg.event)

    def _bin_of(self, blade, r: np.ndarray) -> np.ndarray:
        x = (r - blade.r_inner_m) / (blade.r_outer_m - blade.r_inner_m)
        return np.minimum(np.maximum((x * BEAD_BINS).astype(np.int64), 0), BEAD_BINS - 1)

    def _bin_points(self, blade, angle: float, ahead: float = 0.0) -> np.ndarray:
        """(BEAD_BINS, 2) centres of the bins along the blade at ``angle``, ``ahead`` m in front of it."""
        r = blade.r_inner_m + (np.arange(BEAD_BINS) + 0.5) / BEAD_BINS * (blade.r_outer_m - blade.r_inner_m)
        d = np.array([math.cos(angle), math.sin(angle)])
        nrm = np.array([-d[1], d[0]])
        return np.asarray(blade.pivot) + r[:, None] * d + ahead * nrm

    def _sweep_blade(self, b: int, blade, ta: float, tb: float, wear: float) -> None:
        lo, hi = min(ta, tb), max(ta, tb)
        bead = self.beads[b]
        # Drops: everything the rubber passed over (its width and the drop's radius as a margin ahead).
        if self.count:
            rel = self.pos - np.asarray(blade.pivot)
            r = np.hypot(rel[:, 0], rel[:, 1])
            phi = np.arctan2(rel[:, 1], rel[:, 0])
            a = self.radius()
            margin = (a + BLADE_HALF_WIDTH_M) / np.maximum(r, 1e-3)
            in_r = (r + a >= blade.r_inner_m) & (r - a <= blade.r_outer_m)
            if tb > ta:
                in_phi = (phi >= lo) & (phi <= hi + margin)
            else:
                in_phi = (phi >= lo - margin) & (phi <= hi)
            swept = in_r & in_phi
            if swept.any():
                np.add.at(bead, self._bin_of(blade, r[swept]), self.mass[swept])
                self._keep(~swept)
        # Film: cells whose centres the blade passed over.
        r_c, phi_c = self._cell_polar[b]
        cells = np.flatnonzero(
            (r_c >= blade.r_inner_m) & (r_c <= blade.r_outer_m) & (phi_c >= lo) & (phi_c <= hi)
        )
        if len(cells) == 0:
            return
        flat = self.film.ravel()
        bins = self._bin_of(blade, r_c[cells])
        np.add.at(bead, bins, flat[cells])
        flat[cells] = 0.0
        # The rubber leaves a thin residue where it pushed water, paid from the bead.
        want = RHO_W * RESIDUE_M * (1.0 + 4.0 * wear) * self._areas_flat[cells]
        need = np.bincount(bins, weights=want, minlength=BEAD_BINS)
        scale = np.where(need > 0, np.minimum(1.0, bead / np.maximum(need, 1e-300)), 0.0)
        leave = want * scale[bins]
        flat[cells] += leave
        bead -= np.bincount(bins, weights=leave, minlength=BEAD_BINS)
        # Over capacity the bead leaks past the rubber: spread the excess over the cells just swept.
        cap = BEAD_CAPACITY_KG_M * (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        has_cells = np.bincount(bins, minlength=BEAD_BINS) > 0
        excess = np.where(has_cells, np.maximum(bead - cap, 0.0), 0.0)
        if excess.any():
            area_bin = np.bincount(bins, weights=self._areas_flat[cells], minlength=BEAD_BINS)
            share = self._areas_flat[cells] / area_bin[bins]
            flat[cells] += excess[bins] * share
            bead -= excess
        np.maximum(bead, 0.0, out=bead)

    def _bead_off_glass(self, b: int, blade, angle: float) -> None:
        """Water pushed past an edge of the glass (into the cowl, off the side) leaves it: wiped."""
        off = ~self.glass.contains(self._bin_points(blade, angle))
        if off.any():
            self.wiped += float(self.beads[b][off].sum())
            self.beads[b][off] = 0.0

    def _end_of_stroke(self, b: int, blade, angle: float, event: str) -> None:
        """At a reversal the bead sheds: END_LEAVE_FRACTION stays as a row of drops just past the blade."""
        bead = self.beads[b]
        if not bead.any():
            return
        sign = 1.0 if event == "top" else -1.0  # the blade was moving towards +angle on the up-stroke
        where = self._bin_points(blade, angle, ahead=sign * 3.0 * BLADE_HALF_WIDTH_M)
        left = END_LEAVE_FRACTION * bead
        inside = self.glass.contains(where)
        left[~inside] = 0.0
        self.wiped += float((bead - left).sum())
        room = max(self._budget - self.count, 0)
        as_drop = inside & (left >= M_OBJECT_MIN)
        as_drop[np.flatnonzero(as_drop)[room:]] = False
        film_part = inside & ~as_drop & (left > 0)
        np.add.at(self.film.ravel(), self.glass.cell_index(where[film_part]), left[film_part])
        self._append(where[as_drop], np.zeros((int(as_drop.sum()), 2)), left[as_drop])
        bead[:] = 0.0

    # --- film -----------------------------------------------------------------------------------------------
    def _film_step(self, h: float, evap_kg_s: np.ndarray, inputs: GlassInputs) -> None:
        """Evaporation (``evap_kg_s``: kg/s per cell for a wet cell) and beading of the film."""
        flat = self.film.ravel()
        loss = np.minimum(flat, evap_kg_s * h)
        flat -= loss
        self.evaporated += float(loss.sum())
        idx = np.flatnonzero(flat > self._bead_mass)
        # Beading: a film thicker than the threshold pulls together into a drop somewhere in its cell.
        thick = idx
        if len(thick) == 0:
            return
        room = max(int(inputs.drop_budget) - self.count, 0)
        thick = thick[np.argsort(-flat[thick] / self._areas_flat[thick], kind="stable")]
        keep = BEAD_KEEP * RHO_W * BEAD_THRESHOLD_M * self._areas_flat[thick]
        if len(thick) > room:  # a full glass: the surplus film joins drops already in those cells
            over, over_keep = thick[room:], keep[room:]
            joined = self._give_to_drops(over, flat[over] - over_keep)
            flat[over[joined]] = over_keep[joined]
            thick, keep = thick[:room], keep[:room]
        m = flat[thick] - keep
        flat[thick] = keep
        iv, iu = np.divmod(thick, FILM_CELLS)
        uv = np.stack(
            [
                (iu + self.rng.random(len(thick))) / FILM_CELLS,
                (iv + self.rng.random(len(thick))) / FILM_CELLS,
            ],
            axis=1,
        )
        self._append(self.glass.from_uv(uv), np.zeros((len(thick), 2)), m)

    # --- shedding -------------------------------------------------------------------------------------------
    def _shed_outside(self) -> None:
        inside = self.glass.contains(self.pos)
        if not inside.all():
            self.shed += float(self.mass[~inside].sum())
            self._keep(inside)
        # Drops worn down by their trails below half the object size become film where they are.
        tiny = self.mass < 0.5 * M_OBJECT_MIN
        if tiny.any():
            np.add.at(self.film.ravel(), self.glass.cell_index(self.pos[tiny]), self.mass[tiny])
            self._keep(~tiny)

    # --- the step -------------------------------------------------------------------------------------------
    def _reset_frame_records(self) -> None:
        self._impacts: list[np.ndarray] = []
        self._trails: list[np.ndarray] = []
        self._sweep_ranges = [[math.inf, -math.inf] for _ in self.blades]

    def frame_impacts(self) -> np.ndarray:
        """Impacts of the last step: (n, 4) s, t (m), splash radius (m), satellite film thickness (m)."""
        return np.concatenate(self._impacts) if self._impacts else np.zeros((0, 4))

    def frame_trails(self) -> np.ndarray:
        """Paths of running drops in the last step: (n, 5) s0, t0, s1, t1 (m), drop radius (m)."""
        return np.concatenate(self._trails) if self._trails else np.zeros((0, 5))

    def frame_sweeps(self) -> list[tuple[float, float] | None]:
        """Per blade, the range of angles (rad) its rubber swept in the last step, or None."""
        return [(lo, hi) if lo <= hi else None for lo, hi in self._sweep_ranges]

    def step(self, dt_s: float, inputs: GlassInputs) -> None:
        """Advance the water and the wipers by dt_s seconds (finite, ≥ 0; clamped to MAX_FRAME_DT_S)."""
        if not (math.isfinite(dt_s) and dt_s >= 0.0):
            raise ValueError(f"dt_s must be a finite number ≥ 0 s, got {dt_s!r}")
        self._reset_frame_records()
        dt_s = min(float(dt_s), MAX_FRAME_DT_S)
        if dt_s == 0.0:
            return
        self._budget = int(inputs.drop_budget)
        key = (
            inputs.rate_mm_h,
            inputs.sheltered,
            inputs.drop_scale,
            np.asarray(inputs.car_rotation).tobytes(),
            np.asarray(inputs.car_velocity_m_s).tobytes(),
            np.asarray(inputs.wind_m_s).tobytes(),
        )
        if self._rate_cache is None or self._rate_cache[0] != key:
            self._rate_cache = (key, self.arrival_rate_per_s(inputs))
        arrivals = self._rate_cache[1]
        air_local = inputs.relative_air_local()
        air = _norm(_air_velocity(self.glass, self.cell_centres.reshape(-1, 2), air_local))
        evap = FILM_EVAP_KG_M2_S * (1.0 + air / EVAP_AIR_M_S) * self._areas_flat
        n_sub = max(1, math.ceil(dt_s / MAX_SUBSTEP_S - 1e-9))
        h = dt_s / n_sub
        for _ in range(n_sub):
            self._arrive(h, arrivals, inputs)
            start, disp = self._move(h, air_local, inputs)
            self._merge(start, disp)
            self._shed_outside()
            self.sensor_kg_m2 = self.sensor_reading()
            segments = self.wipers.advance(
                h,
                inputs.wiper_mode,
                inputs.wiper_interval_s,
                inputs.wiper_low_cpm,
                inputs.wiper_high_cpm,
                self.sensor_kg_m2,
                inputs.wiper_sensitivity,
            )
            for seg in segments:
                self._sweep(seg, inputs.blade_wear)
            self._film_step(h, evap, inputs)
            self._sort_drops()
        self.time_s += dt_s


# --- the effect (GPU) ---------------------------------------------------------------------------------------
TEXTURE_UNITS = (12, 13, 14, 15)  # this effect's samplers
FILM_DIFFUSION_M2_S = 5e-6  # visual spreading of thin water in the film texture
FILM_BEAD_RATE_PER_S = 0.15  # a thin film left alone pulls into micro-droplets over several seconds
CABIN_DEPTH_M = 1.3  # the frame nearer than this (view depth) is the cabin: refracted rays see past it
PUPIL_RADIUS_M = (
    0.002  # the driver's eye, focused on the road, sees each point of the glass through its pupil
)
EYE_APERTURE_BLUR = 0.0037  # blur through water as a fraction of the frame height (a ~4 mm pupil at ~1 m)


def _mat_bytes(m: np.ndarray) -> bytes:
    return np.ascontiguousarray(np.asarray(m, dtype=np.float32).T).tobytes()


class WindshieldEffect(Effect):
    """The windshield effect (a ``rain_core.renderer.Effect``): runs ``WindshieldSim``, draws the glass.

    Stages: ``prepare`` (the water textures: film relaxation and deposits, drop and bead splats, the water
    thickness/slope texture) and ``overlay`` (copy the frame without the glass, then draw the glass mesh over
    it with refraction, haze, glints and the blades). Active only with the camera inside the car and the
    effect enabled, and then only if there is water on the glass, rain reaching it, or the wipers are running:
    a dry, clean glass costs nothing. Textures use units TEXTURE_UNITS (12–15).

    ``WindshieldEffect(ctx, shaders=None, settings=None, seed=0, spec=CAR_SPEC)``. ``status()`` gives numbers
    for a panel (drops, water on the glass in g, wiper cycles, rain-sensor reading).
    """

    name = "windshield"
    stages = ("prepare", "overlay")

    def __init__(self, ctx, shaders=None, settings=None, seed: int = 0, spec: VehicleSpec = CAR_SPEC):
        self.ctx = ctx
        self.shaders = shaders or ShaderLibrary(ctx)
        self.settings = settings
        self.seed = int(seed)
        self.sim = WindshieldSim(spec, seed)
        self.glass = self.sim.glass
        self.film_prog = self.shaders.program("common/fullscreen.vert", "windshield/film.frag")
        self.normals_prog = self.shaders.program("common/fullscreen.vert", "windshield/normals.frag")
        self.splat_prog = self.shaders.program("windshield/splat.vert", "windshield/splat.frag")
        self.glass_prog = self.shaders.program("windshield/glass.vert", "windshield/glass.frag")
        for prog in (self.film_prog, self.normals_prog, self.splat_prog, self.glass_prog):
            if "u_glass" in prog:
                prog["u_glass"].value = (self.glass.width_bottom, self.glass.width_top, self.glass.height)
        self.splat_prog["u_cap_rn"].value = _R_CAP
        self._film_vao = ctx.vertex_array(self.film_prog, [])
        self._normals_vao = ctx.vertex_array(self.normals_prog, [])
        pos, nrm, uv, tris = windshield_surface(spec, 48, 24)
        verts = np.hstack([pos, nrm, uv]).astype(np.float32)
        self._mesh_vbo = ctx.buffer(verts.tobytes())
        self._mesh_ibo = ctx.buffer(np.asarray(tris, np.int32).tobytes())
        self._glass_vao = ctx.vertex_array(
            self.glass_prog,
            [(self._mesh_vbo, "3f 3f 2f", "in_position", "in_normal", "in_uv")],
            index_buffer=self._mesh_ibo,
            index_element_size=4,
        )
        self._splat_buf = ctx.buffer(reserve=32 * 1024)
        self._splat_vao = ctx.vertex_array(
            self.splat_prog, [(self._splat_buf, "4f 4f/i", "in_seg", "in_info")]
        )
        self.resolution = 0
        self._film: list = []
        self._film_index = 0
        self._coarse = [ctx.texture((FILM_CELLS, FILM_CELLS), 1, dtype="f4") for _ in range(2)]
        for tex in self._coarse:
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            tex.write(np.zeros((FILM_CELLS, FILM_CELLS), np.float32).tobytes())
        self._coarse_index = 0
        self._frame_copy = None
        self._last_time: float | None = None
        self._inputs = GlassInputs()
        self._dt = 0.0

    # --- resources ------------------------------------------------------------------------------------------
    def _ensure_textures(self, resolution: int) -> None:
        if resolution == self.resolution:
            return
        self._release_textures()
        n = int(resolution)
        size = (n, n)
        self._film = [float_target(self.ctx, size, 1, "f2") for _ in range(2)]
        for target in self._film:
            target.color.build_mipmaps()
            target.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            target.fbo.clear(0.0, 0.0, 0.0, 0.0)
            target.color.build_mipmaps()
        self._drops = float_target(self.ctx, size, 1, "f2")
        self._water = float_target(self.ctx, size, 4, "f2")
        self.resolution = n

    def _release_textures(self) -> None:
        for target in [*self._film, getattr(self, "_drops", None), getattr(self, "_water", None)]:
            if target is not None:
                target.release()
        self._film = []
        self.resolution = 0

    def _ensure_frame_copy(self, size: tuple[int, int]):
        if self._frame_copy is None or self._frame_copy.size != tuple(size):
            if self._frame_copy is not None:
                self._frame_copy.release()
            self._frame_copy = float_target(self.ctx, size, 4, "f2", depth=True)
            self._frame_copy.depth.compare_func = ""
            self._frame_copy.color.build_mipmaps()
            self._frame_copy.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        return self._frame_copy

    # --- Effect protocol ------------------------------------------------------------------------------------
    def _settings(self, frame):
        return frame.settings if frame.settings is not None else self.settings

    def _sheltered(self, frame) -> bool:
        centre = frame.ego.to_world(self.glass.local_points(np.array([[0.0, 0.5 * self.glass.height]])))[0]
        roof = float(np.asarray(frame.world.occluder_height(centre[0], centre[2])))
        return roof > centre[1]

    def active(self, frame) -> bool:
        settings = self._settings(frame)
        if not frame.camera.inside_car or frame.ego is None:
            return False
        if settings is not None and not settings.windshield.enabled:
            return False
        if self.sim.has_water() or self.sim.wipers.running:
            return True
        if settings is not None and settings.wipers.mode in ("intermittent", "low", "high"):
            return True
        scale = settings.windshield.drop_scale if settings is not None else 1.0
        return frame.rain_rate_mm_h > 0.0 and scale > 0.0 and not self._sheltered(frame)

    def inputs_for(self, frame) -> GlassInputs:
        """The GlassInputs of a frame (weather, ego motion, roof, settings)."""
        settings = self._settings(frame)
        ego = frame.ego
        wind = np.zeros(3)
        if frame.weather is not None:
            wind = np.asarray(frame.weather.wind.velocity_m_s, dtype=np.float64)
        kw = {}
        if settings is not None:
            w, ws = settings.wipers, settings.windshield
            kw = dict(
                drop_scale=ws.drop_scale,
                drop_budget=ws.drop_budget,
                wiper_mode=w.mode,
                wiper_interval_s=w.interval_s,
                wiper_low_cpm=w.low_cycles_per_min,
                wiper_high_cpm=w.high_cycles_per_min,
                wiper_sensitivity=w.auto_sensitivity,
                blade_wear=w.blade_wear,
            )
        return GlassInputs(
            rate_mm_h=frame.rain_rate_mm_h,
            car_velocity_m_s=ego.velocity(),
            wind_m_s=wind,
            car_rotation=ego.model_matrix()[:3, :3],
            sheltered=self._sheltered(frame),
            **kw,
        )

    def update(self, frame, rc) -> None:
        if self._last_time is None or frame.time_s < self._last_time:
            dt = float(frame.dt_s)
        else:
            dt = float(frame.time_s - self._last_time)
        self._last_time = float(frame.time_s)
        self._inputs = self.inputs_for(frame)
        self._dt = min(dt, MAX_FRAME_DT_S)
        self.sim.step(self._dt, self._inputs)

    def render(self, stage: str, rc) -> None:
        if stage == "prepare":
            self._draw_water(rc)
        elif stage == "overlay":
            self._draw_glass(rc)

    def describe(self) -> str:
        st = self.status()
        return f"{st['drops']} drops, {st['water_g']:.1f} g on the glass, {st['wipe_cycles']} wipes"

    def status(self) -> dict:
        """Numbers for the Rain Manager: drops, water on the glass (g), wiper cycles, sensor (g/m²)."""
        sim = self.sim
        return {
            "drops": sim.count,
            "water_g": 1e3 * sim.mass_on_glass(),
            "film_g": 1e3 * float(sim.film.sum()),
            "wipe_cycles": sim.wipers.cycles,
            "sensor_g_m2": 1e3 * sim.sensor_kg_m2,
            "arrived_g": 1e3 * sim.arrived,
            "wiped_g": 1e3 * sim.wiped,
            "shed_g": 1e3 * sim.shed,
        }

    # --- the water textures ---------------------------------------------------------------------------------
    def _splats(self, rows: np.ndarray) -> int:
        data = np.ascontiguousarray(rows, dtype=np.float32)
        if data.nbytes > self._splat_buf.size:
            self._splat_buf.orphan(int(data.nbytes * 1.5))
        if data.nbytes:
            self._splat_buf.write(data.tobytes())
        return len(data)

    def _texel_m(self) -> float:
        return max(self.glass.width_bottom, self.glass.height) / self.resolution

    def drop_splats(self) -> np.ndarray:
        """Instances (n, 8) for the drop-height texture: drops as caps with tails, beads as lines (mm)."""
        sim = self.sim
        rows = []
        if sim.count:
            a = sim.radius()
            a_vis = np.maximum(a, 0.75 * self._texel_m())
            h_mm = 1e3 * HEIGHT_PER_RADIUS * a * (a / a_vis)  # a sub-texel drop: wider, lower lens
            speed = _norm(sim.vel)
            tail = a * np.minimum(speed / 0.25, 1.5)
            back = -sim.vel / np.maximum(speed, 1e-9)[:, None] * tail[:, None]
            rows.append(
                np.column_stack([sim.pos, sim.pos + back, a_vis, h_mm, np.zeros(len(a)), np.zeros(len(a))])
            )
        direction = 1.0 if (sim.wipers.phase or 0.0) < 0.5 else -1.0
        for b, blade in enumerate(sim.blades):
            bead = sim.beads[b]
            if not bead.any():
                continue
            angle = float(blade.angle(sim.wipers.progress))
            bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
            centres = sim._bin_points(blade, angle, ahead=direction * 0.004)
            d = np.array([math.cos(angle), math.sin(angle)]) * 0.5 * bin_len
            w = np.minimum(np.sqrt(2.0 * bead / (RHO_W * bin_len) / math.pi), 0.01)
            keep = w > 0
            w_vis = np.maximum(w, 0.75 * self._texel_m())
            rows.append(
                np.column_stack(
                    [
                        centres - d,
                        centres + d,
                        w_vis,
                        1e3 * w * (w / w_vis),
                        np.ones(len(w)),
                        np.zeros(len(w)),
                    ]
                )[keep]
            )
        return np.concatenate(rows) if rows else np.zeros((0, 8))

    def film_splats(self) -> np.ndarray:
        """Instances (n, 8) added to the film texture (µm): wet trail lines and splash speckle."""
        sim = self.sim
        rows = []
        trails = sim.frame_trails()
        if len(trails):
            rows.append(
                np.column_stack(
                    [
                        trails[:, :4],
                        trails[:, 4],
                        np.full(len(trails), TRAIL_FILM_M * 1e6 * 4 / math.pi),
                        np.ones(len(trails)),
                        np.zeros(len(trails)),
                    ]
                )
            )
        impacts = sim.frame_impacts()
        if len(impacts):
            impacts = impacts[impacts[:, 2] >= 0.5 * self._texel_m()][:4096]
            seeds = np.arange(len(impacts)) + 7 * sim.arrival_count
            rows.append(
                np.column_stack(
                    [
                        impacts[:, :2],
                        impacts[:, :2],
                        impacts[:, 2],
                        impacts[:, 3] * 1e6,
                        np.full(len(impacts), 2.0),
                        seeds % 65536,
                    ]
                )
            )
        return np.concatenate(rows) if rows else np.zeros((0, 8))


    def _draw_splats(self, splats, equation) -> None:
        """Blend splats into the bound target: FUNC_ADD accumulates water, MAX keeps the tallest drop."""
        count = self._splats(splats)
        if not count:
            return
        ctx = self.ctx
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.ONE, moderngl.ONE)
        ctx.blend_equation = equation
        self._splat_vao.render(moderngl.TRIANGLES, vertices=6, instances=count)
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.disable(moderngl.BLEND)
    def _draw_water(self, rc) -> None:
        ctx = self.ctx
        settings = self._settings(rc.frame)
        self._ensure_textures(int(settings.quality.windshield_resolution) if settings is not None else 512)
        n = self.resolution
        lod = math.log2(n / FILM_CELLS)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        # The CPU film now, as mean thickness (µm) per cell.
        cur = 1 - self._coarse_index
        self._coarse[cur].write((self.sim.film_thickness_m() * 1e6).astype(np.float32).tobytes())
        prev = self._coarse[self._coarse_index]
        src, dst = self._film[self._film_index], self._film[1 - self._film_index]
        # 1. relax last frame's film (rescaled to the CPU film it showed) and wipe what the blades swept.
        prog = self.film_prog
        src.color.use(TEXTURE_UNITS[0])
        prev.use(TEXTURE_UNITS[1])
        prog["u_film"].value = TEXTURE_UNITS[0]
        prog["u_coarse"].value = TEXTURE_UNITS[1]
        prog["u_coarse_lod"].value = lod
        prog["u_texel"].value = (1.0 / n, 1.0 / n)
        dt = self._dt
        prog["u_diffusion"].value = min(FILM_DIFFUSION_M2_S * dt / self._texel_m() ** 2, 0.2)
        head = max(float(self._inputs.relative_air_local()[2]), 0.0) * 0.65
        prog["u_dry_um"].value = FILM_EVAP_KG_M2_S * (1.0 + head / EVAP_AIR_M_S) * dt / RHO_W * 1e6
        prog["u_bead_mix"].value = 1.0 - math.exp(-FILM_BEAD_RATE_PER_S * dt)
        residue_um = RESIDUE_M * (1.0 + 4.0 * self._inputs.blade_wear) * 1e6
        blades, sweeps = [], []
        for blade, sweep in zip(self.sim.blades, self.sim.frame_sweeps(), strict=True):
            blades.append((*blade.pivot, blade.r_inner_m, blade.r_outer_m))
            sweeps.append((sweep[0], sweep[1], 1.0, residue_um) if sweep else (0.0, 0.0, 0.0, 0.0))
        prog["u_blade"].write(np.array(blades, np.float32).tobytes())
        prog["u_sweep"].write(np.array(sweeps, np.float32).tobytes())
        prog["u_seed"].value = self.seed % 100000
        dst.fbo.use()
        ctx.disable(moderngl.BLEND)
        self._film_vao.render(moderngl.TRIANGLES, vertices=3)
        # 2. deposits: wet trails and splash speckle, added.
        self._draw_splats(self.film_splats(), moderngl.FUNC_ADD)
        dst.color.build_mipmaps()
        # 3. drops and beads: heights (mm), overlapping splats keep the highest.
        self._drops.fbo.use()
        self._drops.fbo.clear(0.0, 0.0, 0.0, 0.0)
        self._draw_splats(self.drop_splats(), moderngl.MAX)
        # 4. the water texture: thickness, film, slopes.
        prog = self.normals_prog
        self._drops.color.use(TEXTURE_UNITS[0])
        dst.color.use(TEXTURE_UNITS[1])
        self._coarse[cur].use(TEXTURE_UNITS[2])
        prog["u_drops"].value = TEXTURE_UNITS[0]
        prog["u_film"].value = TEXTURE_UNITS[1]
        prog["u_coarse"].value = TEXTURE_UNITS[2]
        prog["u_coarse_lod"].value = lod
        prog["u_texel"].value = (1.0 / n, 1.0 / n)
        self._water.fbo.use()
        self._normals_vao.render(moderngl.TRIANGLES, vertices=3)
        self._film_index = 1 - self._film_index
        self._coarse_index = cur

    # --- the glass ------------------------------------------------------------------------------------------
    def _draw_glass(self, rc) -> None:
        ctx = self.ctx
        frame = rc.frame
        settings = self._settings(frame)
        copy = self._ensure_frame_copy(rc.size)
        ctx.copy_framebuffer(copy.fbo, rc.hdr.fbo)
        copy.color.build_mipmaps()
        prog = self.glass_prog
        rc.set_frame_uniforms(prog)
        model = frame.ego.model_matrix().copy()
        model[2, 3] -= rc.shift_z
        prog["u_model"].write(_mat_bytes(model))
        rot = model[:3, :3]
        prog["u_axis_s"].value = tuple(rot @ self.glass.right)
        prog["u_axis_t"].value = tuple(rot @ self.glass.up)
        prog["u_refraction"].value = float(settings.windshield.refraction) if settings is not None else 1.0
        blur = math.log2(max(1.0, EYE_APERTURE_BLUR * rc.size[1]))
        prog["u_drop_lod"].value = blur + 0.5
        angles = self.sim.blade_angles()
        prog["u_blade"].write(
            np.array([(*b.pivot, b.r_inner_m, b.r_outer_m) for b in self.sim.blades], np.float32).tobytes()
        )
        prog["u_blade_angle"].write(np.array(angles, np.float32).tobytes())
        lighting = frame.lighting
        cabin = (
            0.02
            * 0.5
            * (np.asarray(lighting.sky_zenith) + np.asarray(lighting.sky_horizon))
            * lighting.exposure
        )
        prog["u_cabin"].value = tuple(float(c) for c in cabin)
        prog["u_aperture_m"].value = PUPIL_RADIUS_M
        prog["u_near_far"].value = (frame.camera.near_m, frame.camera.far_m)
        prog["u_cabin_depth"].value = CABIN_DEPTH_M
        self._water.color.use(TEXTURE_UNITS[0])
        copy.color.use(TEXTURE_UNITS[1])
        copy.depth.use(TEXTURE_UNITS[2])
        prog["u_water"].value = TEXTURE_UNITS[0]
        prog["u_frame"].value = TEXTURE_UNITS[1]
        prog["u_depth"].value = TEXTURE_UNITS[2]
        rc.hdr.fbo.use()
        ctx.enable(moderngl.DEPTH_TEST)
        rc.hdr.fbo.depth_mask = False
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA)
        self._glass_vao.render(moderngl.TRIANGLES)
        ctx.disable(moderngl.BLEND)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        rc.hdr.fbo.depth_mask = True

    def release(self) -> None:
        self._release_textures()
        for obj in (
            *self._coarse,
            self._mesh_vbo,
            self._mesh_ibo,
            self._splat_buf,
            self._glass_vao,
            self._splat_vao,
            self._film_vao,
            self._normals_vao,
        ):
            obj.release()
        if self._frame_copy is not None:
            self._frame_copy.release()


def make_windshield(ctx, settings=None, shaders=None, seed: int = 0) -> WindshieldEffect:
    """The windshield effect for ``Scene(..., effects=[...])`` / ``scene.default_effects``."""
    return WindshieldEffect(ctx, shaders, settings, seed)
