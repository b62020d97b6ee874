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

"""Shared, cached course simulations for the tests (each course is planned once per test run)."""
import functools
import os

from digital_actor_planner.cli import read_commands
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.scene import load_scene
from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.core.upper_body import UpperBodyConfig, UpperBodyPlanner
from digital_actor_planner.evaluation.trajectory_check import check_trajectory
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')


@functools.lru_cache(maxsize=None)
def skeleton():
    return Skeleton()


@functools.lru_cache(maxsize=None)
def scene(name):
    return load_scene(os.path.join(SCENES, name + '.yaml'), skeleton())


def judged(blocks, environment):
    """
    Stack a walk's blocks and judge them with the independent checker.

    (times, frames, report): a walk's blocks stacked and judged by the independent checker against
    ``environment``.
    """
    times = np.concatenate([b.times for b in blocks])
    frames = np.vstack([b.frames for b in blocks])
    return times, frames, check_trajectory(skeleton(), environment, times, frames)


@functools.lru_cache(maxsize=None)
def simulate(name, window_steps=3, upper_body=True, greedy_restart=True, lasting_branches=None,
             upper_body_seed=True):
    """
    Plan course ``name``: (scene, times (k,), frames (k, 22), blocks).

    ``lasting_branches``: a tuple overrides the upper-body planner's ``lasting_branches``.
    ``upper_body_seed``: ``ActorConfig.upper_body_seed``.
    """
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    config = ActorConfig(plan_upper_body=upper_body,
                         footsteps=FootstepConfig(window_steps=window_steps,
                                                  greedy_restart=greedy_restart),
                         upper_body_seed=upper_body_seed)
    if lasting_branches is None:
        actor = Actor(skeleton(), sc.environment, config, start=sc.start)
    else:
        actor = actor_with_lasting_branches(sc.environment, sc.start, lasting_branches, config)
    blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                          [c.angular_z for c in commands])
    times = np.concatenate([b.times for b in blocks])
    frames = np.vstack([b.frames for b in blocks])
    return sc, times, frames, tuple(blocks)


def actor_with_lasting_branches(environment, start, lasting_branches, config=ActorConfig(),
                                planner_seed=0):
    """
    Build an Actor with the upper-body planner's lasting branches and seed set.

    An Actor built as its constructor builds one, but with the upper-body planner's
    ``lasting_branches`` set (``()``: no branch prefers lasting postures) and its random generator
    seeded with ``planner_seed`` (the constructor's: 0).
    """
    collision = BodyCollision(skeleton(), environment)
    upper = UpperBodyPlanner(skeleton(), collision,
                             UpperBodyConfig(lasting_branches=tuple(lasting_branches)),
                             rng=np.random.default_rng(planner_seed))
    return Actor(skeleton(), environment, config, start=start, upper_body_planner=upper,
                 body_collision=collision)


def course_names():
    return sorted(os.path.splitext(f)[0] for f in os.listdir(SCENES) if f.endswith('.yaml'))
