"""How each visual anomaly (engine.anomalies) is drawn: full-screen passes run for each eye
in that eye's viewport, in visual-field terms, and the changes a perspective anomaly makes
to an eye's projection.

A pass sees the frame as ``u_scene`` and works in the eye's own coordinates: ``v_uv`` runs
0..1 across the eye's viewport, ``u_eye`` is that viewport in the frame's texture
coordinates, and ``u_tan_half`` the tangents of half the eye's horizontal and vertical field
of view, so ``field_deg(v_uv)`` is the direction a pixel is seen in (degrees right and up of
the line of sight). Neglect and hemianopia are thus drawn per eye about each eye's own line
of sight (a homonymous loss, as a stroke behind the optic chiasm causes), and double vision
and blur are given in degrees of visual angle, the same in mono and in each eye of a stereo
pair. Samples never leave the eye's viewport, so one eye never bleeds into the other.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.anomalies import Value
from services.render.camera import Eye

HEADER = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform vec4 u_eye;       // the eye's viewport in the frame's texture coordinates
uniform vec2 u_tan_half;  // tangents of half the eye's field of view (x, y)
out vec4 f_color;

// the frame at a point of this eye (0..1 across its viewport), never outside it
vec4 scene_at(vec2 local) {
    vec2 half_texel = 0.5 / vec2(textureSize(u_scene, 0)) / u_eye.zw;
    return texture(u_scene, u_eye.xy + clamp(local, half_texel, 1.0 - half_texel) * u_eye.zw);
}
// the direction a point of this eye is seen in: degrees right and up of the line of sight
vec2 field_deg(vec2 local) { return degrees(atan((local * 2.0 - 1.0) * u_tan_half)); }
// where a direction (degrees right and up) lands in this eye
vec2 local_at(vec2 deg) { return tan(radians(deg)) / u_tan_half * 0.5 + 0.5; }
bool inside(vec2 local) { return all(greaterThanEqual(local, vec2(0.0))) &&
                                 all(lessThanEqual(local, vec2(1.0))); }
"""

COPY = HEADER + """
void main() { f_color = scene_at(v_uv); }
"""

_DOUBLE_VISION = HEADER + """
uniform vec2 u_offset;  // degrees
uniform float u_rotation;  // degrees
uniform float u_mix;
void main() {
    vec4 base = scene_at(v_uv);
    float a = radians(-u_rotation);
    vec2 seen = field_deg(v_uv);
    vec2 source = local_at(mat2(cos(a), sin(a), -sin(a), cos(a)) * seen - u_offset);
    f_color = inside(source) ? mix(base, scene_at(source), u_mix) : base;
}
"""

_DISTORTION = HEADER + """
uniform float u_strength;
void main() {
    vec2 ndc = v_uv * 2.0 - 1.0;
    vec2 source = ndc * (1.0 + u_strength * dot(ndc, ndc)) * 0.5 + 0.5;  // > 0: barrel
    f_color = inside(source) ? scene_at(source) : vec4(0.0, 0.0, 0.0, 1.0);
}
"""

#: Taps on each side of the centre of the separable Gaussian blur.
BLUR_TAPS = 12
_BLUR = HEADER + f"#define TAPS {BLUR_TAPS}\n" + """
uniform vec2 u_step;  // between taps, in the eye's coordinates: along x or along y
uniform float u_sigma_taps;  // the Gaussian's standard deviation, in taps
void main() {
    vec4 sum = scene_at(v_uv);
    float total = 1.0;
    for (int i = 1; i <= TAPS; ++i) {
        float w = exp(-0.5 * float(i * i) / (u_sigma_taps * u_sigma_taps));
        sum += w * (scene_at(v_uv + u_step * float(i)) + scene_at(v_uv - u_step * float(i)));
        total += 2.0 * w;
    }
    f_color = sum / total;
}
"""

_MOTION = HEADER + """
uniform sampler2D u_previous;
uniform float u_keep;
uniform int u_first;
void main() {
    vec4 now = scene_at(v_uv);
    vec4 before = texture(u_previous, u_eye.xy + v_uv * u_eye.zw);
    f_color = u_first == 1 ? now : mix(now, before, u_keep);
}
"""

#: Averages a texture's level ``u_level`` over each eye's viewport: drawn into a row of
#: one texel per eye (the eye's mean colour), so a contrast pass needs one fetch for it.
#: Level 0 would be exact but slow; a mip level of at most MEAN_TEXELS wide sums the same
#: (a box filter of even sizes) in a few thousand fetches for one fragment per eye.
MEAN = """#version 330
uniform sampler2D u_scene;
uniform int u_level;
uniform vec4 u_rects[2];  // each eye's viewport in texture coordinates
out vec4 f_color;
void main() {
    vec4 rect = u_rects[int(gl_FragCoord.x)];
    ivec2 size = textureSize(u_scene, u_level);
    ivec2 lo = ivec2(floor(rect.xy * vec2(size) + 0.5));
    ivec2 hi = max(ivec2(floor((rect.xy + rect.zw) * vec2(size) + 0.5)), lo + 1);
    vec4 sum = vec4(0.0);
    for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x) sum += texelFetch(u_scene, ivec2(x, y), u_level);
    f_color = sum / float((hi.x - lo.x) * (hi.y - lo.y));
}
"""
#: The widest mip level the eye means are summed over (texels).
MEAN_TEXELS = 128

_CONTRAST = HEADER + """
uniform sampler2D u_mean;  // one texel per eye: its mean colour
uniform int u_eye_index;
uniform float u_keep;  // 1 - Loss
void main() {
    vec4 c = scene_at(v_uv);
    vec3 mean = texelFetch(u_mean, ivec2(u_eye_index, 0), 0).rgb;
    f_color = vec4(mean + u_keep * (c.rgb - mean), c.a);
}
"""

_NEGLECT = HEADER + """
uniform float u_side;  // -1 left, +1 right
uniform float u_start;  // degrees toward that side
uniform float u_width;
uniform float u_amount;  // Depth: how far toward the fill
uniform vec3 u_fill;
void main() {
    vec4 c = scene_at(v_uv);
    float toward = u_side * field_deg(v_uv).x - u_start;
    float fade = u_width > 0.0 ? smoothstep(0.0, u_width, toward) : step(0.0, toward);
    f_color = vec4(mix(c.rgb, u_fill, u_amount * fade), c.a);
}
"""

_HEMIANOPIA = HEADER + """
uniform float u_side;  // -1 left, +1 right
uniform float u_sparing;  // degrees
uniform float u_border;
uniform float u_amount;  // Depth: how far toward the fill
uniform vec3 u_fill;
void main() {
    vec4 c = scene_at(v_uv);
    vec2 seen = field_deg(v_uv);
    float b = max(u_border, 1e-3) * 0.5;
    float lost = smoothstep(-b, b, u_side * seen.x);
    if (u_sparing > 0.0) lost *= smoothstep(u_sparing - b, u_sparing + b, length(seen));
    f_color = vec4(mix(c.rgb, u_fill, u_amount * lost), c.a);
}
"""


@dataclass(frozen=True, slots=True)
class Stage:
    """One full-screen pass of an anomaly: its program's source and its uniforms for an
    eye. ``feedback``: it reads its own last output (``u_previous``); ``mean``: it reads
    each eye's mean colour (``u_mean``, ``u_eye_index``). ``skip`` says when
    its parameters leave the image as it is (see :data:`MEAN`)."""

    name: str
    source: str
    uniforms: Callable[[Mapping[str, Value], EyeGeometry], dict[str, Any]]
    skip: Callable[[Mapping[str, Value]], bool] = lambda values: False
    feedback: bool = False
    mean: bool = False


@dataclass(frozen=True, slots=True)
class EyeGeometry:
    """What a pass needs of an eye: its viewport in the frame's texture coordinates and in
    pixels, and the tangents of half its field of view."""

    rect: tuple[float, float, float, float]
    pixels: tuple[int, int]
    tan_half: tuple[float, float]


def eye_geometry(eye: Eye, size: tuple[int, int]) -> EyeGeometry:
    x, y, w, h = eye.viewport
    return EyeGeometry((x / size[0], y / size[1], w / size[0], h / size[1]), (w, h),
                       (1.0 / eye.proj[0, 0], 1.0 / eye.proj[1, 1]))


def _side(values: Mapping[str, Value]) -> float:
    return -1.0 if values["Side"] == "left" else 1.0


def _blur(axis: int) -> Stage:
    """One direction of the acuity blur: a Gaussian of ``Acuity`` degrees of visual angle,
    in :data:`BLUR_TAPS` taps each way spread over three standard deviations."""

    def uniforms(values: Mapping[str, Value], eye: EyeGeometry) -> dict[str, Any]:
        sigma = math.tan(math.radians(float(values["Acuity"]))) / eye.tan_half[axis] / 2.0
        spacing = max(3.0 * sigma / BLUR_TAPS, 1.0 / eye.pixels[axis])  # eye units
        step = [0.0, 0.0]
        step[axis] = spacing
        return {"u_step": tuple(step), "u_sigma_taps": max(sigma / spacing, 1e-3)}

    return Stage(f"blur_{'xy'[axis]}", _BLUR, uniforms,
                 skip=lambda values: float(values["Acuity"]) <= 0.0)


#: The passes of each anomaly, in the order they run (perspective's Fov, Tilt and Aspect
#: change the eye's projection instead; see :func:`adjust_eye`).
STAGES: dict[str, tuple[Stage, ...]] = {
    "perspective": (Stage("distortion", _DISTORTION,
                          lambda v, e: {"u_strength": float(v["Distortion"])},
                          skip=lambda v: float(v["Distortion"]) == 0.0),),
    "double_vision": (Stage("double_vision", _DOUBLE_VISION,
                            lambda v, e: {"u_offset": tuple(v["Offset"]),  # type: ignore[arg-type]
                                          "u_rotation": float(v["Rotation"]),
                                          "u_mix": float(v["Mix"])},
                            skip=lambda v: float(v["Mix"]) == 0.0),),
    "blur": (_blur(0), _blur(1),
             Stage("motion", _MOTION, lambda v, e: {"u_keep": float(v["Motion"])},
                   skip=lambda v: float(v["Motion"]) == 0.0, feedback=True)),
    "contrast_loss": (Stage("contrast", _CONTRAST,
                            lambda v, e: {"u_keep": 1.0 - float(v["Loss"])},
                            skip=lambda v: float(v["Loss"]) == 0.0, mean=True),),
    "neglect": (Stage("neglect", _NEGLECT,
                      lambda v, e: {"u_side": _side(v), "u_start": float(v["Start"]),
                                    "u_width": float(v["Width"]), "u_amount": float(v["Depth"]),
                                    "u_fill": tuple(v["Fill"])},  # type: ignore[arg-type]
                      skip=lambda v: float(v["Depth"]) == 0.0),),
    "hemianopia": (Stage("hemianopia", _HEMIANOPIA,
                         lambda v, e: {"u_side": _side(v), "u_sparing": float(v["Sparing"]),
                                       "u_border": float(v["Border"]),
                                       "u_amount": float(v["Depth"]),
                                       "u_fill": tuple(v["Fill"])},  # type: ignore[arg-type]
                         skip=lambda v: float(v["Depth"]) == 0.0),),
}


def adjust_eye(eye: Eye, values: Mapping[str, Value]) -> Eye:
    """The eye as a perspective anomaly shows it: its field of view widened or narrowed by
    ``Fov`` (capped below 170 degrees), the world rolled by ``Tilt`` about the line of
    sight, and the picture stretched sideways by ``Aspect``."""
    tan_y = 1.0 / eye.proj[1, 1]
    fov = min(2.0 * math.degrees(math.atan(tan_y)) * float(values["Fov"]), 170.0)  # type: ignore[arg-type]
    scale = tan_y / math.tan(math.radians(fov) / 2.0)
    a = math.radians(float(values["Tilt"]))  # type: ignore[arg-type]
    roll = np.eye(4)
    roll[:2, :2] = ((math.cos(a), -math.sin(a)), (math.sin(a), math.cos(a)))
    stretch = np.diag([scale * float(values["Aspect"]), scale, 1.0, 1.0])  # type: ignore[arg-type]
    return Eye(roll @ eye.view, stretch @ eye.proj, eye.position, eye.viewport)
