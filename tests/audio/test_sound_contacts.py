"""Contact-sound decisions on hand-built contact batches: impacts ring, rest is silent."""

from __future__ import annotations

import numpy as np
import pytest

from engine.physics.backend import CONTACT_DTYPE
from services.audio import ContactSoundFilter, ContactSoundSettings

DT = 1 / 60
G = 9.81


def _batch(*contacts: tuple[int, int, float]) -> np.ndarray:
    """Contacts (a, b, impulse) at made-up points."""
    out = np.zeros(len(contacts), CONTACT_DTYPE)
    for i, (a, b, impulse) in enumerate(contacts):
        out[i] = (a, b, (float(a), 0.0, 0.0), (0.0, 0.0, 1.0), 0.001, impulse)
    return out


def _stack_at_rest(levels: int, mass: float) -> np.ndarray:
    """A stack on the ground (-1): each contact carries the weight above it, four corners."""
    contacts = []
    for level in range(levels):
        below = -1 if level == 0 else level - 1
        impulse = (levels - level) * mass * G * DT / 4
        contacts += [(level, below, impulse)] * 4
    return _batch(*contacts)


def test_gain_curve_is_documented_square_root_of_impulse() -> None:
    f = ContactSoundFilter(ContactSoundSettings(min_impulse=0.1, full_impulse=5.0))
    assert f.gain(0.05) == 0.0
    assert f.gain(1.25) == pytest.approx(0.5)
    assert f.gain(5.0) == 1.0 and f.gain(50.0) == 1.0


@pytest.mark.parametrize("mass", [0.5, 5.0, 50.0])
def test_a_resting_stack_is_silent(mass: float) -> None:
    """Heavy or light, a stack at rest from its first frame never makes a sound."""
    f = ContactSoundFilter()
    rng = np.random.default_rng(3)
    stack = _stack_at_rest(5, mass)
    for frame in range(600):
        batch = stack.copy()
        batch["impulse"] *= rng.uniform(0.9, 1.1, len(batch))  # solver jitter
        if frame % 97 == 0:  # a contact point flickers out for a frame
            batch = batch[1:]
        assert f.process(batch, frame * DT) == []


def test_a_landing_sounds_once_with_gain_from_its_impulse() -> None:
    f = ContactSoundFilter()
    mass, speed = 1.0, 3.0
    rest = mass * G * DT
    t = 0.0
    assert f.process(_batch(), t) == []
    t += DT
    assert f.process(_batch((7, -1, mass * speed + rest)), t) == []  # decided next frame
    sounds = []
    for _ in range(60):
        t += DT
        sounds += f.process(_batch((7, -1, rest)), t)
    assert len(sounds) == 1
    (s,) = sounds
    assert (s.a, s.b) == (7, -1) and s.position == (7.0, 0.0, 0.0)
    assert s.gain == pytest.approx(((mass * speed + rest) / 5.0) ** 0.5)


def test_weight_moving_between_contact_points_is_silent() -> None:
    """ODE moves a resting box's weight between its corners; the pair's sum holds."""
    f = ContactSoundFilter()
    rng = np.random.default_rng(5)
    rest = 2.0 * G * DT
    for frame in range(300):
        n = int(rng.integers(1, 5))
        share = rng.dirichlet(np.ones(n)) * rest
        assert f.process(_batch(*[(2, 1, j) for j in share]), frame * DT) == []


def test_a_bounce_sounds_and_a_gentle_placement_does_not() -> None:
    f = ContactSoundFilter()
    f.process(_batch((1, -1, 2.0), (2, -1, 0.3)), 0.0)
    hits = f.process(_batch((2, -1, 0.3)), DT)  # 1 bounced away; 2 stays put
    assert [(h.a, h.b) for h in hits] == [(1, -1)]


def test_blows_on_a_resting_stack_sound_but_not_faster_than_the_pair_limit() -> None:
    f = ContactSoundFilter(ContactSoundSettings(pair_interval=0.25))
    stack = _stack_at_rest(2, 2.0)
    hammered = stack.copy()
    hammered["impulse"][4:] *= 20  # a blow on the top box...
    times, t = [], 0.0
    for frame in range(150):
        hit = frame >= 30 and frame % 6 == 0  # ...ten times a second after half a second
        sounds = f.process(hammered if hit else stack, t)
        assert all(h.gain > 0 and {h.a, h.b} == {0, 1} for h in sounds)
        times += [t] * len(sounds)
        t += DT
    assert len(times) >= 6  # it is heard...
    assert np.diff(times).min() >= 0.25 - 1e-9  # ...but never twice within pair_interval


def test_pairs_are_unordered_sum_their_points_and_sound_at_the_strongest() -> None:
    f = ContactSoundFilter()
    f.process(_batch((3, 4, 0.5), (4, 3, 2.5), (3, 4, 1.0)), 0.0)
    (hit,) = f.process(_batch(), DT)
    assert hit.impulse == 4.0 and (hit.a, hit.b) == (4, 3) and hit.position[0] == 4.0


def test_below_the_minimum_impulse_nothing_sounds() -> None:
    f = ContactSoundFilter(ContactSoundSettings(min_impulse=0.5))
    f.process(_batch((1, 2, 0.4)), 0.0)
    assert f.process(_batch(), DT) == []


def test_a_load_that_stays_after_its_impact_sounds_once() -> None:
    """A heavy box dropped on a resting one: one knock, then its weight is the new rest."""
    f = ContactSoundFilter()
    t, heard = 0.0, []
    for frame in range(120):
        impulse = 0.3 if frame < 30 else (6.0 if frame == 30 else 3.0)
        heard += f.process(_batch((1, 2, impulse)), t)
        t += DT
    assert len(heard) == 1 and heard[0].impulse == 6.0


def test_freshly_created_bodies_settle_silently() -> None:
    """A solver popping a just-placed stack apart (impulses jumping) is not an impact."""
    f = ContactSoundFilter(ContactSoundSettings(settle_time=0.15))
    for body in (1, 2):
        f.settle(body, 0.0)
    pops = [0.8, 0.05, 0.9, 2.5, 1.2, 1.0, 0.95, 1.0, 1.05, 1.0]
    heard = []
    for frame in range(120):
        impulse = pops[frame] if frame < len(pops) else 1.0
        heard += f.process(_batch((1, 2, impulse)), frame * DT)
    assert heard == []
    assert len(f.process(_batch((1, 2, 8.0)), 2.0)) == 1  # later blows are heard
