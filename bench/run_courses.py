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

"""
Simulate every shipped course and judge it with the independent checker.

Run: .venv/bin/python bench/run_courses.py [course ...] [--no-upper-body]
Prints one line per course: steps, reach, stuck events, planning p50/p99, real-time factor, and
the checker's verdict.
"""
import argparse
import glob
import os
import sys
import time

from digital_actor_planner.cli import read_commands
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.scene import load_scene
from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.evaluation.trajectory_check import check_trajectory
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(name, skeleton, upper_body=True, window_steps=3, check=True):
    """Simulate course ``name``; return (scene, times, frames, blocks, wall seconds)."""
    scene = load_scene(os.path.join(ROOT, 'config', 'scenes', name + '.yaml'), skeleton)
    commands = read_commands(os.path.join(ROOT, 'config', 'scenes', name + '.csv'))
    actor = Actor(skeleton, scene.environment,
                  ActorConfig(plan_upper_body=upper_body,
                              footsteps=FootstepConfig(window_steps=window_steps)),
                  start=scene.start)
    started = time.perf_counter()
    blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                          [c.angular_z for c in commands])
    wall = time.perf_counter() - started
    times = np.concatenate([b.times for b in blocks])
    frames = np.vstack([b.frames for b in blocks])
    return scene, times, frames, blocks, wall


def main(argv=None):
    parser = argparse.ArgumentParser()
    parser.add_argument('courses', nargs='*')
    parser.add_argument('--no-upper-body', action='store_true')
    parser.add_argument('--window-steps', type=int, default=3)
    args = parser.parse_args(argv)
    names = args.courses or sorted(os.path.splitext(os.path.basename(p))[0] for p in
                                   glob.glob(os.path.join(ROOT, 'config', 'scenes', '*.yaml')))
    skeleton = Skeleton()
    for name in names:
        scene, times, frames, blocks, wall = run(name, skeleton, not args.no_upper_body,
                                                 args.window_steps)
        steps = [b.planning_time for b in blocks if b.status == 'walking']
        stuck = sorted({b.reason for b in blocks if b.status == 'stuck'})
        report = check_trajectory(skeleton, scene.environment, times, frames, stride=2)
        print(f'{name:14s} steps {len(steps):3d} x {frames[-1, 0]:6.2f} y {frames[-1, 1]:5.2f} '
              f'yaw {frames[-1, 3]:5.2f} | plan p50 {1e3 * np.percentile(steps, 50):5.1f} ms '
              f'p99 {1e3 * np.percentile(steps, 99):5.1f} ms | x{times[-1] / wall:5.1f} '
              f'real time | {"OK" if report.ok else "FAIL"} | stuck: {stuck[:2]}')
        for failure in report.failures()[:4]:
            print('     ', failure)
        sys.stdout.flush()


if __name__ == '__main__':
    main()
