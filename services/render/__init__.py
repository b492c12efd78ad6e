"""moderngl renderer: headless EGL or a window, instanced meshes, shadows, user shader states,
post-processing, HUD and screenshots. See :class:`services.render.renderer.Renderer`."""

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
