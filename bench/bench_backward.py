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
Backward walking: walked speed, the arc of a backward turn, steps up and down, escapes.

Run: .venv/bin/python bench/bench_backward.py [--speeds 0.1 0.2 0.3 0.4 0.5]
     [--heights 0.05 0.08 0.10 0.12 0.13 0.14 0.16 0.20]

Every walk is judged by the independent checker (``check_trajectory``: every link against the
meshes, a foot always down, limits, no jumps, stance slip <= 1 cm); the legs only, except the
escapes, which plan the whole body.

1. Straight backward on the flat course for 8 s from x = 8 m at each speed: walked speed (the
   pelvis's distance over the walking steps' time), steps and their mean length.
2. Backward arcs (-0.4 m/s, +-0.3 / +-0.6 / +-1.0 rad/s, 6 s): the largest distance of the pelvis
   from the circle ``cmd_vel`` means (centre v / w to the left of the start) and the heading
   turned against the command's.
3. One step up and one down, backward, for each height: a floor with a step at x = 1 m; up
   from x = 0 facing away from it, down from x = 2.5 m facing away from the edge. Taken (the
   pelvis over the other level) or stopped, and why.
4. The stops of the shipped infeasible courses, left by a backward drag (-0.4 m/s, 4 s): the
   wall, the beam too low, the flat floor's far edge, Figure 8's trap with a window of one
   footstep; steps taken and metres gone back.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import machine, print_command  # noqa: E402
from course_runs import judged, scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
from digital_actor_planner.core.footsteps import FootstepConfig  # noqa: E402
import numpy as np  # noqa: E402
from scene_helpers import box  # noqa: E402

LEGS = ActorConfig(plan_upper_body=False)


def verdict(report) -> str:
    slip = max(report.slip.values()) if report.slip else 0.0
    return f'ok (slip {1000 * slip:.1f} mm)' if report.ok else '; '.join(report.failures()[:2])


def speeds(values):
    print('| command m/s | walked m/s | steps | mean step m | checker |')
    print('|---:|---:|---:|---:|---|')
    sc = scene('flat')
    for v in values:
        actor = Actor(skeleton(), sc.environment, LEGS, start=(8.0, 0.0, 0.0))
        blocks = run_commands(actor, [0.0, 8.0], [-v, -v], [0.0, 0.0])
        _, frames, report = judged(blocks, sc.environment)
        walking = [b for b in blocks if b.status == 'walking']
        duration = sum(b.times[-1] - b.times[0] + 1.0 / LEGS.frame_rate for b in walking)
        gone = walking[0].frames[0, 0] - walking[-1].frames[-1, 0] if walking else 0.0
        print(f'| {-v:.2f} | {gone / max(duration, 1e-9):.3f} | {len(walking)} | '
              f'{gone / max(len(walking), 1):.3f} | {verdict(report)} |', flush=True)


def arcs(rates):
    print('\n| command (m/s, rad/s) | off the arc, max m | heading turned rad (commanded) | '
          'stuck blocks | checker |')
    print('|---|---:|---:|---:|---|')
    sc = scene('flat')
    v = -0.4
    for w in rates:
        actor = Actor(skeleton(), sc.environment, LEGS, start=(6.0, 0.0, 0.0))
        blocks = run_commands(actor, [0.0, 6.0], [v, v], [w, w])
        _, frames, report = judged(blocks, sc.environment)
        centre = np.array([6.0, v / w])
        off = np.abs(np.hypot(*(frames[:, :2] - centre).T) - abs(v / w)).max()
        stuck = sum(b.status == 'stuck' for b in blocks)
        print(f'| ({v}, {w:+.1f}) | {off:.3f} | {frames[-1, 3]:+.2f} ({6.0 * w:+.1f}) | '
              f'{stuck} | {verdict(report)} |', flush=True)


def steps(heights):
    print('\n| step m | up backward | down backward |')
    print('|---:|---|---|')
    stand = skeleton().leg.standing_height
    for h in heights:
        environment = Environment([box((-2, -2, -0.2), (4, 2, 0.0)),
                                   box((1.0, -2, -0.2), (4, 2, h))])
        cells = []
        for start, upper in (((0.0, 0.0, np.pi), True), ((2.5, 0.0, 0.0), False)):
            actor = Actor(skeleton(), environment, LEGS, start=start)
            blocks = run_commands(actor, [0.0, 8.0], [-0.4, -0.4], [0.0, 0.0])
            _, frames, report = judged(blocks, environment)
            taken = frames[-1, 2] > stand + h - 0.05 if upper else frames[-1, 2] < stand + 0.05
            stuck = next((b.reason for b in blocks if b.status == 'stuck'), '')
            cells.append(('taken' if taken else f'stopped ({stuck})') + f', {verdict(report)}')
        print(f'| {h:.2f} | {cells[0]} | {cells[1]} |', flush=True)


def escapes():
    print('\n| stuck at | reason | backward steps (4 s) | m back | checker | plan s |')
    print('|---|---|---:|---:|---|---:|')
    one = ActorConfig(plan_upper_body=False,
                      footsteps=FootstepConfig(window_steps=1, greedy_restart=False))
    cases = (('wall', None, ActorConfig()), ('beam_too_low', None, ActorConfig()),
             ('flat', (13.0, 0.0, 0.0), LEGS), ('figure8_trap', None, one))
    for name, start, config in cases:
        sc = scene(name)
        started = time.perf_counter()
        actor = Actor(skeleton(), sc.environment, config,
                      start=sc.start if start is None else start)
        before = run_commands(actor, [0.0, 10.0], [0.8, 0.8], [0.0, 0.0])
        stuck_at = actor.configuration[:2].copy()
        reason = before[-1].reason if before[-1].status == 'stuck' else '(not stuck)'
        actor.set_command(-0.4, 0.0)
        after = []
        while actor.time < before[-1].times[-1] + 4.0:
            after.append(actor.plan_next())
        _, frames, report = judged(before + after, sc.environment)
        facing = np.array([np.cos(frames[-1, 3]), np.sin(frames[-1, 3])])
        back = float((stuck_at - frames[-1, :2]) @ facing)
        taken = sum(b.status == 'walking' for b in after)
        print(f'| {name} ({stuck_at[0]:.2f}, {stuck_at[1]:.2f}) | {reason} | {taken} | '
              f'{back:.2f} | {verdict(report)} | {time.perf_counter() - started:.1f} |',
              flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--speeds', type=float, nargs='+', default=[0.1, 0.2, 0.3, 0.4, 0.5])
    parser.add_argument('--heights', type=float, nargs='+',
                        default=[0.05, 0.08, 0.10, 0.12, 0.13, 0.14, 0.16, 0.20])
    args = parser.parse_args(argv)
    if any(not 0.0 < v <= LEGS.max_backward_speed for v in args.speeds):
        parser.error(f'--speeds must lie in (0, {LEGS.max_backward_speed}] m/s (backward), '
                     f'got {args.speeds}')
    if any(not 0.0 < h <= 0.4 for h in args.heights):
        parser.error(f'--heights must lie in (0, 0.4] m, got {args.heights}')
    print(machine())
    speeds(args.speeds)
    arcs([0.3, -0.3, 0.6, -0.6, 1.0, -1.0])
    steps(args.heights)
    escapes()
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
