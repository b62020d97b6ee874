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

"""check_trajectory: the independent judge, on hand-built trajectories."""
import time

from digital_actor_planner.core.actor import start_configuration
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.evaluation.trajectory_check import check_trajectory
import numpy as np
import pytest
from scene_helpers import box

RATE = 100.0


@pytest.fixture(scope='module')
def floor_world():
    return Environment([box((-3, -3, -0.2), (15, 3, 0.0))])


@pytest.fixture(scope='module')
def standing(skeleton, floor_world):
    return start_configuration(floor_world, (0.0, 0.0, 0.0), skeleton)


def _hold(q, seconds):
    times = np.arange(int(round(seconds * RATE))) / RATE
    return times, np.tile(q, (len(times), 1))


def _ramp(frames, joint_index, start, stop, change):
    """Add ``change`` to one joint, smoothly (cosine) from frame ``start`` to ``stop``."""
    frames = frames.copy()
    s = np.clip((np.arange(len(frames)) - start) / (stop - start), 0.0, 1.0)
    frames[:, joint_index] += change * (1 - np.cos(np.pi * s)) / 2
    return frames


def test_standing_actor_passes(skeleton, floor_world, standing):
    times, frames = _hold(standing, 2.0)
    report = check_trajectory(skeleton, floor_world, times, frames)
    assert report.ok, report.failures()
    assert report.failures() == []
    assert report.frames == report.frames_checked == len(times)
    assert report.foot_down_gap == 0.0
    assert max(report.penetration.values()) == 0.0
    assert report.slip == {'left_foot': 0.0, 'right_foot': 0.0}


def test_sunk_actor_fails_naming_the_feet(skeleton, floor_world, standing):
    times, frames = _hold(standing, 0.3)
    frames[:, skeleton.index['root_z']] -= 0.052                    # soles 5 cm deep
    report = check_trajectory(skeleton, floor_world, times, frames)
    assert not report.ok
    text = ' '.join(report.failures())
    assert 'left_foot penetrates' in text and 'right_foot penetrates' in text
    assert report.penetration['left_foot'] == pytest.approx(0.05, abs=0.001)
    assert 'no foot down' not in text


def test_feet_may_rest_in_the_ground_up_to_their_tolerance(skeleton, floor_world, standing):
    times, frames = _hold(standing, 0.3)
    frames[:, skeleton.index['root_z']] -= 0.012                    # 10 mm into the floor
    assert check_trajectory(skeleton, floor_world, times, frames).ok
    frames[:, skeleton.index['root_z']] -= 0.010                    # 20 mm
    report = check_trajectory(skeleton, floor_world, times, frames)
    assert [f.split()[0] for f in report.failures()] == ['left_foot', 'right_foot']


def test_any_other_link_in_an_obstacle_fails(skeleton, standing):
    q = standing.copy()
    torso_front = 0.11                                               # half the torso depth
    for overlap, ok in ((0.002, True), (0.01, False)):
        wall = box((torso_front - overlap, -0.5, 1.1), (0.6, 0.5, 1.4))
        env = Environment([box((-3, -3, -0.2), (3, 3, 0.0)), wall])
        times, frames = _hold(q, 0.2)
        report = check_trajectory(skeleton, env, times, frames)
        assert report.ok is ok, report.failures()
        assert report.penetration['torso'] == pytest.approx(overlap, abs=0.0005)
        if not ok:
            assert report.failures()[0].startswith('torso penetrates the environment by 10.0 mm')


def test_floating_actor_fails_foot_down(skeleton, floor_world, standing):
    times, frames = _hold(standing, 0.5)
    frames = _ramp(frames, skeleton.index['root_z'], 10, 30, 0.1)   # rises 10 cm
    report = check_trajectory(skeleton, floor_world, times, frames)
    failures = report.failures()
    assert len(failures) == 1 and failures[0].startswith('no foot down at t = ')
    assert report.foot_down_gap == pytest.approx(0.102, abs=1e-4)
    assert report.foot_down_time >= 0.2


def test_sliding_stance_foot_fails(skeleton, floor_world, standing):
    times, frames = _hold(standing, 1.0)
    frames = _ramp(frames, skeleton.index['root_x'], 20, 80, 0.03)  # slides 3 cm
    report = check_trajectory(skeleton, floor_world, times, frames)
    failures = report.failures()
    assert any(f.startswith('stance foot left_foot slides 30.0 mm') for f in failures)
    assert report.slip['right_foot'] == pytest.approx(0.03, abs=1e-6)


def test_turning_a_lifted_foot_is_not_a_slip_but_turning_it_on_the_ground_is(
        skeleton, floor_world, standing):
    """A swing foot may land elsewhere; a stance foot may not twist on the ground."""
    times, frames = _hold(standing, 1.6)
    index = skeleton.index
    swing = _ramp(frames, index['left_hip_pitch'], 10, 40, 0.4)
    swing = _ramp(swing, index['left_knee'], 10, 40, 0.8)
    swing = _ramp(swing, index['left_ankle'], 10, 40, 0.4)         # keeps the sole level
    swing = _ramp(swing, index['left_hip_yaw'], 50, 90, 0.3)       # turned in the air
    swing = _ramp(swing, index['left_hip_pitch'], 100, 140, -0.4)
    swing = _ramp(swing, index['left_knee'], 100, 140, -0.8)
    swing = _ramp(swing, index['left_ankle'], 100, 140, -0.4)
    report = check_trajectory(skeleton, floor_world, times, swing)
    assert report.ok, report.failures()
    twist = _ramp(frames, index['left_hip_yaw'], 50, 90, 0.3)       # turned on the ground
    report = check_trajectory(skeleton, floor_world, times, twist)
    failures = report.failures()
    assert len(failures) == 1 and failures[0].startswith('stance foot left_foot slides')
    assert report.slip['left_foot'] > 0.02


def test_nan_frames_jumps_and_limits_fail_naming_joint_and_time(
        skeleton, floor_world, standing):
    times, frames = _hold(standing, 0.5)
    frames[20, skeleton.index['left_elbow']] = np.nan
    frames[30:, skeleton.index['waist_yaw']] += 0.2                  # a 0.2 rad jump at 0.3 s
    frames[40, skeleton.index['right_elbow']] = -0.1                 # below its lower limit 0
    report = check_trajectory(skeleton, floor_world, times, frames)
    assert report.non_finite and report.non_finite_times == (0.2,)
    failures = report.failures()
    assert failures[0] == '1 frame(s) hold NaN/inf (t = 0.200 s)'
    assert any(f.startswith('joint waist_yaw jumps by 0.2 in one frame at t = 0.300 s')
               for f in failures)
    assert any(f.startswith('joint waist_yaw moves at 20/s') for f in failures)
    assert any(f.startswith('joint right_elbow = -0.1 outside its limit 0 at t = 0.400 s')
               for f in failures)
    # A limit is a hard bound, up to 1e-6.
    times, frames = _hold(standing, 0.1)
    frames[:, skeleton.index['right_elbow']] = -5e-7
    assert check_trajectory(skeleton, floor_world, times, frames).ok


def test_speed_within_limit_passes_and_over_it_fails(skeleton, floor_world, standing):
    times, frames = _hold(standing, 1.0)
    limit = skeleton.velocity_limit[skeleton.index['waist_yaw']]
    slow = frames.copy()
    slow[:, skeleton.index['waist_yaw']] = np.clip((times - 0.2) * limit * 1.0, 0, 0.5)
    assert check_trajectory(skeleton, floor_world, times, slow).ok
    fast = frames.copy()
    fast[:, skeleton.index['waist_yaw']] = np.clip((times - 0.2) * limit * 1.2, 0, 0.5)
    report = check_trajectory(skeleton, floor_world, times, fast)
    assert [f.split(' moves')[0] for f in report.failures()] == ['joint waist_yaw']


def test_bad_input_is_rejected(skeleton, floor_world, standing):
    times, frames = _hold(standing, 0.1)
    with pytest.raises(ValueError, match='frames must have shape'):
        check_trajectory(skeleton, floor_world, times, frames[:, :21])
    with pytest.raises(ValueError, match=r'increase strictly: times\[4\]'):
        check_trajectory(skeleton, floor_world, np.where(np.arange(10) == 5, 0.04, times),
                         frames)
    with pytest.raises(ValueError, match='stride'):
        check_trajectory(skeleton, floor_world, times, frames, stride=0)
    with pytest.raises(ValueError, match='penetration_tol'):
        check_trajectory(skeleton, floor_world, times, frames, penetration_tol=-1.0)


def test_ten_seconds_at_100_hz_are_checked_in_seconds(skeleton, floor_world, standing):
    times, frames = _hold(standing, 10.0)
    frames = _ramp(frames, skeleton.index['waist_pitch'], 100, 900, 0.3)
    start = time.perf_counter()
    report = check_trajectory(skeleton, floor_world, times, frames)
    elapsed = time.perf_counter() - start
    assert report.ok and report.frames_checked == 1000
    assert elapsed < 20.0  # generous on a shared 2-core machine; about 1 s when idle
    sparse = check_trajectory(skeleton, floor_world, times, frames, stride=10)
    assert sparse.frames_checked == 101 and sparse.ok              # every 10th and the last


def test_a_link_wholly_inside_a_solid_is_found(skeleton, standing):
    """FCL tests surfaces; a foot buried inside a block touches none of its triangles."""
    block = box((-0.5, 0.02, -0.1), (0.5, 0.5, 0.2))              # around the left foot
    env = Environment([box((-3, -3, -0.2), (3, 3, 0.0)), block])
    times, frames = _hold(standing, 0.1)
    report = check_trajectory(skeleton, env, times, frames)
    assert report.penetration['left_foot'] == pytest.approx(0.198, abs=1e-6)
    assert report.penetration['right_foot'] == 0.0
    assert any(f.startswith('left_foot penetrates the environment by 198.0 mm')
               for f in report.failures())


def test_legs_passing_through_each_other_fail_naming_the_links(skeleton, floor_world,
                                                               standing):
    """
    Knock-kneed: both thighs turned in and flexed until the knees meet.

    The checker judges each leg's thigh, shank and foot against the other leg's (their URDF shapes,
    FCL).
    """
    times, frames = _hold(standing, 0.2)
    assert check_trajectory(skeleton, floor_world, times, frames).leg_contacts == ()
    index = skeleton.index
    crossed = frames.copy()
    for side, yaw in (('left', -0.6), ('right', 0.6)):
        crossed[:, index[f'{side}_hip_yaw']] = yaw
        crossed[:, index[f'{side}_hip_pitch']] = 0.8
        crossed[:, index[f'{side}_knee']] = 0.8
    report = check_trajectory(skeleton, floor_world, times, crossed)
    pairs = {(a, b) for a, b, _, _ in report.leg_contacts}
    assert ('left_thigh', 'right_thigh') in pairs
    assert all(count == len(times) for _, _, _, count in report.leg_contacts)
    assert any(f.startswith('left_thigh and right_thigh pass into each other (by more than '
                            '3.0 mm) at t = 0.000 s') for f in report.failures())
    # Turned in 0.084 rad the thighs' cylinders overlap by 1.8 mm (their axes 128.2 mm
    # apart): within the default 3 mm, not within 1 mm.
    touching = frames.copy()
    for side, yaw in (('left', -0.084), ('right', 0.084)):
        touching[:, index[f'{side}_hip_yaw']] = yaw
        touching[:, index[f'{side}_hip_pitch']] = 0.8
        touching[:, index[f'{side}_knee']] = 0.8
    assert check_trajectory(skeleton, floor_world, times, touching).leg_contacts == ()
    strict = check_trajectory(skeleton, floor_world, times, touching, leg_contact_tol=0.001)
    assert {(a, b) for a, b, _, _ in strict.leg_contacts} >= {('left_thigh', 'right_thigh')}
    with pytest.raises(ValueError, match='leg_contact_tol'):
        check_trajectory(skeleton, floor_world, times, frames, leg_contact_tol=-0.001)
