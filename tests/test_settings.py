"""rain_core.settings: defaults, validation with named fields, TOML round trips, shipped presets."""

import functools
import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.settings import (
    RainSection,
    RainSettings,
    ScenarioSyntaxError,
    Settings,
    SettingsError,
    all_fields,
    apply_rain_preset,
    field_info,
    get_value,
    list_presets,
    load_scenario,
    preset_settings,
    save_scenario,
    set_value,
    to_toml,
)


def test_defaults_are_valid_and_described():
    s = Settings()
    s.validate()
    assert RainSettings is Settings
    infos = all_fields()
    assert len({i.path for i in infos}) == len(infos) > 40
    sections = {i.path.split(".")[0] for i in infos}
    assert {"rain", "road", "wind", "wipers", "camera", "time_of_day", "traffic", "quality", "ripples",
            "rainfall", "spray", "windshield", "atmosphere"} <= sections
    for info in infos:
        assert get_value(s, info.path) == info.default
        if info.range:
            assert info.range[0] <= info.range[1]
        assert info.kind in ("float", "int", "bool", "str")
    assert field_info("rain.rate_mm_h").unit == "mm/h"
    assert field_info("rain.rate_mm_h").range == (0.0, physics.R_MAX_MM_H)


@pytest.mark.parametrize(
    "path, value",
    [
        ("rain.rate_mm_h", -0.1),
        ("rain.rate_mm_h", 500.5),
        ("rain.rate_mm_h", math.nan),
        ("rain.rate_mm_h", math.inf),
        ("rain.rate_mm_h", "heavy"),
        ("rain.rate_mm_h", True),
        ("rain.rate_mm_h", None),
        ("rain.wetness", 1.2),
        ("traffic.count", True),
        ("traffic.count", 2.5),
        ("traffic.count", 21),
        ("road.enabled", 1),
        ("camera.mode", "top"),
        ("wipers.mode", 3),
        ("time_of_day.hour", 25.0),
    ],
)
def test_invalid_values_name_field_value_and_range(path, value):
    s = Settings()
    before = get_value(s, path)
    with pytest.raises(SettingsError) as exc:
        set_value(s, path, value)
    err = exc.value
    assert isinstance(err, ValueError)
    assert err.field_path == path
    msg = str(err)
    assert path in msg and repr(value) in msg and err.allowed in msg
    assert get_value(s, path) == before  # nothing stored


def test_range_is_in_the_message():
    with pytest.raises(SettingsError, match=r"\[0, 500\] mm/h"):
        set_value(Settings(), "rain.rate_mm_h", -1)


def test_valid_values_are_stored_and_ints_become_floats():
    s = Settings()
    set_value(s, "rain.rate_mm_h", 7)
    assert s.rain.rate_mm_h == 7.0 and isinstance(s.rain.rate_mm_h, float)
    set_value(s, "traffic.count", np.int64(3))
    assert s.traffic.count == 3 and type(s.traffic.count) is int
    set_value(s, "rain.puddles", 0.4)
    set_value(s, "rain.puddles", None)
    assert s.rain.puddles is None


def test_construction_validates():
    with pytest.raises(SettingsError, match="rain.rate_mm_h"):
        RainSection(rate_mm_h=-1.0)
    with pytest.raises(SettingsError, match="rain"):
        Settings(rain="heavy")


@pytest.mark.parametrize("path", ["rain.rate", "rainfall", "weather.rate_mm_h", "rain.rate_mm_h.x", 3])
def test_unknown_paths(path):
    with pytest.raises(SettingsError, match="unknown setting"):
        set_value(Settings(), path, 1.0)


def test_path_lookups_resolve_the_sections_once(monkeypatch):
    # The Rain Manager reads each widget's value by path every frame: resolving the sections' string annotations
    # at each lookup cost ~0.2 ms, 2 ms a frame (python -m rain_core.bench panel).
    import typing

    calls = []
    hints = typing.get_type_hints
    monkeypatch.setattr(typing, "get_type_hints", lambda *a, **k: calls.append(a) or hints(*a, **k))
    monkeypatch.delattr(Settings, "_section_types", raising=False)  # as a new process finds it
    s = Settings()
    for _ in range(50):
        set_value(s, "rain.rate_mm_h", get_value(s, "rain.rate_mm_h") + 1.0)
        field_info("camera.fov_deg")
    assert len(calls) == 1 and s.rain.rate_mm_h == 52.0
    sections = Settings.section_types()
    assert list(sections)[:2] == ["rain", "road"] and sections["rain"] is RainSection
    with pytest.raises(TypeError):  # one mapping shared by every caller: read-only
        sections["rain"] = RainSection


def test_round_trip_is_identical(tmp_path):
    s = Settings()
    set_value(s, "rain.rate_mm_h", 0.1 + 0.2)  # not representable in short decimal
    set_value(s, "rain.wetness", 1 / 3)
    set_value(s, "camera.exposure_s", 1e-4)
    set_value(s, "wind.direction_deg", 359.99999999999994)
    set_value(s, "road.puddle_seed", 2**31 - 1)
    set_value(s, "wipers.mode", "intermittent")
    set_value(s, "road.debug_regions", True)
    path = save_scenario(s, tmp_path / "sub" / "a.toml", title="round trip\nsecond line")
    back = load_scenario(path)
    assert back == s
    assert back.rain.rate_mm_h == 0.1 + 0.2 and back.rain.cracks is None
    assert Settings.from_dict(s.to_dict()) == s
    assert to_toml(back) == to_toml(s)


def test_partial_file_overrides_defaults_or_base(tmp_path):
    p = tmp_path / "p.toml"
    p.write_text("[rain]\nrate_mm_h = 12\npuddles = 0.5\n")
    s = load_scenario(p)
    assert s.rain.rate_mm_h == 12.0 and s.rain.puddles == 0.5 and s.road == Settings().road
    base = Settings()
    set_value(base, "traffic.count", 0)
    assert load_scenario(p, base=base).traffic.count == 0 and base.rain.rate_mm_h == 2.0


@pytest.mark.parametrize(
    "text, path, fragment",
    [
        ("[rain]\nrate = 3.0\n", "rain.rate", "unknown setting"),
        ("[weather]\nrate_mm_h = 3.0\n", "weather", "unknown setting"),
        ('[rain]\nrate_mm_h = "heavy"\n', "rain.rate_mm_h", "a number in [0, 500] mm/h"),
        ("[rain]\nrate_mm_h = -2.0\n", "rain.rate_mm_h", "a number in [0, 500] mm/h"),
        ("[traffic]\ncount = true\n", "traffic.count", "an integer in [0, 20]"),
        ("[road]\nenabled = 1\n", "road.enabled", "true or false"),
        ("rain = 3\n", "rain", "table"),
        ("[rain]\nrate_mm_h = nan\n", "rain.rate_mm_h", "[0, 500]"),
    ],
)
def test_bad_files_name_file_and_field(tmp_path, text, path, fragment):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(SettingsError) as exc:
        load_scenario(p)
    msg = str(exc.value)
    assert exc.value.field_path == path and path in msg and fragment in msg and str(p) in msg


def test_toml_syntax_error_names_file_and_line(tmp_path):
    p = tmp_path / "broken.toml"
    p.write_text("[rain]\nrate_mm_h = 3.0\nwetness = = 0.2\n")
    with pytest.raises(ScenarioSyntaxError) as exc:
        load_scenario(p)
    assert exc.value.line == 3
    assert str(p) in str(exc.value) and "line 3" in str(exc.value)
    assert isinstance(exc.value, SettingsError)


def test_shipped_presets(tmp_path):
    names = list_presets()
    assert names[: len(physics.RAIN_PRESETS)] == list(physics.RAIN_PRESETS)
    for name in physics.RAIN_PRESETS:
        s = preset_settings(name)
        assert s.rain.rate_mm_h == physics.RAIN_PRESETS[name] and s.rain.preset == name
        assert load_scenario(save_scenario(s, tmp_path / f"{name}.toml")) == s
    heavy = [preset_settings(n) for n in physics.RAIN_PRESETS]
    assert [s.rain.rate_mm_h for s in heavy] == sorted(s.rain.rate_mm_h for s in heavy)
    assert preset_settings("very heavy") == preset_settings("very_heavy")
    with pytest.raises(SettingsError, match="drizzle"):
        preset_settings("monsoon")


def test_apply_rain_preset():
    s = Settings()
    apply_rain_preset(s, "Very Heavy")
    assert s.rain.rate_mm_h == physics.RAIN_PRESETS["very_heavy"] and s.rain.preset == "very_heavy"
    with pytest.raises(SettingsError, match="rain.preset"):
        apply_rain_preset(s, "monsoon")


# --- issue 18: integers too large for a float, capped messages, deep nesting, BOM ------------------------

NUMERIC = [i for i in all_fields() if i.kind in ("float", "int")]


@pytest.mark.parametrize("value", [10**60, 10**400, -(10**400), 10**5000], ids=["1e60", "1e400", "-1e400", "1e5000"])
@pytest.mark.parametrize("path", [i.path for i in NUMERIC])
def test_huge_integers_are_value_errors_at_every_entrance(path, value):
    sec, key = path.split(".")
    section_type = Settings.section_types()[sec]
    entrances = [
        lambda: set_value(Settings(), path, value),
        lambda: section_type(**{key: value}),
        lambda: Settings.from_dict({sec: {key: value}}),
    ]
    for enter in entrances:
        with pytest.raises(SettingsError) as exc:
            enter()
        msg = str(exc.value)
        assert exc.value.field_path == path and path in msg and field_info(path).allowed() in msg
        assert len(msg) < 300


@pytest.mark.parametrize("value", ["3.0", "nan", b"1", [1.0], {"v": 1}, 1j])
def test_strings_and_other_types_where_numbers_are_expected(value):
    for info in NUMERIC:
        with pytest.raises(SettingsError, match=info.path.replace(".", r"\.")):
            set_value(Settings(), info.path, value)


@pytest.mark.parametrize("make", [
    lambda: "x" * 10_000_000,
    lambda: b"x" * 10_000_000,
    lambda: list(range(5_000_000)),
    lambda: {str(i): i for i in range(200_000)},
    lambda: np.zeros(5_000_000),
    lambda: functools.reduce(lambda inner, _: [inner], range(5000), []),  # 5000 levels deep
])
def test_messages_quote_a_capped_value_quickly(make):
    value = make()
    for path in ("rain.rate_mm_h", "traffic.count", "road.enabled", "camera.mode"):
        with pytest.raises(SettingsError) as exc:
            set_value(Settings(), path, value)
        assert len(str(exc.value)) < 300 and path in str(exc.value)
    with pytest.raises(SettingsError) as exc:
        Settings.from_dict({"rain": {"nope": value}})
    assert len(str(exc.value)) < 400


def test_long_unknown_keys_are_cut_in_the_message():
    with pytest.raises(SettingsError, match="unknown setting") as exc:
        set_value(Settings(), "rain." + "k" * 1_000_000, 1.0)
    assert len(str(exc.value)) < 400
    with pytest.raises(SettingsError, match="unknown setting") as exc:
        Settings.from_dict({"k" * 1_000_000: {}})
    assert len(str(exc.value)) < 400


@pytest.mark.parametrize("text", [
    "[rain]\nrate_mm_h = " + "[" * 1000 + "]" * 1000 + "\n",
    "[rain]\nrate_mm_h = " + "{a = " * 1000 + "1" + "}" * 1000 + "\n",
    "[rain]\n" + ".".join(["a"] * 5000) + " = 1\n",
    ".".join(["a"] * 5000) + " = 1\n",
    "x = " + "[" * 100_000 + "\n",
], ids=["array-1000", "inline-table-1000", "dotted-key-5000-in-section", "dotted-key-5000", "unclosed-100000"])
def test_deeply_nested_files_are_clear_errors(tmp_path, text):
    p = tmp_path / "deep.toml"
    p.write_text(text)
    with pytest.raises(SettingsError) as exc:  # not RecursionError
        load_scenario(p)
    msg = str(exc.value)
    assert str(p) in msg and len(msg) < 400
    assert "nested too deeply" in msg or "unknown setting" in msg


def test_a_byte_order_mark_is_accepted(tmp_path):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf[rain]\nrate_mm_h = 3.5\n")
    assert load_scenario(p).rain.rate_mm_h == 3.5
    p.write_bytes(b"\xef\xbb\xbf")
    assert load_scenario(p) == Settings()


def test_big_values_in_files_give_short_messages_and_huge_files_are_refused(tmp_path):
    p = tmp_path / "big.toml"
    p.write_text('[rain]\nrate_mm_h = "' + "y" * 500_000 + '"\n')
    with pytest.raises(SettingsError, match="rain.rate_mm_h") as exc:
        load_scenario(p)
    assert len(str(exc.value)) < 300
    p.write_text('[rain]\nrate_mm_h = "' + "y" * 10_000_000 + '"\n')
    with pytest.raises(ScenarioSyntaxError, match="larger than") as exc:
        load_scenario(p)
    assert str(p) in str(exc.value)
