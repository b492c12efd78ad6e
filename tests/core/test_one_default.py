"""A setting has one default: the scene's blocks and the settings their plugins read agree
because one reads the other (the World block's are in tests/physics/test_world_settings.py)."""

from __future__ import annotations

from engine.experiments.design import Design
from engine.experiments.scene import EXPERIMENT_BLOCK
from engine.scene.schema import SCHEMAS
from systems.session import SessionSettings


def test_an_experiment_block_s_defaults_are_the_design_s() -> None:
    keys, design = {k.name: k for k in EXPERIMENT_BLOCK.keys}, Design("")
    for key, name in (("Order", "order"), ("Blocks", "blocks"), ("Repeats", "repeats"),
                      ("Practice", "practice"), ("Timeout", "timeout"), ("Reset", "reset"),
                      ("EndOn", "end_on"), ("Seed", "seed"), ("TrackCamera", "track_camera"),
                      ("TrackRate", "track_rate"), ("Break", "pause")):
        assert keys[key].default == getattr(design, name), key


def test_a_session_without_a_block_has_the_block_s_defaults() -> None:
    keys, settings = SCHEMAS["Session"], SessionSettings()
    assert (settings.folder, settings.name, settings.chair, settings.pose_rate,
            settings.ground, settings.end_run) == (
        keys["Folder"].default, keys["Name"].default, keys["Chair"].default,
        keys["PoseRate"].default, tuple(keys["Ground"].default), bool(keys["EndRun"].default))
