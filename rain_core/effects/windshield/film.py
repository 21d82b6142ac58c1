"""The film (mixed into ``WindshieldSim``): evaporation, and beading of a thick film into drops.

The film is kg per cell of a FILM_CELLS × FILM_CELLS grid over the glass's UV square. It dries at
FILM_EVAP_KG_M2_S, faster in the air over the glass; where it is thicker than BEAD_THRESHOLD_M it pulls
together into a drop somewhere in its cell, leaving BEAD_KEEP × the threshold.
"""

from __future__ import annotations

import numpy as np

from rain_core.effects.windshield.constants import BEAD_KEEP, BEAD_THRESHOLD_M, FILM_CELLS
from rain_core.physics import RHO_WATER


class FilmBeading:
    """The film part of ``WindshieldSim`` (its state: ``film``, ``_areas_flat``, ``_bead_mass``, ``rng``)."""

    def _film_step(self, h: float, evap_kg_s: np.ndarray, inputs) -> None:
        """Evaporation (``evap_kg_s``: kg/s per cell for a wet cell) and beading of the film."""
        flat = self.film.ravel()
        loss = np.minimum(flat, evap_kg_s * h)
        flat -= loss
        self.evaporated += float(loss.sum())
        # Beading: a film thicker than the threshold pulls together into a drop somewhere in its cell.
        thick = np.flatnonzero(flat > self._bead_mass)
        if len(thick) == 0:
            return
        thick, m = self._beads(flat, thick, max(int(inputs.drop_budget) - self.count, 0))
        iv, iu = np.divmod(thick, FILM_CELLS)
        u = (iu + self.rng.random(len(thick))) / FILM_CELLS
        v = (iv + self.rng.random(len(thick))) / FILM_CELLS
        self._bead_drops(u, v, m)

    def _beads(self, flat: np.ndarray, thick: np.ndarray, room: int) -> tuple[np.ndarray, np.ndarray]:
        """Of the film cells ``thick`` (indices into ``flat``, the film in kg, edited here), the ones that bead —
        thickest first, at most ``room`` (the drop budget left); the surplus of a full glass joins drops already
        in its cell — and the bead masses (kg). Each beading cell keeps BEAD_KEEP × the threshold. Shared by
        the reference and the fast path (``WindshieldSim._film_step``)."""
        thick = thick[(-flat[thick] / self._areas_flat[thick]).argsort(kind="stable")]
        keep = BEAD_KEEP * RHO_WATER * BEAD_THRESHOLD_M * self._areas_flat[thick]
        if len(thick) > room:  # a full glass: the surplus film joins drops already in those cells
            over, over_keep = thick[room:], keep[room:]
            joined = self._give_to_drops(over, flat[over] - over_keep)
            flat[over[joined]] = over_keep[joined]
            thick, keep = thick[:room], keep[:room]
        m = flat[thick] - keep
        flat[thick] = keep
        return thick, m

    def _bead_drops(self, u: np.ndarray, v: np.ndarray, m: np.ndarray) -> None:
        """New drops at rest at film UV (u, v) of masses m (kg)."""
        self._append(self.glass.from_uv(np.stack([u, v], axis=1)), np.zeros((len(u), 2)), m)
