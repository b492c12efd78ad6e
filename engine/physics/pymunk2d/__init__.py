"""pymunk in 2D: a DynamicsBackend for prototyping in the world's X–Z side view.

Select it with ``--backend pymunk`` or :func:`engine.physics.create_backend`
(``"pymunk"``). The same content runs as under ODE, flattened onto X–Z: motion
and rotation about Y are simulated, Y positions and out-of-plane tilts are kept
as authored, and anything the plane cannot hold is logged once per object on
``colosseum.physics.pymunk``. Beyond the protocol it offers what the ODE backend
offers, with the same meaning: ``add_static_plane``, ``is_sleeping``, ``has_joint``,
``keys``, ``take_faults``, and the sleep rule's state (``sleep_states``,
``set_sleep_state``). It uses pymunk's public API, and for the reads and writes of
every step the chipmunk functions pymunk's cffi library exports (``pymunk.cp``; the
same ones ``pymunk.batch`` calls, their C types checked at import; ``_rows``).
"""

from engine.physics.pymunk2d.backend import PymunkBackend

__all__ = ["PymunkBackend"]
