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
Turning walks on flat ground: how far a stance foot slides (at most 1 cm).

Run: .venv/bin/python bench/bench_turns.py [--speeds 0.5 0.8 1.0]
     [--turn-rates 0.3 0.5 0.7 1.0 -0.7] [--list]

On the flat course (lower body only) the actor walks straight for 1.5 s at each speed, then
turns at each rate until 7 s, then stops. Every walk is judged by the independent checker
(``check_trajectory``): the largest horizontal drift of a sole corner while it bears weight
(within 10 mm of the ground over a run of frames) must stay under 10 mm. Walks that leave the
floor's edge end stuck; the check covers what they walked.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.evaluation.trajectory_check import check_trajectory  # noqa: E402
import numpy as np  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--speeds', type=float, nargs='+', default=[0.5, 0.8, 1.0])
    parser.add_argument('--turn-rates', type=float, nargs='+',
                        default=[0.3, 0.5, 0.7, 1.0, -0.7])
    parser.add_argument('--list', action='store_true', help='print every walk')
    args = parser.parse_args(argv)
    sk = skeleton()
    sc = scene('flat')
    slips, failures = [], []
    for speed in args.speeds:
        for rate in args.turn_rates:
            actor = Actor(sk, sc.environment, ActorConfig(plan_upper_body=False), start=sc.start)
            blocks = run_commands(actor, [0.0, 1.5, 7.0], [speed, speed, 0.0], [0.0, rate, 0.0])
            times = np.concatenate([b.times for b in blocks])
            frames = np.vstack([b.frames for b in blocks])
            report = check_trajectory(sk, sc.environment, times, frames)
            slip = 1e3 * max(report.slip.values())
            slips.append(slip)
            if not report.ok:
                failures.append((speed, rate, report.failures()))
            if args.list:
                print(f'{speed:.2f} m/s, {rate:+.2f} rad/s: largest stance slip {slip:.1f} mm, '
                      f'turned {frames[-1, 3]:+.2f} rad, checker '
                      f'{"ok" if report.ok else "; ".join(report.failures()[:2])}', flush=True)
    slips = np.array(slips)
    print(f'\n{len(slips)} turning walks (speeds {args.speeds} m/s x turn rates '
          f'{args.turn_rates} rad/s)\n')
    print('| walks | checker failures | stance slip: median / p90 / max mm |')
    print('|---:|---:|---:|')
    print(f'| {len(slips)} | {len(failures)} | {np.median(slips):.1f} / '
          f'{np.percentile(slips, 90):.1f} / {slips.max():.1f} |')
    for speed, rate, reasons in failures:
        print(f'- {speed:.2f} m/s, {rate:+.2f} rad/s: {"; ".join(reasons[:2])}')
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
