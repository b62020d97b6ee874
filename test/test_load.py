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

"""A slow plan costs latency, never the outcome: the courses walk the same on a loaded machine."""
import os
import time

from course_runs import SCENES, simulate, skeleton
from digital_actor_planner.cli import read_commands
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.upper_body import UpperBodyConfig, UpperBodyPlanner
import numpy as np
import pytest

#: The obstacle courses whose upper body searches (the CT-roadmap) and one that stops.
COURSES = ('low_beam', 'beam_too_low')


class SlowClock:
    """
    Wall clock that runs a second ahead at every reading.

    A wall clock that runs a second ahead at every reading: a machine so loaded that any wall-clock
    budget is spent at its first look.
    """

    def __init__(self):
        self.now = time.perf_counter()

    def __call__(self):
        self.now += 1.0
        return self.now


@pytest.mark.parametrize('name', COURSES)
def test_course_outcome_does_not_depend_on_the_wall_clock(monkeypatch, name):
    _, times, frames, blocks = simulate(name)
    clock = SlowClock()
    for reading in ('perf_counter', 'monotonic', 'time'):
        monkeypatch.setattr(time, reading, clock)
    # The course planned afresh (not the cached run) with every wall clock racing ahead.
    _, slow_times, slow_frames, slow_blocks = simulate.__wrapped__(name)
    assert [b.status for b in slow_blocks] == [b.status for b in blocks]
    assert [b.reason for b in slow_blocks] == [b.reason for b in blocks]
    assert np.array_equal(slow_times, times) and np.array_equal(slow_frames, frames)
    # The slow clock was read: planning times are reported from it, and they are huge.
    assert min(b.planning_time for b in slow_blocks) >= 1.0


def test_a_cpu_budget_far_above_need_leaves_the_plan_unchanged(monkeypatch):
    """
    A CPU-time budget far above what a plan takes gives the same plan as none.

    A CPU-time budget (``UpperBodyConfig.time_budget``) far above what a plan takes: the same plan
    as without one, however slow the wall clock runs.
    """
    sc, _, frames, _ = simulate('low_beam')
    monkeypatch.setattr(time, 'perf_counter', SlowClock())
    collision = BodyCollision(skeleton(), sc.environment)
    config = ActorConfig()
    upper = UpperBodyPlanner(skeleton(), collision,
                             UpperBodyConfig(time_budget=30.0),
                             rng=np.random.default_rng(0))
    actor = Actor(skeleton(), sc.environment, config, start=sc.start,
                  upper_body_planner=upper, body_collision=collision)
    commands = read_commands(os.path.join(SCENES, 'low_beam.csv'))
    blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                          [c.angular_z for c in commands])
    assert np.array_equal(np.vstack([b.frames for b in blocks]), frames)


@pytest.mark.parametrize('pause_at', [2.45, 2.9])
def test_a_stop_before_the_low_beam_does_not_change_where_the_walk_ends(pause_at):
    """
    A walk stopped by late commands on a loaded machine still gets under the beam.

    On a loaded machine the node's commands arrive late and it stops the actor (its command
    timeout), which then walks on: the walk must get under the beam as it does without the stop.
    Stopped 0.6 m before the beam, the waist's search leaned back to its limit, and under the beam
    every step from there was blocked.
    """
    sc, _, frames, _ = simulate('low_beam')
    actor = Actor(skeleton(), sc.environment, ActorConfig(), start=sc.start)
    run_commands(actor, [0.0, pause_at], [0.8, 0.0], [0.0, 0.0])
    run_commands(actor, [actor.time, actor.time + 1.0], [0.0, 0.0], [0.0, 0.0])
    blocks = run_commands(actor, [actor.time, actor.time + 6.0], [0.8, 0.0], [0.0, 0.0])
    assert not [b.reason for b in blocks if b.status == 'stuck']
    assert blocks[-1].frames[-1, 0] >= sc.expect['reach_x']
