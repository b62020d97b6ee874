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

"""The readable search of a footstep window (§4.2) and its compiled twin: the same footsteps."""
import os

from course_runs import course_names, scene, SCENES, simulate, skeleton
from digital_actor_planner.cli import read_commands
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.footstep_window import (configuration_effort, IMPROVEMENT,
                                                        search_footstep_window, WindowFeet)
from digital_actor_planner.core.footsteps import (FootstepConfig, FootstepPlanner, GroundProfile,
                                                  RIGHT)
import numpy as np
import pytest

DS = 0.02
TERRAIN = {'stairs': lambda s: 0.12 * (np.floor((s - 0.4) / 0.3) + 1) if s > 0.4 else 0.0,
           'holes': lambda s: np.nan if 0.5 < s < 0.85 or 1.5 < s < 1.8 else 0.0,
           'bumps': lambda s: 0.25 if 0.9 < s < 0.96 else 0.03 * np.sin(9 * s)}


def profile_from(height_of, length=4.0, s0=-0.3):
    """Make a two-track profile from a height function of arc length (NaN = hole)."""
    s = s0 + DS * np.arange(int(length / DS))
    both = np.vstack([[height_of(v) for v in s]] * 2).astype(float)
    return GroundProfile(s0=s0, ds=DS, height=both, low=both.copy(),
                         headroom=np.full_like(both, np.inf), obstacle=both.copy())


def planners(**fields):
    leg = skeleton().leg
    return (FootstepPlanner(FootstepConfig(**fields), leg),
            FootstepPlanner(FootstepConfig(window_search='readable', **fields), leg))


def assert_same_window(compiled, readable, case):
    assert (compiled is None) == (readable is None), case
    if compiled is None:
        return
    assert readable.indices == compiled.indices, case
    assert readable.effort == compiled.effort, case
    assert readable.evaluated == compiled.evaluated, case
    for name in ('lengths', 'arc_lengths', 'heights', 'pitches', 'sides'):
        np.testing.assert_array_equal(getattr(readable, name), getattr(compiled, name),
                                      err_msg=f'{name} {case}')


@pytest.mark.parametrize('greedy_restart', [True, False])
def test_both_searches_plan_the_same_window_from_far_starts(greedy_restart):
    """
    Both searches plan the same window from far starts.

    On stairs, over holes and bumps, from random starts, with random first footsteps banned and a
    random longest footstep: the same footsteps, effort and configurations judged.
    """
    compiled, readable = planners(greedy_restart=greedy_restart)
    rng = np.random.default_rng(3)
    far = 0
    for name, height_of in TERRAIN.items():
        profile = profile_from(height_of)
        for _ in range(15):
            start = tuple(int(j) for j in rng.integers(0, 14, 3))
            s_init = float(rng.uniform(0.3, 0.7))
            banned = tuple(int(j) for j in rng.integers(0, 14, rng.integers(0, 3)))
            max_length = float(rng.choice([np.inf, 0.6, 0.3]))
            case = (name, start, s_init, banned, max_length)
            windows = [planner.plan(profile, RIGHT, 0.0, 0.0, 0.0, 0.0, s_init, 0.5,
                                    start=start, banned_first=banned, max_length=max_length)
                       for planner in (compiled, readable)]
            assert_same_window(*windows, case)
            far += windows[0] is not None and windows[0].evaluated > 14
    assert far >= 10, 'too few searches that had to go far for the test to mean much'


def test_the_readable_search_is_judged_by_its_own_effort():
    """
    The readable search is judged by its own effort.

    The search's answer is collision-free by :func:`configuration_effort`, has that effort, and no
    climbing neighbour is cheaper.
    """
    planner = planners()[1]
    profile = profile_from(TERRAIN['stairs'])
    table = planner.foothold_table(profile, RIGHT, 0.0)
    feet = WindowFeet(0.0, 0.0, 0.0, 0.0, 0.5, 0.5)
    limits = planner.window_limits
    found = search_footstep_window(table, limits, feet, (0, 0, 0))
    assert found is not None
    assert configuration_effort(found.configuration, table, limits, feet) == found.effort
    m = limits.intervals
    for i in range(3):
        for delta in (-1, 1):
            neighbour = list(found.configuration)
            neighbour[i] += delta
            if not 0 <= neighbour[i] <= m:
                continue
            value = configuration_effort(tuple(neighbour), table, limits, feet)
            assert value is None or value >= found.effort - IMPROVEMENT, neighbour


def test_an_unknown_window_search_is_named():
    with pytest.raises(ValueError, match='window_search'):
        FootstepPlanner(FootstepConfig(window_search='fast'), skeleton().leg)


def _walk(name, window_search):
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    config = ActorConfig(footsteps=FootstepConfig(window_search=window_search))
    actor = Actor(skeleton(), sc.environment, config, start=sc.start)
    return run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                        [c.angular_z for c in commands])


@pytest.mark.slow
@pytest.mark.parametrize('name', course_names())
def test_every_course_is_walked_alike_with_the_readable_search(name):
    """
    Every course is walked alike with the readable search.

    A course walked with the readable search is the walk of the compiled one: the same blocks and
    frames (so the same footsteps).
    """
    _, times, frames, blocks = simulate(name)
    readable = _walk(name, 'readable')
    assert [b.status for b in readable] == [b.status for b in blocks], name
    np.testing.assert_array_equal(np.concatenate([b.times for b in readable]), times)
    np.testing.assert_array_equal(np.vstack([b.frames for b in readable]), frames)
