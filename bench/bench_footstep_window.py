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
The footstep window's two searches side by side: the readable one and its compiled twin.

Run: .venv/bin/python bench/bench_footstep_window.py [--courses flat stairs_up ...] [--rounds 3]

Walks each course (upper-body planning off) with ``FootstepConfig.window_search`` set to
``'compiled'`` and to ``'readable'``, in alternating order, checks that both walks have the same
frames, and reports the CPU time of one window's search (every ``FootstepPlanner.plan`` call of
the walks, timed) and the wall time of a whole step (``StepBlock.planning_time``), medians.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_common import machine, paired_walks  # noqa: E402
from course_runs import scene, SCENES, skeleton  # noqa: E402
from digital_actor_planner.cli import read_commands  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.footsteps import FootstepConfig, FootstepPlanner  # noqa: E402
import numpy as np  # noqa: E402

COURSES = ('flat', 'rough', 'slope', 'stairs_up', 'stairs_down', 'blocks', 'gap', 'turn')


def walk(name: str, window_search: str, searches: list):
    """Walk course ``name``; each window's search CPU time (s) appended to ``searches``."""
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    config = ActorConfig(plan_upper_body=False,
                         footsteps=FootstepConfig(window_search=window_search))
    actor = Actor(skeleton(), sc.environment, config, start=sc.start)
    plan = FootstepPlanner.plan

    def timed(self, *arguments, **keywords):
        begin = time.process_time()
        try:
            return plan(self, *arguments, **keywords)
        finally:
            searches.append(time.process_time() - begin)

    FootstepPlanner.plan = timed
    try:
        blocks = run_commands(actor, [c.time for c in commands],
                              [c.linear_x for c in commands], [c.angular_z for c in commands])
    finally:
        FootstepPlanner.plan = plan
    return blocks


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--rounds', type=int, default=3)
    args = parser.parse_args(argv)
    print(machine())
    kinds = ('compiled', 'readable')
    walks = paired_walks(args.courses, args.rounds, walk, 'searches')
    if walks is None:
        return 1
    searches, steps = walks
    print(f'{"search":<10} {"windows":>8} {"window CPU, ms":>15} {"step wall, ms":>14}')
    for kind in kinds:
        print(f'{kind:<10} {len(searches[kind]):>8} {1e3 * np.median(searches[kind]):>15.3f} '
              f'{1e3 * np.median(steps[kind]):>14.2f}')
    ratio = np.median(searches['readable']) / np.median(searches['compiled'])
    print(f'the readable search takes {ratio:.0f} times as long per window '
          f'({", ".join(args.courses)}; {args.rounds} rounds; the same frames)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
