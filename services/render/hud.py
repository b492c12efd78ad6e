"""The HUD: one line of text drawn over the frame: the run's figures (fps, physics ms,
real-time factor) when switched on, and a status line content sets (task progress:
Lua's ``emit("hud", text)``), shown whenever it is not empty.

Text is rasterised with pillow into a texture only when it changes, so the HUD costs one
small quad per frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from services.render import glsl


def hud_line(fps: float, physics_ms: float, real_time_factor: float) -> str:
    """The HUD text the engine shows; the rate is "--" until two frames were drawn (a
    headless run draws only the frame it saves).

    >>> hud_line(0.0, 0.5, 1.0)
    '   -- fps | physics   0.50 ms | real-time x1.00'
    """
    rate = f"{fps:5.1f}" if fps > 0.0 else "   --"
    return f"{rate} fps | physics {physics_ms:6.2f} ms | real-time x{real_time_factor:4.2f}"


def text_image(text: str, font_size: int = 14) -> np.ndarray:
    """RGBA pixels of white text on a translucent dark box, rows top to bottom."""
    from PIL import Image, ImageDraw, ImageFont

    try:
        font = ImageFont.load_default(font_size)
    except TypeError:  # pillow without FreeType sizes
        font = ImageFont.load_default()
    left, top, right, bottom = font.getbbox(text or " ")
    pad = 4
    img = Image.new("RGBA", (right - left + 2 * pad, bottom - top + 2 * pad), (0, 0, 0, 150))
    ImageDraw.Draw(img).text((pad - left, pad - top), text, font=font, fill=(255, 255, 255, 255))
    return np.asarray(img, dtype=np.uint8)


class Hud:
    """Draws :attr:`text` (when :attr:`enabled`) and :attr:`status` at the top-left of a
    framebuffer."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.enabled = False
        self.text = ""
        self.status = ""
        self._drawn_text: str | None = None
        self._texture: Any = None
        self._program = ctx.program(vertex_shader=glsl.HUD_VERTEX,
                                    fragment_shader=glsl.HUD_FRAGMENT)
        self._vao = ctx.vertex_array(self._program, [])

    def toggle(self) -> None:
        self.enabled = not self.enabled

    def draw(self, fbo: Any, size: tuple[int, int]) -> bool:
        """Draw the line into ``fbo`` (of ``size``); whether there was one to draw."""
        shown = " | ".join(t for t in (self.text if self.enabled else "", self.status) if t)
        if not shown:
            return False
        if self._drawn_text != shown:
            pixels = text_image(shown)
            if self._texture is not None:
                self._texture.release()
            h, w = pixels.shape[:2]
            self._texture = self.ctx.texture((w, h), 4, np.ascontiguousarray(pixels).tobytes())
            self._drawn_text = shown
        w, h = self._texture.size
        x0, y1 = -1.0 + 8.0 / size[0] * 2, 1.0 - 8.0 / size[1] * 2
        x1, y0 = x0 + 2.0 * w / size[0], y1 - 2.0 * h / size[1]
        fbo.use()
        fbo.viewport = (0, 0, *size)
        self._program["u_rect"].value = (x0, y0, x1, y1)
        self._texture.use(0)
        self.ctx.enable(self.ctx.BLEND)
        self.ctx.blend_func = self.ctx.SRC_ALPHA, self.ctx.ONE_MINUS_SRC_ALPHA
        self.ctx.disable(self.ctx.DEPTH_TEST)
        self._vao.render(vertices=6)
        self.ctx.disable(self.ctx.BLEND)
        return True

    def release(self) -> None:
        if self._texture is not None:
            self._texture.release()
        self._vao.release()
        self._program.release()
