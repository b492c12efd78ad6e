"""The 3D dynamics backend: ODE 0.16 through our own Cython extension (``_ode``).

The typed layer is split by concept like ``pymunk2d``: ``backend`` (the
:class:`OdeBackend`), ``shapes``, ``materials``, ``joints`` and ``values`` (what
is checked before it reaches ODE). Everything per step or per body (collision
callback, contact joints, contact impulses, the non-finite check, batch reads and
writes, the six-DOF drives) runs in C inside ``_ode``, with the GIL released around
collision and QuickStep.

Conventions beyond the protocol:

* Contacts: ``a`` is always a moving body; ``normal`` points from ``b`` into
  ``a`` (moving ``a`` along it by ``depth`` separates them); ``impulse`` is
  ``|f|·dt`` from the contact joint's feedback. Pairs where every body sleeps
  are not collided, so resting stacks report no contacts.
* A body's ODE frame sits at its centre of mass; poses and velocities in and
  out of the backend are those of the entity origin, converted in C.
* A body whose state turns non-finite in a step, or whose speed or spin passes
  ``_ode.MAX_BODY_SPEED`` (an exploding joint or motor), is put back at its last
  good pose, at rest, and disabled; it is reported by ``take_faults`` and the
  world steps on. Inputs that would cause that (velocities past the limit, a
  force or torque that would reach it in one step) are refused with
  ``ValueError`` before they reach ODE, which aborts the process on a non-finite
  rotation.
* Sleeping is :mod:`engine.physics.sleep`'s rule with ODE's own auto-disable
  off: the rule reads every body's velocity after the step and disables the
  islands it finds quiet (at zero velocity). ODE's island builder enables a
  disabled body that an enabled one touches or is jointed to, which is the
  wake-up. ``set_collision_enabled`` disables the body's geoms (ODE skips them
  in collision and ray casts); ``set_gravity_enabled`` is ODE's gravity mode.
"""

from engine.physics.ode3d.backend import OdeBackend

__all__ = ["OdeBackend"]
