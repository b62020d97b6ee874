# Copyright 2026 digital_actor_planner developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""§4.1's key frames of a step and the Bezier swing (core/key_frames.py), by what they promise."""
from digital_actor_planner.core.gait import FootPose
from digital_actor_planner.core.key_frames import (bezier_swing, GaitError, step_category,
                                                   step_key_frames, SwingCurve, SwingFootprint,
                                                   SwingLimits)
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest

ANKLE = 0.08
LIMITS = SwingLimits(lift=0.07, max_lift=0.55, ankle_height=ANKLE)
ALONG = np.linspace(-0.07, 0.18, 9)
LEG = Skeleton().leg


def foot(sole, pitch=0.0):
    """Return a level foot resting with its sole at height ``sole``, m."""
    return FootPose(np.zeros(2), sole + ANKLE, 0.0, pitch, sole)


def footprint(ground, frames=60):
    """Return the footprint of a swing over ``ground(u) -> (P,) heights`` at every frame."""
    u = np.arange(1, frames + 1) / frames
    tops = np.array([ground(x) for x in u])
    zeros = np.zeros(frames)
    return SwingFootprint(np.arange(frames), ALONG, tops, u, zeros, zeros), u


def test_the_level_of_the_next_foothold_sets_the_category():
    assert step_category(foot(0.0), foot(0.02)) == 'level'
    assert step_category(foot(0.0), foot(-0.02)) == 'level'
    assert step_category(foot(0.0), foot(0.1)) == 'uphill'
    assert step_category(foot(0.1), foot(0.0)) == 'downhill'


def test_uphill_the_pelvis_rises_late_and_downhill_it_is_down_before_touchdown():
    """Figure 4: the key frames' pelvis heights differ by category."""
    tau = np.arange(1, 101) / 100
    level = step_key_frames(foot(0.0), foot(0.0), 0.9, LEG, 0.035, tau)
    up = step_key_frames(foot(0.0), foot(0.15), 0.9, LEG, 0.035, tau)
    down = step_key_frames(foot(0.15), foot(0.0), 1.05, LEG, 0.035, tau)
    assert (level.category, up.category, down.category) == ('level', 'uphill', 'downhill')
    for frames in (level, up, down):
        heights = frames.pelvis_heights()
        # From the start height to the touchdown height, never beyond either.
        assert heights[-1] == pytest.approx(frames.touchdown_height)
        low, high = sorted((frames.start_height, frames.touchdown_height))
        assert low - 1e-12 <= heights.min() and heights.max() <= high + 1e-12
    # The touchdown height is over the middle of the two ankles.
    legs = LEG.thigh + LEG.shank
    assert up.touchdown_height == pytest.approx(0.5 * (2 * ANKLE + 0.15) + legs - 0.035)
    # Uphill nothing rises in the first third of the step; at mid-step less than on level
    # ground; downhill the pelvis is down before the foot lands.
    assert np.all(up.weight[:33] == 0.0) and up.weight[49] < level.weight[49]
    assert np.all(down.weight[95:] == 1.0) and up.weight[95] < 1.0


def test_over_clear_ground_the_swing_keeps_its_nominal_lift():
    """The cubic's analytic top: control points h above both ends lift the middle by 0.75 h."""
    prints, u = footprint(lambda x: np.full(9, -np.inf))
    curve = bezier_swing(foot(0.0), foot(0.0), prints, np.zeros(u.size), LIMITS)
    assert curve == SwingCurve(ANKLE, ANKLE, 0.07, 0.07)
    assert curve.heights(np.array([0.5]))[0] == pytest.approx(ANKLE + 0.75 * 0.07)
    assert curve.heights(np.array([0.0, 1.0])) == pytest.approx([ANKLE, ANKLE])


def test_a_swing_lifting_off_a_heel_off_lifts_more_briskly():
    prints, u = footprint(lambda x: np.full(9, -np.inf))
    curve = bezier_swing(foot(0.0, pitch=-0.2), foot(0.0), prints, np.zeros(u.size), LIMITS)
    assert curve.raise_lift_off == pytest.approx(0.14) and curve.raise_touchdown == 0.07


@pytest.mark.parametrize('height', [0.05, 0.12, 0.2])
def test_the_curve_is_raised_until_the_sole_clears_an_obstacle(height):
    """An obstacle under the middle of the swing: the curve rises over it, not much higher."""
    def ground(x):
        return np.full(9, height if 0.3 < x < 0.7 else -np.inf)

    prints, u = footprint(ground)
    curve = bezier_swing(foot(0.0), foot(0.0), prints, np.zeros(u.size), LIMITS)
    sole = curve.heights(u) - ANKLE
    over = (u > 0.3) & (u < 0.7)
    assert np.all(sole[over] >= height - 1e-4)
    # Raised only as far as the worst sample needs (each round's step overshoots a little).
    assert sole[over].min() < height + 0.03
    assert not curve.flat_topped and curve.lift >= 0.07


def test_a_block_just_ahead_of_the_lifting_toe_takes_the_flat_topped_curve():
    def ground(x):
        return np.full(9, 0.25 if 0.12 < x < 0.9 else -np.inf)

    prints, u = footprint(ground)
    curve = bezier_swing(foot(0.0), foot(0.0), prints, np.zeros(u.size), LIMITS)
    assert curve.flat_topped
    sole = curve.heights(u) - ANKLE
    over = (u > 0.12) & (u < 0.9)
    assert np.all(sole[over] >= 0.25 - 1e-4)
    assert curve.lift <= LIMITS.max_lift


def test_a_swing_that_no_curve_can_clear_fails_back_to_the_footstep_planner():
    prints, u = footprint(lambda x: np.full(9, 0.8 if 0.2 < x < 0.8 else -np.inf))
    with pytest.raises(GaitError, match='would have to lift 0.80 m, at most 0.55 m'):
        bezier_swing(foot(0.0), foot(0.0), prints, np.zeros(u.size), LIMITS)
