"""Materials for the ODE backend: the (M, M) table of contact parameters per pair.

A pair's friction is the geometric mean of the two materials' (Coulomb,
``dContactApprox1``: ``mu`` is a coefficient), bounce and bounce velocity the
larger ones, softness (ODE ``soft_cfm``; 0 = rigid, 1e-3 to 1e-2 visibly soft, used
with the world ERP) the larger one. A :class:`MaterialPair` overrides any of them,
or disables the pair (``collide=False``).
"""

from __future__ import annotations

import numpy as np

from components import MaterialProps
from engine.physics.backend import MaterialPair
from engine.physics.ode3d import _ode


class MaterialTable:
    """Materials by index (as geoms carry them) and the pair table made from them."""

    def __init__(self) -> None:
        self.materials: list[MaterialProps] = []
        self._index: dict[tuple, int] = {}

    def index(self, m: MaterialProps) -> tuple[int, bool]:
        """The material's index, and whether it is new (the pair table must grow)."""
        sig = (m.name, m.friction, m.bounce, m.bounce_velocity, m.softness)
        idx = self._index.get(sig)
        if idx is not None:
            return idx, False
        for what, value in (("friction", m.friction), ("bounce", m.bounce),
                            ("bounce_velocity", m.bounce_velocity),
                            ("softness", m.softness)):
            if not value >= 0:
                raise ValueError(f"material {m.name!r}: {what} must be >= 0, got {value}")
        idx = len(self.materials)
        self.materials.append(m)
        self._index[sig] = idx
        return idx, True

    def pair_table(self, erp: float, pairs: list[MaterialPair]) -> np.ndarray:
        """The (M, M, 7) table ``_ode.World.set_pairs`` takes (columns ``PAIR_COLUMNS``)."""
        mats = self.materials
        fr = np.array([m.friction for m in mats])
        bo = np.array([m.bounce for m in mats])
        bv = np.array([m.bounce_velocity for m in mats])
        so = np.array([m.softness for m in mats])
        with np.errstate(invalid="ignore"):
            mu = np.sqrt(np.outer(fr, fr))
        mu[np.isnan(mu)] = 0.0  # 0 * inf: frictionless wins
        table = np.empty((len(mats), len(mats), 7))
        table[..., 0] = 1.0
        table[..., 2] = mu
        table[..., 3] = np.maximum.outer(bo, bo)
        table[..., 4] = np.maximum.outer(bv, bv)
        table[..., 5] = erp
        table[..., 6] = np.maximum.outer(so, so)
        names = [m.name for m in mats]
        for pair in pairs:
            ia = [i for i, n in enumerate(names) if n == pair.a]
            ib = [i for i, n in enumerate(names) if n == pair.b]
            for i in ia:
                for k in ib:
                    for r, c in ((i, k), (k, i)):
                        table[r, c, 0] = float(pair.collide)
                        if pair.friction is not None:
                            table[r, c, 2] = pair.friction
                        if pair.bounce is not None:
                            table[r, c, 3] = pair.bounce
                        if pair.softness is not None:
                            table[r, c, 6] = pair.softness
        mode = np.full(table.shape[:2], _ode.MODE_APPROX1, np.float64)
        mode += np.where(table[..., 3] > 0, _ode.MODE_BOUNCE, 0)
        mode += np.where(table[..., 6] > 0, _ode.MODE_SOFT, 0)
        table[..., 1] = mode
        return np.ascontiguousarray(table)
