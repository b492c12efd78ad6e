"""Skeletal animation: clips sampled, blended and composed for every avatar at once
(:mod:`engine.animation.mixer`), the CPU skinning reference (:mod:`.skinning`) and two-bone
inverse kinematics (:mod:`.ik`).

The data comes from :mod:`engine.assets.skinned` (glTF files); the avatars plugin
(``systems/avatars.py``) drives it from scene files and scripts; the renderer skins the
meshes on the GPU with the palettes it produces.
"""

from engine.animation.library import ClipInfo, Library, Rig
from engine.animation.mixer import (
    AnimationEnded,
    AnimationError,
    Animator,
    ClipSettings,
    Mixer,
    Palettes,
)

__all__ = ["AnimationEnded", "AnimationError", "Animator", "ClipInfo", "ClipSettings",
           "Library", "Mixer", "Palettes", "Rig"]
