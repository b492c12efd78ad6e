"""Render backends by name: ``headless`` (an EGL standalone context drawing into an offscreen
framebuffer; Mesa llvmpipe on machines without a GPU) and ``window`` (moderngl-window with
pyglet or glfw, imported only when a display exists). ``auto`` picks the window when there is a
display and headless otherwise.
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys
from typing import Any, Protocol

BACKENDS = ("auto", "headless", "window")
#: moderngl-window's mouse button numbers -> names.
MOUSE_BUTTONS = {1: "left", 2: "right", 3: "middle"}


class InputSink(Protocol):
    """Where a window's keyboard and mouse go (the input layer's window device)."""

    def key(self, name: str, pressed: bool) -> None: ...

    def pointer(self, x: float, y: float) -> None: ...

    def scroll(self, notches: float) -> None: ...

    def mouse_button(self, name: str, pressed: bool) -> None: ...


@functools.cache
def libgl() -> Any:
    """The GL library, for the few calls moderngl does not make (an instance divisor, an
    external depth attachment, a scaled blit): GLVND dispatches them to the current
    context, EGL or GLX."""
    return ctypes.CDLL("libGL.so.1")


class RenderBackendError(RuntimeError):
    """A render backend that cannot start, with the reason and what to try instead."""


def has_display() -> bool:
    """True when a window can be opened (an X or Wayland display, or a desktop OS)."""
    if sys.platform in ("win32", "darwin"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


class HeadlessTarget:
    """An EGL standalone context and an offscreen framebuffer of ``size``."""

    kind = "headless"

    def __init__(self, size: tuple[int, int], ctx: Any = None) -> None:
        import moderngl

        self._owns_ctx = ctx is None
        if ctx is None:
            try:
                ctx = moderngl.create_context(standalone=True, backend="egl", require=330)
            except Exception as exc:  # glcontext raises plain Exceptions with the EGL reason
                raise RenderBackendError(
                    f"headless EGL context failed: {exc}. Install Mesa's EGL (libegl1, "
                    "libegl-mesa0, libgl1-mesa-dri; `tools/dev setup` does), or run on a "
                    "display without --headless to draw in a window") from exc
        self.ctx = ctx
        self.size = (int(size[0]), int(size[1]))
        self.fbo = self._framebuffer(self.size)
        #: Never called: a headless target has no keyboard or mouse.
        self.input: InputSink | None = None

    def _framebuffer(self, size: tuple[int, int]) -> Any:
        return self.ctx.framebuffer(color_attachments=[self.ctx.renderbuffer(size, 4)],
                                    depth_attachment=self.ctx.depth_renderbuffer(size))

    @property
    def renderer_name(self) -> str:
        return str(self.ctx.info.get("GL_RENDERER", "?"))

    @property
    def is_closing(self) -> bool:
        return False

    def resize(self, size: tuple[int, int]) -> None:
        if tuple(size) != self.size:
            self.fbo.release()
            self.size = (int(size[0]), int(size[1]))
            self.fbo = self._framebuffer(self.size)

    def present(self) -> None:
        """Nothing to show: the frame stays in :attr:`fbo` for screenshots."""

    def close(self) -> None:
        self.fbo.release()
        if self._owns_ctx:
            self.ctx.release()


class WindowTarget:
    """A moderngl-window window (pyglet, or glfw when pyglet is missing)."""

    kind = "window"

    def __init__(self, size: tuple[int, int], title: str = "Colosseum",
                 window_library: str | None = None) -> None:
        if not has_display():
            raise RenderBackendError("no display (DISPLAY/WAYLAND_DISPLAY unset): "
                                     "use --headless")
        import moderngl_window

        errors = []
        window = None
        for name in ([window_library] if window_library else ["pyglet", "glfw"]):
            try:
                cls = moderngl_window.get_local_window_cls(name)
                window = cls(size=tuple(size), title=title, gl_version=(3, 3), vsync=False,
                             resizable=True)
                break
            except Exception as exc:  # import or window-system errors differ per library
                errors.append(f"{name}: {exc}")
        if window is None:
            raise RenderBackendError("cannot open a window: " + "; ".join(errors))
        moderngl_window.activate_context(window=window)
        self.window = window
        self.ctx = window.ctx
        self.input: InputSink | None = None
        keys = window.keys
        #: window-library key code -> engine key name ("f1", "a", "space", "up"...)
        self.key_names = {getattr(keys, n): n.lower() for n in dir(keys)
                           if n.isupper() and not n.startswith("ACTION_")}
        window.key_event_func = self._on_key
        window.mouse_position_event_func = self._on_move
        window.mouse_drag_event_func = self._on_move
        window.mouse_press_event_func = lambda x, y, b: self._on_button(b, True)
        window.mouse_release_event_func = lambda x, y, b: self._on_button(b, False)
        window.mouse_scroll_event_func = self._on_scroll

    def _on_key(self, key: Any, action: Any, modifiers: Any) -> None:
        if self.input is not None:
            self.input.key(self.key_names.get(key, str(key)),
                           action == self.window.keys.ACTION_PRESS)

    def _on_move(self, x: int, y: int, dx: int, dy: int) -> None:
        if self.input is not None:
            width, height = self.window.size
            self.input.pointer(x / max(width, 1), y / max(height, 1))

    def _on_button(self, button: int, pressed: bool) -> None:
        if self.input is not None:
            self.input.mouse_button(MOUSE_BUTTONS.get(button, str(button)), pressed)

    def _on_scroll(self, x_offset: float, y_offset: float) -> None:
        if self.input is not None:
            self.input.scroll(y_offset)

    @property
    def size(self) -> tuple[int, int]:
        return tuple(self.window.buffer_size)  # type: ignore[return-value]

    @property
    def fbo(self) -> Any:
        return self.ctx.screen

    @property
    def renderer_name(self) -> str:
        return str(self.ctx.info.get("GL_RENDERER", "?"))

    @property
    def is_closing(self) -> bool:
        return bool(self.window.is_closing)

    def resize(self, size: tuple[int, int]) -> None:
        """The window owns its size; the user resizes it."""

    def present(self) -> None:
        self.window.swap_buffers()

    def close(self) -> None:
        self.window.destroy()


def create_target(backend: str = "auto", size: tuple[int, int] = (1280, 720),
                  title: str = "Colosseum") -> HeadlessTarget | WindowTarget:
    """Open the named backend (``auto``, ``headless`` or ``window``)."""
    if backend not in BACKENDS:
        raise RenderBackendError(f"unknown render backend {backend!r}; "
                                 f"choose one of {', '.join(BACKENDS)}")
    if backend == "window" or (backend == "auto" and has_display()):
        return WindowTarget(size, title)
    return HeadlessTarget(size)
