"""One-euro smoothing and constant-velocity prediction, on recorded traces."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.scene.inputs import InputSpec, TrackerSpec
from services.input import InputHub, TrackerPose, read_recording
from services.input.record import FrameInput, RecordWriter


def record_trace(path: Path, positions: np.ndarray, orientations: np.ndarray,
                 times: np.ndarray, per_frame: int) -> None:
    """A recording of one tracker's samples, ``per_frame`` of them delivered per frame."""
    writer = RecordWriter(path, {"scene": "", "seed": 0, "devices": []})
    for frame, start in enumerate(range(0, len(times), per_frame)):
        events = [TrackerPose("hand_r", tuple(positions[i]), tuple(orientations[i]), None,
                              float(times[i])) for i in range(start, start + per_frame)]
        writer.write(frame, FrameInput(float(times[start + per_frame - 1]), events))
    writer.close()


def replay(path: Path, tracker: TrackerSpec) -> list[TrackerPose]:
    """Every processed pose of the recording, as the input hub delivers them."""
    recording = read_recording(path)
    hub = InputHub(InputSpec(trackers=(tracker,)), [])
    hub.replay(recording)
    out: list[TrackerPose] = []
    for frame in range(max(recording.frames) + 1):
        out += [e for e in hub.step(frame) if isinstance(e, TrackerPose)]
    hub.close()
    return out


def minimum_jerk(s: np.ndarray) -> np.ndarray:
    """A human reach's profile (Flash and Hogan): 0 to 1 with no jerk at either end."""
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(a * a, axis=1))))


@pytest.mark.parametrize("rate", [120.0, 240.0, 480.0])
def test_the_one_euro_filter_removes_jitter_at_rest_and_follows_a_reach(tmp_path: Path,
                                                                         rate: float):
    """A hand at rest, a 0.41 m reach in 0.5 s (1.5 m/s at its fastest), at rest again,
    seen through 4 mm of sensor noise, filtered with the scene's default settings."""
    rng = np.random.default_rng(3)
    times = 100.0 + np.arange(int(3 * rate)) / rate
    t = times - times[0]
    reach = minimum_jerk(np.clip((t - 1.0) / 0.5, 0.0, 1.0))
    truth = np.stack([0.4 * reach, 0.1 * reach, np.full_like(t, 1.2)], axis=1)
    noisy = truth + rng.normal(0.0, 0.004, truth.shape)
    identity = np.tile([1.0, 0.0, 0.0, 0.0], (len(t), 1))
    path = tmp_path / "reach.jsonl"
    record_trace(path, noisy, identity, times, per_frame=int(rate // 60))
    raw = np.array([p.position for p in replay(path, TrackerSpec("hand_r"))])
    np.testing.assert_array_equal(raw, noisy)  # without a filter the samples pass untouched
    smooth = np.array([p.position for p in replay(path, TrackerSpec("hand_r",
                                                                    filter="oneeuro"))])
    fixed = np.array([p.position for p in replay(path, TrackerSpec(
        "hand_r", filter="oneeuro", beta=0.0))])  # a plain 1 Hz low-pass, for comparison
    rest = ((t > 0.5) & (t < 1.0)) | (t > 2.0)
    moving = (t >= 1.0) & (t <= 1.5)
    assert rms(smooth[rest] - truth[rest]) < 0.3 * rms(raw[rest] - truth[rest])
    lag = np.linalg.norm(smooth[moving] - truth[moving], axis=1).max()
    assert lag < 0.025  # metres behind the hand at worst, at 1.5 m/s
    assert lag < 0.3 * np.linalg.norm(fixed[moving] - truth[moving], axis=1).max()


@pytest.mark.parametrize("lead_ms", [10.0, 50.0])
@pytest.mark.parametrize("rate", [90.0, 240.0])
def test_prediction_extrapolates_constant_velocity_exactly(tmp_path: Path, lead_ms, rate):
    velocity = np.array([0.4, -0.2, 0.1])
    spin = np.array([0.0, 0.0, 1.5])  # rad/s about z
    times = 50.0 + np.arange(30) / rate

    def pose_at(t: float) -> tuple[np.ndarray, np.ndarray]:
        angle = spin[2] * (t - times[0])
        q = np.array([np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)])
        return np.array([0.1, 0.2, 1.0]) + velocity * (t - times[0]), q

    positions, orientations = zip(*(pose_at(t) for t in times), strict=True)
    path = tmp_path / "steady.jsonl"
    record_trace(path, np.array(positions), np.array(orientations), times, per_frame=1)
    lead = lead_ms / 1000.0
    predicted = replay(path, TrackerSpec("hand_r", predict=lead))
    for pose, t in list(zip(predicted, times, strict=True))[2:]:
        future_p, future_q = pose_at(t + lead)
        np.testing.assert_allclose(pose.position, future_p, atol=1e-9)
        same = abs(float(np.dot(pose.orientation, future_q)))
        assert same == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(pose.velocity, velocity, atol=1e-9)


def test_a_pose_past_float_range_is_dropped_and_the_filter_starts_afresh(caplog):
    """A raw 1e308 is refused by the devices (beyond ±1e9); a sane sample that the scene's
    Scale takes past float range is dropped with a message, and the one-euro filter,
    which an inf once turned to NaN for the rest of the run, starts again from the next."""
    hub = InputHub(InputSpec(trackers=(TrackerSpec("hand_r", filter="oneeuro", scale=1e301),)),
                   [])
    identity = (1.0, 0.0, 0.0, 0.0)
    xs = [0.0, 1e8, -1e8, 0.5, 0.5]
    for i, x in enumerate(xs):
        hub.apply(FrameInput(10.0 + i, [TrackerPose("hand_r", (x, 0.0, 0.0), identity, None,
                                                    10.0 + i)]))
    assert hub.delivered["tracker"] == 3  # 1e8 and -1e8 (1e309 calibrated) dropped
    tracker = hub.state.tracker("hand_r")
    assert np.isfinite(tracker.position).all() and np.isfinite(tracker.velocity).all()
    assert tracker.position[0] == pytest.approx(0.5e301)  # the filter was reset at 0.5
    assert "pose is not finite (check the Tracker's Scale" in caplog.text


def test_the_orientation_filter_follows_a_fast_turn_and_stills_a_resting_one() -> None:
    """The rotation filter's cutoff rises with the angular speed, as the position one's
    does with speed: a 3 rad/s turn is followed within a few hundredths of a radian
    (at the resting cutoff of 1 Hz it would trail by half a radian), while 0.01 rad of
    jitter on a still hand is cut (white jitter at 120 Hz reads as some speed itself, so
    by less than a slow drift would be)."""
    from engine.rotation import quat_from_rotation_vector, rotation_vector
    from services.input.filters import OneEuroRotation

    rate, speed = 120.0, 3.0
    turning = OneEuroRotation()
    for i in range(121):
        t = i / rate
        out = turning(quat_from_rotation_vector((0.0, 0.0, speed * t)), t)
    lag = np.linalg.norm(rotation_vector(out, quat_from_rotation_vector((0.0, 0.0, speed))))
    assert lag < 0.05
    rng = np.random.default_rng(0)
    still = OneEuroRotation()
    noise = rng.normal(0.0, 0.01, (600, 3))
    seen = np.array([rotation_vector((1.0, 0.0, 0.0, 0.0),
                                     still(quat_from_rotation_vector(tuple(n)), i / rate))
                     for i, n in enumerate(noise)])
    assert seen[120:].std() < 0.75 * noise.std()
