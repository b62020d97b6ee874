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

"""Bridge configuration, tick conversion and the safety envelope, without ROS or a bus."""
import math

from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.dynamixel.config import (
    config_from_parameters, ConfigError, load_config, servo_joint_names, ServoConfig)
from digital_actor_planner.dynamixel.safety import SafetyEnvelope
import numpy as np
import pytest


@pytest.fixture(scope='module')
def skeleton():
    return Skeleton()


def test_shipped_config_drives_the_18_body_joints_with_distinct_ids(skeleton):
    config = load_config('config/dynamixel.yaml', skeleton)
    assert config.joint_names == servo_joint_names(skeleton)
    assert len(config.servos) == 18
    assert len({s.id for s in config.servos}) == 18
    assert not any(name.startswith('root_') for name in config.joint_names)
    assert config.baud_rate == 1_000_000


def test_ticks_follow_offset_direction_and_resolution():
    resolution = 2 * math.pi / 4096
    plain = ServoConfig('left_knee', 1)
    assert plain.to_ticks(0.0) == 2048
    assert plain.to_ticks(math.pi / 2) == 3072
    assert plain.to_ticks(10 * resolution) - plain.to_ticks(9 * resolution) == 1
    mirrored = ServoConfig('right_knee', 2, offset=0.1, direction=-1)
    # -0.5 rad joint angle -> +0.5 rad servo angle, plus the 0.1 rad mounting offset
    assert mirrored.to_ticks(-0.5) == round(2048 + 0.6 / resolution)
    for ticks in (0, 1000, 2048, 3333, 4095):
        assert mirrored.to_ticks(mirrored.to_angle(ticks)) == ticks


@pytest.mark.parametrize('change, named', [
    ({'servos.left_knee.id': 1}, 'duplicate servo ID 1'),
    ({'servo_joints': ['waist_yaw', 'left_toe']}, "'left_toe'"),
    ({'servo_joints': ['waist_yaw', 'root_x']}, "'root_x'"),
    ({'servo_joints': ['waist_yaw', 'waist_yaw']}, 'listed twice'),
    ({'servos.left_knee.max_position': 2.9}, 'servos.left_knee: safe range'),
    ({'servos.left_knee.min_position': -0.2}, 'outside the URDF limits'),
    ({'baud_rate': 250000}, 'baud_rate: 250000'),
    ({'servos.left_knee.direction': 0}, 'servos.left_knee.direction'),
    ({'servos.left_knee.max_speed': 0.0}, 'servos.left_knee.max_speed'),
    ({'servos.left_knee.offset': 3.0}, 'servos.left_knee: angle'),
    ({'servos.left_kne.id': 4}, 'servos.left_kne.id'),
    ({'watchdog_timeout': -1.0}, 'watchdog_timeout'),
])
def test_invalid_configuration_names_the_bad_item(skeleton, change, named):
    parameters = {'servo_joints': ['waist_yaw', 'left_knee']}
    parameters.update(change)
    with pytest.raises(ConfigError, match=None) as error:
        config_from_parameters(parameters, skeleton)
    assert named in str(error.value)


def test_defaults_use_the_urdf_limits(skeleton):
    config = config_from_parameters({'servo_joints': ['left_knee']}, skeleton)
    knee = config.servos[0]
    i = skeleton.index['left_knee']
    assert (knee.min_position, knee.max_position) == (skeleton.lower[i], skeleton.upper[i])
    assert knee.max_speed == skeleton.velocity_limit[i]


def _envelope(timeout=0.5):
    return SafetyEnvelope(['a', 'b'], [-1.0, 0.0], [1.0, 2.0], [2.0, 0.5], timeout,
                          max_step_time=0.05)


def test_envelope_clamps_and_rate_limits():
    envelope = _envelope()
    envelope.reset([0.0, 1.0], now=0.0)
    envelope.command(['a', 'b'], [5.0, -3.0], now=0.0)
    assert envelope.target.tolist() == [1.0, 0.0]
    positions = []
    for k in range(1, 301):
        envelope.command(['a', 'b'], [5.0, -3.0], now=0.01 * k)
        positions.append(envelope.step(0.01 * k))
    steps = np.abs(np.diff(np.array(positions), axis=0))
    assert np.all(steps <= np.array([2.0, 0.5]) * 0.01 + 1e-12)
    assert positions[-1].tolist() == pytest.approx([1.0, 0.0])


def test_envelope_ignores_nan_inf_and_unknown_names():
    envelope = _envelope()
    envelope.reset([0.2, 1.0], now=0.0)
    ignored = envelope.command(['a', 'b', 'c'], [float('nan'), float('inf'), 0.4], now=0.0)
    assert ignored == ['a', 'b', 'c']
    assert envelope.target.tolist() == [0.2, 1.0]
    assert envelope.holding  # nothing valid arrived, so the watchdog was not fed


def test_envelope_watchdog_holds_the_last_commanded_position():
    envelope = _envelope(timeout=0.2)
    envelope.reset([0.0, 0.0], now=0.0)
    envelope.command(['b'], [2.0], now=0.0)
    for k in range(1, 101):
        held = envelope.step(0.01 * k)
    assert envelope.holding
    # 0.5 rad/s for about the 0.2 s watchdog time, then nothing more
    assert held[1] == pytest.approx(0.1, abs=0.006)
    assert envelope.step(5.0)[1] == held[1]


def test_a_stalled_cycle_does_not_become_a_jump():
    envelope = _envelope(timeout=100.0)
    envelope.reset([0.0, 0.0], now=0.0)
    envelope.command(['a'], [1.0], now=0.0)
    assert envelope.step(3.0)[0] == pytest.approx(2.0 * 0.05)


def test_envelope_rejects_bad_construction():
    with pytest.raises(ValueError, match='max_speed'):
        SafetyEnvelope(['a'], [0.0], [1.0], [0.0], 0.5)
    with pytest.raises(ValueError, match='watchdog_timeout'):
        SafetyEnvelope(['a'], [0.0], [1.0], [1.0], float('nan'))


def test_goals_at_and_beyond_the_limits_stay_inside_the_safe_range(skeleton):
    """The ends of a range rarely fall on a tick: the goal tick is the nearest one inside."""
    config = config_from_parameters({}, skeleton)
    servos = list(config.servos) + [
        ServoConfig('left_knee', 40, offset=0.25, min_position=0.1, max_position=1.5),
        ServoConfig('right_knee', 41, offset=-0.25, direction=-1, min_position=0.1,
                    max_position=1.5)]
    past = 0
    for servo in servos:
        for end, beyond in ((servo.min_position, -1e-4), (servo.max_position, 1e-4)):
            nearest = round(2048 + (servo.direction * end + servo.offset) / (2 * math.pi / 4096))
            past += servo.to_angle(nearest) < servo.min_position or servo.to_angle(
                nearest) > servo.max_position
            for angle in (end, end - beyond):  # the end itself and just inside it
                reached = servo.to_angle(servo.to_ticks(angle))
                assert servo.min_position - 1e-12 <= reached <= servo.max_position + 1e-12, (
                    servo.joint, angle, reached)
                # still the closest such tick: less than one tick from where it was asked
                assert abs(reached - angle) < 2 * math.pi / 4096
    assert past > 0  # plain rounding would have put some of these past their limit


def _ease_in(envelope, start, seconds, period=0.01):
    envelope.reset(start, now=0.0)
    return np.array([envelope.step(period * k) for k in range(int(seconds / period) + 1)])


def test_a_joint_found_outside_its_range_eases_in_at_its_speed_limit():
    # 'b' (range [0, 2], 0.5 rad/s) switched on at -0.5 rad, as a knee left folded back
    positions = _ease_in(_envelope(), [0.3, -0.5], seconds=2.0)
    assert positions[0].tolist() == [0.3, -0.5]  # the first goal is where the servo is
    steps = np.abs(np.diff(positions, axis=0))
    assert np.all(steps <= np.array([2.0, 0.5]) * 0.01 + 1e-12)
    assert positions[-1, 1] == pytest.approx(0.0)  # at the nearest end, then held there
    reached = int(np.argmax(positions[:, 1] >= -1e-12))
    assert reached * 0.01 == pytest.approx(1.0, abs=0.02)  # 0.5 rad at 0.5 rad/s
    assert np.all(positions[reached:, 1] >= -1e-12)
    # a joint brought back alone starts from where it is too
    envelope = _envelope()
    envelope.reset([0.0, 1.0], now=0.0)
    envelope.resume([0], [1.6])
    assert envelope.commanded[0] == 1.6 and envelope.step(0.01)[0] == pytest.approx(1.58)
