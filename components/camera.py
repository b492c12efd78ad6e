"""Viewpoints."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.transform import Transform


@dataclass(slots=True)
class Camera:
    """A viewpoint looking along its local +Y. ``follow`` names an entity to follow at
    ``offset``."""

    fov: float = 60.0
    near: float = 0.05
    far: float = 500.0
    active: bool = True
    follow: int | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    look_at: tuple[float, float, float] | None = None
    eye_separation: float = 0.0


def _floats(values: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in values)


def build_camera(c: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Camera`` block: a viewpoint at Position, or following an object (linked once
    the objects exist; one left out is told, and the camera follows nothing)."""
    camera = Camera(fov=float(c["Fov"]), near=float(c["Near"]), far=float(c["Far"]),
                    active=bool(c["Active"]), offset=_floats(c["Offset"]),
                    look_at=_floats(c["LookAt"]), eye_separation=float(c["EyeSeparation"]))
    if ctx.given("Follow") and ctx.left_out(c["Follow"]):
        ctx.problem("Follow", f"camera '{ctx.owner}' follows nothing: object "
                    f"'{c['Follow']}' was left out")
    elif ctx.given("Follow"):
        ctx.link(camera, "follow", c["Follow"])
    _view(c, ctx)
    return [Transform(c["Position"]), camera]


def _view(c: Mapping[str, Any], ctx: BuildContext) -> None:
    """Warn about a camera with no well-defined view direction (the picture and the 3D
    sound listener follow it): LookAt at its eye, or straight along Z."""
    if ctx.given("Follow"):  # LookAt and Offset are in the followed object's frame
        if not ctx.given("LookAt"):
            return  # it takes the object's orientation
        eye = c["Offset"]
    else:
        eye = c["Position"]
    problem = ctx.view_problem(tuple(float(a) - float(b) for a, b in zip(
        c["LookAt"], eye, strict=True)))
    if problem is not None:
        ctx.problem("LookAt" if ctx.given("LookAt") else "Position",
                    f"camera '{ctx.owner}': {problem}; the view is meaningless and 3D sound "
                    "unpanned: move its LookAt (or Position) so it looks across, not along, Z",
                    warning=True)


CAMERA_BLOCK = declare(BlockDeclaration(
    "Camera", inside=("Scene",), build=build_camera,
    doc="a viewpoint (the first active one is drawn and heard from)", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this camera",
            example='"main"'),
        Key("Position", "vec3", (0.0, -5.0, 2.0), "world frame (with Follow, see Offset)",
            unit="m"),
        Key("LookAt", "vec3", (0.0, 0.0, 0.0), "the point it looks at (in the followed "
            "object's frame with Follow)", unit="m"),
        Key("Fov", "float", 60.0, "vertical", unit="degrees"),
        Key("Near", "float", 0.05, "nearest distance drawn", unit="m"),
        Key("Far", "float", 500.0, "farthest distance drawn", unit="m"),
        Key("Active", "bool", 1, "1: the one drawn and heard from (the first active)"),
        Key("Follow", "ref", None, "object to follow at Offset", ref="Object",
            example='"ball"'),
        Key("Offset", "vec3", (0.0, 0.0, 0.0), "its place in the followed object's frame",
            unit="m"),
        Key("EyeSeparation", "float", 0.0, "m; > 0 renders stereo"),
    )))
