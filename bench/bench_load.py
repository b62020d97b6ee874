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
The obstacle courses walked on an idle machine and with a CPU hog on every core: same outcome.

Run: .venv/bin/python bench/bench_load.py [--courses low_beam beam_too_low ...] [--hogs N]

Each course is planned from its command file twice, whole body: once as the machine is, once
while ``--hogs`` processes (default: one per CPU) spin at full speed beside it. A slow plan
may cost latency, never the outcome: reported per course, where the actor ended (x, and the
stuck reason if any) in both runs, whether every frame is the same, and the planning time per
block (p50 / max ms) in both. The planners hold no wall-clock deadline (the upper body's
optional ``time_budget`` is CPU time, and off by default), so the frames must match exactly.
"""
import argparse
import multiprocessing
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import scene, SCENES, skeleton  # noqa: E402
from digital_actor_planner.cli import read_commands  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
import numpy as np  # noqa: E402

COURSES = ('low_beam', 'beam_too_low', 'table', 'pillars', 'uneven_beam', 'wall', 'blocks',
           'stairs_up')


def _spin(stop) -> None:
    """Burn CPU until ``stop`` is set (a hog's body)."""
    while not stop.is_set():
        sum(i * i for i in range(10000))


def walk(name: str):
    """(frames (k, 22), blocks) of course ``name`` planned from its command file."""
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    actor = Actor(skeleton(), sc.environment, ActorConfig(), start=sc.start)
    blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                          [c.angular_z for c in commands])
    return np.vstack([b.frames for b in blocks]), blocks


def outcome(frames, blocks) -> str:
    """Where a walk ended: its x and, when it stopped, why."""
    stuck = [b.reason for b in blocks if b.status == 'stuck']
    return f'x {frames[-1, 0]:.2f} m' + (f', stuck: {stuck[-1]}' if stuck else '')


def planning(blocks) -> str:
    times = 1e3 * np.array([b.planning_time for b in blocks])
    return f'{np.percentile(times, 50):.1f} / {times.max():.0f}'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--hogs', type=int, default=os.cpu_count() or 2)
    args = parser.parse_args(argv)
    unknown = [c for c in args.courses if not os.path.exists(os.path.join(SCENES, c + '.yaml'))]
    if unknown or args.hogs < 1:
        parser.error(f'unknown courses {unknown}' if unknown else '--hogs must be >= 1')
    for name in args.courses:
        scene(name)  # loaded before timing either run
    walk(args.courses[0])  # the kernels compiled before either run
    idle = {name: walk(name) for name in args.courses}
    stop = multiprocessing.Event()
    hogs = [multiprocessing.Process(target=_spin, args=(stop,), daemon=True)
            for _ in range(args.hogs)]
    for hog in hogs:
        hog.start()
    try:
        time.sleep(0.5)  # the hogs are running before the loaded runs start
        loaded = {name: walk(name) for name in args.courses}
    finally:
        stop.set()
        for hog in hogs:
            hog.join(timeout=5.0)
            if hog.is_alive():
                hog.terminate()
    print(f'\nObstacle courses, whole body, idle and beside {args.hogs} CPU hogs\n')
    print('| course | idle: end | loaded: end | same frames | planning idle p50 / max ms | '
          'loaded p50 / max ms |')
    print('|---|---|---|---:|---:|---:|')
    same = 0
    for name in args.courses:
        (frames_a, blocks_a), (frames_b, blocks_b) = idle[name], loaded[name]
        equal = frames_a.shape == frames_b.shape and np.array_equal(frames_a, frames_b)
        same += equal
        print(f'| {name} | {outcome(frames_a, blocks_a)} | {outcome(frames_b, blocks_b)} | '
              f'{"yes" if equal else "NO"} | {planning(blocks_a)} | {planning(blocks_b)} |')
    print(f'\n{same} of {len(args.courses)} courses walked the same under load')
    print_command(__file__, argv)
    return 0 if same == len(args.courses) else 1


if __name__ == '__main__':
    sys.exit(main())
