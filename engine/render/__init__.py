"""moderngl renderer: headless EGL or a window, instanced meshes, shadows, user shader states,
post-processing, HUD and screenshots. See :class:`engine.render.renderer.Renderer`.

Its names load on first use (:mod:`engine.lazy`): a module that needs :mod:`engine.render.math3d`
alone (avatars, the headset's projection) does not load the renderer's modules with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from engine.render.camera import CameraView, camera_from_component
    from engine.render.context import (
        BACKENDS,
        HeadlessTarget,
        RenderBackendError,
        WindowTarget,
        create_target,
        has_display,
    )
    from engine.render.lights import LightInfo, light_from_component
    from engine.render.meshes import ModelError
    from engine.render.postprocess import PostPass, PostProcessing
    from engine.render.renderer import FrameStats, Renderer
    from engine.render.shaders import (
        FragmentShader,
        ShaderError,
        ShaderLibrary,
        ShaderProgram,
        ShaderState,
        Uniform,
        VertexShader,
    )

__all__ = [
    "BACKENDS",
    "CameraView",
    "FragmentShader",
    "FrameStats",
    "HeadlessTarget",
    "LightInfo",
    "ModelError",
    "PostPass",
    "PostProcessing",
    "RenderBackendError",
    "Renderer",
    "ShaderError",
    "ShaderLibrary",
    "ShaderProgram",
    "ShaderState",
    "Uniform",
    "VertexShader",
    "WindowTarget",
    "camera_from_component",
    "create_target",
    "has_display",
    "light_from_component",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    "engine.render.camera": ("CameraView", "camera_from_component"),
    "engine.render.context": ("BACKENDS", "HeadlessTarget", "RenderBackendError", "WindowTarget",
                              "create_target", "has_display"),
    "engine.render.lights": ("LightInfo", "light_from_component"),
    "engine.render.meshes": ("ModelError",),
    "engine.render.postprocess": ("PostPass", "PostProcessing"),
    "engine.render.renderer": ("FrameStats", "Renderer"),
    "engine.render.shaders": ("FragmentShader", "ShaderError", "ShaderLibrary", "ShaderProgram",
                              "ShaderState", "Uniform", "VertexShader")})
