"""The current OpenGL context's native handles, which an OpenXR graphics binding names.

moderngl makes the context (EGL standalone, or a window's GLX one) but keeps its handles
to itself; EGL and GLX both say which context, display and surface are current, and
which configuration a context was made with, so they are asked here through ctypes.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Any

EGL_CONFIG_ID = 0x3028
EGL_NONE = 0x3038
GLX_FBCONFIG_ID = 0x8013


class BindingError(RuntimeError):
    """The context's handles cannot be found (no EGL or GLX, or no current context)."""


@dataclass(slots=True)
class EglHandles:
    display: int
    config: int
    context: int
    get_proc_address: Any  # eglGetProcAddress, as a C function pointer


@dataclass(slots=True)
class GlxHandles:
    x_display: int
    visual_id: int
    fb_config: int
    drawable: int
    context: int


def _library(name: str) -> Any:
    try:
        return ctypes.CDLL(name)
    except OSError as exc:
        raise BindingError(f"{name} cannot be loaded: {exc}") from exc


def current_egl() -> EglHandles:
    """The current EGL context's display, configuration and context."""
    egl = _library("libEGL.so.1")
    for fn in ("eglGetCurrentDisplay", "eglGetCurrentContext"):
        getattr(egl, fn).restype = ctypes.c_void_p
    egl.eglQueryContext.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                    ctypes.POINTER(ctypes.c_int)]
    egl.eglChooseConfig.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int),
                                    ctypes.POINTER(ctypes.c_void_p), ctypes.c_int,
                                    ctypes.POINTER(ctypes.c_int)]
    display, context = egl.eglGetCurrentDisplay(), egl.eglGetCurrentContext()
    if not display or not context:
        raise BindingError("no EGL context is current")
    config_id = ctypes.c_int()
    if not egl.eglQueryContext(display, context, EGL_CONFIG_ID, ctypes.byref(config_id)):
        raise BindingError("eglQueryContext(EGL_CONFIG_ID) failed")
    attributes = (ctypes.c_int * 3)(EGL_CONFIG_ID, config_id.value, EGL_NONE)
    config, found = ctypes.c_void_p(), ctypes.c_int()
    if not egl.eglChooseConfig(display, attributes, ctypes.byref(config), 1,
                               ctypes.byref(found)) or found.value < 1:
        raise BindingError(f"no EGL config with ID {config_id.value}")
    proc = ctypes.cast(egl.eglGetProcAddress, ctypes.c_void_p).value
    return EglHandles(display, config.value or 0, context, proc)


def current_glx() -> GlxHandles:
    """The current GLX context's X display, visual, FB configuration, drawable and
    context."""
    glx = _library("libGL.so.1")
    x11 = _library("libX11.so.6")
    for fn in ("glXGetCurrentDisplay", "glXGetCurrentContext"):
        getattr(glx, fn).restype = ctypes.c_void_p
    glx.glXGetCurrentDrawable.restype = ctypes.c_ulong
    glx.glXQueryContext.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                    ctypes.POINTER(ctypes.c_int)]
    glx.glXGetFBConfigs.restype = ctypes.POINTER(ctypes.c_void_p)
    glx.glXGetFBConfigs.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_int)]
    glx.glXGetFBConfigAttrib.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                         ctypes.POINTER(ctypes.c_int)]
    x11.XDefaultScreen.argtypes = [ctypes.c_void_p]
    display, context = glx.glXGetCurrentDisplay(), glx.glXGetCurrentContext()
    if not display or not context:
        raise BindingError("no GLX context is current")
    fb_id = ctypes.c_int()
    glx.glXQueryContext(display, context, GLX_FBCONFIG_ID, ctypes.byref(fb_id))
    count = ctypes.c_int()
    # Mesa's glXChooseFBConfig finds no config by its ID, so the configs are searched
    configs = glx.glXGetFBConfigs(display, x11.XDefaultScreen(display), ctypes.byref(count))
    found = None
    for i in range(count.value if configs else 0):
        value = ctypes.c_int()
        glx.glXGetFBConfigAttrib(display, configs[i], GLX_FBCONFIG_ID, ctypes.byref(value))
        if value.value == fb_id.value:
            found = configs[i]
            break
    if found is None:
        raise BindingError(f"no GLX FB config with ID {fb_id.value}")
    visual = ctypes.c_int()
    glx.glXGetFBConfigAttrib(display, found, 0x800B, ctypes.byref(visual))  # GLX_VISUAL_ID
    return GlxHandles(display, visual.value, found, glx.glXGetCurrentDrawable(), context)
