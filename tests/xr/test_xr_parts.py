"""The headset display's parts that need no OpenXR runtime: the lifecycle driven by
recorded state sequences, the frame-timing arithmetic, the controller bindings per
profile, the swapchain format choice and the frame conversion (the projection is tested
against the frustum in tests/render/test_stereo_single_pass.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from components.display import HEADSET_ACTIONS, HEADSET_PROFILES
from engine.rotation import quat_to_matrix
from services.input.calibration import openxr_to_engine
from services.xr.bindings import ACTION_NAMES, PROFILE_PATHS, PROFILES, Rebinding, suggestions
from services.xr.formats import FormatError, choose_color_format, choose_depth_format
from services.xr.lifecycle import Action, SessionState, replay
from services.xr.projection import Fov, XrOrigin, fov_projection, yaw_of
from services.xr.timing import FrameCounts, StepPlanner

S = SessionState


# -- lifecycle ---------------------------------------------------------------------------
def test_a_session_that_runs_and_is_asked_to_exit_begins_ends_and_quits_once():
    life, actions = replay([S.IDLE, S.READY, S.SYNCHRONIZED, S.VISIBLE, S.FOCUSED,
                            S.STOPPING, S.IDLE, S.EXITING])
    assert actions == [Action.BEGIN, Action.END, Action.QUIT]
    assert life.furthest == S.FOCUSED and life.ended == "exiting" and not life.running


def test_input_acts_only_while_focused():
    life, _ = replay([S.IDLE, S.READY, S.SYNCHRONIZED, S.VISIBLE])
    assert life.running and life.shown and not life.focused
    life.change(S.FOCUSED)
    assert life.focused


def test_a_lost_session_ends_the_run_with_its_session_ended():
    life, actions = replay([S.IDLE, S.READY, S.SYNCHRONIZED, S.FOCUSED, S.LOSS_PENDING])
    assert actions == [Action.BEGIN, Action.END, Action.QUIT] and life.ended == "lost"


def test_a_runtime_going_away_before_the_session_ran_quits_without_ending_it():
    life, actions = replay([S.IDLE])
    assert life.instance_lost() == [Action.QUIT] and life.ended == "lost"


@pytest.mark.parametrize("when_hidden, paused", [("pause", True), ("run", False)])
def test_a_headset_taken_off_pauses_as_the_scene_says(when_hidden, paused):
    life, _ = replay([S.IDLE, S.READY, S.SYNCHRONIZED, S.VISIBLE, S.FOCUSED, S.VISIBLE,
                      S.SYNCHRONIZED], when_hidden)
    assert life.paused is paused
    life.change(S.VISIBLE)
    assert not life.paused


def test_a_session_not_yet_shown_is_not_paused():
    life, _ = replay([S.IDLE, S.READY, S.SYNCHRONIZED], "pause")
    assert not life.paused


def test_a_session_restarted_after_stopping_begins_again():
    _, actions = replay([S.IDLE, S.READY, S.SYNCHRONIZED, S.STOPPING, S.IDLE, S.READY])
    assert actions == [Action.BEGIN, Action.END, Action.BEGIN]


def test_an_unknown_when_hidden_is_refused():
    with pytest.raises(ValueError, match="WhenHidden"):
        replay([], "sleep")


# -- frame timing -----------------------------------------------------------------------
@pytest.mark.parametrize("display_hz, dt", [(90.0, 0.01), (120.0, 0.01), (72.0, 1 / 60),
                                            (20.0, 0.005), (60.0, 1 / 60)])
def test_simulated_time_follows_the_display_whatever_the_two_rates(display_hz, dt):
    plan = StepPlanner(dt, max_steps=100)
    frames = int(display_hz * 10)
    steps = [plan.steps(1.0 / display_hz) for _ in range(frames)]
    assert abs(plan.simulated - 10.0) <= dt  # within one step after 10 s
    assert 0.0 <= plan.carry < dt
    assert max(steps) - min(steps) <= 1  # steps spread evenly over the frames


def test_frames_shorter_than_a_step_take_none_and_the_rest_carries():
    plan = StepPlanner(0.01)
    assert [plan.steps(1 / 120) for _ in range(6)] == [0, 1, 1, 1, 1, 1]


def test_a_long_frame_runs_slow_rather_than_catching_up_forever():
    plan = StepPlanner(0.01, max_steps=8)
    assert plan.steps(0.5) == 8 and plan.carry < 0.01 and plan.dropped > 0.4


def test_late_and_skipped_frames_are_counted():
    counts = FrameCounts()
    counts.ended(True, 100, 200)
    counts.ended(True, 300, 200)  # ended after it was due
    counts.ended(False, 300, 200)  # the runtime said not to draw: skipped, not late
    counts.ended(True, None, 200)  # the runtime cannot say the time: not counted late
    assert (counts.submitted, counts.late, counts.skipped) == (3, 1, 1)


# -- bindings ---------------------------------------------------------------------------
def test_the_scene_vocabulary_is_the_bindings_own():
    assert tuple(HEADSET_ACTIONS) == ACTION_NAMES
    assert tuple(HEADSET_PROFILES) == tuple(PROFILE_PATHS)


def test_every_profile_binds_poses_and_haptics_on_both_hands_and_a_grasp():
    for profile in PROFILES:
        for action in ("grip", "aim", "haptic"):
            assert all(profile.components[action]), (profile.path, action)
        assert "trigger" in profile.components or "squeeze" in profile.components


def test_profiles_needing_an_extension_are_suggested_only_with_it():
    without = suggestions(set())
    pico = "/interaction_profiles/bytedance/pico4_controller"
    assert pico not in without
    assert pico in suggestions({"XR_BD_controller_interaction"})


def test_face_buttons_are_on_their_own_hands():
    pairs = suggestions(set())["/interaction_profiles/oculus/touch_controller"]
    assert ("x", "/user/hand/left/input/x/click") in pairs
    assert not any(p.startswith("/user/hand/right") for a, p in pairs if a in ("x", "y"))
    assert ("squeeze", "/user/hand/right/input/squeeze/value") in pairs


def test_a_rebinding_replaces_the_suggestion_on_its_hand_only():
    rebind = Rebinding("squeeze", "oculus/touch_controller",
                       "/user/hand/right/input/trigger/value")
    pairs = suggestions(set(), (rebind,))["/interaction_profiles/oculus/touch_controller"]
    squeezes = [p for a, p in pairs if a == "squeeze"]
    assert squeezes == ["/user/hand/left/input/squeeze/value",
                        "/user/hand/right/input/trigger/value"]
    assert rebind.problem() is None
    assert "unknown action" in Rebinding("grab", "oculus/touch_controller", "/user/x").problem()


# -- swapchain formats ------------------------------------------------------------------
GL_RGBA8, GL_SRGB8_ALPHA8, GL_RGBA16F, GL_DEPTH24, GL_DEPTH32F = (0x8058, 0x8C43, 0x881A,
                                                                  0x81A6, 0x8CAC)


def test_srgb_is_chosen_and_written_as_it_is():
    chosen = choose_color_format([GL_RGBA8, GL_SRGB8_ALPHA8])
    assert chosen.gl_format == GL_SRGB8_ALPHA8 and not chosen.decode


def test_a_linear_format_gets_the_colours_decoded():
    chosen = choose_color_format([0x1234, GL_RGBA16F, GL_RGBA8])
    assert chosen.gl_format == GL_RGBA16F and chosen.decode


def test_no_usable_format_is_one_clear_error():
    with pytest.raises(FormatError, match="offered: 0x1234"):
        choose_color_format([0x1234])


def test_the_deepest_depth_is_chosen_and_none_is_fine():
    assert choose_depth_format([GL_DEPTH24, GL_DEPTH32F]).gl_format == GL_DEPTH32F
    assert choose_depth_format([GL_RGBA8]) is None


# -- frames and projection --------------------------------------------------------------
def test_an_openxr_pose_looking_ahead_is_an_engine_camera_looking_along_y():
    position, orientation = openxr_to_engine((0.1, 1.7, -0.5), (1.0, 0.0, 0.0, 0.0))
    assert np.allclose(position, (0.1, 0.5, 1.7))
    forward = quat_to_matrix(np.asarray(orientation))[:, 1]
    assert np.allclose(forward, (0.0, 1.0, 0.0))


def test_the_origin_puts_the_player_under_the_camera_facing_its_way():
    camera = np.array([2.0, -3.0, 1.45])
    heading = math.radians(30.0)
    turn = np.array([math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)])
    origin = XrOrigin.under(camera, turn, floor=True)
    position, orientation = origin.place_xr((0.0, 1.6, 0.0), (1.0, 0.0, 0.0, 0.0))
    assert np.allclose(position, (2.0, -3.0, 1.6))  # own height, the floor at z = 0
    assert math.isclose(yaw_of(orientation), heading, abs_tol=1e-12)
    local = XrOrigin.under(camera, turn, floor=False)
    assert np.allclose(local.place_xr((0.0, 0.0, 0.0), (1, 0, 0, 0))[0], camera)


def test_recentering_moves_the_head_over_the_target_and_turns_it_its_way():
    origin = XrOrigin()
    head_q = np.array([math.cos(0.4), 0.0, 0.0, math.sin(0.4)])  # turned 0.8 rad
    target_q = np.array([math.cos(-0.2), 0.0, 0.0, math.sin(-0.2)])
    new = origin.recentered(np.array([0.5, 0.3, 1.7]), head_q, np.array([4.0, 1.0, 1.2]),
                            target_q, floor=True)
    position, orientation = new.place(np.array([0.5, 0.3, 1.7]), head_q)
    assert np.allclose(position[:2], (4.0, 1.0)) and math.isclose(position[2], 1.7)
    assert math.isclose(yaw_of(orientation), -0.4, abs_tol=1e-12)


def test_a_field_of_view_that_cannot_be_drawn_is_refused():
    with pytest.raises(ValueError, match="empty field of view"):
        fov_projection(Fov(0.5, -0.5, 0.5, -0.5), 0.1, 10.0)
    with pytest.raises(ValueError, match="within ±90°"):
        fov_projection(Fov(-2.0, 0.5, 0.5, -0.5), 0.1, 10.0)


def test_a_player_carried_by_a_moving_camera_keeps_their_place_on_it():
    chair = (np.array([1.0, 2.0, 0.3]), np.array([math.cos(0.3), 0.0, 0.0, math.sin(0.3)]))
    origin = XrOrigin.under(*chair, floor=True)
    relative = origin.relative_to(*chair)
    assert np.allclose(relative.carried_by(*chair).position, origin.position)
    moved = (np.array([4.0, -1.0, 0.3]), np.array([math.cos(0.9), 0.0, 0.0, math.sin(0.9)]))
    carried = relative.carried_by(*moved)
    head = (np.array([0.0, 0.0, 1.2]), np.array([1.0, 0.0, 0.0, 0.0]))
    position, orientation = carried.place(*head)
    assert np.allclose(position[:2], moved[0][:2]) and math.isclose(position[2], 1.2)
    assert math.isclose(yaw_of(orientation), 1.8, abs_tol=1e-12)  # turned with the chair
