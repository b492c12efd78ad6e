"""Renderer.render_scale (``--render-scale``): the view drawn at a share of the output's
resolution and scaled up, for frame rate on a software rasteriser; off by default."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_anomalies import scene, with_anomaly

from app.cli import main
from app.scaffold import scaffold

W, H = 240, 180


def shaded_and_image(r) -> tuple[int, np.ndarray]:
    """Fragments that passed the depth test (all of them drawn, at whatever size), and
    the output image."""
    query = r.ctx.query(samples=True)
    with query:
        r.render()
    return query.samples, r.read_pixels().astype(float)


def test_a_half_scale_view_shades_a_quarter_of_the_pixels_and_looks_the_same(
        make_renderer):
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    assert r.render_scale == 1.0 and r.view_size((W, H)) == (W, H)
    full_count, full = shaded_and_image(r)
    r.render_scale = 0.5
    assert r.view_size((W, H)) == (W // 2, H // 2)
    half_count, half = shaded_and_image(r)
    assert half.shape == full.shape  # the output keeps its size
    upscaled = W * H  # the scaling up draws each output pixel once
    assert (half_count - upscaled) / full_count == pytest.approx(0.25, rel=0.1)
    blurred = full.reshape(H // 2, 2, W // 2, 2, 3).mean(axis=(1, 3))  # what half sees
    shrunk = half.reshape(H // 2, 2, W // 2, 2, 3).mean(axis=(1, 3))
    assert np.abs(shrunk - blurred).mean() < 3.0
    assert np.abs(half - full).mean() > 0.5  # it is not the full-size frame
    r.render_scale = 1.0
    assert np.array_equal(shaded_and_image(r)[1], full)


def test_anomalies_are_drawn_in_the_scaled_view_in_the_eyes_coordinates(make_renderer):
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    with_anomaly(r, "neglect", Side="left", Start=0.0, Width=0.0, Depth=1.0)
    _, full = shaded_and_image(r)
    r.render_scale = 0.5
    _, half = shaded_and_image(r)
    assert half[:, : W // 2 - 2].max() <= 1 and full[:, : W // 2 - 2].max() <= 1
    right = (slice(None), slice(W // 2 + 2, None))
    assert np.abs(half[right] - full[right]).mean() < 6.0 and half[right].mean() > 50


def test_a_render_scale_out_of_range_is_refused_with_its_range(make_renderer):
    r = make_renderer()
    for bad in (0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match="render scale must be 0.25 to 1"):
            r.render_scale = bad
    assert r.render_scale == 1.0


def test_the_cli_draws_at_the_render_scale_asked_and_refuses_one_out_of_range(
        tmp_path: Path, capsys):
    """--render-scale 0.5 gives a screenshot of the window's size, softer than one at full
    resolution (less energy at the highest spatial frequencies)."""
    sim = scaffold(tmp_path / "sim")
    detail = {}
    for scale in ("1", "0.5"):
        shot = tmp_path / f"shot {scale}.png"
        result = subprocess.run(
            [sys.executable, "-m", "app.cli", "run", str(sim), "--headless", "--frames",
             "3", "--fast", "--size", "160x120", "--render-scale", scale, "--screenshot",
             str(shot)], capture_output=True, text=True, timeout=120)
        assert result.returncode == 0, result.stderr
        image = np.asarray(Image.open(shot).convert("L"), float)
        assert image.shape == (120, 160) and image.std() > 5
        laplacian = (4 * image[1:-1, 1:-1] - image[:-2, 1:-1] - image[2:, 1:-1]
                     - image[1:-1, :-2] - image[1:-1, 2:])
        detail[scale] = float((laplacian ** 2).mean())
    assert detail["0.5"] < 0.8 * detail["1"], detail
    with pytest.raises(SystemExit) as exit_:
        main(["run", str(sim), "--headless", "--frames", "1", "--render-scale", "2"])
    assert exit_.value.code == 2
    assert "--render-scale: must be 0.25 to 1, got 2" in capsys.readouterr().err
