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
Random furniture beside the path at arm height: the arms with and without lasting postures.

Run: .venv/bin/python bench/bench_arm_obstacles.py [--scenes 40] [--seed 0] [--planner-seed 0]
         [--default-only]

Each scene (test/scene_helpers.py, ``furniture_scene``) is flat ground with one box beside the
path (left or right, its near side 0.17-0.32 m from the path, top 0.65-1.05 m, 0.4-2.0 m long)
and, in half of them, a smaller box standing on it at the near edge. The actor walks along +x
at 0.8 m/s for 8 s with the whole body planned, once with the upper-body planner's default (the
arms prefer lasting postures, ``UpperBodyConfig.lasting_branches``) and once with the
preference off (``()``: plain best-first ranking by closeness to the pattern). Reported per
setting: scenes passed (x >= 6 m), stuck, how far the arm on the box's side
swung off its pattern at the shoulder (mean, max), in how many scenes its elbow flexed >= 0.3
rad beyond the pattern, and the slowest step of each run (p50, p90, max over the scenes, wall
ms). The same scenes and commands for both settings. ``--planner-seed`` seeds the upper-body
planner's random generator (roadmap growth; the actor's own is seeded 0): where an outcome is
close to a coin toss, another seed shows it. ``--default-only`` runs the default setting only.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from course_runs import actor_with_lasting_branches, skeleton  # noqa: E402
from digital_actor_planner.core.actor import run_commands  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
from digital_actor_planner.core.upper_body import motion_patterns  # noqa: E402
import numpy as np  # noqa: E402
from scene_helpers import furniture_scene  # noqa: E402

SETTINGS = (('lasting arm postures (default)', ('left_arm', 'right_arm')),
            ('closeness only', ()))


def walk(environment, lasting_branches, planner_seed=0):
    """Blocks of the 8 s walk along +x at 0.8 m/s."""
    actor = actor_with_lasting_branches(environment, (0.0, 0.0, 0.0), lasting_branches,
                                        planner_seed=planner_seed)
    return run_commands(actor, [0.0, 8.0], [0.8, 0.0], [0.0, 0.0])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--scenes', type=int, default=40)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--planner-seed', type=int, default=0,
                        help="seed of the upper-body planner's random generator")
    parser.add_argument('--default-only', action='store_true',
                        help='run the default setting only (lasting arm postures)')
    parser.add_argument('--list', action='store_true',
                        help='print every scene where the settings differ in outcome (with '
                             '--default-only: every scene not passed)')
    args = parser.parse_args(argv)
    if args.scenes < 1:
        parser.error(f'--scenes must be >= 1, got {args.scenes}')
    sk = skeleton()
    rng = np.random.default_rng(args.seed)
    settings = SETTINGS[:1] if args.default_only else SETTINGS
    results = {name: [] for name, _ in settings}
    for index in range(args.scenes):
        meshes, arm = furniture_scene(rng)
        environment = Environment(meshes, resolution=0.02)
        for name, branches in settings:
            blocks = walk(environment, branches, args.planner_seed)
            frames = np.vstack([b.frames for b in blocks])
            off = frames - motion_patterns(sk, frames)
            results[name].append({
                'passed': frames[-1, 0] >= 6.0, 'stuck': blocks[-1].status == 'stuck',
                'shoulder': float(np.abs(off[:, sk.index[f'{arm}_shoulder_pitch']]).max()),
                'elbow': float(off[:, sk.index[f'{arm}_elbow']].max()),
                'slowest': 1e3 * max(b.planning_time for b in blocks),
                'x': float(frames[-1, 0]), 'reason': blocks[-1].reason})
        outcomes = [results[name][-1] for name, _ in settings]
        # With one setting, --list prints the scenes it did not pass.
        differ = (len({(r['passed'], r['stuck']) for r in outcomes}) > 1 if len(outcomes) > 1
                  else not outcomes[0]['passed'])
        if args.list and differ:
            boxes = '; '.join(f'{np.round(m.bounds[0], 2).tolist()}..'
                              f'{np.round(m.bounds[1], 2).tolist()}' for m in meshes[1:])
            print(f'scene {index} ({arm} arm; {boxes}):')
            for (name, _), r in zip(settings, outcomes):
                print(f'  {name}: x {r["x"]:.2f} m, {r["reason"] or "walking"}')
    print(f'\n{args.scenes} random scenes (seed {args.seed}), 8 s walk at 0.8 m/s each\n')
    print('| arms | passed | stuck | shoulder off its swing: mean / max rad | elbow flexed '
          '>= 0.3 rad | slowest step: p50 / p90 / max ms |')
    print('|---|---:|---:|---:|---:|---:|')
    for name, rows in results.items():
        shoulder = np.array([r['shoulder'] for r in rows])
        slowest = np.array([r['slowest'] for r in rows])
        print(f'| {name} | {sum(r["passed"] for r in rows)} | {sum(r["stuck"] for r in rows)} '
              f'| {shoulder.mean():.3f} / {shoulder.max():.2f} '
              f'| {sum(r["elbow"] >= 0.3 for r in rows)} '
              f'| {np.percentile(slowest, 50):.1f} / {np.percentile(slowest, 90):.1f} / '
              f'{slowest.max():.1f} |')
    load = os.getloadavg()[0] if hasattr(os, 'getloadavg') else float('nan')
    print(f'\n(command: python bench/bench_arm_obstacles.py --scenes {args.scenes} --seed '
          f'{args.seed} --planner-seed {args.planner_seed}'
          f'{" --default-only" if args.default_only else ""}; load average {load:.1f})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
