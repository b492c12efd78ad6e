"""The HUD's status line: content sets it (Lua's emit("hud", text)); it shows whether or
not the figures line is on, and goes when emptied."""

from __future__ import annotations

from render_helpers import floor

from components import Shape, Visual
from engine import EngineConfig
from engine.events import CustomEvent
from systems import create_engine
from systems.render import RenderSystem


def test_the_status_line_shows_without_the_figures(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    floor(r)
    r.render()
    assert r.read_pixels()[:20, :80].max() == 0
    r.hud.status = "breakfast 3/5 | swept 40/200"
    r.render()
    assert r.read_pixels()[:20, :80].max() > 200  # white text in the top-left corner
    r.hud.status = ""
    r.render()
    assert r.read_pixels()[:20, :80].max() == 0


def test_lua_sets_the_status_line_through_an_event():
    config = EngineConfig(backend="ballistic", fast=True, render=True,
                          options={"size": "160x120"})
    with create_engine(config) as engine:
        engine.spawn(Visual(shapes=[Shape("box", (1, 1, 1))]))
        engine.run(frames=1)
        engine.events.emit(CustomEvent("hud", "swept 12/200"))
        engine.run(frames=1)
        assert engine.resource(RenderSystem).renderer.hud.status == "swept 12/200"
