"""The scene's anomaly blocks (``DoubleVision``, ``Hemianopia``, ...; engine.anomalies),
declared on the block registry as blocks that fill a scene-wide setting (the scene's
anomalies) rather than make an entity.

The schema checks types; the build checks what the vocabulary adds: a severity out of its
range is clamped with a warning at its line (the scene still runs); two blocks with one ID
are an error. An ``Input`` binding is checked when the anomalies plugin binds it, as a
Controller's is (a bad one is told with its scene line and ignored).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from components.blocks import BlockDeclaration, Build, BuildContext, Key, declare
from engine.anomalies import (
    ANOMALIES,
    COMMON_DOCS,
    EYES,
    ONSET_DEFAULT,
    AnomalyKind,
    AnomalySpec,
    check_onset,
    check_value,
)


def _builder(kind: AnomalyKind) -> Build:
    """The build of ``kind``'s block: its checked spec added to the scene's anomalies."""
    def build(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
        anomaly_id = ctx.owner
        first = ctx.claim("anomaly", anomaly_id)
        if first is not None:
            ctx.error(None, f"a second anomaly '{anomaly_id}' (the first is at {first}); "
                      "give one an ID of its own")
            return []
        severity = {}
        for param in kind.params:
            value = v[param.key]
            severity[param.key], problem = check_value(
                kind, param.key, list(value) if isinstance(value, tuple) else value)
            if problem:
                ctx.problem(param.key, problem, warning=True)
        onset, problem = check_onset(float(v["Onset"]))
        if problem:
            ctx.problem("Onset", problem, warning=True)
        binding = v["Input"]
        ctx.scene("anomalies").append(AnomalySpec(
            anomaly_id, kind.name, severity, bool(v["Enabled"]), onset, str(v["Eye"]),
            None if binding is None else str(binding), ctx.where("Input")))
        return []
    return build


def _keys(kind: AnomalyKind) -> tuple[Key, ...]:
    """Its common keys, then a key per severity parameter with its range in the docs."""
    keys = [Key("ID", "string", "", COMMON_DOCS["ID"]),
            Key("Enabled", "bool", 1, COMMON_DOCS["Enabled"]),
            Key("Onset", "float", ONSET_DEFAULT, COMMON_DOCS["Onset"]),
            Key("Eye", "enum", "both", COMMON_DOCS["Eye"], allowed=EYES),
            Key("Input", "string", None, COMMON_DOCS["Input"])]
    for p in kind.params:
        doc = f"{p.doc} ({p.range_text()})"
        if p.choices:
            keys.append(Key(p.key, "enum", p.default, doc, allowed=p.choices))
        elif p.size > 1:
            keys.append(Key(p.key, "vector", p.default, doc, lengths=(p.size,)))
        else:
            keys.append(Key(p.key, "float", p.default, doc))
    return tuple(keys)


#: A block per anomaly, in the order of the vocabulary (the scene's anomalies keep it).
ANOMALY_BLOCKS = tuple(declare(BlockDeclaration(
    kind.block, _keys(kind), _builder(kind), f"a visual anomaly: {kind.doc} "
    "(engine.anomalies)", inside=("Scene",), unnamed=kind.name, entity=False))
    for kind in ANOMALIES.values())
