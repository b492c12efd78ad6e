"""Lab Streaming Layer where it cannot load: one clear message naming what to install, the
device (or output) left out, and the run going on — never a traceback.

Two ways it is missing on a lab machine: pylsl not installed at all (made so here by
hiding the module from the import system), and pylsl installed without the liblsl it
loads (the real pylsl package, copied without its bundled library, in a fresh process:
this machine has no other liblsl for it to find)."""

from __future__ import annotations

import logging
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from input_helpers import input_engine

from services.input import DeviceError
from services.input.lsl import INSTALL_HINT, load_pylsl

SCENE = """
Input { Device { ID "lab" Kind "lsl" Scope "machine" Streams ["hand_r"] } }
Output { Kind "lsl" Scope "machine" Name "colo" Value "tracker:hand_r" }
"""


def test_without_pylsl_the_device_and_output_are_told_once_each_and_the_run_goes_on(
        monkeypatch, tmp_path: Path, caplog):
    monkeypatch.setitem(sys.modules, "pylsl", None)  # `import pylsl` fails as if absent
    with pytest.raises(DeviceError) as caught:
        load_pylsl("machine")
    assert str(caught.value) == f"lsl: pylsl is not installed; {INSTALL_HINT}"
    assert "pip install pylsl" in str(caught.value)
    with caplog.at_level(logging.WARNING), input_engine(SCENE, tmp_path) as engine:
        engine.run(frames=5)
        assert engine.frame == 5
    told = {(r.levelno, r.getMessage()) for r in caplog.records if r.levelno >= logging.WARNING}
    assert told == {
        (logging.ERROR, f"input device 'lab' (lsl, streams hand_r): lsl: pylsl is not "
                        f"installed; {INSTALL_HINT}; the run goes on without it"),
        (logging.ERROR, f"output 'colo' (lsl): lsl: pylsl is not installed; {INSTALL_HINT}; "
                        f"the run goes on without this output")}
    assert sum(r.levelno >= logging.WARNING for r in caplog.records) == 2  # once each
    assert "Traceback" not in caplog.text


def test_pylsl_without_liblsl_names_what_to_install(tmp_path: Path):
    import pylsl

    package = Path(pylsl.__file__).parent
    shutil.copytree(package, tmp_path / "pylsl",
                    ignore=shutil.ignore_patterns("*.so", "*.so.*", "*.dylib", "*.dll",
                                                  "__pycache__"))
    probe = textwrap.dedent("""
        import sys
        sys.path.insert(0, sys.argv[1])
        from services.input import DeviceError
        from services.input.lsl import load_pylsl
        try:
            load_pylsl("machine")
        except DeviceError as exc:
            print(exc)
        else:
            print("loaded")
    """)
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    done = subprocess.run([sys.executable, "-c", probe, str(tmp_path)], capture_output=True,
                          text=True, env=env, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    out = done.stdout.strip()
    if out == "loaded":
        pytest.skip("this machine has a liblsl of its own for pylsl to find")
    assert out.startswith("lsl: liblsl cannot be loaded (") and out.endswith(INSTALL_HINT)
    assert "Traceback" not in done.stdout + done.stderr
