"""Each visual anomaly changes the pixels as it says, in degrees of visual angle and per eye;
its onset ramps the effect monotonically, and switched off it leaves the image exactly as
it was."""

from __future__ import annotations

import math

import numpy as np
import pytest
from render_helpers import floor

from components import Shape, Visual
from engine.anomalies import ANOMALIES, Anomalies, check_value
from services.render import CameraView, LightInfo

W, H = 240, 180
LUMA = np.array([0.2126, 0.7152, 0.0722])


def scene(make_renderer, size=(W, H), separation: float = 0.0, background=(0.0, 0.0, 0.0),
          radius=(0.05, 0.2)):
    """Scattered coloured balls (no repeating pattern), lit evenly."""
    r = make_renderer(size=size)
    r.background = background
    r.ambient = (0.6, 0.6, 0.6)
    r.lights = [LightInfo("directional", direction=(0.0, 0.3, -1.0), shadows=False)]
    r.camera = CameraView.looking_at((0.0, -6.0, 1.5), (0.0, 0.0, 1.0), fov=50.0,
                                     eye_separation=separation)
    rng = np.random.default_rng(7)
    for i in range(60):
        r.add(i + 1, Visual(shapes=[Shape("sphere", (rng.uniform(*radius),))],
                            color=(*rng.uniform(0.2, 1.0, 3), 1.0)),
              position=(rng.uniform(-3, 3), rng.uniform(-1, 3), rng.uniform(0.0, 2.5)))
    return r


def with_anomaly(r, kind: str, anomaly_id: str | None = None, onset: float = 0.0,
                 eye: str = "both", **values) -> Anomalies:
    anomalies = Anomalies()
    checked = {k: check_value(ANOMALIES[kind], k, v)[0] for k, v in values.items()}
    anomalies.declare(anomaly_id or kind, checked, kind=kind, onset=onset, eye=eye)
    anomalies.switch(anomaly_id or kind, True, "test")
    anomalies.step(0.0 if onset else 1.0)
    r.anomalies = anomalies.active()
    return anomalies


def draw(r) -> np.ndarray:
    r.render()
    return r.read_pixels().astype(float)


def luminance(image: np.ndarray) -> np.ndarray:
    return image @ LUMA


def focal_pixels(r, width: int) -> float:
    """Pixels per unit of tan(angle) across an eye ``width`` pixels wide."""
    eye = r.camera.eyes(*r.target.size)[0]
    return eye.proj[0, 0] * width / 2.0


def test_double_vision_puts_an_autocorrelation_peak_at_its_offset(make_renderer):
    r = scene(make_renderer, radius=(0.01, 0.03))  # points of light: a sharp self-peak
    for i in range(61, 400):
        r.add(i, Visual(shapes=[Shape("sphere", (0.02,))], color=(1, 1, 1, 1)),
              position=tuple(np.random.default_rng(i).uniform((-2, 0, 0), (2, 2, 2.5))))
    clean = luminance(draw(r))
    with_anomaly(r, "double_vision", Offset=(5.0, 2.0), Mix=0.5)
    double = luminance(draw(r))
    middle = double[H // 4: 3 * H // 4, W // 4: 3 * W // 4]  # where angles are near linear
    spectrum = np.fft.fft2(middle - middle.mean())
    correlation = np.fft.fftshift(np.real(np.fft.ifft2(spectrum * np.conj(spectrum))))
    cy, cx = H // 4, W // 4
    correlation[cy - 4:cy + 5, cx - 4:cx + 5] = 0  # the trivial peak at no shift
    y, x = np.unravel_index(np.argmax(correlation), correlation.shape)
    f = focal_pixels(r, W)
    expected = (math.tan(math.radians(5.0)) * f, math.tan(math.radians(2.0)) * f)
    assert abs(abs(x - cx) - expected[0]) <= 1.5 and abs(abs(y - cy) - expected[1]) <= 1.5
    assert (x - cx) * (y - cy) < 0  # right and up: rows count downward
    assert not np.array_equal(clean, double)


def test_neglect_darkens_the_chosen_side_only(make_renderer):
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    clean = luminance(draw(r))
    depths = []
    for depth in (0.3, 0.6, 0.9):
        with_anomaly(r, "neglect", Side="left", Start=0.0, Width=10.0, Depth=depth)
        image = luminance(draw(r))
        depths.append(image[:, : W // 4].mean() / clean[:, : W // 4].mean())
        assert np.abs(image[:, W // 2 + 2:] - clean[:, W // 2 + 2:]).max() < 1.0
    # beyond 10 degrees into the left field the light is (1 - Depth) of what it was
    assert depths == pytest.approx([0.7, 0.4, 0.1], abs=0.02)


def test_hemianopia_takes_half_the_field_to_the_fill_and_spares_the_macula(make_renderer):
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    clean = draw(r)
    with_anomaly(r, "hemianopia", Side="right", Sparing=6.0, Border=1.0,
                 Fill=(0.0, 0.2, 0.4))
    image = draw(r)
    f = focal_pixels(r, W)
    ys, xs = np.mgrid[0:H, 0:W] + 0.5
    deg_x = np.degrees(np.arctan((xs - W / 2) / f))
    deg_y = np.degrees(np.arctan((H / 2 - ys) / (r.camera.eyes(W, H)[0].proj[1, 1] * H / 2)))
    eccentricity = np.hypot(deg_x, deg_y)
    lost = (deg_x > 1.0) & (eccentricity > 7.0)
    seen = (deg_x < -1.0) | (eccentricity < 5.0)
    assert np.abs(image[lost] - (0, 51, 102)).max() <= 1
    assert np.abs(image[seen] - clean[seen]).max() <= 1
    assert lost.mean() > 0.4 and (seen & (deg_x > 1.0)).sum() > 100  # a spared disc


def test_contrast_loss_scales_the_luminance_spread_by_the_severity(make_renderer):
    r = scene(make_renderer, background=(0.3, 0.4, 0.6))
    clean = luminance(draw(r))
    for loss in (0.25, 0.5, 0.8):
        with_anomaly(r, "contrast_loss", Loss=loss)
        faded = luminance(draw(r))
        assert faded.std() / clean.std() == pytest.approx(1.0 - loss, abs=0.02)
        assert faded.mean() == pytest.approx(clean.mean(), abs=1.0)


def test_acuity_blur_takes_away_high_frequencies_more_as_it_grows(make_renderer):
    r = scene(make_renderer)
    energies = []
    for acuity in (0.0, 0.2, 0.5, 1.5):
        if acuity:
            with_anomaly(r, "blur", Acuity=acuity, Motion=0.0)
        image = luminance(draw(r))
        laplacian = (4 * image[1:-1, 1:-1] - image[:-2, 1:-1] - image[2:, 1:-1]
                     - image[1:-1, :-2] - image[1:-1, 2:])
        energies.append(float((laplacian ** 2).mean()))
    ratios = np.array(energies[1:]) / np.array(energies[:-1])
    assert np.all(ratios < 0.7), ratios
    assert energies[2] < 0.2 * energies[0]  # half a degree: detail of ~1.6 px gone


def test_motion_smear_keeps_a_share_of_the_last_frame(make_renderer):
    r = scene(make_renderer)
    r.add(100, Visual(shapes=[Shape("box", (0.6, 0.6, 0.6))], color=(1, 1, 1, 1)),
          position=(0.0, 0.0, 1.0))
    with_anomaly(r, "blur", Acuity=0.0, Motion=0.6)
    before = luminance(draw(r))
    r.set_pose(100, (10.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0))  # gone from view
    trail = luminance(draw(r))
    r.anomalies = []
    gone = luminance(draw(r))
    centre = (slice(H // 2 - 3, H // 2 + 3), slice(W // 2 - 3, W // 2 + 3))
    expected = 0.6 * before[centre] + 0.4 * gone[centre]
    assert np.abs(trail[centre] - expected).max() < 2.0


def test_perspective_tilts_the_horizon_and_widens_the_field(make_renderer):
    r = make_renderer(size=(W, H))
    r.background = (0.0, 0.0, 0.0)
    r.camera = CameraView.looking_at((0.0, -6.0, 1.0), (0.0, 0.0, 1.0), fov=50.0)
    floor(r, color=(1.0, 1.0, 1.0, 1.0))
    r.ambient = (1.0, 1.0, 1.0)
    r.add(1, Visual(shapes=[Shape("sphere", (0.4,))], color=(1, 0, 0, 1)),
          position=(0.0, 0.0, 1.0))

    def horizon_slope(image: np.ndarray) -> float:
        columns = np.arange(20, W - 20, 10)
        rows = [np.argmax(luminance(image)[:, c] > 60) for c in columns]  # first floor row
        return float(np.polyfit(columns, rows, 1)[0])

    def red_area(image: np.ndarray) -> int:
        return int(((image[..., 0] > 120) & (image[..., 1] < 60)).sum())

    clean = draw(r)
    with_anomaly(r, "perspective", Tilt=12.0, Fov=1.0, Aspect=1.0, Distortion=0.0)
    tilted = draw(r)
    # rows grow downward: a counter-clockwise roll raises the horizon on the right
    assert math.degrees(math.atan(-horizon_slope(tilted))) == pytest.approx(12.0, abs=1.0)
    assert abs(horizon_slope(clean)) < 0.01
    with_anomaly(r, "perspective", Tilt=0.0, Fov=1.4, Aspect=1.0, Distortion=0.0)
    wider = draw(r)
    tan = math.tan(math.radians(25.0))
    expected = (tan / math.tan(math.radians(25.0 * 1.4))) ** 2  # the ball's area shrinks
    assert red_area(wider) / red_area(clean) == pytest.approx(expected, rel=0.1)


def test_onset_ramps_the_effect_monotonically_and_off_restores_the_image_exactly(
        make_renderer):
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    clean = draw(r)
    anomalies = Anomalies()
    anomalies.declare("neglect", {"Depth": 1.0, "Width": 0.0}, onset=0.5)
    left = []
    anomalies.switch("neglect", True, "test")
    for _ in range(40):  # 0.8 s at 50 frames/s: on over 0.5 s, then held
        anomalies.step(0.02)
        r.anomalies = anomalies.active()
        left.append(luminance(draw(r))[:, : W // 2 - 2].mean())
    assert np.all(np.diff(left[:25]) < 0) and left[24] == pytest.approx(0.0, abs=0.5)
    assert np.ptp(left[25:]) < 1e-9
    anomalies.switch("neglect", False, "test")
    for _ in range(30):
        anomalies.step(0.02)
        r.anomalies = anomalies.active()
        left.append(luminance(draw(r))[:, : W // 2 - 2].mean())
    assert np.all(np.diff(left[40:65]) > 0)
    assert r.anomalies == [] and np.array_equal(draw(r), clean)


def test_side_by_side_stereo_has_the_parallax_of_the_eyes(make_renderer):
    separation = 0.065
    r = make_renderer(size=(2 * W, H))
    r.background = (0.0, 0.0, 0.0)
    r.ambient = (1.0, 1.0, 1.0)
    r.camera = CameraView.looking_at((0.0, -6.0, 1.0), (0.0, 0.0, 1.0), fov=50.0,
                                     eye_separation=separation)
    distance = 2.0
    r.add(1, Visual(shapes=[Shape("sphere", (0.05,))], color=(1, 1, 1, 1)),
          position=(0.0, -6.0 + distance, 1.0))
    image = luminance(draw(r))
    centres = []
    for half in (image[:, :W], image[:, W:]):
        ys, xs = np.nonzero(half > 100)
        centres.append(xs.mean())
    expected = separation * focal_pixels(r, W) / distance
    assert centres[0] - centres[1] == pytest.approx(expected, abs=0.5)
    assert expected > 5


def test_anomalies_are_drawn_per_eye_in_each_eyes_visual_field(make_renderer):
    r = scene(make_renderer, size=(2 * W, H), separation=0.065, background=(0.5, 0.5, 0.5))
    clean = draw(r)
    with_anomaly(r, "hemianopia", Side="left", Border=0.0)
    image = draw(r)
    for x0 in (0, W):  # the left half of each eye's view, not of the frame
        assert image[:, x0: x0 + W // 2 - 2].max() <= 1
        assert np.abs(image[:, x0 + W // 2 + 2: x0 + W] - clean[:, x0 + W // 2 + 2: x0 + W]
                      ).max() <= 1
    with_anomaly(r, "double_vision", eye="right", Offset=(3.0, 0.0))
    image = draw(r)
    assert np.array_equal(image[:, :W], clean[:, :W])  # the left eye sees one image
    assert np.abs(image[:, W:] - clean[:, W:]).mean() > 2


def test_a_stereo_double_vision_of_two_blocks_shifts_each_eye_its_own_way(make_renderer):
    r = scene(make_renderer, size=(2 * W, H), separation=0.065)
    clean = luminance(draw(r))
    shift = 13  # pixels at the centre of view: the offset's angle
    angle = math.degrees(math.atan(shift / focal_pixels(r, W)))
    anomalies = Anomalies()
    anomalies.declare("l", {"Offset": (-angle, 0.0), "Mix": 1.0}, kind="double_vision",
                      enabled=True, eye="left")
    anomalies.declare("r", {"Offset": (angle, 0.0), "Mix": 1.0}, kind="double_vision",
                      enabled=True, eye="right")
    r.anomalies = anomalies.active()
    image = luminance(draw(r))
    for x0, sign in ((0, -1), (W, 1)):  # with Mix 1 each eye sees only its moved image
        a, b = x0 + W // 2 - 25, x0 + W // 2 + 25  # the middle, where a shift is uniform
        assert np.abs(image[:, a:b] - clean[:, a - sign * shift: b - sign * shift]
                      ).mean() < 1.5
        assert np.abs(image[:, a:b] - clean[:, a:b]).mean() > 5


#: Each anomaly at a severity that changes the image plainly, every parameter away from
#: its value without effect (so each one's ramp and restore is exercised).
SEVERE = {
    "double_vision": {"Offset": (4.0, 1.5), "Rotation": 10.0, "Mix": 0.5},
    "blur": {"Acuity": 0.6, "Motion": 0.6},
    "perspective": {"Fov": 1.2, "Tilt": 8.0, "Aspect": 1.3, "Distortion": 0.2},
    "neglect": {"Side": "left", "Start": 0.0, "Width": 10.0, "Depth": 0.9},
    "hemianopia": {"Side": "right", "Sparing": 3.0, "Depth": 1.0},
    "contrast_loss": {"Loss": 0.5},
}


def test_every_anomaly_kind_has_a_severe_case():
    assert set(SEVERE) == set(ANOMALIES)


@pytest.mark.parametrize("kind", sorted(SEVERE))
def test_each_anomaly_ramps_in_and_off_restores_the_image_exactly(make_renderer, kind):
    """Switched on, the image moves away from the clean one as the onset ramps; while it
    is on a box sweeps across the view (motion blur keeps it in its history); switched off
    and ramped out, the frame is the clean frame to the bit. Switched on at once after
    that, its first frame is the one it drew when first switched on at once: no history
    or state is left over from before."""
    r = scene(make_renderer, background=(0.5, 0.5, 0.5))
    home = (0.0, 0.0, 1.0)
    r.add(100, Visual(shapes=[Shape("box", (0.5, 0.5, 0.5))], color=(1, 1, 1, 1)),
          position=home)
    clean = draw(r)
    anomalies = Anomalies()
    values = {k: check_value(ANOMALIES[kind], k, v)[0] for k, v in SEVERE[kind].items()}
    anomalies.declare(kind, values)

    def frame() -> tuple[np.ndarray, float]:
        anomalies.step(0.02)
        r.anomalies = anomalies.active()
        image = draw(r)
        return image, float(np.abs(image - clean).mean())

    anomalies.set(kind, "test", enabled=True, onset=0.0)
    instant, change = frame()
    assert change > 2.0  # a plain change: grey levels on average
    anomalies.switch(kind, False, "test")
    assert np.array_equal(frame()[0], clean) and r.anomalies == []
    anomalies.set(kind, "test", enabled=True, onset=0.3)
    ramp = [frame()[1] for _ in range(16)]  # 0.32 s: the 0.3 s onset, and held
    assert ramp[-1] == pytest.approx(change, rel=0.05), ramp
    assert np.all(np.diff(ramp[:14]) >= -0.02 * ramp[-1]) and ramp[13] > 3 * ramp[1], ramp
    for x in np.linspace(-2.0, 2.0, 6):  # the box sweeps across the view
        r.set_pose(100, (x, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0))
        frame()
    r.set_pose(100, home, (1.0, 0.0, 0.0, 0.0))
    anomalies.switch(kind, False, "test")
    fade = [frame()[1] for _ in range(16)]
    assert np.all(np.diff(fade) <= 0.02 * ramp[-1]), fade
    assert fade[-1] == 0.0 and r.anomalies == [], fade
    if kind == "blur":  # the sweep's smear was in the motion history as the fade began
        assert fade[0] > 1.1 * ramp[-1], (fade, ramp)
    assert np.array_equal(draw(r), clean)
    anomalies.set(kind, "test", enabled=True, onset=0.0)
    assert np.array_equal(frame()[0], instant)


def horizon_view(make_renderer, ball: tuple[float, float] | None = None):
    """A white floor to the horizon under a black sky, seen level at eye height 1 m; with
    ``ball`` (x, radius), a red ball at that x, 6 m ahead at eye height."""
    r = make_renderer(size=(W, H))
    r.background = (0.0, 0.0, 0.0)
    r.camera = CameraView.looking_at((0.0, -6.0, 1.0), (0.0, 0.0, 1.0), fov=50.0)
    r.ambient = (1.0, 1.0, 1.0)
    if ball is None:
        floor(r, color=(1.0, 1.0, 1.0, 1.0))
    else:
        r.add(1, Visual(shapes=[Shape("sphere", (ball[1],))], color=(1, 0, 0, 1)),
              position=(ball[0], 0.0, 1.0))
    return r


def red(image: np.ndarray) -> np.ndarray:
    return (image[..., 0] > 120) & (image[..., 1] < 60)


def test_double_visions_rotation_turns_the_second_image_about_the_line_of_sight(
        make_renderer):
    """Rotation alone, with Mix 1 (only the second image): the horizon turns by the
    Rotation, counter-clockwise, in degrees of visual angle. Each column's first floor
    row lies where the clean horizon's direction lands once turned."""
    r = horizon_view(make_renderer)
    columns = np.arange(20, W - 20, 4)

    def first_floor_rows(image: np.ndarray) -> np.ndarray:
        return np.array([np.argmax(luminance(image)[:, c] > 60) for c in columns])

    clean = first_floor_rows(draw(r))
    assert np.ptp(clean) == 0  # level
    fx, fy = focal_pixels(r, W), r.camera.eyes(W, H)[0].proj[1, 1] * H / 2
    horizon = math.degrees(math.atan((H / 2 - clean[0]) / fy))  # its edge: degrees up
    for rotation in (7.0, -12.0):
        with_anomaly(r, "double_vision", Offset=(0.0, 0.0), Rotation=rotation, Mix=1.0)
        rows = first_floor_rows(draw(r))
        a = math.radians(rotation)
        seen_x = np.degrees(np.arctan((columns + 0.5 - W / 2) / fx))
        seen_y = (horizon + math.sin(a) * seen_x) / math.cos(a)  # turned by +a, it is there
        expected = H / 2 - fy * np.tan(np.radians(seen_y))
        assert np.abs(rows - expected).max() <= 1.5, (rows, expected)
        assert np.sign(rows[0] - rows[-1]) == np.sign(rotation)  # up on the right: CCW


def test_perspective_aspect_stretches_the_view_sideways_only(make_renderer):
    r = horizon_view(make_renderer, ball=(0.0, 0.4))

    def extent(image: np.ndarray) -> tuple[int, int]:
        ys, xs = np.nonzero(red(image))
        return int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)

    width, height = extent(draw(r))
    for aspect in (1.5, 0.7):
        with_anomaly(r, "perspective", Tilt=0.0, Fov=1.0, Aspect=aspect, Distortion=0.0)
        w, h = extent(draw(r))
        assert w == pytest.approx(aspect * width, abs=1.5) and abs(h - height) <= 1


def test_perspective_distortion_bends_the_view_radially(make_renderer):
    """A ball off the centre of view: barrel distortion (Distortion > 0) draws what is at
    ``x0`` at ``d`` with ``d (1 + s d^2) = x0`` (normalised across the eye), pulling it in;
    pincushion (s < 0) pushes it out."""
    r = horizon_view(make_renderer, ball=(2.2, 0.1))

    def centre_ndc(image: np.ndarray) -> float:
        ys, xs = np.nonzero(red(image))
        return float((xs.mean() + 0.5) / W * 2.0 - 1.0)

    x0 = centre_ndc(draw(r))
    assert 0.4 < x0 < 0.7
    for strength in (0.5, -0.2):
        with_anomaly(r, "perspective", Tilt=0.0, Fov=1.0, Aspect=1.0, Distortion=strength)
        roots = np.roots([strength, 0.0, 1.0, -x0])
        (d,) = [root.real for root in roots if abs(root.imag) < 1e-9 and 0 < root.real <= 1]
        seen = centre_ndc(draw(r))
        assert seen == pytest.approx(d, abs=1.0 / W)  # half a pixel
        assert (seen - x0) * strength < 0 and abs(seen - x0) > 4.0 / W  # 2 px or more
