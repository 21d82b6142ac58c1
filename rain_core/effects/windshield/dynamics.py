"""Drop motion on the glass (mixed into ``WindshieldSim``): forces, pinning, sliding, trails and shedding.

A drop on glass is a spherical cap of contact radius a with contact angle θ = CONTACT_ANGLE_DEG: volume
k_V·a³, height a·tan(θ/2). Forces along the glass:

* gravity, m·g projected on the (curved) surface (``GlassGeometry.gravity``);
* air drag in the boundary layer over the glass (``airflow``);
* contact-line pinning (Furmidge): F = γ·2a·Δcosθ. A drop at rest stays put while the other forces are weaker
  (small drops stick; large ones run), a moving drop feels KINETIC_PIN × that against its motion;
* viscous resistance in the moving drop, linear in its speed (implicit, stable for any step).

A running drop sweeps up the film in its path and leaves a trail: a thin wet line (film) and, every few radii,
a small droplet. Drops that leave the glass are shed.
"""

from __future__ import annotations

import numpy as np

from rain_core.effects.windshield.airflow import air_velocity, drag
from rain_core.effects.windshield.constants import (
    DROP_EVAP_KG_M_S,
    EVAP_AIR_M_S,
    GAMMA_W,
    HYSTERESIS,
    KINETIC_PIN,
    M_OBJECT_MIN,
    MU_W,
    TRAIL_FILM_M,
    TRAIL_FRACTION,
    TRAIL_PARENT_MIN,
    TRAIL_SPACING_RADII,
    V_STOP_M_S,
    VISCOUS_C,
    norm2,
)
from rain_core.physics import RHO_WATER


class DropDynamics:
    """The motion part of ``WindshieldSim`` (its state: ``pos``, ``vel``, ``mass``, ``trail``, ``film``, …)."""

    def _move(self, h: float, air_local: np.ndarray, inputs) -> tuple[np.ndarray, np.ndarray]:
        """Forces, pinning, viscous sliding; returns (start positions, displacements) for the merge test."""
        n = self.count
        if n == 0:
            return np.zeros((0, 2)), np.zeros((0, 2))
        a = self.radius()
        m = self.mass
        air = air_velocity(self.glass, self.pos, air_local)
        force = m[:, None] * self.glass.gravity(self.pos) + drag(self.glass, self.pos, a, air, self.vel)
        fmag = norm2(force)
        pin = GAMMA_W * 2.0 * a * HYSTERESIS
        speed = norm2(self.vel)
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
        creeping = moving & (norm2(vnew) < V_STOP_M_S) & (fmag < pin)
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

    def _sweep_film_and_trail(self, h, run, start, disp, step_len, a, inputs) -> None:
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
        wet = np.minimum(RHO_WATER * TRAIL_FILM_M * swept_area, 0.1 * self.mass[idx])
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

    def _shed_outside(self) -> None:
        """Drops that left the glass are shed; drops worn below half the object size become film."""
        inside = self.glass.contains(self.pos)
        if not inside.all():
            self.shed += float(self.mass[~inside].sum())
            self._keep(inside)
        # Drops worn down by their trails below half the object size become film where they are.
        tiny = self.mass < 0.5 * M_OBJECT_MIN
        if tiny.any():
            np.add.at(self.film.ravel(), self.glass.cell_index(self.pos[tiny]), self.mass[tiny])
            self._keep(~tiny)
