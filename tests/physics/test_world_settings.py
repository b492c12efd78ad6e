"""Each world setting has one default (WorldSettings) and one range (WORLD_RANGES): the
scene's World block, both backends and the CLI read them from there."""

from __future__ import annotations

import math

import pytest

from engine.app import EngineConfig
from engine.physics.backend import WORLD_RANGES, Range, WorldSettings
from engine.physics.ode3d import OdeBackend
from engine.physics.pymunk2d import PymunkBackend
from engine.scene import schema


def test_a_range_says_what_it_holds_and_refuses_what_is_not_a_number() -> None:
    warm = Range(0.0, 0.99)
    assert 0.0 in warm and 0.99 in warm and 0.995 not in warm and -1e-9 not in warm
    assert warm.text() == "from 0 to 0.99"
    positive = Range(0.0, low_open=True)
    assert 0.0 not in positive and 1e-300 in positive and positive.text() == "more than 0"
    assert math.nan not in Range() and math.inf not in Range(0.0)
    assert Range(1).text() == "at least 1"


def test_every_default_lies_in_its_range_and_the_scene_defaults_are_the_settings() -> None:
    defaults = WorldSettings()
    assert defaults.problems() == []
    for name in WORLD_RANGES:
        assert hasattr(defaults, name), name
    world = schema.SCHEMAS["World"]
    for key, name in (("Gravity", "gravity"), ("ERP", "erp"), ("CFM", "cfm"),
                      ("Iterations", "iterations"), ("MaxContacts", "max_contacts"),
                      ("WarmStart", "warm_start"), ("ContactSoftness", "contact_softness"),
                      ("ExactRows", "exact_rows"), ("SleepTime", "sleep_time"),
                      ("SleepLinear", "sleep_linear"), ("Extent", "extent")):
        assert world[key].default == getattr(defaults, name), key


@pytest.mark.parametrize("backend", [OdeBackend, PymunkBackend])
@pytest.mark.parametrize(("name", "value"), [("iterations", 0), ("warm_start", 0.995),
                                             ("erp", -0.1), ("sleep_time", 0.0)])
def test_both_backends_refuse_a_setting_outside_its_range(backend, name, value) -> None:
    settings = WorldSettings(**{name: value})
    engine = backend()
    try:
        with pytest.raises(ValueError, match=f"{name} must be {WORLD_RANGES[name].text()}"):
            engine.configure(settings)
    finally:
        engine.close()


def test_the_command_line_s_engine_defaults_are_engine_config_s() -> None:
    from app.cli import build_parser

    args = build_parser().parse_args(["run"])
    config = EngineConfig()
    for name in ("mode", "seed", "substeps", "early", "late", "max_dt", "sound"):
        assert getattr(args, name) == getattr(config, name), name
