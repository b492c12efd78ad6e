"""The ``Session`` block: where a run's session log goes and what it records (the session
plugin, systems.session, writes it), a scene-wide setting declared on the block registry."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare


@dataclass(frozen=True, slots=True)
class SessionSettings:
    """A scene's ``Session`` block."""

    folder: str = ""
    name: str = ""
    chair: str | None = None
    pose_rate: float = 10.0
    ground: tuple[str, ...] = ("floor",)
    end_run: bool = True


def build_session(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Session`` block: the scene's settings of the session log."""
    ctx.scene("settings")["Session"] = SessionSettings(
        folder=str(v["Folder"]), name=str(v["Name"]), chair=v["Chair"],
        pose_rate=float(v["PoseRate"]), ground=tuple(v["Ground"]), end_run=bool(v["EndRun"]))
    return []


_DEFAULT = SessionSettings()
SESSION_BLOCK = declare(BlockDeclaration(
    "Session", inside=("Scene",), build=build_session, entity=False, once=True, named=False,
    doc="a session log: one JSON-lines file per run with the time, task events, grasps, the "
    "chair's pose and collisions, anomaly switches (the session plugin)", keys=(
        Key("Folder", "string", _DEFAULT.folder, "the folder session logs go to, relative to "
            "the working directory (default: sessions/ there; never inside the content "
            "folder, never out of the working directory); colosseum run --sessions DIR wins",
            example='"sessions"'),
        Key("Name", "string", _DEFAULT.name, "the log file's name before its date and time "
            "(a name, not a path; default: the content folder's name)", example='"stroke"'),
        Key("Chair", "ref", _DEFAULT.chair, "the wheelchair whose pose is logged at PoseRate "
            "and whose collisions are logged (its chassis and what is jointed to it)",
            ref="Object", example='"wheelchair"'),
        Key("PoseRate", "float", _DEFAULT.pose_rate, "Hz: how often the chair's pose is "
            "logged"),
        Key("Ground", "stringvector", _DEFAULT.ground, "objects the chair rolls on: touching "
            "them is not a collision", ref="Object", example='["floor" "ramp"]'),
        Key("EndRun", "bool", int(_DEFAULT.end_run), "1: the run stops when a script ends "
            "the session (emit(\"session_end\", {reason = ...}))"),
    )))
