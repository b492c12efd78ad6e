"""Render test fixtures: one headless EGL context for the whole session, small renderers."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from render_helpers import CONTENT, H, W

from services.render import CameraView, HeadlessTarget, LightInfo, Renderer


@pytest.fixture(scope="session")
def gl_ctx() -> object:
    import moderngl

    ctx = moderngl.create_context(standalone=True, backend="egl", require=330)
    yield ctx
    ctx.release()


@pytest.fixture
def make_renderer(gl_ctx: object) -> Iterator[Callable[..., Renderer]]:
    made: list[Renderer] = []

    def make(size: tuple[int, int] = (W, H), root: Path = CONTENT, **kw: object) -> Renderer:
        renderer = Renderer(HeadlessTarget(size, ctx=gl_ctx), root=root, **kw)
        renderer.camera = CameraView.looking_at((0.0, -6.0, 3.0), (0.0, 0.0, 0.5))
        renderer.lights = [LightInfo("directional", direction=(-0.2, 0.3, -1.0))]
        made.append(renderer)
        return renderer

    yield make
    for renderer in made:
        renderer.release()
        renderer.target.close()
