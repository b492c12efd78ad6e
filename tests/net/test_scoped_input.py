"""A user's input on the server: sources named USER/source, calibrated as the scene
calibrates ``source``, and bound by controllers as ``tracker:USER/source``."""

from __future__ import annotations

import pytest

from engine.scene.inputs import ButtonSpec, InputSpec, TrackerSpec
from services.input import InputHub, parse_binding
from services.input.events import Button, TrackerPose


def test_a_users_tracker_is_calibrated_as_the_scene_says_for_its_own_name() -> None:
    spec = InputSpec(trackers=(TrackerSpec("hand_r", offset=(0.0, 0.0, 1.0), scale=0.01),),
                     buttons=(ButtonSpec("grip", "glove_r", "index", invert=True),))
    hub = InputHub(spec, [])
    hub.inject(TrackerPose("alice/hand_r", (100.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0),
                           timestamp=1.0))
    hub.inject(TrackerPose("hand_r", (100.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), timestamp=1.0))
    hub.inject(Button("alice/glove_r", "index", True, 1.0))
    hub.step(0)
    alice, local = hub.state.tracker("alice/hand_r"), hub.state.tracker("hand_r")
    assert alice is not None and local is not None
    assert list(alice.position) == pytest.approx([1.0, 0.0, 1.0])  # scaled, then offset
    assert list(alice.position) == pytest.approx(list(local.position))
    assert hub.state.buttons[("alice/glove_r", "index")] is False  # inverted like glove_r


@pytest.mark.parametrize(("text", "parts"), [
    ("tracker:alice/hand_r", ("alice/hand_r",)), ("wheel:bob/left", ("bob/left",)),
    ("button:alice/glove_r/index", ("alice/glove_r", "index")),
    ("axis:bob/pad/x", ("bob/pad", "x")), ("tracker:hand_r", ("hand_r",)),
    ("button:start", ("start",))])
def test_bindings_name_a_users_sources(text: str, parts: tuple[str, ...]) -> None:
    assert parse_binding(text).parts == parts
