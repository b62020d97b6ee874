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
Terrain a user expects the actor to walk: single features swept, then random courses.

Run: .venv/bin/python bench/bench_terrain.py [--features block stairs_up ...] [--random 60]
         [--first-seed 0] [--list] [--no-sweep] [--phases]

**Sweep.** One feature across a 2 m wide floor, walked straight at 0.5, 0.8 and 1.1 m/s from
the origin, the feature starting 1.6, 1.75, 1.9 or 2.05 m ahead (so the footsteps meet it in
every phase): a block (0.08-0.28 m high, 0.3-1.2 m long), a 4-step flight up or down (rise
0.1-0.2 m, tread 0.26-0.4 m), a drop (0.1-0.3 m), a ditch (0.15-0.45 m wide) and a ramp up
(6-14 degrees). ``--phases`` walks, instead, blocks a swing may pass over from 20 starts 4 cm
apart. A walk *passes* when the pelvis gets 1 m past the feature; each walk is judged
by the independent checker (every link against the meshes, a foot always down, limits, no
jumps, stance slip <= 1 cm).

**Random courses.** Seeded courses of six or seven features in a row along x (flat floor, a
block, stairs up or down, a ramp, a ditch, small bumps, a step down), 3.2 m wide, walked at
one seeded speed (0.4-1.1 m/s) by a user who steers back to the course's centre line (turn
rate -1.2 y - 1.5 yaw, at most 0.4 rad/s, in steps of 0.1 as a mouse stream changes). A course
is *passed* when the pelvis gets within 2 m of its far end; a stop the user does not steer out
of (the command stays as it is) fails it. Lower body only (the upper-body courses have their
own benches) unless ``--upper-body``.
"""
import argparse
import collections
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import judged, skeleton  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
import numpy as np  # noqa: E402
from scene_helpers import box  # noqa: E402
import trimesh  # noqa: E402

#: Half the width of the swept features' floor and of the random courses, m.
SWEEP_HALF_WIDTH = 1.0
COURSE_HALF_WIDTH = 1.6
SPEEDS = (0.5, 0.8, 1.1)
STARTS = (1.6, 1.75, 1.9, 2.05)
FEATURES = {
    'block': [(h, length) for h in (0.08, 0.15, 0.22, 0.28) for length in (0.3, 0.6, 1.2)],
    'stairs_up': [(rise, tread) for rise in (0.1, 0.15, 0.2) for tread in (0.26, 0.32, 0.4)],
    'stairs_down': [(rise, tread) for rise in (0.1, 0.15, 0.2) for tread in (0.26, 0.32, 0.4)],
    'drop': [(h,) for h in (0.1, 0.2, 0.3)],
    'ditch': [(width,) for width in (0.15, 0.3, 0.45)],
    'ramp': [(degrees,) for degrees in (6, 10, 14)],
}

#: ``--phases``: blocks low enough for a swing to pass over (max_swing_height 0.25 m) and short
#: enough that the front foot strides over them, met from 20 starts 4 cm apart (every phase of
#: the footsteps against the block's faces).
PHASE_BLOCKS = {'block': [(0.24, 0.31), (0.22, 0.35), (0.24, 0.5)]}
PHASE_STARTS = tuple(np.round(1.6 + 0.04 * np.arange(20), 2))
PHASE_SETTINGS = {'block': 'high x long 0.24 x 0.31 / 0.22 x 0.35 / 0.24 x 0.5 m, from 20 '
                           'starts 1.6-2.36 m'}

SETTINGS = {
    'block': 'high 0.08 / 0.15 / 0.22 / 0.28 x long 0.3 / 0.6 / 1.2 m',
    'stairs_up': '4 steps, rise 0.1 / 0.15 / 0.2 x tread 0.26 / 0.32 / 0.4 m',
    'stairs_down': '4 steps, rise 0.1 / 0.15 / 0.2 x tread 0.26 / 0.32 / 0.4 m',
    'drop': '0.1 / 0.2 / 0.3 m',
    'ditch': '0.15 / 0.3 / 0.45 m wide, 0.6 m deep',
    'ramp': '6 / 10 / 14 degrees, 1.5 m long',
}


def ramp(x0, x1, z0, z1, half):
    """Make a solid wedge from x0 (top z0) to x1 (top z1), bottom at -0.1 m."""
    corners = [[x, y, z] for x, top in ((x0, z0), (x1, z1)) for y in (-half, half)
               for z in (-0.1, top)]
    return trimesh.convex.convex_hull(np.array(corners))


def feature(kind, parameters, x, half=SWEEP_HALF_WIDTH):
    """Meshes of one swept feature starting at ``x``, and the x the pelvis must pass."""
    def slab(x0, x1, top, bottom=-0.1):
        return box([x0, -half, bottom], [x1, half, top])

    if kind == 'block':
        height, length = parameters
        return [slab(-1, x + length + 4, 0.0), slab(x, x + length, height)], x + length + 1.0
    if kind in ('stairs_up', 'stairs_down'):
        rise, tread = parameters
        steps = 4
        tops = [rise * (i + 1) for i in range(steps)]
        if kind == 'stairs_down':
            tops = tops[::-1][1:] + [0.0]
        first = 0.0 if kind == 'stairs_up' else rise * steps
        meshes = [slab(-1, x, first)] + [slab(x + i * tread, x + (i + 1) * tread, top)
                                         for i, top in enumerate(tops)]
        end = x + steps * tread
        return meshes + [slab(end, end + 3, tops[-1])], end + 1.0
    if kind == 'drop':
        height, = parameters
        return [slab(-1, x, height), slab(x, x + 4, 0.0)], x + 1.0
    if kind == 'ditch':
        width, = parameters
        return [slab(-1, x, 0.0, -0.6), slab(x + width, x + width + 4, 0.0, -0.6),
                slab(x - 0.1, x + width + 0.1, -0.6, -0.8)], x + width + 1.0
    if kind == 'ramp':
        degrees, = parameters
        length = 1.5
        rise = float(np.tan(np.radians(degrees)) * length)
        return [slab(-1, x, 0.0), ramp(x, x + length, 0.0, rise, half),
                slab(x + length, x + length + 3, rise)], x + length + 1.0
    raise ValueError(f'unknown feature {kind!r}')


def random_course(rng):
    """Meshes of one seeded course along +x, and the names and start x of its features."""
    half = COURSE_HALF_WIDTH

    def slab(x0, x1, top, bottom=-0.1):
        return box([x0, -half, bottom], [x1, half, top])

    meshes, x, z, parts = [slab(-1.5, 1.0, 0.0)], 1.0, 0.0, []
    while x < 9.0:
        kind = str(rng.choice(['flat', 'block', 'stairs', 'ramp', 'ditch', 'bumps', 'step down']))
        if kind == 'step down' and z < 0.05:
            kind = 'flat'
        parts.append((kind, round(x, 2)))
        if kind == 'flat':
            length = rng.uniform(0.5, 1.5)
            meshes.append(slab(x, x + length, z))
            x += length
        elif kind == 'step down':
            z -= min(z, rng.uniform(0.05, 0.3))
            length = rng.uniform(0.6, 1.2)
            meshes.append(slab(x, x + length, z))
            x += length
        elif kind == 'block':
            height, length = rng.uniform(0.04, 0.26), rng.uniform(0.3, 1.4)
            meshes.append(slab(x, x + length, z + height))
            x += length
            length = rng.uniform(0.5, 1.0)
            meshes.append(slab(x, x + length, z))
            x += length
        elif kind == 'stairs':
            steps, rise, tread = int(rng.integers(2, 5)), rng.uniform(0.08, 0.2), \
                rng.uniform(0.26, 0.45)
            up = rng.random() < 0.6 or z < steps * rise
            for _ in range(steps):
                z = z + rise if up else z - rise
                meshes.append(slab(x, x + tread, z))
                x += tread
            length = rng.uniform(0.6, 1.0)
            meshes.append(slab(x, x + length, z))
            x += length
        elif kind == 'ramp':
            slope = np.tan(np.radians(rng.uniform(4, 13)))
            length = rng.uniform(0.8, 2.0)
            rise = slope * length * (1 if (rng.random() < 0.6 or z < 0.3) else -1)
            meshes.append(ramp(x, x + length, z, z + rise, half))
            x, z = x + length, z + rise
            length = rng.uniform(0.5, 1.0)
            meshes.append(slab(x, x + length, z))
            x += length
        elif kind == 'ditch':
            width = rng.uniform(0.08, 0.45)
            length = rng.uniform(0.6, 1.2)
            meshes.append(slab(x + width, x + width + length, z, -0.6))
            meshes.append(slab(x, x + width, -0.6, -0.7))
            x += width + length
        else:  # bumps
            length = rng.uniform(1.0, 2.0)
            meshes.append(slab(x, x + length, z))
            for _ in range(int(rng.integers(2, 7))):
                bx, by = rng.uniform(x, x + length - 0.1), rng.uniform(-0.6, 0.6)
                sx, sy, height = rng.uniform(0.05, 0.3), rng.uniform(0.05, 0.3), \
                    rng.uniform(0.01, 0.08)
                meshes.append(box([bx, by, z - 0.01], [bx + sx, by + sy, z + height]))
            x += length
    meshes.append(slab(x, x + 3.0, z))
    return meshes, parts


def steer_to_centre(actor, speed, x_goal, duration):
    """Walk at ``speed`` steering back to y = 0 until past ``x_goal`` or ``duration`` s."""
    blocks = []
    while actor.time < duration:
        x, y, _, yaw = actor.stance.pelvis
        if x > x_goal:
            break
        turn = round(float(np.clip(-1.2 * y - 1.5 * yaw, -0.4, 0.4)), 1)
        actor.set_command(speed, turn)
        blocks.append(actor.plan_next())
    return blocks


def first_stop(blocks):
    reasons = [b.reason for b in blocks if b.status == 'stuck']
    return reasons[0] if reasons else 'too slow'


def sweep(kinds, listing, upper_body=False, features=FEATURES, starts=STARTS,
          settings=SETTINGS):
    """Print the single-feature table; return the number of checker failures."""
    sk = skeleton()
    config = ActorConfig(plan_upper_body=upper_body)
    failures, why = 0, collections.Counter()
    print('| feature | settings | walks | passed |')
    print('|---|---|---:|---:|')
    for kind in kinds:
        passed = walks = 0
        for parameters in features[kind]:
            for start in starts:
                meshes, goal = feature(kind, parameters, start)
                environment = Environment(meshes, resolution=0.02)
                for speed in SPEEDS:
                    actor = Actor(sk, environment, config, start=(0.0, 0.0, 0.0))
                    blocks = run_commands(actor, [0.0, goal / speed * 1.6 + 4.0],
                                          [speed, 0.0], [0.0, 0.0])
                    walks += 1
                    if actor.stance.pelvis[0] > goal:
                        passed += 1
                    else:
                        why[(kind, first_stop(blocks).split(' (')[0])] += 1
                        if listing:
                            print(f'{kind} {parameters} at {start} m, {speed} m/s: stopped at '
                                  f'x = {actor.stance.pelvis[0]:.2f} m ({first_stop(blocks)})')
                    _, _, report = judged(blocks, environment)
                    if not report.ok:
                        failures += 1
                        print(f'{kind} {parameters} at {start} m, {speed} m/s: checker: '
                              f'{"; ".join(report.failures()[:2])}')
        print(f'| {kind} | {settings[kind]} | {walks} | {passed} |')
    print(f'\nchecker failures: {failures}; why the other walks stopped:')
    for (kind, reason), count in why.most_common():
        print(f'- {kind}: {count} x {reason}')
    return failures


def random_courses(count, first_seed, listing, upper_body=False):
    """Print the random-course table; return the number of checker failures."""
    sk = skeleton()
    config = ActorConfig(plan_upper_body=upper_body)
    passed = failures = 0
    why = collections.Counter()
    for seed in range(first_seed, first_seed + count):
        rng = np.random.default_rng(seed)
        meshes, parts = random_course(rng)
        x_goal = max(mesh.bounds[1][0] for mesh in meshes) - 2.0
        environment = Environment(meshes, resolution=0.02)
        speed = float(rng.uniform(0.4, 1.1))
        actor = Actor(sk, environment, config, start=(0.0, 0.0, 0.0))
        blocks = steer_to_centre(actor, speed, x_goal, 1.6 * x_goal / speed + 6.0)
        _, _, report = judged(blocks, environment)
        if not report.ok:
            failures += 1
            print(f'seed {seed}: checker: {"; ".join(report.failures()[:2])}')
        if actor.stance.pelvis[0] > x_goal:
            passed += 1
            continue
        why[first_stop(blocks).split(' (')[0]] += 1
        if listing:
            print(f'seed {seed} ({speed:.2f} m/s, {parts}): stopped at '
                  f'x = {actor.stance.pelvis[0]:.2f} m ({first_stop(blocks)})')
    print(f'\n{count} random courses (seeds {first_seed}-{first_seed + count - 1}): '
          f'**{passed}** passed, checker failures {failures}; the others stopped:')
    for reason, number in why.most_common():
        print(f'- {number} x {reason}')
    return failures


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--features', nargs='+', default=list(FEATURES),
                        choices=list(FEATURES))
    parser.add_argument('--random', type=int, default=60, help='random courses (0: none)')
    parser.add_argument('--first-seed', type=int, default=0)
    parser.add_argument('--list', action='store_true', help='print every walk that stopped')
    parser.add_argument('--no-sweep', action='store_true', help='random courses only')
    parser.add_argument('--phases', action='store_true',
                        help='instead of the sweep: blocks a swing passes over, met in 20 phases')
    parser.add_argument('--upper-body', action='store_true',
                        help='plan the upper body too (the node default)')
    args = parser.parse_args(argv)
    if args.random < 0:
        parser.error(f'--random must be >= 0, got {args.random}')
    started = time.perf_counter()
    failures = 0
    if args.phases:
        failures += sweep(['block'], args.list, args.upper_body, PHASE_BLOCKS, PHASE_STARTS,
                          PHASE_SETTINGS)
    elif not args.no_sweep:
        failures += sweep(args.features, args.list, args.upper_body)
    if args.random:
        failures += random_courses(args.random, args.first_seed, args.list, args.upper_body)
    print(f'\n({time.perf_counter() - started:.0f} s)')
    print_command(__file__)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
