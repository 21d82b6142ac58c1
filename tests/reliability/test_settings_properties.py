"""Property-based tests of the settings (issue 18): ``set_value`` for every path in the declarations, and the
scenario loader (valid settings → TOML → load is exact; junk → ValueError, never another exception).

Strategies come from ``all_fields()``, so a new setting is covered without touching this file.
"""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from rain_core.settings import (
    FieldInfo,
    Settings,
    SettingsError,
    all_fields,
    get_value,
    load_scenario,
    set_value,
    to_toml,
)

FIELDS = {info.path: info for info in all_fields()}
MAX_MESSAGE = 400  # characters; a message quotes a capped value
HUGE_INTS = st.integers(min_value=2**1024) | st.integers(max_value=-(2**1024)) | st.sampled_from(
    [10**60, -(10**60), 10**400, 10**5000])
OTHER_TYPES = (st.text(max_size=20) | st.binary(max_size=10) | st.lists(st.integers(), max_size=3)
               | st.dictionaries(st.text(max_size=3), st.integers(), max_size=2) | st.complex_numbers())


def valid_values(info: FieldInfo) -> st.SearchStrategy:
    """Values ``set_value`` must accept for ``info`` (ints included for float fields)."""
    if info.kind == "bool":
        base = st.booleans()
    elif info.kind == "str":
        base = st.sampled_from(info.choices)
    elif info.kind == "int":
        base = st.integers(*info.range)
    else:
        lo, hi = info.range
        base = st.floats(lo, hi) | st.sampled_from([lo, hi])
        if math.ceil(lo) <= math.floor(hi):
            base |= st.integers(math.ceil(lo), math.floor(hi))
    return base | st.none() if info.optional else base


def invalid_values(info: FieldInfo) -> st.SearchStrategy:
    """Values ``set_value`` must refuse with a ValueError naming ``info.path``."""
    options = [OTHER_TYPES]
    if not info.optional:
        options.append(st.none())
    if info.kind == "bool":
        options += [st.integers(), st.floats()]
    elif info.kind == "str":
        options += [st.text(max_size=30).filter(lambda s: s not in info.choices), st.integers(), st.floats()]
    else:
        lo, hi = info.range
        options += [st.booleans(), HUGE_INTS, st.sampled_from([math.nan, math.inf, -math.inf]),
                    st.floats(max_value=lo, exclude_max=True), st.floats(min_value=hi, exclude_min=True)]
        options.append(st.text(max_size=10).map(str))  # numeric-looking strings are strings too
        if info.kind == "int":
            options += [st.integers(max_value=int(lo) - 1), st.integers(min_value=int(hi) + 1), st.floats()]
        else:
            options += [st.integers(max_value=math.ceil(lo) - 1), st.integers(min_value=math.floor(hi) + 1)]
    if info.kind == "str":  # a text drawn for the other types may happen to be a valid choice
        return st.one_of(options).filter(lambda v: not (isinstance(v, str) and v in info.choices))
    return st.one_of(options)


def test_every_declared_setting_is_enumerated():
    assert len(FIELDS) > 40 and all(info.kind in ("float", "int", "bool", "str") for info in FIELDS.values())
    assert all(info.range for info in FIELDS.values() if info.kind in ("float", "int"))
    assert all(info.choices for info in FIELDS.values() if info.kind == "str")


# --- set_value -------------------------------------------------------------------------------------------


VALID = {path: valid_values(info) for path, info in FIELDS.items()}
INVALID = {path: invalid_values(info) for path, info in FIELDS.items()}

# Each example draws one value for every path (one Hypothesis test per property, not one per path: the same
# coverage at a fraction of the overhead).


@given(data=st.data())
def test_valid_values_round_trip_for_every_path(data):
    s = Settings()
    for path, info in FIELDS.items():
        value = data.draw(VALID[path], label=path)
        set_value(s, path, value)
        stored = get_value(s, path)
        assert stored == value or (value is None and stored is None), path
        if info.kind == "float" and value is not None:
            assert type(stored) is float, path
    assert Settings.from_dict(s.to_dict()) == s


@given(data=st.data())
def test_invalid_values_raise_value_error_naming_the_path(data):
    s = Settings()
    for path, info in FIELDS.items():
        value = data.draw(INVALID[path], label=path)
        before = get_value(s, path)
        with pytest.raises(ValueError) as exc:
            set_value(s, path, value)
        msg = str(exc.value)
        assert path in msg and info.allowed() in msg and len(msg) < MAX_MESSAGE, msg
        assert isinstance(exc.value, SettingsError) and exc.value.field_path == path
        assert get_value(s, path) == before  # nothing stored


@given(data=st.data())
def test_constructors_and_from_dict_refuse_what_set_value_refuses(data):
    for path in FIELDS:
        value = data.draw(INVALID[path], label=path)
        sec, key = path.split(".")
        for enter in (lambda: Settings.section_types()[sec](**{key: value}),  # noqa: B023 (called at once)
                      lambda: Settings.from_dict({sec: {key: value}})):  # noqa: B023
            with pytest.raises(SettingsError) as exc:
                enter()
            assert exc.value.field_path == path and len(str(exc.value)) < MAX_MESSAGE


# --- scenario files --------------------------------------------------------------------------------------


def settings_dicts(valid=True) -> st.SearchStrategy:
    """Nested {section: {key: value}} dicts over random subsets of the fields (valid, or valid-looking)."""
    sections: dict[str, list[FieldInfo]] = {}
    for info in FIELDS.values():
        sections.setdefault(info.path.split(".")[0], []).append(info)
    return st.fixed_dictionaries({}, optional={
        sec: st.fixed_dictionaries({}, optional={i.path.split(".")[1]: valid_values(i) for i in infos})
        for sec, infos in sections.items()})


@given(data=settings_dicts())
def test_valid_settings_survive_toml_exactly(tmp_path_factory, data):
    settings = Settings.from_dict(data)
    path = tmp_path_factory.mktemp("round") / "s.toml"
    path.write_text(to_toml(settings, title="property test"), encoding="utf-8")
    back = load_scenario(path)
    assert back == settings and to_toml(back) == to_toml(settings)
    for sec, values in data.items():
        for key, value in values.items():
            assert get_value(back, f"{sec}.{key}") == value


def toml_value(value) -> str:
    """A TOML rendering of a JSON-like value (floats may be nan/inf; strings and keys are JSON-quoted)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, int | str):
        return str(value) if isinstance(value, int) else json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


KEYS = st.sampled_from(sorted({p.split(".")[1] for p in FIELDS})) | st.text(max_size=12)
SECTIONS = st.sampled_from(sorted({p.split(".")[0] for p in FIELDS})) | st.text(max_size=12)
LEAVES = (st.booleans() | st.integers() | st.floats() | st.text(max_size=20)
          | st.sampled_from(["heavy", "auto", "driver", 10**400, -(10**30)]))
VALUES = st.recursive(LEAVES, lambda inner: st.lists(inner, max_size=3)
                      | st.dictionaries(st.text(max_size=5), inner, max_size=3), max_leaves=8)
TOML_DOCS = st.dictionaries(SECTIONS, st.dictionaries(KEYS, VALUES, max_size=4), max_size=4).map(
    lambda doc: "\n".join(f"[{json.dumps(sec)}]\n" + "\n".join(f"{json.dumps(k)} = {toml_value(v)}"
                                                                for k, v in table.items())
                          for sec, table in doc.items()) + "\n")


def assert_loads_or_value_error(path) -> None:
    try:
        result = load_scenario(path)
    except ValueError as exc:
        msg = str(exc)
        assert str(path) in msg and len(msg) < MAX_MESSAGE + len(str(path)), msg
    else:
        result.validate()


@given(text=TOML_DOCS)
@example(text='[rain]\nrate_mm_h = ' + "[" * 1000 + "]" * 1000 + "\n")  # deeper cases: tests/test_settings.py
@example(text='[rain]\nrate_mm_h = "' + "x" * 100_000 + '"\n')
@example(text="[rain]\nrate_mm_h = 1" + "0" * 400 + "\n")
def test_structured_junk_is_a_value_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("junk") / "j.toml"
    path.write_text(text, encoding="utf-8")
    assert_loads_or_value_error(path)


@given(raw=st.binary(max_size=200) | st.text(max_size=200).map(lambda t: t.encode("utf-8", "surrogatepass")),
       prefix=st.sampled_from([b"", b"\xef\xbb\xbf", b"[rain]\n", b"\xef\xbb\xbf[rain]\nrate_mm_h = "]))
@example(raw=b"\xff\xfe[rain]", prefix=b"")
@example(raw=b"\xef\xbb\xbf\xef\xbb\xbf", prefix=b"")
def test_random_bytes_are_a_value_error(tmp_path_factory, raw, prefix):
    path = tmp_path_factory.mktemp("bytes") / "b.toml"
    path.write_bytes(prefix + raw)
    assert_loads_or_value_error(path)


@given(data=settings_dicts(), cut=st.integers(0, 10_000), insert=st.text(max_size=5))
def test_mutated_valid_files_load_or_are_value_errors(tmp_path_factory, data, cut, insert):
    text = to_toml(Settings.from_dict(data))
    cut %= len(text)
    path = tmp_path_factory.mktemp("mut") / "m.toml"
    path.write_bytes((text[:cut] + insert + text[cut + 1:]).encode("utf-8", "surrogatepass"))
    assert_loads_or_value_error(path)
