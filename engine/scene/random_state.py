"""The scene's random generator in a saved state (``World { RandomState }``).

``randInterval``/``randNormal`` in text a script spawns draw from the engine's generator
(seeded by ``--seed``); a saved state keeps where it stood, so the continued run draws
the same numbers as the run that never stopped.

>>> import numpy as np
>>> g = np.random.default_rng(7); _ = g.random(3)
>>> h = np.random.default_rng(0); restore(h, text(g)); bool(h.random() == g.random())
True
"""

from __future__ import annotations

import numpy as np

#: What RandomState holds, for the message when it does not.
FORMAT = "PCG64 STATE INC HAS_UINT32 UINTEGER (five words, four integers)"


def text(rng: np.random.Generator) -> str | None:
    """The generator's state as one line (None for a generator other than PCG64)."""
    state = rng.bit_generator.state
    if state.get("bit_generator") != "PCG64":
        return None
    inner = state["state"]
    return f"PCG64 {inner['state']} {inner['inc']} {state['has_uint32']} {state['uinteger']}"


def parse(line: str) -> dict[str, object]:
    """The bit generator state a line of :func:`text` describes. Raises ValueError."""
    words = line.split()
    if len(words) != 5 or words[0] != "PCG64":
        raise ValueError(f"RandomState must be {FORMAT}, got {line!r}")
    try:
        state, inc, has_uint32, uinteger = (int(w) for w in words[1:])
    except ValueError:
        raise ValueError(f"RandomState must be {FORMAT}, got {line!r}") from None
    if not (0 <= state < 2**128 and 0 <= inc < 2**128 and has_uint32 in (0, 1)
            and 0 <= uinteger < 2**32):
        raise ValueError(f"RandomState numbers out of range: {line!r}")
    return {"bit_generator": "PCG64", "state": {"state": state, "inc": inc},
            "has_uint32": has_uint32, "uinteger": uinteger}


def restore(rng: np.random.Generator, line: str) -> None:
    rng.bit_generator.state = parse(line)
