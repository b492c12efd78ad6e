"""Components: plain data attached to entities. No behaviour, no heavy imports.

One module per feature; every component is re-exported here. Units and axes
everywhere: metres, kilograms, seconds; angles in degrees where an author
writes them (the scene format), radians inside the engine; Z is up.
Orientations are unit quaternions ``(w, x, y, z)``. The vocabularies
(:class:`~components.joint.JointKind`, :class:`~components.physical.BodyKind`,
:class:`~components.shape.ShapeKind`) live beside the component that uses them.
"""

import components.avatar_block  # noqa: E402, F401, I001  (declares the Avatar block)
from components.avatar import Avatar, ClipSpec, Hold
from components.camera import Camera
from components.controller import Controller
from components.display import Display, Headset
from components.hand import Graspable, Hand, HandState
from components.joint import Joint
from components.light import Light
from components.name import Name
from components.physical import MaterialProps, Physical
from components.script import Script
from components.session import SessionSettings
from components.shape import Shape
from components.sound import Sound
from components.transform import Transform
from components.trigger import Trigger
from components.user import UserOwned
from components.visual import Visual
from components.wheelchair import Wheelchair

__all__ = [
    "Avatar",
    "Camera",
    "ClipSpec",
    "Controller",
    "Display",
    "Graspable",
    "Hand",
    "HandState",
    "Headset",
    "Hold",
    "Joint",
    "Light",
    "MaterialProps",
    "Name",
    "Physical",
    "Script",
    "SessionSettings",
    "Shape",
    "Sound",
    "Transform",
    "Trigger",
    "UserOwned",
    "Visual",
    "Wheelchair",
]
