"""The avatars plugin: skinned figures from ``Avatar`` blocks, animated, walking paths over
the ground, carrying things; scripted from Lua (``avatar:play("Run", {fade=0.3})``).

One system in PRE_PHYSICS, so what it moves (capsules, held objects) reaches this frame's
step. Each frame, for all avatars at once:

1. clips advance (fades, phases, queues); clips that ended become :class:`AnimationEnded`
   events (``onAnimationEnd(clip)`` in the avatar's scripts, ``onAnimationEnd(avatar,
   clip)`` in scene scripts);
2. avatars with a path turn toward their next point (at most ``TurnRate``) and walk on at
   the ground speed of the clips they play;
3. every skeleton is evaluated (:class:`engine.animation.Mixer`);
4. one physics query casts every ray down — under each ground-following root and each
   foot — and roots are put on the ground (steps taken over ``Smoothing`` seconds, slopes
   followed exactly); two-bone IK puts the feet on it, and bones a remote user's tracker
   drives reach their poses;
5. joint matrices are published (:class:`engine.animation.Palettes`) for the renderer; held
   objects follow their bones and capsules their avatars (kinematic targets).
"""

from __future__ import annotations

import difflib
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Avatar, Hold, Name, Physical, Shape, Transform, Visual
from components.avatar_saved import SavedAvatar, SavedDrive, SavedHold
from components.physical import BodyKind
from engine.animation import AnimationEnded, AnimationError, ClipSettings, Mixer, Palettes
from engine.animation.ik import Chains, from_to, make_chains, solve
from engine.assets import AssetError, Assets, SkinnedModel
from engine.assets.skinned import AVATAR_AXES
from engine.messages import MessageLog
from engine.physics import commands as cmd
from engine.rotation import euler_to_quat, matrix_to_quat, quat_multiply, quat_to_matrix
from engine.services import AVATAR_METHODS, AvatarControl, AvatarStates
from engine.system import Phase, PluginName, System
from services.render.math3d import compose

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.avatars")

#: Below this distance (m) a path point counts as reached.
ARRIVE = 0.2
#: Rays start this far above the highest point they look for and reach this far below.
RAY_DROP = 5.0
#: A change of ground height steeper than this (rise per metre walked) is a step.
MAX_SLOPE = 1.0
#: Collision category of avatar capsules; the avatars' own rays skip it.
CAPSULE_CATEGORY = 1 << 30
#: Dynamic bodies a ray passes through before it gives up (a ball is not ground).
LOOSE_SKIPS = 3


@dataclass(slots=True)
class _Held:
    entity: int
    node: int
    offset: np.ndarray
    rotation: np.ndarray
    kind: str  # "visual", "kinematic" or "dynamic"
    last: np.ndarray | None = None


@dataclass(slots=True)
class _Drive:
    """A bone held at a world pose (a remote user's tracked hand), its two parents bent."""

    node: int
    position: np.ndarray
    orientation: np.ndarray


@dataclass(frozen=True, slots=True)
class _Legs:
    """The legs of the ground-following avatars: their IK chains, the avatar (among the
    followers) each belongs to, and each ankle's row."""

    key: tuple
    chains: Chains
    owner: np.ndarray
    ankle: np.ndarray


@dataclass(slots=True)
class _Figure:
    """What the plugin keeps per avatar besides its animation."""

    entity: int
    spec: Avatar
    model: SkinnedModel
    capsule: int | None = None
    path: list[np.ndarray] = field(default_factory=list)
    path_loop: bool = True
    waypoint: int = 0
    ground: float | None = None  # ground height under the root last frame
    offset: float = 0.0  # height still to be taken after a step (smoothed away)
    legs: list[tuple[int, int, int]] = field(default_factory=list)
    held: list[_Held] = field(default_factory=list)
    drives: dict[int, _Drive] = field(default_factory=dict)
    last_xy: tuple[float, float] | None = None  # where the root was when last on ground


class AvatarSystem(System):
    """Animates every entity with an ``Avatar``; the :class:`AvatarControl` of scripts."""

    phase = Phase.PRE_PHYSICS
    reads = (Avatar, Transform, Name, Physical, Visual)
    writes = (Transform, Name, Physical)

    def __init__(self) -> None:
        self.mixer = Mixer()
        self.palettes = Palettes()
        self.figures: dict[int, _Figure] = {}
        self._pending: list[int] = []
        self._engine: Engine | None = None
        self._rays: Any = None  # the physics query in flight (threaded mode)
        self._loose: set[int] = set()  # dynamic bodies: not ground to stand on
        self._leg_cache: _Legs | None = None
        #: the last frame's final skeletons (IK included) and each avatar's first row
        self._posed: tuple[np.ndarray, dict[int, int]] = (np.zeros((0, 4, 4)), {})
        self._messages = MessageLog(log)

    # -- lifecycle --------------------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        self._engine = engine
        world = engine.world
        world.on_add(Avatar, lambda e, _: self._pending.append(e))
        world.on_remove(Avatar, lambda e, _: self._forget(e))
        world.on_add(Physical, self._body_added)
        world.on_remove(Physical, lambda e, _: self._loose.discard(e))
        for entity, body in world.get_component(Physical):
            self._body_added(entity, body)
        self._pending.extend(e for e, _ in world.get_component(Avatar))
        engine.events.subscribe(AnimationEnded, self._tell_scripts)
        engine.insert_resource(self)
        engine.insert_resource(self, as_type=AvatarControl)
        engine.insert_resource(self, as_type=AvatarStates)
        engine.insert_resource(self.palettes)

    def _body_added(self, entity: int, body: Physical) -> None:
        if body.kind == BodyKind.DYNAMIC:
            self._loose.add(entity)

    def _forget(self, entity: int) -> None:
        figure = self.figures.pop(entity, None)
        self.mixer.remove(entity)
        engine = self._engine
        if figure is not None and figure.capsule is not None and engine is not None:
            engine.despawn(figure.capsule)

    def _start(self, engine: Engine, entity: int) -> None:
        world = engine.world
        spec = world.try_component(entity, Avatar)
        if spec is None or entity in self.figures:
            return
        try:
            model = Assets.of(engine).skinned(spec.model)
        except AssetError as exc:
            self._messages.error(f"avatar {self._name(entity)!r}: {exc.message}; it is not "
                                 "animated")
            return
        if not model.skin_count:
            self._messages.error(f"avatar {self._name(entity)!r}: model {spec.model!r} has no "
                                 "skin; it is not animated")
            return
        rig = self.mixer.library.rig_for(model)
        settings = {c.name: ClipSettings(c.speed, c.loop, None if c.ground_speed is None
                                         else c.ground_speed / spec.scale)
                    for c in spec.clips if c.name in rig.clips}
        self.mixer.add(entity, rig, settings, spec.fade)
        figure = _Figure(entity, spec, model)
        self.figures[entity] = figure
        self._animate(entity, spec)
        saved = spec.saved
        for hip, knee, ankle in spec.foot_ik:
            nodes = (model.node(hip), model.node(knee), model.node(ankle))
            if None not in nodes:
                figure.legs.append(nodes)  # type: ignore[arg-type]
        if saved is None:
            figure.path = [np.asarray(p, np.float64) for p in spec.path]
            figure.path_loop = spec.path_loop
            holds = [SavedHold(h) for h in spec.holds]
        else:
            self._resume(figure, saved)
            holds = list(saved.holds)
        names = {n.id: e for e, n in world.get_component(Name)}
        for held in holds:
            hold = held.hold
            target = names.get(hold.target) if isinstance(hold.target, str) else hold.target
            try:
                self.hold(entity, target if target is not None else -1, hold.bone,
                          hold.offset, hold.rotation)
            except (KeyError, ValueError) as exc:
                self._messages.error(f"avatar {self._name(entity)!r}: {exc}")
                continue
            if held.last is not None:  # (hold() put it last)
                figure.held[-1].last = np.asarray(held.last, np.float64)
        if spec.capsule is not None:
            figure.capsule = self._capsule(engine, entity, spec.capsule,
                                           None if saved is None else saved.capsule)

    def _animate(self, entity: int, spec: Avatar) -> None:
        """Its clips: where a saved run left them, else as its block says."""
        try:
            if spec.saved is not None:
                self.mixer.restore(entity, spec.saved.groups, spec.saved.queue)
                return
            if spec.blend:
                self.mixer.blend(entity, spec.blend, 0.0, spec.speed, spec.loop)
            elif spec.clip is not None:
                self.mixer.play(entity, spec.clip, 0.0, spec.speed, spec.loop)
            for name in spec.queue:
                self.mixer.queue(entity, name)
        except AnimationError as exc:
            self._messages.error(f"avatar {self._name(entity)!r}: {exc}")

    def _resume(self, figure: _Figure, saved: SavedAvatar) -> None:
        """Where a saved run left the avatar's walk, its ground following and its driven
        bones (its clips and held objects are restored beside this)."""
        figure.path = [np.asarray(p, np.float64) for p in saved.path]
        figure.path_loop, figure.waypoint = saved.path_loop, saved.waypoint
        figure.ground, figure.last_xy = saved.ground, saved.ground_at
        figure.offset = saved.step_offset
        for drive in saved.drives:
            try:
                self.drive_bone(figure.entity, drive.bone, drive.position, drive.orientation)
            except ValueError as exc:
                self._messages.error(f"avatar {self._name(figure.entity)!r}: {exc}")

    def _capsule(self, engine: Engine, entity: int, capsule: tuple[float, float],
                 pose: tuple[Any, Any] | None = None) -> int:
        """A kinematic capsule standing on the avatar's root (or at a saved ``pose``),
        moved with it."""
        radius, length = capsule
        if pose is None:
            pose = (engine.world.component_for_entity(entity, Transform).position.copy(),
                    (1.0, 0.0, 0.0, 0.0))
        body = Physical(kind=BodyKind.KINEMATIC, mass=None, gravity=False, can_sleep=False,
                        category=CAPSULE_CATEGORY, shapes=[Shape("capsule", (radius, length),
                                      offset=(0.0, 0.0, radius + 0.5 * length))])
        return engine.spawn(Name(f"{self._name(entity)}:capsule"), Transform(*pose), body)

    # -- saved states -------------------------------------------------------------------
    def saved_avatars(self, object_name: Callable[[int], str | None]
                      ) -> dict[int, SavedAvatar]:
        """Every animated avatar's state (see :class:`AvatarStates`); one not started yet
        has none (it starts as its block says)."""
        engine = self._engine
        states: dict[int, SavedAvatar] = {}
        for entity, figure in self.figures.items():
            groups, queue = self.mixer.capture(entity)
            bones = figure.model.node_names
            holds = []
            for held in figure.held:
                name = object_name(held.entity)
                if name is None:
                    log.warning("saved state: avatar %r holds an object that is not saved "
                                "(%s); it lets go of it", self._name(entity),
                                self._name(held.entity))
                    continue
                holds.append(SavedHold(Hold(bones[held.node], name, _floats(held.offset),
                                            _floats(held.rotation)),
                                       None if held.last is None else _floats(held.last)))
            capsule = None
            if figure.capsule is not None and engine is not None and \
                    engine.world.entity_exists(figure.capsule):
                t = engine.world.component_for_entity(figure.capsule, Transform)
                capsule = (_floats(t.position), _floats(t.orientation))
            states[entity] = SavedAvatar(
                groups, queue, tuple(_floats(p) for p in figure.path), figure.path_loop,
                figure.waypoint, figure.ground, figure.last_xy, figure.offset, tuple(holds),
                tuple(SavedDrive(bones[d.node], _floats(d.position), _floats(d.orientation))
                      for d in figure.drives.values()), capsule)
        return states

    def _name(self, entity: int) -> str:
        engine = self._engine
        named = None if engine is None else engine.world.try_component(entity, Name)
        return named.id if named is not None else str(entity)

    # -- per frame ----------------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        if self._pending:
            pending, self._pending = self._pending, []
            for entity in pending:
                if engine.world.entity_exists(entity):
                    self._start(engine, entity)
        if not self.figures:
            return
        for ended in self.mixer.advance(dt):
            engine.events.emit(ended)
        poses = engine.world.poses
        entities = list(self.figures)
        rows = poses.rows(entities)
        self._walk(poses, entities, rows, dt)
        world, plan = self.mixer.evaluate()
        self._ground(engine, poses, entities, rows, world, dt)
        self._drive(poses, entities, rows, world)
        self._publish(world, plan)
        self._posed = (world, {e: a.row for e, a in self.mixer.animators.items()})
        self._carry(engine, poses, entities, rows, world, dt)

    def _placement(self, position: np.ndarray, orientation: np.ndarray, scale: float
                   ) -> np.ndarray:
        """Model frame -> world: the root's pose, the model's scale and axes."""
        return compose(position, orientation, np.full(3, scale)) @ AVATAR_AXES

    def _walk(self, poses: Any, entities: list[int], rows: np.ndarray, dt: float) -> None:
        """Turn toward the next path point and walk on at the clips' ground speed."""
        speeds = None
        for entity, row in zip(entities, rows.tolist(), strict=True):
            figure = self.figures[entity]
            if not figure.path or row < 0 or figure.waypoint >= len(figure.path):
                continue
            if speeds is None:
                speeds = self.mixer.ground_speeds()
            position = poses.position[row]
            q = poses.orientation[row]
            heading = math.atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2))
            to = figure.path[figure.waypoint] - position
            if math.hypot(to[0], to[1]) < ARRIVE:
                figure.waypoint += 1
                if figure.waypoint >= len(figure.path) and figure.path_loop:
                    figure.waypoint = 0
                continue
            want = math.atan2(-to[0], to[1])  # facing +Y at heading 0
            turn = (want - heading + math.pi) % (2 * math.pi) - math.pi
            step = figure.spec.turn_rate * dt
            heading += max(-step, min(step, turn))
            poses.orientation[row] = (math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2))
            speed = speeds.get(entity, 0.0) * figure.spec.scale
            poses.position[row, 0] -= math.sin(heading) * speed * dt
            poses.position[row, 1] += math.cos(heading) * speed * dt

    def _legs(self, followers: list[_Figure]) -> _Legs:
        """Every leg of the ground-following avatars, laid out for batched IK (kept while
        the avatars and their skeletons' rows stay)."""
        key = tuple((f.entity, self.mixer.animators[f.entity].row) for f in followers)
        if self._leg_cache is not None and self._leg_cache.key == key:
            return self._leg_cache
        items, owner, ankles = [], [], []
        for i, figure in enumerate(followers):
            animator = self.mixer.animators[figure.entity]
            for hip, knee, ankle in figure.legs:
                items.append((animator.row, animator.rig.parents, hip, knee, ankle))
                owner.append(i)
                ankles.append(animator.row + ankle)
        self._leg_cache = _Legs(key, make_chains(items), np.array(owner, np.int64),
                                np.array(ankles, np.int64))
        return self._leg_cache

    def _ground(self, engine: Engine, poses: Any, entities: list[int], rows: np.ndarray,
                world: np.ndarray, dt: float) -> None:
        """One query casts every ray down (under each root and each foot); roots onto the
        ground, then feet by IK, batched over every avatar."""
        pairs = [(self.figures[e], r) for e, r in zip(entities, rows.tolist(), strict=True)
                 if self.figures[e].spec.ground_follow and r >= 0]
        if not pairs:
            return
        followers = [f for f, _ in pairs]
        at = np.array([r for _, r in pairs], np.int64)
        position = poses.position[at].copy()
        scale = np.array([f.spec.scale for f in followers])
        step = np.array([f.spec.step_height for f in followers])
        place = compose(position, poses.orientation[at], scale[:, None] * np.ones(3)) \
            @ AVATAR_AXES
        legs = self._legs(followers)
        ankle = np.einsum("lij,lj->li", place[legs.owner], world[legs.ankle, :, 3])[:, :3]
        tops = np.concatenate([position[:, 2], position[legs.owner, 2]]) + np.concatenate(
            [step, step[legs.owner]])
        origins = np.column_stack([np.concatenate([position[:, :2], ankle[:, :2]]), tops])
        hits = self._cast(engine, origins, np.concatenate([step, step[legs.owner]]) + RAY_DROP)
        if hits is None:
            return
        n = len(followers)
        height = np.array([np.nan if h is None else h.position[2] for h in hits])
        normal = np.array([(0.0, 0.0, 1.0) if h is None else h.normal for h in hits],
                          np.float64).reshape(-1, 3)
        foot_ground = height[n:]
        lowest = np.full(n, np.inf)  # the lowest ground under each avatar's feet
        np.minimum.at(lowest, legs.owner, np.where(np.isnan(foot_ground), np.inf, foot_ground))
        for i, figure in enumerate(followers):
            if not np.isnan(height[i]):
                position[i, 2] = self._settle(figure, position[i], float(height[i]),
                                              float(lowest[i]), dt)
        poses.position[at, 2] = position[:, 2]
        if not len(legs.owner):
            return
        # IK: each ankle as high over its ground as the clip has it over the root, the foot
        # turned to the slope; a foot with no ground under it keeps its pose
        rise = ankle[:, 2] - place[legs.owner, 2, 3]  # over the root, as animated
        ok = ~np.isnan(foot_ground) & ~np.isnan(height[legs.owner])
        target = ankle.copy()
        target[ok, 2] = foot_ground[ok] + rise[ok]
        place[:, 2, 3] = position[:, 2]
        inverse = np.linalg.inv(place)[legs.owner]
        local = np.einsum("lij,lj->li", inverse[:, :3, :3], target) + inverse[:, :3, 3]
        axes = place[legs.owner, :3, :3] / scale[legs.owner, None, None]  # model -> world
        up = axes[:, 2, :]  # world up in the model frame: the third row of the rotation
        turned = np.einsum("lji,lj->li", axes, normal[n:])
        slope = from_to(up, np.where(ok[:, None], turned, up))
        solve(world, legs.chains, np.where(ok[:, None], local, world[legs.chains.c, :3, 3]),
              slope @ world[legs.chains.c, :3, :3])

    def _cast(self, engine: Engine, origins: np.ndarray, lengths: np.ndarray
              ) -> list[Any] | None:
        """The hits of ``rays`` (straight down) on what one can stand on — not capsules,
        not dynamic bodies (a ray goes on past a ball): now in serial mode; in threaded
        mode the answer to last frame's query (None while it is not in)."""
        down = np.array([0.0, 0.0, -1.0])
        loose = frozenset(self._loose)
        mask = 0xFFFFFFFF & ~CAPSULE_CATEGORY

        rays = list(zip(origins, lengths.tolist(), strict=True))

        def query(backend: Any) -> list[Any]:
            hits = []
            for origin, length in rays:
                hit = backend.raycast(origin, down, length, None, mask)
                for _ in range(LOOSE_SKIPS):
                    if hit is None or hit.key not in loose:
                        break
                    hit = backend.raycast(origin, down, length, hit.key, mask)
                hits.append(None if hit is not None and hit.key in loose else hit)
            return hits

        previous = self._rays
        if previous is None or previous.done():
            self._rays = engine.physics.request(query)
        # serial: this frame's answer is in already; threaded: last frame's, once it is
        future = self._rays if self._rays.done() else previous
        if future is None or not future.done():
            return None
        try:
            hits = future.result()
        except Exception as exc:  # no physics plugin, or a backend without ray casts
            self._messages.error(f"avatars cannot follow the ground: {exc}")
            return None
        return hits if len(hits) == len(rays) else None

    def _settle(self, figure: _Figure, position: np.ndarray, ground: float, lowest: float,
                dt: float) -> float:
        """The root's height on the ground: slopes exactly, steps over ``Smoothing``
        seconds, the hips lower when a foot stands lower than the root (so its leg
        reaches)."""
        x, y = float(position[0]), float(position[1])
        if figure.ground is not None and figure.last_xy is not None:
            walked = math.hypot(x - figure.last_xy[0], y - figure.last_xy[1])
            rise = ground - figure.ground
            if abs(rise) > MAX_SLOPE * walked + 1e-3:  # a step: keep the root where it was
                figure.offset -= rise
        tau = figure.spec.smoothing
        figure.offset *= math.exp(-dt / tau) if tau > 0 else 0.0
        if abs(figure.offset) < 1e-5:
            figure.offset = 0.0
        figure.ground = ground
        figure.last_xy = (x, y)
        root = ground + figure.offset
        drop = min(max(root - lowest, 0.0), figure.spec.step_height) if lowest < math.inf \
            else 0.0
        return root - drop

    def _drive(self, poses: Any, entities: list[int], rows: np.ndarray, world: np.ndarray
               ) -> None:
        """Bones held at world poses (trackers): their two parents bent to reach."""
        items, targets, ends = [], [], []
        for entity, row in zip(entities, rows.tolist(), strict=True):
            figure = self.figures[entity]
            if not figure.drives or row < 0:
                continue
            place = self._placement(poses.position[row], poses.orientation[row],
                                    figure.spec.scale)
            inverse = np.linalg.inv(place)
            axes = place[:3, :3] / figure.spec.scale
            animator = self.mixer.animators[entity]
            parents = animator.rig.parents
            for drive in figure.drives.values():
                b = int(parents[drive.node])
                a = int(parents[b]) if b >= 0 else -1
                if a < 0:
                    continue
                bone = world[animator.row + drive.node, :3, :3]
                items.append((animator.row, parents, a, b, drive.node))
                targets.append((inverse @ np.append(drive.position, 1.0))[:3])
                # the wanted world rotation, in the model frame, keeping the bone's scale
                ends.append(axes.T @ quat_to_matrix(drive.orientation)
                            * np.linalg.norm(bone, axis=0))
        if items:
            solve(world, make_chains(items), np.array(targets), np.array(ends))

    def _publish(self, world: np.ndarray, plan: Any) -> None:
        """Joint matrices of every avatar, for the renderer."""
        self.palettes.matrices = np.ascontiguousarray(plan.palettes(world)[:, :3, :],
                                                      np.float32)
        self.palettes.offsets = plan.palette_offsets
        self.palettes.version += 1

    def _carry(self, engine: Engine, poses: Any, entities: list[int], rows: np.ndarray,
               world: np.ndarray, dt: float) -> None:
        """Held objects onto their bones; capsules onto their avatars (kinematic targets
        reached as this frame's time passes, then waiting there however many steps the
        physics thread takes)."""
        for entity, row in zip(entities, rows.tolist(), strict=True):
            figure = self.figures[entity]
            if row < 0:
                continue
            position, orientation = poses.position[row], poses.orientation[row]
            if figure.capsule is not None and engine.world.entity_exists(figure.capsule):
                # upright and round: it never turns (nor leaves a 2D backend's plane)
                engine.physics.push(cmd.SetKinematicTarget(figure.capsule, position.copy(),
                                                           (1.0, 0.0, 0.0, 0.0), dt))
            if not figure.held:
                continue
            place = self._placement(position, orientation, figure.spec.scale)
            base = self.mixer.animators[entity].row
            for held in list(figure.held):
                if not engine.world.entity_exists(held.entity):
                    figure.held.remove(held)
                    continue
                bone = place @ world[base + held.node]
                rot = bone[:3, :3] / np.linalg.norm(bone[:3, :3], axis=0)
                at = bone[:3, 3] + rot @ held.offset
                quat = quat_multiply(matrix_to_quat(rot), held.rotation)
                try:
                    self._move(engine, held, at, quat, dt)
                except cmd.CommandError as exc:  # a bone posed out of the world (a scale
                    figure.held.remove(held)  # of 0, a far path): let go, and say so
                    self._messages.error(f"avatar {self._name(entity)!r} lets go of "
                                         f"{self._name(held.entity)!r}: {exc}")

    def _move(self, engine: Engine, held: _Held, at: np.ndarray, quat: np.ndarray,
              dt: float) -> None:
        if held.kind == "kinematic":
            engine.physics.push(cmd.SetKinematicTarget(held.entity, at, quat, dt))
        elif held.kind == "dynamic":  # put back each frame, moving as the hand does
            velocity = np.zeros(3) if held.last is None or dt <= 0 else (at - held.last) / dt
            engine.physics.set_pose(held.entity, at, quat)
            engine.physics.set_velocity(held.entity, velocity, np.zeros(3))
        else:
            row = engine.world.poses.row_of.get(held.entity)
            if row is not None:
                engine.world.poses.position[row] = at
                engine.world.poses.orientation[row] = quat
        held.last = at

    def _tell_scripts(self, event: AnimationEnded) -> None:
        """``onAnimationEnd`` in the avatar's own scripts and in scene scripts."""
        engine = self._engine
        if engine is None:
            return
        from services.scripting.runtime import ScriptRuntime

        runtime = engine.try_resource(ScriptRuntime)
        if runtime is None:
            return
        for script in list(runtime.scripts):
            if script.entity == event.avatar:
                runtime.call(script, "onAnimationEnd", event.clip)
            elif script.entity is None:
                runtime.call(script, "onAnimationEnd", runtime.kernel.handle(event.avatar),
                             event.clip)

    # -- control (Python and Lua) ---------------------------------------------------------
    def _figure(self, entity: int) -> _Figure:
        figure = self.figures.get(entity)
        if figure is None:
            engine = self._engine
            if engine is not None and entity in self._pending:
                self._pending.remove(entity)
                self._start(engine, entity)
                figure = self.figures.get(entity)
            if figure is None:
                raise KeyError(f"object {self._name(entity)!r} is not an avatar")
        return figure

    def hold(self, entity: int, target: int, bone: str,
             offset: Any = (0.0, 0.0, 0.0), rotation: Any = (1.0, 0.0, 0.0, 0.0)) -> None:
        """Bone ``bone`` of avatar ``entity`` carries object ``target`` at ``offset`` (m)
        and ``rotation`` in the bone's frame, until :meth:`release`."""
        figure = self._figure(entity)
        engine = self._engine
        assert engine is not None
        if target < 0 or not engine.world.entity_exists(target):
            raise ValueError(f"there is no such object to hold ({target})")
        if target in (entity, figure.capsule):  # it would chase its own hand away
            raise ValueError(f"avatar {self._name(entity)!r} cannot hold itself")
        node = self._bone(figure, bone)
        # finite, and a rotation: what reaches physics each frame
        offset, rotation = _finite(offset, 3, "offset"), _finite(rotation, 4, "rotation")
        if not any(rotation):
            raise ValueError("rotation must be a non-zero quaternion w, x, y, z")
        body = engine.world.try_component(target, Physical)
        kind = "visual" if body is None else (
            "kinematic" if body.kind == BodyKind.KINEMATIC else "dynamic")
        self.release(entity, target)
        figure.held.append(_Held(target, node, np.asarray(offset, np.float64),
                                 np.asarray(rotation, np.float64), kind))

    def release(self, entity: int, target: int) -> None:
        """Let go of ``target`` (a dynamic body falls, with the hand's velocity)."""
        figure = self._figure(entity)
        figure.held = [h for h in figure.held if h.entity != target]

    def drive_bone(self, entity: int, bone: str, position: Any, orientation: Any) -> None:
        """Hold ``bone`` at a world pose (a tracked hand); its parent and grandparent
        bend to reach it. Until :meth:`release_bone`."""
        figure = self._figure(entity)
        node = self._bone(figure, bone)
        parents = figure.model.parents
        if parents[node] < 0 or parents[parents[node]] < 0:  # (it was ignored, silently)
            raise ValueError(f"bone {bone!r} has no parent and grandparent to bend (a hand "
                             "driven by a tracker hangs below a forearm and an upper arm)")
        pose = self._checked(cmd.SetPose(entity, position, orientation))  # finite, a rotation
        figure.drives[node] = _Drive(node, np.asarray(pose.position),
                                     np.asarray(pose.orientation))

    def release_bone(self, entity: int, bone: str) -> None:
        figure = self._figure(entity)
        figure.drives.pop(self._bone(figure, bone), None)

    def bone_pose(self, entity: int, bone: str) -> tuple[np.ndarray, np.ndarray]:
        """World position and orientation of ``bone`` as drawn last frame."""
        figure = self._figure(entity)
        node = self._bone(figure, bone)
        engine = self._engine
        assert engine is not None
        t = engine.world.component_for_entity(entity, Transform)
        world, rows = self._posed
        if entity not in rows:  # not drawn yet: as its clips have it now
            world, _ = self.mixer.evaluate()
            rows = {entity: self.mixer.animators[entity].row}
        m = self._placement(t.position, t.orientation, figure.spec.scale) @ world[
            rows[entity] + node]
        rot = m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0)
        return m[:3, 3].copy(), matrix_to_quat(rot)

    def set_path(self, entity: int, points: list[Any], loop: bool = True) -> None:
        """Walk through ``points`` (world, m) in turn; an empty list stops walking."""
        figure = self._figure(entity)
        figure.path = [np.asarray(self._checked(cmd.SetPose(entity, p, (1, 0, 0, 0))).position)
                       for p in points]
        figure.path_loop = bool(loop)
        figure.waypoint = 0

    def _checked(self, pose: cmd.SetPose) -> cmd.SetPose:
        """A pose a script gave, inside the world (CommandError, a ValueError, if not: a
        path walked out of it would end in a capsule target physics refuses)."""
        assert self._engine is not None
        cmd.check_limits(pose, self._engine.physics.limits)
        return pose

    def _bone(self, figure: _Figure, bone: str) -> int:
        node = figure.model.node(str(bone))
        if node is None:
            close = difflib.get_close_matches(str(bone), figure.model.node_names, 1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ValueError(f"model {figure.spec.model!r} has no bone {bone!r}{hint}")
        return node

    def script_call(self, entity: int, method: str, args: list[Any]) -> Any:
        """Lua's ``avatar:method(...)`` (see :data:`engine.services.AVATAR_METHODS`)."""
        self._figure(entity)
        if method not in AVATAR_METHODS:
            raise ValueError(f"unknown avatar method {method!r}")
        first = args[0] if args else None
        if method in ("play", "queue", "blend", "stopAnimation", "animation"):
            return self._clip_call(entity, method, first, args)
        if method == "clips":
            return list(self.figures[entity].model.clip_names)
        if method == "setPath":
            if not isinstance(first, list):
                raise ValueError("expected a list of points {{x, y, z}, ...}")
            self.set_path(entity, first, bool(args[1]) if len(args) > 1 else True)
        elif method == "hold":
            self.hold(entity, _object_id(first), str(args[1]) if len(args) > 1 else "",
                      *self._hold_options(args[2] if len(args) > 2 else {}))
        elif method == "release":
            self.release(entity, _object_id(first))
        elif method == "driveBone":
            if len(args) < 3:
                raise ValueError("expected (bone, {x, y, z}, {w, x, y, z})")
            self.drive_bone(entity, str(first), args[1], args[2])
        elif method == "releaseBone":
            self.release_bone(entity, str(first))
        elif method == "bonePose":
            position, orientation = self.bone_pose(entity, str(first))
            return (*position.tolist(), *orientation.tolist())
        return None

    def _clip_call(self, entity: int, method: str, first: Any, args: list[Any]) -> Any:
        """The clip methods: play, queue, blend, stopAnimation and animation."""
        mixer = self.mixer
        timing = _timing(args[1] if len(args) > 1 and method in ("play", "queue", "blend")
                         else {})
        if method in ("play", "queue"):
            if not isinstance(first, str | dict):
                raise ValueError(f"expected a clip name, got {first!r}")
            if isinstance(first, dict) and method == "play":
                raise ValueError("expected a clip name (use blend{...} for weights)")
            getattr(mixer, method)(entity, first, **timing)
        elif method == "blend":
            if not isinstance(first, dict):
                raise ValueError("expected a table of weights, {Walk=0.7, Run=0.3}")
            mixer.blend(entity, first, **timing)
        elif method == "stopAnimation":
            if first is not None and not isinstance(first, dict):
                raise ValueError(f"options are a table {{fade=s}}, got {first!r}")
            fade = (first or {}).get("fade")
            if fade is not None and (isinstance(fade, bool) or not isinstance(fade, int | float)
                                     or not 0.0 <= fade < 1e6):
                raise ValueError(f"fade must be a number >= 0, got {fade!r}")
            mixer.stop(entity, fade)
        else:  # animation
            playing = mixer.playing(entity)
            if not playing:
                return None
            name, time, _ = max(playing, key=lambda p: p[2])
            return name, time
        return None

    @staticmethod
    def _hold_options(opts: Any) -> tuple[Any, Any]:
        if not isinstance(opts, dict):
            raise ValueError("options are a table {offset=, orientation=}")
        unknown = set(opts) - {"offset", "orientation"}
        if unknown:
            raise ValueError(f"unknown option {sorted(unknown)[0]!r} (offset, orientation)")
        offset = opts.get("offset", (0.0, 0.0, 0.0))
        turn = opts.get("orientation", (0.0, 0.0, 0.0))
        if not isinstance(turn, list | tuple) or len(turn) != 3 or not all(
                isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
                for x in turn):
            raise ValueError(f"orientation is 3 finite numbers (degrees), got {turn!r}")
        return offset, euler_to_quat(turn)


class AvatarsPlugin:
    """Animates the scene's avatars (``requestPlugin("avatars")``)."""

    name = PluginName.AVATARS

    def build(self, engine: Engine) -> None:
        engine.add_system(AvatarSystem())


def _finite(values: Any, n: int, what: str) -> tuple[float, ...]:
    """``n`` finite numbers (a script's or a saved state's), or ValueError naming ``what``."""
    if not isinstance(values, list | tuple | np.ndarray) or len(values) != n or not all(
            isinstance(x, int | float | np.floating) and not isinstance(x, bool)
            and math.isfinite(x) for x in values):
        raise ValueError(f"{what} must be {n} finite numbers, got {values!r}")
    return tuple(float(x) for x in values)


def _floats(values: Any) -> Any:
    """A vector as a tuple of plain floats (what a saved state holds)."""
    return tuple(float(x) for x in values)



def _timing(opts: Any) -> dict[str, Any]:
    """A clip call's options table {fade=s, speed=x, loop=bool}, checked."""
    if not isinstance(opts, dict):
        raise ValueError(f"options are a table {{fade=s, speed=x, loop=bool}}, got {opts!r}")
    unknown = set(opts) - {"fade", "speed", "loop"}
    if unknown:
        raise ValueError(f"unknown option {sorted(unknown)[0]!r} (fade, speed, loop)")
    if not isinstance(opts.get("loop", True), bool):
        raise ValueError(f"loop must be true or false, got {opts['loop']!r}")
    return {k: opts[k] for k in ("fade", "speed", "loop") if k in opts}

def _object_id(value: Any) -> int:
    """An object's entity id as a script passed it (a handle arrives as its id); -1 for
    anything else (true is not entity 1)."""
    return int(value) if isinstance(value, int) and not isinstance(value, bool) else -1
