"""Zigzag mouse steering on the courses: every walk judged, every stop steered away from.

Run: .venv/bin/python bench/bench_steer_away.py [--courses flat rough ...] [--seeds 8] [--list]

A mouse user does not drive straight. Each walk here (seeded, 12 s) holds a command for 0.3-2 s
at a time: linear 0.2-1.2 m/s (0 one time in seven: the mouse stands still) and a turn of up
to 1.2 rad/s that alternates left and right, so the actor weaves along the course, into its
obstacles and, as often, to the edge of its floor (2 m either side of the start line). The
whole body is planned and the independent checker judges the whole walk (every link against the
meshes, a foot always down, limits, no jumps, stance slip <= 1 cm).

Where a walk first stops (stuck), the walk is replayed to 0.3 s after the stop and the user
then steers away with each of five commands for 4 s: turn on the spot left and right (0, +-1),
walk a tight arc left and right (0.3 m/s, +-0.8 rad/s), and walk slowly on (0.5 m/s). The stop
counts as *left* when one of them takes at least two steps; otherwise the actor is *trapped*
there (issue 2: "a later command that turns it away lets it go on"). Also counted: steps in
which the two feet's collision boxes interpenetrate (the checker does not judge the body
against itself).

A second table turns on the spot at the floor's edge (flat, gap and blocks courses): standing
0.4-0.7 m from the edge facing it at 60, 90 or 120 degrees, told (0, +-1) for 4 s, with and
without ``ActorConfig.pivot_turn``; a turn counts when the heading changed by more than 1 rad.
"""
import argparse
import os
import sys

import fcl
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import judged, scene, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402

COURSES = ('flat', 'rough', 'blocks', 'stairs_up', 'gap', 'low_beam', 'table', 'pillars')
AWAY = ((0.0, 1.0), (0.0, -1.0), (0.3, 0.8), (0.3, -0.8), (0.5, 0.0))


def zigzag(seed: int, duration: float = 12.0):
    """(times, linear, angular) of one seeded weaving walk, ending with a stop."""
    rng = np.random.default_rng(seed)
    times = [0.0]
    while times[-1] < duration:
        times.append(times[-1] + rng.uniform(0.3, 2.0))
    count = len(times)
    linear = np.where(rng.random(count) < 0.15, 0.0, rng.uniform(0.2, 1.2, count))
    angular = rng.uniform(0.0, 1.2, count) * (-1.0) ** np.arange(count)
    linear[-1] = angular[-1] = 0.0
    return times, linear.tolist(), angular.tolist()


class FeetOverlap:
    """Whether the two feet's collision boxes interpenetrate (the checker judges links against
    the meshes only, not against each other)."""

    def __init__(self, sk):
        self.sk = sk
        self.shapes = [next(i for i, shape in enumerate(sk.collision_shapes)
                            if shape.link == link and shape.kind == 'box')
                       for link in ('left_foot', 'right_foot')]
        self.boxes = [fcl.CollisionObject(fcl.Box(*sk.collision_shapes[i].size), fcl.Transform())
                      for i in self.shapes]

    def depth(self, frames) -> float:
        """Deepest interpenetration of the feet over ``frames``, m (0 when apart)."""
        transforms = self.sk.shape_transforms_at(frames, self.shapes)
        worst = 0.0
        for pair in transforms:
            for box, transform in zip(self.boxes, pair):
                box.setTransform(fcl.Transform(transform[:3, :3], transform[:3, 3]))
            request = fcl.CollisionRequest(num_max_contacts=4, enable_contact=True)
            result = fcl.CollisionResult()
            if fcl.collide(self.boxes[0], self.boxes[1], request, result):
                worst = max([worst] + [c.penetration_depth for c in result.contacts])
        return worst


def walk(sk, sc, times, linear, angular):
    actor = Actor(sk, sc.environment, ActorConfig(), start=sc.start)
    return run_commands(actor, times, linear, angular)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--seeds', type=int, default=8)
    parser.add_argument('--list', action='store_true', help='print every stop')
    args = parser.parse_args(argv)
    sk = skeleton()
    walks = failures = stops = trapped = 0
    feet = FeetOverlap(sk)
    steps = overlapping = 0
    deepest = 0.0
    walked = stuck_time = total_time = 0.0
    for name in args.courses:
        sc = scene(name)
        for seed in range(args.seeds):
            times, linear, angular = zigzag(seed)
            blocks = walk(sk, sc, times, linear, angular)
            t, frames, report = judged(blocks, sc.environment)
            walks += 1
            if not report.ok:
                failures += 1
                print(f'{name} seed {seed}: checker: {"; ".join(report.failures()[:2])}',
                      flush=True)
            walked += float(np.hypot(*np.diff(frames[:, :2], axis=0).T).sum())
            for block in blocks:
                if block.category:  # a step (holds have none)
                    steps += 1
                    depth = feet.depth(block.frames)
                    overlapping += depth > 0
                    deepest = max(deepest, depth)
            stuck_time += sum(b.times[-1] - b.times[0] for b in blocks if b.status == 'stuck')
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
                              [angular[i] for i in kept] + [w, 0.0])
                taken.append(sum(b.status == 'walking' for b in replay if b.times[0] > at))
            left = max(taken) >= 2
            trapped += not left
            if args.list or not left:
                x, y, _, yaw = first.frames[-1, :4]
                print(f'{name} seed {seed}: stopped at t = {first.times[0]:.2f} s, '
                      f'({x:.2f}, {y:.2f}) heading {yaw:+.2f} rad ({first.reason}); steps '
                      f'taken steering away {taken}: {"left" if left else "TRAPPED"}',
                      flush=True)
    print(f'\n{walks} weaving walks ({len(args.courses)} courses x {args.seeds} seeds, 12 s '
          'each, whole body)\n')
    print('| walks | checker failures | walked m | time stopped | stops | stops left by '
          'steering away | trapped |')
    print('|---:|---:|---:|---:|---:|---:|---:|')
    print(f'| {walks} | {failures} | {walked:.0f} | {100 * stuck_time / total_time:.0f} % | '
          f'{stops} | {stops - trapped} | {trapped} |')
    print(f'\nSteps with the feet interpenetrating: {overlapping} of {steps} '
          f'(deepest {1e3 * deepest:.0f} mm).')
    print('\n| turns on the spot at the edge | turned | stuck in place | checker failures |')
    print('|---|---:|---:|---:|')
    for label, pivot in (('pivot (default)', ActorConfig().pivot_turn), ('no pivot', 0.0)):
        turned, failures = edge_turns(sk, pivot)
        print(f'| {label} | {turned.sum()} of {turned.size} | {(~turned).sum()} | {failures} |')
    print_command(__file__, argv)
    return 0


def edge_turns(sk, pivot):
    """(turned (N,) bool, checker failures) of the turns on the spot at the floor's edge."""
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


if __name__ == '__main__':
    sys.exit(main())
