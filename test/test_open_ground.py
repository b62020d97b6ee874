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

"""Every legal command on open flat ground is walked: faster is faster, and nothing gets stuck."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'bench'))

from bench_open_ground import open_floor, walk_with_change  # noqa: E402
from course_runs import scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402


def walked_speed(speed: float, duration: float = 7.0) -> float:
    """
    Return the speed walked along the flat course at command ``speed``, m/s.

    Metres per second along the flat course at command ``speed`` over ``duration`` s, from the
    start (the first step's easing in included).
    """
    sc = scene('flat')
    actor = Actor(skeleton(), sc.environment, ActorConfig(), start=sc.start)
    blocks = run_commands(actor, [0.0, duration], [speed, 0.0], [0.0, 0.0])
    assert not [b.reason for b in blocks if b.status == 'stuck']
    return float(blocks[-1].frames[-1, 0] - sc.start[0]) / duration


def test_a_faster_command_walks_faster_up_to_the_maximum():
    top = ActorConfig().max_linear_speed
    speeds = np.linspace(0.3, top, 8)
    walked = np.array([walked_speed(v) for v in speeds])
    assert np.all(np.diff(walked) > 0.02), dict(zip(speeds.round(2), walked.round(3)))
    # The maximum is what the gait walks, not a speed it only asks for.
    assert walked[-1] > 0.85 * top, walked[-1]
    # Beyond the maximum the command is clamped: no slower than at the maximum.
    assert walked_speed(top + 0.5) > walked[-1] - 0.02


@pytest.mark.parametrize('previous', [(1.0, 0.0), (0.6, 0.6), (1.0, -1.0)])
def test_no_command_change_on_open_ground_gets_stuck(previous):
    environment = open_floor()
    stuck = []
    for speed in (0.1, 0.5, 1.0):
        for rate in (-1.0, 0.5, 1.0):
            _, after = walk_with_change(environment, previous, (speed, rate), 5.0, 3.0)
            reasons = {b.reason for b in after if b.status == 'stuck'}
            if reasons:
                stuck.append(((speed, rate), reasons))
            # It walks on: the pelvis moves or turns under the new command.
            moved = np.abs(after[-1].frames[-1, [0, 1, 3]] - after[0].frames[0, [0, 1, 3]])
            assert moved.max() > 0.2, (speed, rate, moved)
    assert not stuck
