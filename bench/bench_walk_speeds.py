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
The obstacle courses walked at other speeds than their command files: passed or stopped.

Run: .venv/bin/python bench/bench_walk_speeds.py [--speeds 0.3 0.4 0.5 0.6 0.7 0.9 1.0]
     [--distances 0.5 0.0] [--list]
     .venv/bin/python bench/bench_walk_speeds.py --flat [--speeds ...]

``--flat``: the walked speed against the commanded one instead. On a 60 m floor the actor walks
straight at each speed (up to ``ActorConfig.max_linear_speed`` and beyond it, where the command
is clamped) for 20 s; reported per speed: the distance, the walked speed, the steps and their
median length and duration. The walked speed must rise with the command up to the maximum.

Each upper-body course (low_beam, table, pillars, uneven_beam) is walked straight along +x at
each speed for the time 7 m takes (at 0.7 m/s at least: faster commands do not make the steps
much faster than that), with the whole body planned, once per
``ActorConfig.upper_body_preview_distance`` in ``--distances`` (0.5 m: the default, the upper
body's preview covers at least that far; 0: a fixed 0.5 s, which at 0.4 m/s sees 0.2 m
ahead). A walk passes when it ends within 0.3 m of the course's ``reach_x``; every walk is
judged by the independent checker (``check_trajectory``: every link against the meshes, a foot
always down, limits, no jumps). Reported per setting: walks passed, stopped, failing the checker,
and the slowest step (wall ms).
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command, spread  # noqa: E402
from course_runs import scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
from digital_actor_planner.evaluation.trajectory_check import check_trajectory  # noqa: E402
import numpy as np  # noqa: E402
from scene_helpers import box  # noqa: E402

COURSES = ('low_beam', 'table', 'pillars', 'uneven_beam')


def walked_speeds(speeds, argv) -> int:
    """Print the walked speed against the commanded one on a 60 m floor (``--flat``)."""
    sk = skeleton()
    environment = Environment([box([-2.0, -3.0, -0.1], [62.0, 3.0, 0.0])])
    duration = 20.0
    print(f'Straight walks of {duration:g} s on a 60 m floor '
          f'(max_linear_speed {ActorConfig().max_linear_speed:g} m/s)\n')
    print('| command m/s | walked m | walked m/s | steps | step length m | step time s |')
    print('|---:|---:|---:|---:|---:|---:|')
    for speed in speeds:
        actor = Actor(sk, environment, ActorConfig(), start=(0.0, 0.0, 0.0))
        blocks = run_commands(actor, [0.0, duration], [speed, 0.0], [0.0, 0.0])
        steps = [b for b in blocks if b.status == 'walking']
        lengths = np.diff([b.frames[-1, 0] for b in steps])
        times = [b.times[-1] - b.times[0] + 1.0 / actor.config.frame_rate for b in steps]
        distance = float(blocks[-1].frames[-1, 0])
        print(f'| {speed:.2f} | {distance:.1f} | {distance / duration:.2f} | {len(steps)} | '
              f'{np.median(lengths):.2f} | {np.median(times):.2f} |', flush=True)
    print_command(__file__, argv)
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--speeds', type=float, nargs='+',
                        default=None, help='m/s (default: the courses 0.3-1.0, --flat '
                        '0.3-1.2)')
    parser.add_argument('--flat', action='store_true',
                        help='walked against commanded speed on open flat ground')
    parser.add_argument('--distances', type=float, nargs='+', default=[0.5, 0.0])
    parser.add_argument('--list', action='store_true', help='print every walk')
    args = parser.parse_args(argv)
    if args.flat:
        speeds = args.speeds or [0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0, 1.2]
        if any(not 0.05 <= v <= 3.0 for v in speeds):
            parser.error(f'--speeds must lie in [0.05, 3] m/s, got {speeds}')
        return walked_speeds(speeds, argv)
    args.speeds = args.speeds or [0.3, 0.4, 0.5, 0.6, 0.7, 0.9, 1.0]
    top = ActorConfig().max_linear_speed
    if any(not 0.05 <= v <= top for v in args.speeds):
        parser.error(f'--speeds must lie in [0.05, {top:g}] m/s, got {args.speeds}')
    sk = skeleton()
    rows = {d: [] for d in args.distances}
    for name in COURSES:
        sc = scene(name)
        reach = sc.expect.get('reach_x', 5.0)
        for speed in args.speeds:
            for distance in args.distances:
                actor = Actor(sk, sc.environment,
                              ActorConfig(upper_body_preview_distance=distance), start=sc.start)
                blocks = run_commands(actor, [0.0, 7.0 / min(speed, 0.7)], [speed, 0.0],
                                      [0.0, 0.0])
                times = np.concatenate([b.times for b in blocks])
                frames = np.vstack([b.frames for b in blocks])
                judged = check_trajectory(sk, sc.environment, times, frames).ok
                passed = frames[-1, 0] >= reach - 0.3
                slowest = 1e3 * max(b.planning_time for b in blocks)
                rows[distance].append((passed, judged, slowest))
                if args.list:
                    print(f'{name} {speed:.2f} m/s, preview >= {distance:.2f} m: '
                          f'{"passed" if passed else "stopped"} at x {frames[-1, 0]:.2f} m, '
                          f'checker {"ok" if judged else "FAILED"}, slowest step '
                          f'{slowest:.0f} ms {blocks[-1].reason}', flush=True)
    walks = len(COURSES) * len(args.speeds)
    print(f'\n{walks} walks: courses {", ".join(COURSES)} at {args.speeds} m/s\n')
    print('| upper_body_preview_distance | passed | stopped | checker failures | '
          'slowest step: p50 / p90 / max ms |')
    print('|---:|---:|---:|---:|---:|')
    for distance, results in rows.items():
        passed = sum(r[0] for r in results)
        failed = sum(not r[1] for r in results)
        print(f'| {distance:.2f} m | {passed} | {len(results) - passed} | {failed} | '
              f'{spread([r[2] for r in results])} |')
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
