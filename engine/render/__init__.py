"""moderngl renderer: headless EGL or a window, instanced meshes, shadows, user shader states,
post-processing, HUD and screenshots. See :class:`engine.render.renderer.Renderer`."""

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
