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
Every legal command on open flat ground: the fraction of walks that end stuck (target 0).

Run: .venv/bin/python bench/bench_open_ground.py [--speeds 0.1 0.3 0.5 0.7 0.85 1.0]
     [--turn-rates -1 -0.6 -0.3 0 0.3 0.6 1] [--walk 6] [--then 5] [--list]

On a 40 x 40 m floor the actor walks each previous command (straight at a slow, a middling and
the top speed, and arcs either way) for ``--walk`` s, then each command of the grid speed x
turn rate for ``--then`` s. A walk counts as stuck when any block after the change is; every
walk is judged by the independent checker (``check_trajectory``). Reported: the walks, the
stuck ones (with their reasons) and the checker's failures.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
from digital_actor_planner.evaluation.trajectory_check import check_trajectory  # noqa: E402
import numpy as np  # noqa: E402
from scene_helpers import box  # noqa: E402

#: (linear m/s, angular rad/s) walked before the change: straight slow, middling and at the
#: top speed, and arcs left and right (at the top speed, the turn reversed).
PREVIOUS = ((0.3, 0.0), (0.6, 0.0), (1.0, 0.0), (0.6, 0.6), (1.0, -1.0), (0.3, 1.0))


def open_floor() -> Environment:
    """Return a 40 x 40 m floor, its top at z = 0, centred on the origin."""
    return Environment([box([-20.0, -20.0, -0.1], [20.0, 20.0, 0.0])])


def walk_with_change(environment, previous, command, walk: float, then: float,
                     plan_upper_body: bool = True):
    """
    Walk one command from the origin, then another; return the blocks before and after.

    Walk ``previous`` (linear m/s, angular rad/s) for ``walk`` s from the origin, then ``command``
    for ``then`` s. Returns (blocks before, blocks after).
    """
    actor = Actor(skeleton(), environment, ActorConfig(plan_upper_body=plan_upper_body),
                  start=(0.0, 0.0, 0.0))
    before = run_commands(actor, [0.0, walk], [previous[0], 0.0], [previous[1], 0.0])
    after = run_commands(actor, [actor.time, actor.time + then], [command[0], 0.0],
                         [command[1], 0.0])
    return before, after


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--speeds', type=float, nargs='+',
                        default=[0.1, 0.3, 0.5, 0.7, 0.85, 1.0])
    parser.add_argument('--turn-rates', type=float, nargs='+',
                        default=[-1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 1.0])
    parser.add_argument('--walk', type=float, default=6.0, help='s of the previous command')
    parser.add_argument('--then', type=float, default=5.0, help='s of the new command')
    parser.add_argument('--list', action='store_true', help='print every walk')
    args = parser.parse_args(argv)
    if args.walk <= 0 or args.then <= 0:
        parser.error('--walk and --then must be > 0 s')
    environment = open_floor()
    walks, stuck, failures = 0, [], []
    for previous in PREVIOUS:
        for speed in args.speeds:
            for rate in args.turn_rates:
                before, after = walk_with_change(environment, previous, (speed, rate),
                                                 args.walk, args.then)
                blocks = before + after
                times = np.concatenate([b.times for b in blocks])
                frames = np.vstack([b.frames for b in blocks])
                report = check_trajectory(skeleton(), environment, times, frames)
                reasons = sorted({b.reason for b in blocks if b.status == 'stuck'})
                walks += 1
                if reasons:
                    stuck.append((previous, speed, rate, reasons))
                if not report.ok:
                    failures.append((previous, speed, rate, report.failures()))
                if args.list:
                    print(f'{previous} -> ({speed:.2f}, {rate:+.2f}): '
                          f'{"stuck: " + "; ".join(reasons) if reasons else "walked"}, checker '
                          f'{"ok" if report.ok else "; ".join(report.failures()[:2])}',
                          flush=True)
    print(f'\n{walks} walks on open flat ground: previous commands {list(PREVIOUS)}, then '
          f'speeds {args.speeds} m/s x turn rates {args.turn_rates} rad/s\n')
    print('| walks | stuck | stuck fraction | checker failures |')
    print('|---:|---:|---:|---:|')
    print(f'| {walks} | {len(stuck)} | {len(stuck) / walks:.3f} | {len(failures)} |')
    for previous, speed, rate, reasons in stuck:
        print(f'- stuck: {previous} -> ({speed:.2f}, {rate:+.2f}): {"; ".join(reasons)}')
    for previous, speed, rate, reasons in failures:
        print(f'- checker: {previous} -> ({speed:.2f}, {rate:+.2f}): {"; ".join(reasons[:2])}')
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
