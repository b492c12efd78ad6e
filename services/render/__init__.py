"""moderngl renderer: headless EGL or a window, instanced meshes, shadows, user shader states,
post-processing, HUD and screenshots. See :class:`services.render.renderer.Renderer`.

Its names load on first use (:mod:`engine.lazy`): a module that needs :mod:`services.render.math3d`
alone (avatars, the headset's projection) does not load the renderer's modules with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from services.render.camera import CameraView, camera_from_component
    from services.render.context import (
        BACKENDS,
        HeadlessTarget,
        RenderBackendError,
        WindowTarget,
        create_target,
        has_display,
    )
    from services.render.lights import LightInfo, light_from_component
    from services.render.meshes import ModelError
    from services.render.postprocess import PostPass, PostProcessing
    from services.render.renderer import FrameStats, Renderer
    from services.render.shaders import (
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
    "services.render.camera": ("CameraView", "camera_from_component"),
    "services.render.context": ("BACKENDS", "HeadlessTarget", "RenderBackendError", "WindowTarget",
                              "create_target", "has_display"),
    "services.render.lights": ("LightInfo", "light_from_component"),
    "services.render.meshes": ("ModelError",),
    "services.render.postprocess": ("PostPass", "PostProcessing"),
    "services.render.renderer": ("FrameStats", "Renderer"),
    "services.render.shaders": ("FragmentShader", "ShaderError", "ShaderLibrary", "ShaderProgram",
                              "ShaderState", "Uniform", "VertexShader")})
