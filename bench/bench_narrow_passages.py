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
Two pillars narrower than the shoulders, moved off the path.

Passed, met in front, or held between them.

Run: .venv/bin/python bench/bench_narrow_passages.py [--centres 0.35 0.36 0.37]
     [--shifts -0.04 -0.03 ... 0.04] [--list]

The pillars course (config/scenes/pillars.yaml: round pillars of radius 0.12 m at x = 3 m, their
centres 0.37 m either side of the path, a 0.50 m gap where the shoulders are 0.52 m wide) with
the pillars' centres ``--centres`` m either side of a line ``--shifts`` m to the left of the path
(test/scene_helpers.py, ``pillars_moved_sideways``). The actor walks along +x at 0.8 m/s for 9 s,
whole body planned, with three settings of ``ActorConfig``: the defaults
(``upper_body_preview_margin`` 0.1 s: a footstep whose upper body is blocked in the preview
less than that after the step is refused; ``upper_body_pause`` 0.2 s: when the upper body
refused every footstep, the first is tried once more after standing that long;
``upper_body_preview_distance`` 0.5 m: the preview covers at least that), the margin without
the pause, and none of the three. Outcome of each walk: passed (x > 4.5 m),
stopped in front (stuck before the chest reaches the pillars) or held between them (stuck
with the body among the pillars); and the slowest step (wall ms).
"""
import argparse
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command, spread  # noqa: E402
from course_runs import SCENES, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from scene_helpers import pillars_moved_sideways  # noqa: E402

#: Label -> (upper_body_preview_margin s, upper_body_pause s, upper_body_preview_distance m).
SETTINGS = {'defaults (margin 0.1 s, pause 0.2 s, preview >= 0.5 m)': (0.1, 0.2, 0.5),
            'margin, no pause': (0.1, 0.0, 0.5),
            'none of them': (0.0, 0.0, 0.0)}

#: Pelvis x beyond which the chest (0.15 m ahead of it) reaches the pillars' front (x 2.88 m).
IN_FRONT = 3.0 - 0.12 - 0.15


def outcome(blocks) -> str:
    x = blocks[-1].frames[-1, 0]
    if x > 4.5:
        return 'passed'
    if blocks[-1].status == 'stuck' and x < IN_FRONT:
        return 'stopped in front'
    return 'held between' if blocks[-1].status == 'stuck' else 'short'


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--centres', type=float, nargs='+', default=[0.35, 0.36, 0.37])
    parser.add_argument('--shifts', type=float, nargs='+',
                        default=[round(0.01 * i, 2) for i in range(-4, 5)])
    parser.add_argument('--list', action='store_true', help='print every walk')
    args = parser.parse_args(argv)
    sk = skeleton()
    labels = ('passed', 'stopped in front', 'held between', 'short')
    counts = {setting: dict.fromkeys(labels, 0) for setting in SETTINGS}
    slowest = {setting: [] for setting in SETTINGS}
    with tempfile.TemporaryDirectory() as directory:
        for centre in args.centres:
            for shift in args.shifts:
                sc = pillars_moved_sideways(SCENES, directory, centre, shift, sk)
                for setting, (margin, pause, distance) in SETTINGS.items():
                    config = ActorConfig(upper_body_preview_margin=margin,
                                         upper_body_pause=pause,
                                         upper_body_preview_distance=distance)
                    actor = Actor(sk, sc.environment, config, start=sc.start)
                    blocks = run_commands(actor, [0.0, 9.0], [0.8, 0.0], [0.0, 0.0])
                    result = outcome(blocks)
                    counts[setting][result] += 1
                    slowest[setting].append(1e3 * max(b.planning_time for b in blocks))
                    if args.list:
                        print(f'centre {centre:.3f} shift {shift:+.3f} {setting}: '
                              f'{result} at x {blocks[-1].frames[-1, 0]:.2f} m '
                              f'{blocks[-1].reason}', flush=True)
    walks = len(args.centres) * len(args.shifts)
    print(f'\n{walks} pillar placements (centres {args.centres} m, shifts {args.shifts} m), '
          '9 s at 0.8 m/s each\n')
    print('| setting | passed | stopped in front | held between | '
          'slowest step: p50 / p90 / max ms |')
    print('|---|---:|---:|---:|---:|')
    for setting in SETTINGS:
        c = counts[setting]
        short = f' (+{c["short"]} short of the end, not stuck)' if c['short'] else ''
        print(f'| {setting} | {c["passed"]} | {c["stopped in front"]} | '
              f'{c["held between"]}{short} | {spread(slowest[setting])} |')
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
