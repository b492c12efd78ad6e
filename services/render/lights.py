"""Lights as the renderer sees them, the default light, and shadow-map projections.

One light casts shadows (the first with ``shadows`` on): a directional light uses an
orthographic map fitted around the shadow casters; a spot or point light a perspective map
from the light's position aimed at them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.rotation import quat_to_matrix
from services.render import math3d


@dataclass(slots=True)
class LightInfo:
    """A light in world space. ``direction`` is where the light shines (directional, spot);
    ``position`` matters for point and spot lights; ``cutoff`` is the spot half-angle (deg)."""

    kind: str = "directional"
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    position: tuple[float, float, float] = (0.0, 0.0, 10.0)
    direction: tuple[float, float, float] = (-0.3, -0.4, -1.0)
    cutoff: float = 30.0
    shadows: bool = True


KIND_CODES = {"directional": 0, "point": 1, "spot": 2}

#: Light used when a scene declares none, so an empty scene still looks right: from over the
#: default camera's shoulder (it looks along +Y), so the faces it sees are lit.
DEFAULT_LIGHT = LightInfo(direction=(0.3, 0.5, -1.0))

#: Ambient term of the default material's lighting.
DEFAULT_AMBIENT = (0.25, 0.25, 0.28)


def light_from_component(light: object, position: np.ndarray | None,
                         orientation: np.ndarray | None) -> LightInfo:
    """A :class:`LightInfo` from a ``components.Light`` and its entity's pose.

    The component's ``direction`` is in the entity's frame, so a rotating lamp turns its beam.
    """
    direction = np.asarray(light.direction, dtype=np.float64)  # type: ignore[attr-defined]
    if orientation is not None:
        direction = quat_to_matrix(orientation) @ direction
    pos = (0.0, 0.0, 10.0) if position is None else tuple(float(x) for x in position)
    return LightInfo(kind=light.kind, color=tuple(light.color),  # type: ignore[attr-defined]
                     intensity=float(light.intensity),  # type: ignore[attr-defined]
                     position=pos, direction=tuple(float(d) for d in direction),
                     cutoff=float(light.cutoff),  # type: ignore[attr-defined]
                     shadows=bool(light.shadows))  # type: ignore[attr-defined]


def shadow_matrix(light: LightInfo, centre: np.ndarray, radius: float) -> np.ndarray:
    """Light view-projection covering a sphere (``centre``, ``radius``) of shadow casters.

    Receivers farther from the light than the far plane still get shadows: the lit shader
    clamps their depth to the far plane.
    """
    centre = np.asarray(centre, dtype=np.float64)
    radius = max(float(radius), 1e-3)
    if light.kind == "directional":
        d = np.asarray(light.direction, dtype=np.float64)
        d /= np.linalg.norm(d) or 1.0
        eye = centre - d * (radius * 2.0)
        view = math3d.look_at_view(eye, centre, _up_for(d))
        proj = math3d.orthographic(-radius, radius, -radius, radius, 0.01, radius * 4.0)
        return proj @ view
    eye = np.asarray(light.position, dtype=np.float64)
    dist = float(np.linalg.norm(centre - eye))
    if dist <= radius * 1.05:  # light inside the casters: look along the spot direction
        d = np.asarray(light.direction, dtype=np.float64)
        target = eye + d
        fov = 120.0
    else:
        target = centre
        fov = math.degrees(2.0 * math.asin(min(radius / dist, 0.99))) * 1.1
    view = math3d.look_at_view(eye, target, _up_for(target - eye))
    near = max(0.05, dist - radius * 2.0) if dist > radius * 1.05 else 0.05
    proj = math3d.perspective(min(fov, 170.0), 1.0, near, dist + radius * 8.0)
    return proj @ view


def _up_for(direction: np.ndarray) -> tuple[float, float, float]:
    d = np.asarray(direction, dtype=np.float64)
    d = d / (np.linalg.norm(d) or 1.0)
    return (0.0, 1.0, 0.0) if abs(d[2]) > 0.99 else (0.0, 0.0, 1.0)
