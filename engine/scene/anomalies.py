"""The scene's anomaly blocks (``DoubleVision``, ``Hemianopia``, ...; engine.anomalies) as
checked specs.

The schema checks types; this module checks what the vocabulary adds: a severity out of
its range is clamped with a warning at its line (the scene still runs); two blocks with one
ID are an error. An ``Input`` binding is checked when the anomalies plugin binds it, as a
Controller's is (a bad one is told with its scene line and ignored).
"""

from __future__ import annotations

from collections.abc import Callable

import engine.scene.schema as sc
from engine.anomalies import ANOMALIES, AnomalySpec, check_onset, check_value
from engine.scene.db import Block
from engine.scene.diagnostics import WARNING, Diagnostic, Loc, Reporter


def read_anomalies(blocks: Callable[[str], list[Block]], report: Reporter,
                   warnings: list[Diagnostic]) -> list[AnomalySpec]:
    """Every anomaly block (``blocks(name)`` gives a top-level key's blocks), in the order
    of the vocabulary, then of the file; errors go to ``report``, warnings (clamped values,
    which leave the scene runnable) to ``warnings``."""

    def warn(loc: Loc, message: str) -> None:
        warnings.append(Diagnostic(loc.path, loc.line, loc.col, WARNING, message))

    specs: list[AnomalySpec] = []
    seen: dict[str, Loc] = {}
    for kind in ANOMALIES.values():
        defaults = {key: f.default for key, f in sc.SCHEMAS[kind.block].items()}
        for block in blocks(kind.block):
            written = {e.key: e.value for e in block}  # the last one written wins
            values = {**defaults, **{key: v.py() for key, v in written.items()}}
            where = {key: v.loc for key, v in written.items()}
            anomaly_id = str(values["ID"]) or kind.name
            first = seen.setdefault(anomaly_id, block.loc)
            if first is not block.loc:
                report.error(block.loc, f"a second anomaly '{anomaly_id}' (the first is at "
                                        f"{first.path}:{first.line}:{first.col}); give one "
                                        "an ID of its own")
                continue
            severity = {}
            for param in kind.params:
                severity[param.key], problem = check_value(kind, param.key, values[param.key])
                if problem:
                    warn(where.get(param.key, block.loc), problem)
            onset, problem = check_onset(float(values["Onset"]))
            if problem:
                warn(where.get("Onset", block.loc), problem)
            binding = values["Input"]
            loc = where.get("Input", block.loc)
            specs.append(AnomalySpec(anomaly_id, kind.name, severity, bool(values["Enabled"]),
                                     onset, str(values["Eye"]),
                                     None if binding is None else str(binding),
                                     f"{loc.path}:{loc.line}"))
    return specs
