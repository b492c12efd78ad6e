"""An ``Object``'s own parts: its pose, its ``VisualAttributes`` and ``PhysicalAttributes``
(shapes, models, mass, material, textures) and a saved state's sleep keys, made into
Name, Transform, Visual, Physical and Trigger, every value checked at its line (the
world's bounds, speeds, masses). The blocks and keys features declare on an Object are
built beside them by the registry's loop (engine.scene.factory)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from components import MaterialProps, Name, Physical, Shape, Transform, Trigger, Visual
from components.hand import HAND_SIZE, PALM_SIZE
from engine.assets import AssetError, Assets, nodes_name
from engine.assets.geometry import convex_hull
from engine.physics.backend import (
    MAX_DENSITY,
    MAX_MASS,
    MAX_SPEED,
    WORLD_EXTENT,
    SleepState,
    metres,
)
from engine.rotation import UNIT_ROUNDING, euler_to_quat, rotate
from engine.scene.db import VECTOR, Value
from engine.scene.diagnostics import ERROR, WARNING, Diagnostic, Loc, Reporter
from engine.scene.reader import Reader as _Reader
from engine.scene.reader import floats

#: Shared defaults (tuples: immutable, so every shape and pose may hold the same one).
_ORIGIN = (0.0, 0.0, 0.0)
_IDENTITY = (1.0, 0.0, 0.0, 0.0)
DEFAULT_SIZES = {"sphere": (1.0,), "box": (1.0, 1.0, 1.0), "capsule": (0.5, 1.0),
                 "cylinder": (0.5, 1.0), "plane": ()}


def _fingered(hand: Value) -> bool:
    """Whether a ``Hand`` block asks for fingers (its palm is then smaller than a hand)."""
    return any(e.key == "Fingers" and bool(e.value.data) for e in hand.data.entries)


def _fields(m: MaterialProps) -> dict[str, Any]:
    return {k: getattr(m, k) for k in m.__slots__}


def _color(c: tuple[float, ...]) -> tuple[float, float, float, float]:
    c = floats(c)
    return c if len(c) == 4 else (*c, 1.0)


def _copy_shape(s: Shape) -> Shape:
    return Shape(s.kind, s.size, s.offset, s.rotation, s.vertices, s.faces)


def _model_shape(triangles: tuple[np.ndarray, np.ndarray], scale: tuple[float, ...],
                 method: str) -> Shape:
    """A model's triangles at ``scale`` as the ParseMethod's shape: the mesh itself, its
    convex hull, or the box or sphere around it (centred on the bounds' centre)."""
    vertices = triangles[0] * np.asarray(scale, np.float64)
    if method == "TriangleMesh":
        return Shape("mesh", (), vertices=vertices, faces=triangles[1].astype(np.int32))
    if method == "ConvexHull":
        hull_vertices, hull_faces = convex_hull(vertices)
        return Shape("hull", (), vertices=hull_vertices, faces=hull_faces.astype(np.int32))
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    center = tuple(float(c) for c in (lo + hi) / 2)
    if method == "Box":
        return Shape("box", tuple(float(e) for e in hi - lo), offset=center)
    radius = float(np.linalg.norm(vertices - (lo + hi) / 2, axis=1).max())
    return Shape("sphere", (radius,), offset=center)


def _model_name(gr: _Reader) -> str:
    """A Geometry's model: its File, or only the File's ``Nodes`` or ``Mesh``."""
    if gr.has("Nodes"):
        return nodes_name(gr("File"), gr("Nodes"))
    return nodes_name(gr("File"), [gr("Mesh")], mesh=True) if gr.has("Mesh") else gr("File")


def _own_bits(shape: Shape, gr: _Reader) -> Shape:
    """``shape`` with the Geometry block's own ``Category``/``Mask``, where it gives them."""
    if gr.has("Category"):
        shape.category = int(gr("Category"))
    if gr.has("Mask"):
        shape.mask = int(gr("Mask"))
    return shape


def _primitive(gr: _Reader, size: Any) -> Shape:
    """A primitive Shape from the format's sizes (diameters) to the component's (radii)."""
    kind = gr("Primitive") or "box"
    given = gr("Size") if gr.has("Size") else size
    s = floats(given) if given is not None else DEFAULT_SIZES[kind]
    if kind == "sphere":
        dims: tuple[float, ...] = (s[0] / 2,)
    elif kind == "box":
        dims = s if len(s) == 3 else (s[0],) * 3
    else:
        dims = (s[0] / 2, s[1] if len(s) > 1 else s[0])
    offset = floats(gr("Offset")) if gr.has("Offset") else _ORIGIN
    rotation = euler_to_quat(gr("Orientation")) if gr.has("Orientation") else _IDENTITY
    return Shape(kind, dims, offset, rotation)


class ObjectBuilder:
    """The part of the scene builder that makes an Object's own components; the builder
    (engine.scene.factory) holds this state and adds what the registry declares on it."""

    folder: Path
    report: Reporter
    assets: Assets
    #: Told problems that leave a part out (an asset that failed) and let the run go on.
    problems: list[Diagnostic]
    materials: dict[str, MaterialProps]
    #: What is built so far (the materials' densities are read from it).
    spec: Any
    #: Half the side of the cube every point of the file must lie in (m), once known.
    extent: float | None
    own_poses: dict[str, tuple[tuple[float, ...], tuple[float, ...]]]
    physical_ids: set[str]
    static_ids: set[str]
    sleep: dict[str, SleepState]

    # -- assets --------------------------------------------------------------
    def problem(self, error: AssetError, outcome: str) -> None:
        """Tell of an asset that failed, at its scene line, and what was left out."""
        self.assets.mark_told(error)
        where = error.where or Loc(str(self.folder), 0, 0)
        self.problems.append(Diagnostic(where.path, where.line, where.col, ERROR,
                                        f"{error.message}; {outcome}"))

    def sound_file(self, r: _Reader, key: str, outcome: str) -> str | None:
        """``r(key)``, a sound file, if it can be played; else None, told as a problem."""
        file = r(key)
        if file is not None:
            try:
                self.assets.sound(file, r.value(key).loc, self.folder)
            except AssetError as exc:
                self.problem(exc, outcome)
                return None
        return file

    def quaternion(self, r: _Reader, key: str) -> tuple[float, ...]:
        """``r(key)`` as a unit quaternion (one already unit kept bit-exact, as a saved
        state wrote it); all zeros is an error."""
        quat = floats(r(key))
        norm = math.sqrt(sum(q * q for q in quat))
        if norm == 0.0:
            self.report.error(r.value(key).loc, f"{key} must not be all zeros")
            return _IDENTITY
        return quat if abs(norm - 1.0) <= UNIT_ROUNDING else tuple(q / norm for q in quat)

    def orientation(self, r: _Reader) -> tuple[float, ...]:
        """The exact ``Quaternion`` where one is written, else ``Orientation`` (degrees)."""
        return self.quaternion(r, "Quaternion") if r.has("Quaternion") else euler_to_quat(
            r("Orientation"))

    def object_parts(self, r: _Reader, oid: str) -> tuple[list[Any], bool]:
        """The object's own components, and whether it has a body."""
        self.inside(r.value("Position"), "Position")
        self.fits(r.value("Size"))
        for key in ("Velocity", "AngularVelocity", "Spin"):
            self.slow_enough(r, key)
        position = floats(r("Position"))
        quat = self.orientation(r)
        angular = tuple(floats(r("Spin"))) if r.has("Spin") else tuple(
            map(math.radians, r("AngularVelocity"))) if r.has("AngularVelocity") else _ORIGIN
        comps: list[Any] = [Name(oid), Transform(position, quat, r("Velocity"), angular)]
        size = r("Size")
        hand_blk = r.value("Hand")
        if hand_blk is not None and size is None:  # a hand's body is a hand-sized box
            size = PALM_SIZE if _fingered(hand_blk) else HAND_SIZE
        vis_blk, phys_blk = r.value("VisualAttributes"), r.value("PhysicalAttributes")
        bare = vis_blk is None and phys_blk is None
        vis = _Reader(vis_blk.data if vis_blk else None, "Visual")
        phys = _Reader(phys_blk.data if phys_blk else None, "Physical")
        visual_shapes, model, scale = self.visual_geometry(vis, size)
        if vis_blk is not None or bare:
            if not visual_shapes and model is None:
                visual_shapes = self.physical_shapes(phys, size, (), None, (1.0,) * 3,
                                                     position, quat)[0]
            comps.append(Visual(
                shapes=visual_shapes, model=model, scale=scale,
                color=_color(vis("Color")), texture=self.texture(vis),
                shader_state=vis("ShaderState"), shadower=bool(vis("Shadower")),
                shadowed=bool(vis("Shadowed")), visible=bool(vis("Visible"))))
        if phys_blk is not None or bare:
            body = self.physical(r, phys, size, visual_shapes, model, scale, position, quat)
            comps.append(body)
            if phys("Trigger"):
                comps.append(Trigger(mask=int(phys("Mask"))))
            self.physical_ids.add(oid)
            if body.kind == "static":
                self.static_ids.add(oid)
            if any(map(r.has, ("Asleep", "SleepVelocity", "SleepTimer", "SleepReference",
                               "RestSteps", "RestSlid", "RestForce", "RestPreloaded"))):
                self.sleep[oid] = self.sleep_spec(r)
        self.own_poses[oid] = (position, quat)
        return comps, phys_blk is not None or bare

    def visual_geometry(self, vis: _Reader, size: Any
                        ) -> tuple[list[Shape], str | None, tuple[float, float, float]]:
        """Primitives and the model drawn (loaded now, so a bad one skips the object and
        the renderer finds it in the cache)."""
        shapes: list[Shape] = []
        model, scale = None, (1.0, 1.0, 1.0)
        for g in vis.blocks("Geometry"):
            gr = _Reader(g, "Geometry")
            if gr.has("File"):
                if model is None:
                    model, scale = _model_name(gr), floats(gr("Scale"))
                    self.assets.model(model, gr.value("File").loc, self.folder)
            elif gr.has("Primitive") and gr("Primitive") != "plane":
                shapes.append(_primitive(gr, size))
        return shapes, model, scale

    def limited(self, value: Value, key: str, most: float, unit: str) -> None:
        """Report a Mass or Density not positive, or past what any body may have."""
        if not (value.data > 0 and math.isfinite(value.data)):
            self.report.error(value.loc, f"{key} must be positive, got {value.data:g}")
        elif value.data > most:
            self.report.error(value.loc, f"{key} {value.data:g} {unit} is past the most a "
                                         f"body may have ({most:g} {unit})")

    def physical(self, r: _Reader, phys: _Reader, size: Any, visual_shapes: list[Shape],
                 model: str | None, scale: tuple[float, ...], position: tuple[float, ...],
                 quat: tuple[float, ...]) -> Physical:
        shapes, has_plane = self.physical_shapes(phys, size, visual_shapes, model, scale,
                                                 position, quat)
        for key, most, unit in (("Mass", MAX_MASS, "kg"), ("Density", MAX_DENSITY, "kg/m³")):
            value = phys.value(key)
            if value is not None:
                self.limited(value, key, most, unit)
        mat_name = str(phys("Material"))
        material = self.materials.get(mat_name) or MaterialProps(name=mat_name)
        if phys.has("Density"):
            material = MaterialProps(**{**_fields(material), "density": float(phys("Density"))})
        if phys.has("Mass"):
            mass: float | None = float(phys("Mass"))
        elif phys.has("Density") or mat_name in self.spec.dense_materials:
            mass = None
        else:
            mass = 1.0
        kind = "dynamic"
        if has_plane or not r("Dynamic"):
            kind = "static"
        elif r("Kinematic"):
            kind = "kinematic"
        if phys("Trigger"):  # detects what its Mask names; nothing collides with it
            return Physical(kind="kinematic" if r("Kinematic") else "static", mass=mass,
                            shapes=shapes, material=material, category=0, mask=0)
        return Physical(kind=kind, mass=mass, shapes=shapes, material=material,
                        linear_damping=float(phys("LinearDamping")),
                        angular_damping=float(phys("AngularDamping")),
                        can_sleep=bool(phys("CanSleep")), category=int(phys("Category")),
                        mask=int(phys("Mask")), gravity=bool(phys("Gravity")),
                        gravity_factor=self.gravity_factor(phys),
                        **self.mass_frame(phys))

    def gravity_factor(self, phys: _Reader) -> float:
        """``GravityFactor``, finite and not too large (told at its number, else 1)."""
        factor = float(phys("GravityFactor"))
        if not math.isfinite(factor) or abs(factor) > 1e3:
            self.report.error(phys.value("GravityFactor").loc, f"GravityFactor must be a "
                              f"finite number from -1000 to 1000, got {factor:g}")
            return 1.0
        return factor

    def mass_frame(self, phys: _Reader) -> dict[str, Any]:
        """``CenterOfMass``, ``Inertia`` and ``InertiaOrientation`` as Physical fields; a
        centre not finite or a moment negative or not finite is told at its number and
        left to the shapes. A moment of 0 is infinite: the body never turns about that
        axis (as KHR_physics_rigid_bodies says)."""
        out: dict[str, Any] = {}
        for key, ok, need in (("CenterOfMass", math.isfinite, "finite numbers of metres"),
                              ("Inertia", lambda x: 0 <= x < math.inf,
                               "moments of kg*m^2, 0 or more (0: infinite)")):
            value = phys.value(key)
            if value is None or value.kind != VECTOR:
                continue
            bad = next((item for item in value.data if not ok(item.data)), None)
            if bad is not None:
                self.report.error(bad.loc, f"{key} must be {need}, got {bad.data:g}")
                continue
            out["center_of_mass" if key == "CenterOfMass" else "inertia"] = floats(phys(key))
        if "inertia" in out:
            out["inertia_rotation"] = euler_to_quat(phys("InertiaOrientation"))
        elif phys.has("InertiaOrientation") and not phys.has("Inertia"):
            self.told(phys.value("InertiaOrientation").loc, "InertiaOrientation turns the "
                      "axes of Inertia's moments; without Inertia it does nothing", WARNING)
        self.inside(phys.value("CenterOfMass"), "CenterOfMass")
        return out

    def physical_shapes(self, phys: _Reader, size: Any, visual_shapes: Any, model: str | None,
                        scale: tuple[float, ...], position: tuple[float, ...],
                        quat: tuple[float, ...]) -> tuple[list[Shape], bool]:
        shapes: list[Shape] = []
        has_plane = False
        for g in phys.blocks("Geometry"):
            gr = _Reader(g, "Geometry")
            self.fits(gr.value("Size"))
            self.inside(gr.value("Offset"), "Offset")
            if gr.has("File") or gr.has("ParseMethod"):
                file_v = gr.value("File")
                file, fscale = (_model_name(gr), floats(gr("Scale"))) if file_v else (model,
                                                                                     scale)
                loc = file_v.loc if file_v else g.loc
                if file is None:
                    self.report.error(loc, "ParseMethod needs a model: give File here or in "
                                           "VisualAttributes Geometry")
                    continue
                shape = self.mesh_shape(file, fscale, gr("ParseMethod") or "ConvexHull", loc)
                shape.offset = floats(gr("Offset"))
                shape.rotation = euler_to_quat(gr("Orientation"))
                shapes.append(_own_bits(shape, gr))
            elif gr("Primitive") == "plane":
                has_plane = True
                normal = rotate(quat, (0.0, 0.0, 1.0))
                d = sum(n * p for n, p in zip(normal, position, strict=True))
                shapes.append(Shape("plane", (*normal, d)))
            else:
                shapes.append(_own_bits(_primitive(gr, size), gr))
        if not shapes:
            if visual_shapes:
                shapes = [_copy_shape(s) for s in visual_shapes]
            elif model is not None:
                shapes = [self.mesh_shape(model, scale, "Box", phys.block.loc if phys.block
                                          else Loc("", 0, 0))]
            else:
                shapes = [_primitive(_Reader(None, "Geometry"), size)]
        return shapes, has_plane

    def model(self, r: _Reader, key: str) -> str | None:
        """``r(key)``, a model file, if it can be read; else None, told as a problem."""
        file = r(key)
        if file is not None:
            try:
                self.assets.model(file, r.value(key).loc, self.folder)
            except AssetError as exc:
                self.problem(exc, "the object keeps its own look")
                return None
        return file

    def texture(self, vis: _Reader) -> str | None:
        """The Visual's texture file; one that cannot be read is told here (the renderer
        draws a checker in its place, so the author sees which surface lost it)."""
        file = vis("Texture")
        if file is not None:
            try:
                self.assets.image(file, vis.value("Texture").loc, self.folder)
            except AssetError as exc:
                self.problem(exc, "drawn with a checker instead")
        return file

    def mesh_shape(self, file: str, scale: tuple[float, ...], method: str, loc: Loc) -> Shape:
        """A physics shape from a model at ``scale`` (made once per file, scale and method;
        each body gets its own Shape). Raises AssetError for a model or hull that fails."""
        model = self.assets.model(file, loc, self.folder)
        path = self.assets.resolve(file, self.folder)
        action = ("build a convex hull of model" if method == "ConvexHull"
                  else "make a physics shape of model")
        made = self.assets.derived(("shape", path, scale, method), action, file, path,
                                   lambda: _model_shape(model.triangles(), scale, method), loc)
        return _copy_shape(made)

    def told(self, loc: Loc, message: str, severity: str = ERROR) -> None:
        """A problem with a model's content (not the text): told, the run goes on."""
        self.problems.append(Diagnostic(loc.path, loc.line, loc.col, severity, message))

    def sleep_spec(self, r: _Reader) -> SleepState:
        """An object's saved sleep-rule state, so a loaded state falls asleep on time."""
        if not r("SleepTimer") >= 0:
            self.report.error(r.value("SleepTimer").loc, "SleepTimer must not be negative")
        if r.has("SleepTimer") and not r.has("SleepReference"):
            self.report.error(r.value("SleepTimer").loc, "SleepTimer needs the "
                              "SleepReference its quiet stretch began with")

        def velocity(key: str) -> np.ndarray | None:
            if not r.has(key):
                return None
            v = np.array(r(key), np.float64)
            v[3:] = np.radians(v[3:])  # written in deg/s, like AngularVelocity
            return v

        steps = int(r("RestSteps"))
        if not 0 <= steps <= 2:
            self.report.error(r.value("RestSteps").loc, "RestSteps must be 0, 1 or 2")
        force = r("RestForce")
        return SleepState(bool(r("Asleep")), velocity("SleepVelocity"),
                          max(float(r("SleepTimer")), 0.0), velocity("SleepReference"),
                          min(max(steps, 0), 2), bool(r("RestSlid")),
                          None if force is None else np.array(floats(force)),
                          bool(r("RestPreloaded")))

    # -- the world's bounds, scene-level entities -----------------------------
    def inside(self, value: Value | None, what: str) -> None:
        """Report a point the file wrote (a VECTOR whose first three numbers are x y z)
        outside the world, at the number that is."""
        if value is None or value.kind != VECTOR:
            return
        extent = self.extent or WORLD_EXTENT
        for axis, item in zip("xyz", value.data, strict=False):
            if abs(item.data) > extent:
                self.report.error(item.loc, f"{what} {axis} = {item.data:g} is outside the "
                                  f"world ({metres(extent)}; World {{ Extent }} sets it)")
                return

    def fits(self, size: Value | None) -> None:
        """Report a Size the file wrote that is not positive or larger than the world (a
        body's bounding box must stay in ODE's range)."""
        if size is None or size.kind != VECTOR:
            return
        extent = self.extent or WORLD_EXTENT
        for item in size.data:
            if not item.data > 0:
                self.report.error(item.loc, f"Size must be positive, got {item.data:g}")
                return
            if item.data > extent:
                self.report.error(item.loc, f"Size {item.data:g} m is larger than the world "
                                            f"({metres(extent)}; World {{ Extent }} sets it)")
                return

    def slow_enough(self, r: _Reader, key: str) -> None:
        """Report a velocity the file wrote that no backend can take."""
        value = r.value(key)
        if value is None or value.kind != VECTOR:
            return
        numbers = [item.data for item in value.data]
        speed = math.hypot(*(map(math.radians, numbers) if key == "AngularVelocity"
                             else numbers))
        if speed > MAX_SPEED:
            unit = "rad/s" if key == "AngularVelocity" else "m/s"
            self.report.error(value.loc, f"{key} is {speed:g} {unit}, over the limit of "
                                         f"{MAX_SPEED:g} {unit}")
