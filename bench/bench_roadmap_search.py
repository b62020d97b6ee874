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
The CT-roadmap's two expansions side by side: the readable one and its compiled twin.

Run: .venv/bin/python bench/bench_roadmap_search.py [--courses low_beam table ...] [--rounds 3]

Walks each course (upper body on) with ``UpperBodyConfig.roadmap_search`` set to
``'compiled'`` and to ``'readable'``, in alternating order, checks that both walks have the same
frames, and reports the CPU time of one branch search (every ``CTRoadmap.solve`` call of the
walks, timed; the median and the slowest) and the wall time of a whole step
(``StepBlock.planning_time``, median).
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
from digital_actor_planner.core.collision import BodyCollision  # noqa: E402
from digital_actor_planner.core.ct_roadmap import CTRoadmap  # noqa: E402
from digital_actor_planner.core.upper_body import (UpperBodyConfig,  # noqa: E402
                                                   UpperBodyPlanner)  # noqa: E402
import numpy as np  # noqa: E402

COURSES = ('low_beam', 'table', 'pillars', 'uneven_beam')


def walk(name: str, roadmap_search: str, searches: list):
    """Walk course ``name``; each branch search's CPU time (s) appended to ``searches``."""
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    config = ActorConfig()
    collision = BodyCollision(skeleton(), sc.environment)
    upper = UpperBodyPlanner(skeleton(), collision,
                             UpperBodyConfig(roadmap_search=roadmap_search),
                             rng=np.random.default_rng(0))
    actor = Actor(skeleton(), sc.environment, config, start=sc.start, upper_body_planner=upper,
                  body_collision=collision)
    solve = CTRoadmap.solve

    def timed(self, *arguments, **keywords):
        begin = time.process_time()
        try:
            return solve(self, *arguments, **keywords)
        finally:
            searches.append(time.process_time() - begin)

    CTRoadmap.solve = timed
    try:
        return run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                            [c.angular_z for c in commands])
    finally:
        CTRoadmap.solve = solve


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--rounds', type=int, default=3)
    args = parser.parse_args(argv)
    print(machine())
    kinds = ('compiled', 'readable')
    walks = paired_walks(args.courses, args.rounds, walk, 'expansions')
    if walks is None:
        return 1
    searches, steps = walks
    print(f'{"expansion":<10} {"searches":>9} {"search CPU, ms":>15} {"slowest, ms":>12} '
          f'{"step wall, ms":>14}')
    for kind in kinds:
        print(f'{kind:<10} {len(searches[kind]):>9} {1e3 * np.median(searches[kind]):>15.3f} '
              f'{1e3 * np.max(searches[kind]):>12.1f} {1e3 * np.median(steps[kind]):>14.2f}')
    ratio = np.max(searches['readable']) / np.max(searches['compiled'])
    print(f'the readable expansion takes {ratio:.1f} times as long on the slowest search '
          f'({", ".join(args.courses)}; {args.rounds} rounds; the same frames)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
