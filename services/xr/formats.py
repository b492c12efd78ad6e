"""Which swapchain formats to ask the runtime for, and how colours reach them.

The engine's colours are display values (what a window shows as they are: sRGB-encoded).
A runtime reads an sRGB swapchain's bytes as sRGB-encoded and a linear (UNORM, float)
one's as linear light. So the engine writes its values unchanged into an sRGB image
(with ``GL_FRAMEBUFFER_SRGB`` off, so GL does not encode them a second time) and decodes
them to linear light for a linear image; either way the headset shows what the window
does. An sRGB format is preferred (8 bits of linear light band in the dark); among
formats alike, the runtime's order (its preference) decides.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The OpenGL internal formats the engine can draw colour into: GL enum -> (name, sRGB).
COLOR_FORMATS: dict[int, tuple[str, bool]] = {
    0x8C43: ("GL_SRGB8_ALPHA8", True),
    0x8C41: ("GL_SRGB8", True),
    0x8058: ("GL_RGBA8", False),
    0x8051: ("GL_RGB8", False),
    0x8059: ("GL_RGB10_A2", False),
    0x881A: ("GL_RGBA16F", False),
    0x8814: ("GL_RGBA32F", False),
}
#: Depth formats, GL enum -> name; a 24-bit or float depth is preferred over 16 bits.
DEPTH_FORMATS: dict[int, str] = {
    0x8CAC: "GL_DEPTH_COMPONENT32F",
    0x81A6: "GL_DEPTH_COMPONENT24",
    0x88F0: "GL_DEPTH24_STENCIL8",
    0x8CAD: "GL_DEPTH32F_STENCIL8",
    0x81A5: "GL_DEPTH_COMPONENT16",
}


class FormatError(RuntimeError):
    """The runtime offers no format the engine can draw into."""


@dataclass(frozen=True, slots=True)
class SwapchainFormat:
    gl_format: int
    name: str
    srgb: bool

    @property
    def decode(self) -> bool:
        """Whether colours are decoded to linear light on their way in (a linear image)."""
        return not self.srgb


def format_name(gl_format: int) -> str:
    known = COLOR_FORMATS.get(gl_format, (DEPTH_FORMATS.get(gl_format), False))[0]
    return known or f"0x{gl_format:04X}"


def choose_color_format(offered: list[int]) -> SwapchainFormat:
    """The colour format for the eyes from the runtime's list (its preference first).

    >>> choose_color_format([0x8058, 0x8C43]).name
    'GL_SRGB8_ALPHA8'
    >>> choose_color_format([0x881A, 0x8058]).name
    'GL_RGBA16F'
    """
    usable = [f for f in offered if f in COLOR_FORMATS]
    if not usable:
        raise FormatError("the OpenXR runtime offers no colour swapchain format the engine "
                          "can draw into (offered: "
                          + (", ".join(format_name(f) for f in offered) or "none") + ")")
    srgb = [f for f in usable if COLOR_FORMATS[f][1]]
    chosen = (srgb or usable)[0]
    name, is_srgb = COLOR_FORMATS[chosen]
    return SwapchainFormat(chosen, name, is_srgb)


def choose_depth_format(offered: list[int]) -> SwapchainFormat | None:
    """The depth format to submit depth in (None: the runtime offers none; depth is then
    not submitted). Stencil-free and deeper first.

    >>> choose_depth_format([0x81A5, 0x88F0]).name
    'GL_DEPTH24_STENCIL8'
    """
    for candidate in DEPTH_FORMATS:
        if candidate in offered:
            return SwapchainFormat(candidate, DEPTH_FORMATS[candidate], False)
    return None
