"""Kernel of a frame's spawn after its draws: ``launch``, ``fly``, ``body_hit``, ``settle_horizons`` and
``file_records`` in one call (``launch_to_records``). None of them draws a number, so the caller makes every
draw they need first, in the twin's order, and the five kernels run back to back as the five calls did: the
same values, one dispatch (each of ~13–26 arguments) instead of five, and no Python between them. Twin: the
five calls of ``spawn.spawn_parcels_fast``'s compiled path (itself checked against the NumPy twins)."""

from __future__ import annotations

from rain_core import jit
from rain_core.effects.spray.kernels.body_test import body_hit
from rain_core.effects.spray.kernels.flight import fly
from rain_core.effects.spray.kernels.launches import launch
from rain_core.effects.spray.kernels.records import file_records, settle_horizons


@jit.kernel
def launch_to_records(w, bounds, nd, age_now, draws, offs, wheel, vehicle, vehicle_consts, launch_tables, mist_lo,
                      mist_span, mist_consts, p0, v0, d_mm, sigma0, growth, air, updraught, wind, fly_consts, gk,
                      max_steps, u, speed, tau, t_ground, vi, body_steps, t_body, cap, life, fate, fates_ids, q90, now,
                      landings_on, mass, birth, file_consts, fates, landings, records, birth_out, death_out):
    """Launch, fly, body-test, settle and file a frame's parcels (droplets [:nd], then mist; ``n`` = len(w)).
    Arguments as the five kernels take them, grouped: ``launch_tables`` (bucket, uniform lo, uniform span, wave),
    ``fly_consts`` (mist v_t, mist τ, g, the drag tail fit, kerb height, road half width, Newton tolerance),
    ``gk`` (the Gunn–Kinzer knots, lows, widths, values and slopes at both ends), ``body_steps`` (samples, zoom,
    rounds), ``fates_ids`` (road, body, air). ``vi`` (≥ n,) int64 scratch: each parcel's vehicle. Updates ``q90``
    and ``fates`` in place; returns (records of ring 0, records, road landings) as ``file_records``."""
    n = w.shape[0]
    bucket_table, uniform_lo, uniform_span, wave_table = launch_tables
    launch(w, bounds, nd, age_now, draws, offs, wheel, vehicle, vehicle_consts, bucket_table, uniform_lo,
           uniform_span, wave_table, mist_lo, mist_span, mist_consts, p0, v0, d_mm, sigma0, growth, air, updraught)
    gk_x, gk_x0, gk_h, gk_y0, gk_y1, gk_d0, gk_d1 = gk
    fly(p0, v0, d_mm, air, updraught, nd, wind, fly_consts[0], fly_consts[1], gk_x, gk_x0, gk_h, gk_y0, gk_y1, gk_d0,
        gk_d1, fly_consts[2], fly_consts[3], fly_consts[4], fly_consts[5], fly_consts[6], max_steps, u, speed, tau,
        t_ground)
    for i in range(n):
        vi[i] = w[i] // 4
    if nd:
        body_hit(p0, v0, u, tau, t_ground, vehicle, vi, age_now, nd, body_steps[0], body_steps[1], body_steps[2],
                 t_body)
    h_drop, h_mist = settle_horizons(t_body[:nd], t_ground, cap, speed, nd, life, fate, growth, fates_ids[0],
                                     fates_ids[1], fates_ids[2], q90)
    return file_records(fate, life, h_drop, h_mist, nd, now, landings_on, mass, p0, v0, u, tau, birth, sigma0,
                        growth, d_mm, vi[:n], vehicle_consts, file_consts, fates, landings, records, birth_out,
                        death_out)
