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
Zigzag mouse steering on the courses: every walk judged, every stop steered away from.

Run: .venv/bin/python bench/bench_steer_away.py [--courses flat rough ...] [--seeds 8]
         [--first-seed 0] [--list]
         [--max-toe-in 0.35] [--no-edge-turns]

A mouse user does not drive straight. Each walk here (seeded, 12 s) holds a command for 0.3-2 s
at a time: linear 0.2-1.2 m/s (0 one time in seven: the mouse stands still) and a turn of up
to 1.2 rad/s that alternates left and right, so the actor weaves along the course, into its
obstacles and, as often, to the edge of its floor (2 m either side of the start line). The
whole body is planned and the independent checker judges the whole walk (every link against the
meshes, a foot always down, limits, no jumps, stance slip <= 1 cm).

Where a walk first stops (stuck), the walk is replayed to 0.3 s after the stop and the user
then steers away with each of five commands for 4 s: turn on the spot left and right (0, +-1),
walk a tight arc left and right (0.3 m/s, +-0.8 rad/s), walk slowly on (0.5 m/s), and drag it
backward (-0.4 m/s). The stop counts as *left* when one of them takes at least two steps;
otherwise the actor is *trapped* there (a later command that turns it away lets it go on). The
stops only the backward drag left are counted too, and the stops the forward commands alone
would leave trapped. Also counted: walks in
which the two legs (thigh, shank, foot) pass into each other, which the checker judges too, and
the time stopped because a step would have.

A second table turns on the spot at the floor's edge (flat, gap and blocks courses): standing
0.4-0.7 m from the edge facing it at 60, 90 or 120 degrees, told (0, +-1) for 4 s, with and
without ``ActorConfig.pivot_turn``; a turn counts when the heading changed by more than 1 rad.
Last, turns on the spot (0, 1) for 3 s started on the rough course's bumps.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import judged, scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
import numpy as np  # noqa: E402

COURSES = ('flat', 'rough', 'blocks', 'stairs_up', 'gap', 'low_beam', 'table', 'pillars')
AWAY = ((0.0, 1.0), (0.0, -1.0), (0.3, 0.8), (0.3, -0.8), (0.5, 0.0), (-0.4, 0.0))
# Stops with the pelvis farther than this (m) from the scene's sides (its meshes' extent
# across the start line, 1.5-2 m either side) are away from the floor's edges, where weaving
# walks end up stopped facing the edge.
EDGE = 0.8


def zigzag(seed: int, duration: float = 12.0):
    """Return (times, linear, angular) of one seeded weaving walk, ending with a stop."""
    rng = np.random.default_rng(seed)
    times = [0.0]
    while times[-1] < duration:
        times.append(times[-1] + rng.uniform(0.3, 2.0))
    count = len(times)
    linear = np.where(rng.random(count) < 0.15, 0.0, rng.uniform(0.2, 1.2, count))
    angular = rng.uniform(0.0, 1.2, count) * (-1.0) ** np.arange(count)
    linear[-1] = angular[-1] = 0.0
    return times, linear.tolist(), angular.tolist()


def walk(sk, sc, times, linear, angular, config=None):
    actor = Actor(sk, sc.environment, config or ActorConfig(), start=sc.start)
    return run_commands(actor, times, linear, angular)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--seeds', type=int, default=8)
    parser.add_argument('--first-seed', type=int, default=0,
                        help='walk seeds first-seed .. first-seed + seeds - 1')
    parser.add_argument('--list', action='store_true', help='print every stop')
    parser.add_argument('--max-toe-in', type=float, default=ActorConfig().max_toe_in,
                        help='ActorConfig.max_toe_in, rad')
    parser.add_argument('--no-edge-turns', action='store_true',
                        help='skip the turns on the spot (at the edge and on the bumps)')
    args = parser.parse_args(argv)
    config = ActorConfig(max_toe_in=args.max_toe_in)
    sk = skeleton()
    walks = failures = stops = trapped = only_backward = backward_left = 0
    steps = legs_walks = 0
    walked = legs_stuck = stuck_time = inner_stuck_time = total_time = 0.0
    for name in args.courses:
        sc = scene(name)
        sides = np.vstack([mesh.vertices for mesh in sc.environment.meshes])[:, 1]
        inner = (float(sides.min()) + EDGE, float(sides.max()) - EDGE)
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            times, linear, angular = zigzag(seed)
            blocks = walk(sk, sc, times, linear, angular, config)
            t, frames, report = judged(blocks, sc.environment)
            walks += 1
            if not report.ok:
                failures += 1
                print(f'{name} seed {seed}: checker: {"; ".join(report.failures()[:2])}',
                      flush=True)
            walked += float(np.hypot(*np.diff(frames[:, :2], axis=0).T).sum())
            steps += sum(1 for block in blocks if block.category)  # holds have none
            legs_walks += bool(report.leg_contacts)
            legs_stuck += sum(b.times[-1] - b.times[0] for b in blocks
                              if b.status == 'stuck' and 'legs would pass' in b.reason)
            stuck_time += sum(b.times[-1] - b.times[0] for b in blocks if b.status == 'stuck')
            inner_stuck_time += sum(b.times[-1] - b.times[0] for b in blocks
                                    if b.status == 'stuck'
                                    and inner[0] < b.frames[-1, 1] < inner[1])
            total_time += float(t[-1])
            first = next((b for b in blocks if b.status == 'stuck'), None)
            if first is None:
                continue
            stops += 1
            at = float(first.times[0]) + 0.3
            kept = [i for i, time in enumerate(times) if time < at]
            taken = []
            for v, w in AWAY:
                replay = walk(sk, sc, [times[i] for i in kept] + [at, at + 4.0],
                              [linear[i] for i in kept] + [v, 0.0],
                              [angular[i] for i in kept] + [w, 0.0], config)
                taken.append(sum(b.status == 'walking' for b in replay if b.times[0] > at))
            left = max(taken) >= 2
            trapped += not left
            only_backward += left and max(taken[:-1]) < 2
            backward_left += taken[-1] >= 2
            if args.list or not left:
                x, y, _, yaw = first.frames[-1, :4]
                print(f'{name} seed {seed}: stopped at t = {first.times[0]:.2f} s, '
                      f'({x:.2f}, {y:.2f}) heading {yaw:+.2f} rad ({first.reason}); steps '
                      f'taken steering away {taken}: {"left" if left else "TRAPPED"}',
                      flush=True)
    print(f'\n{walks} weaving walks ({len(args.courses)} courses x {args.seeds} seeds from '
          f'{args.first_seed}, 12 s '
          'each, whole body)\n')
    print(f'| walks | checker failures | walked m | time stopped | of it over {EDGE} m from '
          "the floor's sides | stops | stops left by steering away | trapped |")
    print('|---:|---:|---:|---:|---:|---:|---:|---:|')
    print(f'| {walks} | {failures} | {walked:.0f} | {100 * stuck_time / total_time:.1f} % | '
          f'{100 * inner_stuck_time / total_time:.1f} % | {stops} | {stops - trapped} | '
          f'{trapped} |')
    print(f'\nStops the backward drag left: {backward_left} of {stops}; only it (trapped '
          f'without it): {only_backward}.')
    print(f'\n{steps} steps; walks with the legs passing into each other: {legs_walks}; '
          f'time stopped because the legs would: {legs_stuck:.1f} s.')
    if not args.no_edge_turns:
        print('\n| turns on the spot at the edge | turned | stuck in place | checker failures |')
        print('|---|---:|---:|---:|')
        for label, pivot in (('pivot (default)', ActorConfig().pivot_turn), ('no pivot', 0.0)):
            turned, failures = edge_turns(sk, pivot)
            print(f'| {label} | {turned.sum()} of {turned.size} | {(~turned).sum()} | '
                  f'{failures} |')
        turned, failures, pitched = bump_turns(sk)
        print(f"\nTurns on the spot on the rough course's bumps ({turned.size} starts, 3 s at "
              f'1 rad/s): {turned.sum()} turned more than 1 rad ({turned[pitched].sum()} of the '
              f'{pitched.sum()} whose feet stand pitched over 0.05 rad); checker failures: '
              f'{failures}.')
    print_command(__file__, argv)
    return 0


def edge_turns(sk, pivot):
    """Turn on the spot at the floor's edge: (turned (N,) bool, checker failures)."""
    turned, failures = [], 0
    for name in ('flat', 'gap', 'blocks'):
        sc = scene(name)
        for distance in (0.4, 0.5, 0.6, 0.7):
            for facing in (np.pi / 3, np.pi / 2, 2 * np.pi / 3):
                for rate in (1.0, -1.0):
                    actor = Actor(sk, sc.environment, ActorConfig(pivot_turn=pivot),
                                  start=(1.0, 2.0 - distance, facing))
                    blocks = run_commands(actor, [0.0, 4.0], [0.0, 0.0], [rate, 0.0])
                    _, frames, report = judged(blocks, sc.environment)
                    failures += not report.ok
                    turned.append(abs(frames[-1, 3] - facing) > 1.0)
    return np.array(turned), failures


def bump_turns(sk):
    """
    Turn on the spot from the rough course's bumps and judge each turn.

    (turned (N,) bool, checker failures, pitched (N,) bool) of turns on the spot started on the
    rough course's bumps (x 2-8 m, y -0.6 / 0 / 0.6 m, facing 0 or 1.5 rad).
    """
    sc = scene('rough')
    turned, pitched, failures = [], [], 0
    for x in np.arange(2.0, 8.01, 0.5):
        for y in (-0.6, 0.0, 0.6):
            for facing in (0.0, 1.5):
                actor = Actor(sk, sc.environment, ActorConfig(plan_upper_body=False),
                              start=(float(x), y, facing))
                pitched.append(max(abs(foot.pitch) for foot in actor.stance.feet) > 0.05)
                blocks = run_commands(actor, [0.0, 3.0], [0.0, 0.0], [1.0, 0.0])
                _, frames, report = judged(blocks, sc.environment)
                failures += not report.ok
                turned.append(frames[-1, 3] - facing > 1.0)
    return np.array(turned), failures, np.array(pitched)


if __name__ == '__main__':
    sys.exit(main())
