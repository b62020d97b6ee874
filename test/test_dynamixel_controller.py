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

"""The bridge's controller against a scripted bus (no ROS, no serial port): shutdown outcomes."""
from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.dynamixel.config import config_from_parameters
from digital_actor_planner.dynamixel.controller import BridgeController
import pytest


class PortGone(RuntimeError):
    pass


class ScriptedBus:
    """Servos 1 and 2 at the centre; ``lost_replies`` torque-off replies go missing first."""

    def __init__(self, lost_replies=0, gone=False):
        self.lost_replies = lost_replies
        self.gone = gone
        self.torque = {1: 0, 2: 0}

    def _check(self):
        if self.gone:
            raise PortGone('/dev/ttyUSB0: device disappeared')

    def open(self):  # noqa: A003 (the bus interface it fakes)
        self._check()

    def close(self):
        pass

    def ping(self, ids, attempts=3):
        self._check()
        return {i: 1020 for i in ids if i in self.torque}

    def read_hardware_errors(self, ids):
        return dict.fromkeys(ids, 0)

    def read_positions(self, ids):
        return dict.fromkeys(ids, 2048)

    def write_goals(self, goals):
        self._check()

    def set_torque(self, ids, enabled):
        self._check()
        done = {}
        for i in ids:
            self.torque[i] = int(enabled)
            lost = not enabled and self.lost_replies > 0
            self.lost_replies -= lost
            done[i] = not lost
        return done


def _controller(bus):
    config = config_from_parameters({'servo_joints': ['left_knee', 'right_knee']}, Skeleton())
    log = []
    controller = BridgeController(config, bus, log=lambda level, text: log.append((level, text)),
                                  bus_error=PortGone)
    controller.start(0.0)
    assert bus.torque == {1: 1, 2: 1}
    return controller, log


@pytest.mark.parametrize('lost', [0, 2])
def test_torque_off_is_confirmed_even_when_replies_are_late(lost):
    bus = ScriptedBus(lost_replies=lost)
    controller, log = _controller(bus)
    assert controller.shutdown() is True
    assert bus.torque == {1: 0, 2: 0} and ('info', 'torque off') in log


def test_servos_that_never_confirm_are_named():
    bus = ScriptedBus(lost_replies=100)
    controller, log = _controller(bus)
    assert controller.shutdown() is False
    errors = [text for level, text in log if level == 'error']
    assert errors and 'TORQUE COULD NOT BE SWITCHED OFF' in errors[-1]
    assert 'left_knee (ID 1), right_knee (ID 2)' in errors[-1] and '2 servos' in errors[-1]


def test_a_port_gone_at_shutdown_is_reported_not_ignored():
    bus = ScriptedBus()
    controller, log = _controller(bus)
    bus.gone = True
    controller.connected = False  # as after the cycle that found the port gone
    assert controller.shutdown() is False
    assert 'device disappeared' in log[-1][1] and bus.torque == {1: 1, 2: 1}


def test_nothing_to_switch_off_is_not_an_error():
    bus = ScriptedBus()
    config = config_from_parameters({'servo_joints': ['left_knee'],
                                     'torque_off_on_shutdown': False}, Skeleton())
    controller = BridgeController(config, bus, bus_error=PortGone)
    controller.start(0.0)
    assert controller.shutdown() is True and bus.torque[1] == 1


class UnreadBus(ScriptedBus):
    """
    Servos left away from the centre, whose reads fail for a while.

    A sync read of both fails ``failed_group_reads`` times, and servo 2's own reads fail
    ``unread_2`` times. Every goal is kept, with what torque was then.
    """

    PLACED = {1: 2048 + 600, 2: 2048 - 500}  # a knee bent, the mirrored knee bent

    def __init__(self, failed_group_reads=0, unread_2=0):
        super().__init__()
        self.failed_group_reads = failed_group_reads
        self.unread_2 = unread_2
        self.goals = []  # (id, goal ticks, torque before the write)
        self._requested = ()

    def read_positions(self, ids):
        ids = tuple(ids)
        if len(ids) > 1 and self.failed_group_reads > 0:
            self.failed_group_reads -= 1
            return {}
        if 2 in ids and self.unread_2 > 0:
            self.unread_2 -= 1
            return {}
        return {i: self.PLACED[i] for i in ids}

    def request_positions(self, ids):
        self._requested = tuple(ids)
        return bool(self._requested)

    def collect_positions(self):
        return self.read_positions(self._requested)

    def write_goals(self, goals):
        super().write_goals(goals)
        self.goals.extend((i, g, self.torque[i]) for i, g in goals.items())

    def first_goals(self):
        """Each servo's goal written just before its torque came on."""
        first = {}
        for servo_id, goal, torque in self.goals:
            if torque:
                continue
            first[servo_id] = goal
        return first


def _started(bus):
    config = config_from_parameters({'servo_joints': ['left_knee', 'right_knee'],
                                     'reconnect_backoff_max': 0.2}, Skeleton())
    log = []
    controller = BridgeController(config, bus, log=lambda level, text: log.append((level, text)),
                                  bus_error=PortGone)
    controller.start(0.0)
    return controller, log


def test_a_failed_first_read_does_not_switch_torque_on_toward_the_old_goal():
    # One lost reply fails the whole sync read at start-up; the servos are away from the
    # goal the bridge starts with, so a goal not read from them would be a jump.
    bus = UnreadBus(failed_group_reads=1)
    _started(bus)
    assert bus.torque == {1: 1, 2: 1}
    assert bus.first_goals() == bus.PLACED  # torque on moves nothing


def test_a_servo_whose_position_cannot_be_read_stays_off_until_it_is():
    bus = UnreadBus(failed_group_reads=10, unread_2=3)
    controller, log = _started(bus)
    assert bus.torque == {1: 1, 2: 0}
    assert all(servo_id == 1 for servo_id, _, _ in bus.goals)  # no goal for servo 2 yet
    assert any('right_knee (ID 2)' in text for level, text in log if level == 'warn')
    now = 0.0
    while bus.torque[2] == 0 and now < 5.0:
        now += 0.01
        controller.cycle(now)
    assert bus.torque[2] == 1
    assert bus.first_goals() == bus.PLACED  # it too came on where it was
