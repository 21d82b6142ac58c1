"""The ripples' tunable numbers: the wave, the solver's bounds and the strength of the sources (DESIGN §3)."""

# Wave speed. Shallow-water gravity waves on a 5 mm film travel at sqrt(g·d) ≈ 0.22 m/s, and capillary-gravity
# ripples of 1–10 cm wavelength at 0.23–0.4 m/s; 0.22 m/s reads as sluggish at driving-view scale, so the
# default sits in the capillary-gravity range.
CAPILLARY_SPEED_M_S = 0.35
# Amplitude e-folding rate, 1/s: a wake fades to ~10 % in ~4.6 s.
DEFAULT_DAMPING_PER_S = 0.5
MAX_COURANT2 = 0.5  # the leapfrog's stability bound on C² = (s·Δt/h)²
MAX_IMPULSE_M = 1e9  # |amount| bound: keeps float32 state finite (no ripple is a kilometre high)
MAX_CELLS_PER_SIDE = 4096  # solver grid bound: 4096² float64 levels are 268 MB (settings allow 2048)
# A step shorter than this fraction of the largest stable sub-step is not taken but carried into the next call:
# 1/Δt of a denormal or 1e-200 s step overflows (the whole field turned non-finite), and such a step moves
# nothing a float can hold anyway.
MIN_STEP_FRACTION = 1e-9
# Work bound of one impulse footprint batch: bumps × (cells across)² evaluated at once (float64 temporaries).
FOOTPRINT_BATCH_CELLS = 1 << 20
DEFAULT_MAX_SUBSTEPS = 1000  # per step() call; a stall longer than this many Δt_max is shortened (see step)
SLEEP_SLOPE = 1e-4  # sleep when the energy is below that of a field with this RMS slope everywhere
MIN_FOOTPRINT_CELLS = 1.5  # impulses narrower than this many cells are widened (volume kept)

# Wheel wake: the dent under a tyre, in metres, is film depth × speed / WAKE_REF_SPEED_M_S (proportional to
# both, as the issue asks): at 10 m/s (36 km/h) the tyre presses a trough as deep as the film.
WAKE_REF_SPEED_M_S = 10.0
# Raindrop dent: depth in metres per unit momentum (kg·m/s), over a crater of radius CRATER_RADIUS_PER_D × D.
# Calibrated so a 2 mm drop at its terminal 6.5 m/s (p = 2.7e-5 kg·m/s) presses a 1 mm deep, 5 mm radius dent
# (craters of a few drop radii, Engel 1966). On a 5 cm grid the dent is spread over 1.5 cells with its
# volume kept, so single drops are µm-scale there; the visible rain rings come from RainRippleTexture.
RAIN_DENT_M_PER_KG_M_S = 37.0
CRATER_RADIUS_PER_D = 2.5

# Solver backends by name: "auto" measures the fast paths (``choose_backend``), "numpy32" the float32 NumPy path,
# "gpu" the fragment-shader path (needs a context), "reference" the float64 NumPy reference.
BACKENDS = ("auto", "numpy32", "gpu", "reference")

# Where the window sits (``window.window_centre_xz``): the road shader fades the field's slopes over this fraction
# of the window at each edge (shaders/road/surface.glsl, road_ripple_slope), so the window's rear edge is put
# this far (plus one re-centring hysteresis) behind what it must cover.
WINDOW_EDGE_FADE = 0.05
