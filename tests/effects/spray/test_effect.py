"""The spray effect in a scene, and the road film it reads (rain_core.effects.spray.effect, .wheels)."""

from types import SimpleNamespace

import numpy as np

from rain_core import water_film
from rain_core.effects.spray import wheels
from rain_core.effects.spray.water import KMH
from rain_core.effects.spray.wheels import road_film_depth_fn
from rain_core.weather import WeatherState


def test_effect_draws_spray_behind_a_truck(truck_scene):
    images, stats = [], []
    for enabled in (True, False):
        scene, effect = truck_scene(enabled=enabled, puddle_mm=0.0)
        for _ in range(12):
            scene.step(1 / 30)
            scene.render()
        images.append(scene.renderer.hdr_image())
        stats.append({s.name: s.ran for s in scene.renderer.stats})
        if enabled:
            assert effect.emitter.stats.mist_puffs > 0 and effect.emitter.alive_counts(scene.time_s)[0] > 0
            assert effect.ego_hydroplaning_risk == 0.0  # a wet film, no standing water
            assert len(effect.wheels) == 2 and effect.wheels[1].vehicle.spec.kind == "truck"
        scene.release()
    assert np.isfinite(images[0]).all()
    assert stats[0]["spray.transparent"] and not stats[1]["spray"]
    diff = np.abs(images[0] - images[1]).max(axis=-1)
    assert (diff > 1e-3).mean() > 0.01  # the spray shows


def test_effect_is_skipped_on_a_dry_road_and_reports_hydroplaning(truck_scene):
    scene, effect = truck_scene(puddle_mm=0.0)
    scene.settings.rain.wetness = 0.0
    scene.settings.rain.rate_mm_h = 0.0
    scene.step(1 / 30)
    scene.render()
    assert not {s.name: s.ran for s in scene.renderer.stats}["spray"]
    scene.release()
    scene, effect = truck_scene(puddle_mm=8.0)
    scene.ego.speed_m_s = 110 * KMH
    scene.step(1 / 30)
    scene.render()
    assert effect.ego_hydroplaning_risk > 0.5
    assert np.all(effect.hydroplaning_risk(scene.traffic.vehicles[0]) < effect.hydroplaning_risk())
    scene.release()


def test_road_film_depth_is_the_roads_film():
    # One model of the film, no copy of its constants: water_film's sampler, film_depth_mm bit for bit.
    assert wheels.film_depth_sampler is water_film.film_depth_sampler
    wet_mm = water_film.WET_FILM_MM
    x, z = np.array([0.0, 3.0, 7.5, 1.75]), np.array([10.0, 20.0, 30.0, 500.0])
    wet = road_film_depth_fn(SimpleNamespace(weather=WeatherState(wetness=0.5), settings=None, world=None))
    assert np.allclose(wet(x, z), [0.5 * wet_mm, 0.5 * wet_mm, 0.0, 0.5 * wet_mm])
    flooded = WeatherState(wetness=1.0, cracks=1.0, puddles=1.0)
    fn = road_film_depth_fn(SimpleNamespace(weather=flooded, settings=None, world=None))
    zz = np.arange(100.0, 1100.0, 0.5)
    assert np.array_equal(fn(np.full_like(zz, 5.25), zz), water_film.film_depth_mm(5.25, zz, 1.0, 1.0, wetness=1.0))
    assert fn(np.full_like(zz, 5.25), zz).max() > 3.0  # standing water where the wheels run


def test_active_is_pure_and_observe_follows_the_frame(truck_scene):
    from rain_core.gfx.frame import SharedResources

    scene, effect = truck_scene(puddle_mm=8.0)
    scene.step(1 / 30)
    frame = scene.frame()
    assert not effect.active(frame) and effect.wheels == []  # nothing observed yet: active changed nothing
    effect.observe(frame)
    assert len(effect.wheels) == 2 and effect.active(frame) and effect.active(frame)
    rc = SimpleNamespace(shared=SharedResources())
    for _ in range(15):  # through standing water: parcels land in it and are published for the ripples
        effect.update(scene.frame(), rc)
        scene.step(1 / 30)
        effect.observe(scene.frame())
    impacts = rc.shared.droplet_impacts
    assert isinstance(impacts, np.ndarray) and impacts.dtype == np.float64 and impacts.shape[1:] == (3,)
    assert len(impacts) > 0 and np.all(impacts[:, 2] >= 0.0)
    assert np.array_equal(impacts, np.array(effect.landed_in_water()))
    scene.settings.spray.enabled = False
    off = scene.frame()
    assert not effect.active(off) and effect.emitter.alive_until() > -np.inf  # still pure when switched off
    effect.observe(off)  # switched off: the parcels in flight are dropped, the last time forgotten
    assert effect.emitter.alive_until() == -np.inf and effect.emitter._last_time is None
    scene.release()


def test_the_pass_writes_its_own_frames_motion_not_the_one_update_made(truck_scene):
    """update makes the frame's camera velocity and forward for its draw; a draw of another frame (another camera,
    the ego moved) writes that frame's own, and the next frame's update makes them again."""
    from rain_core.camera import look_at

    scene, effect = truck_scene()
    try:
        for _ in range(3):
            scene.step(1 / 30)
            frame = scene.render()
        assert effect._motion[0] is frame  # made by update for the frame just drawn
        prog = effect._program
        eye = np.array([1.75, 1.2, 610.0])
        cam = look_at(eye, np.array([6.0, 1.0, 580.0]), fov_y_deg=60.0)
        scene.ego.speed_m_s *= 0.5  # the ego's velocity changes too
        other = scene.frame(cam)
        rc = SimpleNamespace(frame=other, shift_z=0.0, size=(96, 54))
        effect._set_uniforms(prog, rc, 0.5)
        f = cam.forward / np.linalg.norm(cam.forward)
        assert np.allclose(prog["u_cam_forward"].value, f, atol=1e-6)
        assert np.allclose(prog["u_camera_vel"].value, scene.ego.velocity(), atol=1e-6)
        scene.step(1 / 30)
        frame = scene.render()
        assert effect._motion[0] is frame
        assert np.allclose(prog["u_cam_forward"].value, frame.camera.forward / np.linalg.norm(frame.camera.forward),
                           atol=1e-6)
    finally:
        scene.release()


def test_the_forward_uniform_follows_the_camera(truck_scene):
    """The pass writes the camera's normalised forward (through OwnedUniforms: a new direction is written)."""
    from rain_core.camera import look_at

    scene, effect = truck_scene()
    try:
        eye = np.array([1.75, 1.2, 610.0])
        for target in ([1.75, 1.0, 560.0], [6.0, 1.0, 580.0]):
            cam = look_at(eye, np.array(target), fov_y_deg=60.0)
            for _ in range(3):
                scene.step(1 / 30)
                scene.render(cam)
            f = cam.forward / np.linalg.norm(cam.forward)
            assert np.allclose(effect._program["u_cam_forward"].value, f, atol=1e-6)
    finally:
        scene.release()


def test_the_section_is_the_frames_or_the_defaults():
    """The effect reads frame.settings.spray (the panel's live object); a frame without settings gets defaults."""
    from rain_core.effects.spray import SprayEffect
    from rain_core.settings import Settings, SpraySection

    settings = Settings()
    assert SprayEffect._section(SimpleNamespace(settings=settings)) is settings.spray
    assert SprayEffect._section(SimpleNamespace(settings=None)) == SpraySection()
    assert SprayEffect._section(SimpleNamespace()) == SpraySection()


def test_the_gpu_rings_hold_the_emitters_records(truck_scene):
    """After each frame's upload (only the slots written since the last) the two GL buffers hold the rings'
    records byte for byte, through the ring wrapping and a budget change (new rings, new buffers)."""
    scene, effect = truck_scene()
    try:
        for budget in (3000, 1200):
            scene.settings.spray.budget = budget
            for _ in range(25):
                scene.step(1 / 30)
                scene.render()
                for ring, buf in zip(effect.emitter.rings, effect._buffers, strict=True):
                    assert buf.read() == ring.data.tobytes()
        assert effect.emitter.rings[0].head < effect.emitter.stats.parcels - 1200  # it wrapped
    finally:
        scene.release()
