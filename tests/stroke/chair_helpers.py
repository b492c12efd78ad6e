"""The stroke content's wheelchair on test grounds, its real wheels turned by functions of
time (counts over device time, as a counter on the rig sends them)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from components import Name, Physical, Transform
from engine import EngineConfig, Phase, system
from engine.content import REPO_ROOT
from engine.scene import instantiate, spec_from_text
from services.input import InputHub
from services.input.events import WheelCount
from systems import create_engine

CONTENT = REPO_ROOT / "content" / "stroke"
G = 9.81
COUNTS_PER_TURN, WRAP = 1024, 65536  # as wheelchair.scene declares the counters
#: The chair's parts: what the session log and the physics below count as the chair.
PARTS = ("wheelchair", "wheel_l", "wheel_r", "fork_l", "fork_r", "caster_l", "caster_r")
Rates = Callable[[float], tuple[float, float]]


def ground_flat() -> str:
    return ('Object { ID "floor" Dynamic 0 PhysicalAttributes { Material "ground" '
            'Geometry { Primitive "plane" } } }\n')


def ground_ramp(degrees: float) -> str:
    """A 6 m ramp falling along +Y at ``degrees``, its top face through the origin."""
    th = math.radians(degrees)
    along, down = 2.0, 0.1  # the ramp's centre: 2 m down the slope, half its thickness in
    y = along * math.cos(th) - down * math.sin(th)
    z = -along * math.sin(th) - down * math.cos(th)
    return (f'Object {{ ID "ramp" Dynamic 0 Position [0 {y:.9f} {z:.9f}] Orientation '
            f'[{-degrees} 0 0] Size [3 6 0.2] PhysicalAttributes {{ Material "ground" }} }}\n')


def chair_scene(ground: str, dt: float = 1.0 / 60.0, pitch: float = 0.0,
                feedback: bool = False, extra: str = "") -> str:
    """The content's wheelchair.scene on ``ground``, with the content's solver settings."""
    return (f"World {{ TimeStep {dt!r} Iterations 20 }}\n"
            f"chair_x 0 chair_y 0 chair_z 0 chair_yaw 0 chair_pitch {pitch!r} "
            f"chair_feedback {int(feedback)}\n"
            'Include "wheelchair.scene"\n'
            'Material { ID "ground" Friction 0.9 }\n' + ground + extra)


@dataclass
class ChairRun:
    """An engine running a chair scene whose counters turn at ``rates(t)`` (rad/s, left
    and right), each count sent plus ``shift(wheel, t)`` (a counter that starts near its
    wrap, or jumps) while ``sends(wheel, t)`` (unplugged: not); ``track`` rows: t,
    chassis position, orientation, velocity, spin."""

    scene: str
    rates: Rates = lambda t: (0.0, 0.0)  # noqa: E731
    shift: Callable[[int, float], int] = lambda wheel, t: 0  # noqa: E731
    sends: Callable[[int, float], bool] = lambda wheel, t: True  # noqa: E731
    track: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        spec = spec_from_text(self.scene, CONTENT, path="<chair test>")
        config = EngineConfig(content_dir=CONTENT, fast=True, dt=spec.time_step,
                              world=spec.world)
        self.engine = engine = create_engine(config)
        self.ids = instantiate(engine, spec)
        engine.start()
        hub = engine.resource(InputHub)
        hub.clock = lambda: engine.time
        turned = [0.0, 0.0]

        @system(Phase.INPUT, before=("InputSystem",))
        def counters(e, dt):
            rates = self.rates(e.time)
            for i, name in enumerate(("left", "right")):
                turned[i] += rates[i] * dt
                count = round(turned[i] / (2 * math.pi) * COUNTS_PER_TURN) + self.shift(i, e.time)
                if self.sends(i, e.time):
                    hub.inject(WheelCount(name, count % WRAP, e.time))

        @system(Phase.POST_PHYSICS, reads=(Transform,))
        def note(e, dt):
            t = e.world.component_for_entity(self.ids["wheelchair"], Transform)
            self.track.append(np.concatenate([[e.time + dt], t.position, t.orientation,
                                              t.linear_velocity, t.angular_velocity]))

        engine.add_system(counters)
        engine.add_system(note)

    def run(self, seconds: float) -> np.ndarray:
        self.engine.run(seconds=seconds)
        return np.array(self.track)

    def close(self) -> None:
        self.engine.close()

    def __enter__(self) -> ChairRun:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def rolling_mass(self) -> tuple[float, float]:
        """The chair's mass (kg) and its wheels' and casters' Σ I/r² (kg): what rolling
        down a slope accelerates, from the scene's bodies (a cylinder about its axis:
        I = m r²/2)."""
        world = self.engine.world
        mass = spin = 0.0
        for name in PARTS:
            body = world.component_for_entity(self.ids[name], Physical)
            mass += float(body.mass)
            if body.shapes[0].kind == "cylinder":
                spin += float(body.mass) / 2.0
        return mass, spin

    def parts_positions(self) -> dict[str, np.ndarray]:
        world = self.engine.world
        return {n: world.component_for_entity(self.ids[n], Transform).position.copy()
                for n in PARTS}

    def names(self) -> dict[int, str]:
        return {e: n.id for e, n in self.engine.world.get_component(Name)}
