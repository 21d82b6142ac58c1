"""The road heightmap: crown, rutted wheel tracks and cracks on one periodic 48 m patch, and its
GL-texture-compatible bilinear sample. height01 = 0 is the lowest road point (water collects there first)."""


from __future__ import annotations

import numpy as np

from rain_core import layout

_HW = layout.ROAD_HALF_WIDTH_M
HEIGHTMAP_TEXEL_M = 0.05  # m per road heightmap texel (square texels)
HEIGHTMAP_EXTENT_M = (2.0 * layout.ROAD_HALF_WIDTH_M, 48.0)  # m (x, z); PERIOD_M is 25 × 48 m


def sample_heightmap(hmap, extent_m: tuple[float, float], x, z):
    """Bilinear, GL-texture-compatible sample of a road heightmap (see :meth:`World.road_height01`); x, z in m.

    ``hmap`` is one (nz, nx) map, or a tuple of maps on one grid (as a texture's channels): they are sampled
    with one set of indices and weights and a tuple of results comes back, each exactly what sampling that map
    alone gives."""
    maps = hmap if isinstance(hmap, tuple) else (hmap,)
    nz, nx = maps[0].shape
    fx = (np.asarray(x, dtype=np.float64) + extent_m[0] / 2) / extent_m[0] * nx - 0.5
    fz = np.asarray(z, dtype=np.float64) / extent_m[1] * nz - 0.5
    if fx.shape != fz.shape:  # (broadcast_arrays costs more than the rest on a few wheels' points)
        fx, fz = np.broadcast_arrays(fx, fz)
    i0 = np.floor(fx)
    j0 = np.floor(fz)
    tx = fx - i0
    tz = fz - j0
    i0 = i0.astype(np.int64)
    j0 = j0.astype(np.int64)
    # Clamp across x, wrap along z; flat indices and take(): 2-D fancy indexing costs several times more.
    ia = np.minimum(np.maximum(i0, 0), nx - 1)
    ib = np.minimum(np.maximum(i0 + 1, 0), nx - 1)
    ja = np.mod(j0, nz) * nx
    jb = np.mod(j0 + 1, nz) * nx
    taps = (ja + ia, ja + ib, jb + ia, jb + ib)
    ux, uz = 1 - tx, 1 - tz
    out = []
    for m in maps:
        flat = m.ravel() if m.flags.c_contiguous else np.ascontiguousarray(m).ravel()
        # Only the four picked texels are read; float32 texels widen exactly in the float64 products.
        aa, ab, ba, bb = (flat.take(t) for t in taps)
        top = aa * ux + ab * tx
        bot = ba * ux + bb * tx
        out.append(top * uz + bot * tz)
    return tuple(out) if isinstance(hmap, tuple) else out[0]


# ----------------------------------------------------------------------------------------------------------------
# Road heightmap


def _periodic_noise(rng: np.random.Generator, shape, sigma_texels: float) -> np.ndarray:
    """Gaussian-filtered white noise, periodic on both axes (filtered in the Fourier domain), unit std."""
    white = rng.standard_normal(shape)
    kz = np.fft.fftfreq(shape[0])[:, None]
    kx = np.fft.rfftfreq(shape[1])[None, :]
    filt = np.exp(-2.0 * (np.pi * sigma_texels) ** 2 * (kz**2 + kx**2))
    out = np.fft.irfft2(np.fft.rfft2(white) * filt, s=shape)
    return out / (out.std() + 1e-12)


def _crack_mask(rng: np.random.Generator, nz: int, nx: int, dx: float) -> np.ndarray:
    """Thin random-walk cracks (1 texel core, soft shoulders), wrapping along z; float32 in [0, 1]."""
    n = 44
    kind = rng.choice(3, size=n, p=(0.5, 0.25, 0.25))  # 0 longitudinal in wheel paths, 1 transverse, 2 random
    lengths = np.where(kind == 0, rng.uniform(1.5, 6.0, n), np.where(kind == 1, rng.uniform(1.0, 4.0, n),
                                                                      rng.uniform(0.5, 2.5, n)))
    ruts = np.array([c + o for c in layout.LANE_CENTRES_X for o in (-0.9, 0.9)])
    x0 = np.where(kind == 0, rng.choice(ruts, n) + rng.normal(0, 0.12, n), rng.uniform(-_HW + 0.3, _HW - 0.3, n))
    z0 = rng.uniform(0, HEIGHTMAP_EXTENT_M[1], n)
    # Heading measured from +z towards +x.
    theta0 = np.where(kind == 0, rng.normal(0, 0.08, n) + np.pi * rng.integers(0, 2, n),
                      np.where(kind == 1, np.pi / 2 + rng.normal(0, 0.15, n), rng.uniform(0, 2 * np.pi, n)))
    wiggle = np.where(kind == 2, 0.1, 0.04)  # rad per step: random cracks meander, the others run straight
    step = dx * 0.5  # half a texel per step so the line has no gaps
    n_steps = int(np.ceil(lengths.max() / step))
    theta = theta0[:, None] + np.cumsum(rng.normal(0, 1, (n, n_steps)) * wiggle[:, None], axis=1)
    px = x0[:, None] + np.cumsum(np.sin(theta) * step, axis=1)
    pz = z0[:, None] + np.cumsum(np.cos(theta) * step, axis=1)
    alive = (np.arange(n_steps)[None, :] * step) < lengths[:, None]
    i = np.floor((px + _HW) / dx).astype(np.int64)
    j = np.floor(pz / dx).astype(np.int64) % nz
    ok = alive & (i >= 0) & (i < nx)
    core = np.zeros((nz, nx), dtype=np.float32)
    core[j[ok], i[ok]] = 1.0
    # Soft shoulders: half depth on the 4-neighbours (z wraps, x does not).
    side = np.maximum(np.roll(core, 1, axis=0), np.roll(core, -1, axis=0))
    side[:, 1:] = np.maximum(side[:, 1:], core[:, :-1])
    side[:, :-1] = np.maximum(side[:, :-1], core[:, 1:])
    return np.maximum(core, 0.45 * side)


def make_road_heightmap(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The road's relative height as a texture: (height01, crack_mask), both float32 (H, W) = (960, 280), rows
    along z (0.05 m texels over 48 m, seamless), columns along x over the road width (14 m). height01 = 0 is the
    lowest point. Components: crown (2 % cross slope to the kerb gutters), two rutted wheel tracks per lane at
    ±0.9 m from the lane centre (0.7 m wide), shallow depressions, fine aggregate noise, and cracks (crack_mask
    = 1 on a crack's centre line, ~0.45 on its shoulders). The amplitudes are chosen for how water should
    collect, not to metric scale: cracks < ruts and gutters < lane centres < crown."""
    dx = HEIGHTMAP_TEXEL_M
    nx = int(round(HEIGHTMAP_EXTENT_M[0] / dx))
    nz = int(round(HEIGHTMAP_EXTENT_M[1] / dx))
    x = -_HW + (np.arange(nx) + 0.5) * dx
    z = (np.arange(nz) + 0.5) * dx
    ax = np.abs(x)[None, :]
    crown = -0.30 * ax / _HW
    gutter = -0.10 * np.clip(1.0 - (_HW - ax) / 0.4, 0.0, 1.0) ** 2
    # Ruts: raised-cosine grooves whose depth and lateral position wander slowly (whole cycles per tile).
    ruts = np.zeros((nz, nx))
    depth_noise = _periodic_noise(rng, (nz, 8), sigma_texels=60.0)
    for k, c in enumerate(layout.LANE_CENTRES_X):
        for m, off in enumerate((-0.9, 0.9)):
            cycles = rng.integers(1, 4)
            wander = 0.06 * np.sin(2 * np.pi * cycles * z / HEIGHTMAP_EXTENT_M[1] + rng.uniform(0, 2 * np.pi))
            d = (x[None, :] - (c + off) - wander[:, None]) / 0.35
            groove = np.where(np.abs(d) < 1.0, 0.5 * (1.0 + np.cos(np.pi * d)), 0.0)
            depth = 0.26 * (1.0 + 0.3 * depth_noise[:, (2 * k + m) % 8])
            ruts += groove * depth[:, None]
    low = 0.07 * _periodic_noise(rng, (nz, nx), sigma_texels=25.0)
    fine = 0.025 * _periodic_noise(rng, (nz, nx), sigma_texels=0.8)
    h = 0.9 + crown + gutter - ruts + low + fine
    cracks = _crack_mask(rng, nz, nx, dx)
    h = h - cracks * (0.55 + 0.25 * np.clip(h, 0.0, 1.0))
    h = (h - h.min()) / (h.max() - h.min())
    return h.astype(np.float32), cracks

