"""OpenXR: without a runtime the device says so clearly; with none, nothing else breaks."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
from input_helpers import input_engine

from engine.input import DeviceError
from engine.input.openxr import OpenXRDevice

xr = pytest.importorskip("xr", reason="pyopenxr (the openxr extra) is not installed")


def test_no_runtime_is_one_clear_message(monkeypatch, tmp_path: Path):
    monkeypatch.setenv("XR_RUNTIME_JSON", str(tmp_path / "no-runtime.json"))
    with pytest.raises(DeviceError, match=r"'openxr' \(openxr\): no OpenXR runtime found: "
                                          r"install one .*XR_RUNTIME_JSON"):
        OpenXRDevice().open()


def test_a_run_without_a_runtime_goes_on(monkeypatch, tmp_path: Path, caplog):
    monkeypatch.setenv("XR_RUNTIME_JSON", str(tmp_path / "no-runtime.json"))
    with caplog.at_level(logging.ERROR), input_engine('Input { Device { Kind "openxr" } }',
                                                      tmp_path) as engine:
        engine.run(frames=3)
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]
    assert len(errors) == 1 and "no OpenXR runtime found" in errors[0]
