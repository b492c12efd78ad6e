"""Components are plain data and cheap to import."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import components


def test_importing_components_loads_no_engine_library():
    code = ("import sys, components; heavy = {'esper', 'moderngl', 'lupa', 'pymunk', 'openal', "
            "'trimesh', 'soundfile', 'engine'}; "
            "print(sorted(m for m in heavy if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_component_is_a_slotted_dataclass_without_methods():
    for name in components.__all__:
        cls = getattr(components, name)
        assert dataclasses.is_dataclass(cls), name
        assert hasattr(cls, "__slots__"), name
        own = {k for k, v in vars(cls).items() if callable(v) and not k.startswith("__")}
        assert own == set(), f"{name} has behaviour: {own}"
