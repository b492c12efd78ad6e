"""The anomaly vocabulary and a run's anomaly state: one definition behind the schema, the
checks and the docs; onsets that ramp; switches told as events; values clamped with a say."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.anomalies import (
    ANOMALIES,
    ONSET_MAX,
    Anomalies,
    check_onset,
    check_value,
    table_markdown,
)
from engine.events import AnomalySwitched
from engine.scene import schema as sc

ROOT = Path(__file__).resolve().parents[2]


def test_the_schema_is_made_from_the_vocabulary():
    for kind in ANOMALIES.values():
        fields = sc.SCHEMAS[kind.block]
        assert sc.SCHEMAS["Scene"][kind.block].struct == kind.block
        for p in kind.params:
            assert fields[p.key].default == p.default
            assert p.range_text() in fields[p.key].doc
            if p.choices:
                assert fields[p.key].allowed == p.choices
        assert {"ID", "Enabled", "Onset", "Eye", "Input"} <= set(fields)


def test_every_parameter_has_a_default_in_range_and_a_neutral_value_that_is_too():
    for kind in ANOMALIES.values():
        for p in kind.params:
            assert check_value(kind, p.key, p.default) == (p.default, None)
            if p.neutral is not None:
                assert check_value(kind, p.key, p.neutral)[1] is None


def test_the_anomalies_page_and_keys_show_the_generated_table():
    table = table_markdown()
    assert table in (ROOT / "docs" / "howto" / "anomalies.md").read_text(encoding="utf-8")
    for kind in ANOMALIES.values():
        assert f"`{kind.block}`" in table
        for p in kind.params:
            assert f"`{p.key}`" in table


@pytest.mark.parametrize("kind,key,value,clamped", [
    ("double_vision", "Mix", 1.5, 1.0),
    ("double_vision", "Offset", [3, -50], (3.0, -20.0)),
    ("hemianopia", "Sparing", -2, 0.0),
    ("blur", "Motion", 1.0, 0.95),
])
def test_out_of_range_values_are_clamped_and_said(kind, key, value, clamped):
    result, problem = check_value(ANOMALIES[kind], key, value)
    assert result == clamped
    assert "out of range" in problem and "clamped" in problem and key in problem


def test_unreadable_values_fall_back_to_the_default_and_unknown_keys_are_refused():
    kind = ANOMALIES["hemianopia"]
    assert check_value(kind, "Side", "up") == ("left", check_value(kind, "Side", "up")[1])
    assert "must be" in check_value(kind, "Side", "up")[1]
    assert check_value(kind, "Fill", [1, 2])[0] == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="did you mean 'Sparing'"):
        check_value(kind, "Sparring", 2)
    assert check_onset(-3) == (0.0, check_onset(-3)[1]) and "clamped" in check_onset(-3)[1]
    assert check_onset(1e9)[0] == ONSET_MAX


@pytest.mark.parametrize("onset,dt", [(2.0, 1 / 60), (0.5, 0.01), (3.0, 0.1)])
def test_onset_ramps_every_parameter_monotonically_over_its_time(onset, dt):
    anomalies = Anomalies()
    anomalies.declare("double_vision", {"Offset": (4.0, -2.0), "Mix": 0.6}, onset=onset)
    anomalies.switch("double_vision", True, "test")
    mixes, offsets = [], []
    steps = int(round(onset / dt))
    for _ in range(steps + 5):
        anomalies.step(dt)
        values = anomalies.active()[0].values
        mixes.append(values["Mix"])
        offsets.append(values["Offset"][0])
    assert np.all(np.diff(mixes) >= 0) and np.all(np.diff(offsets) >= 0)
    assert mixes[steps // 2] == pytest.approx(0.3, abs=0.6 * 3 / steps + 1e-9)  # halfway
    assert mixes[steps - 2] < 0.6 and mixes[-1] == 0.6 and offsets[-1] == 4.0
    anomalies.switch("double_vision", False, "test")  # and out again over the same time
    fading = []
    for _ in range(steps + 5):
        anomalies.step(dt)
        fading.append(anomalies.active()[0].values["Mix"] if anomalies.active() else 0.0)
    assert np.all(np.diff(fading) <= 0) and fading[steps - 2] > 0 and fading[-1] == 0.0
    assert anomalies.active() == []  # ramped out: nothing to draw


def test_switches_and_changes_are_told_once_each():
    told: list[AnomalySwitched] = []
    anomalies = Anomalies(emit=told.append)
    anomalies.switch("hemianopia", True, "lua:x.lua:3")
    anomalies.switch("hemianopia", True, "lua:x.lua:4")  # already on: nothing to tell
    problems = anomalies.set("hemianopia", "python", values={"sparing": 30, "side": "right"})
    anomalies.switch("hemianopia", False, "input:key:f2")
    assert [(e.enabled, e.source) for e in told] == [
        (True, "lua:x.lua:3"), (True, "python"), (False, "input:key:f2")]
    assert dict(told[1].severity)["Sparing"] == 15.0 and dict(told[1].severity)["Side"] == \
        "right"
    assert len(problems) == 1 and "Sparing 30" in problems[0]
    with pytest.raises(KeyError, match="did you mean 'neglect'"):
        anomalies.switch("neglet", True, "test")


def test_two_blocks_of_one_kind_are_two_anomalies_drawn_in_the_vocabulary_order():
    anomalies = Anomalies()
    anomalies.declare("hemianopia", enabled=True)
    anomalies.declare("right eye", {"Offset": (1.0, 0.0)}, kind="double_vision",
                      enabled=True, eye="right")
    anomalies.declare("left eye", {"Offset": (-1.0, 0.0)}, kind="double_vision",
                      enabled=True, eye="left")
    active = anomalies.active()
    assert [(a.id, a.kind, a.eye) for a in active] == [
        ("right eye", "double_vision", "right"), ("left eye", "double_vision", "left"),
        ("hemianopia", "hemianopia", "both")]
