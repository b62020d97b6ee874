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
Weaving on a gentle hill: stuck events where no contact would occur (target 0).

Run: .venv/bin/python bench/bench_slopes.py [--starts 16] [--duration 16] [--list]

The hill is a heightmap, 30 x 30 m in 0.25 m cells (a cone with a rounded top and a gentle
ripple: slopes 6 degrees at the median, at most 10). From starts spread around it (on rings
4 and 6.5 m from the top, facing up, across and down the slope in turn) the actor walks at
0.5 m/s steered as a mouse weaves: +0.4 and -0.4 rad/s alternating every 2 s, for
``--duration`` s (the walks stay on the hill, 15 m from the top at its edges). Reported: the
starts where the actor cannot stand (its soles do not fit the ground there: a matter of the
start pose, not walked), the walks, those with a stuck event (with the reasons), and the
independent checker's failures (``check_trajectory``); on ground this gentle a stuck event is
a defect, not a limit of the legs.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import skeleton  # noqa: E402
from digital_actor_planner.core.actor import (Actor, ActorConfig, LEG_LINKS,  # noqa: E402
                                              run_commands)  # noqa: E402
from digital_actor_planner.core.collision import BodyCollision  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
from digital_actor_planner.evaluation.trajectory_check import check_trajectory  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402

#: Weaving: the forward speed (m/s), the turn rate (rad/s) and how long each turn lasts (s).
WEAVE_SPEED, WEAVE_RATE, WEAVE_PERIOD = 0.5, 0.4, 2.0


def heightmap_hill(size: float = 30.0, cell: float = 0.25) -> trimesh.Trimesh:
    """
    Return a hill as a heightmap mesh centred on the origin, its lowest point at z = 0.

    A hill as a heightmap mesh, ``size`` m square in ``cell`` m cells, centred on the origin, its
    lowest point at z = 0: slopes about 6 degrees at the median, at most 10.
    """
    n = int(round(size / cell))
    x = np.linspace(-0.5 * size, 0.5 * size, n + 1)
    grid_x, grid_y = np.meshgrid(x, x, indexing='ij')
    height = (-0.115 * np.sqrt(grid_x ** 2 + grid_y ** 2 + 16.0)
              + 0.05 * np.sin(2 * np.pi * grid_x / 6.0) * np.sin(2 * np.pi * grid_y / 7.8))
    vertices = np.column_stack([grid_x.ravel(), grid_y.ravel(), (height - height.min()).ravel()])
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return trimesh.Trimesh(vertices, faces, process=False)


def slopes(mesh: trimesh.Trimesh) -> np.ndarray:
    """Each face's slope, (f,) degrees."""
    return np.degrees(np.arccos(np.clip(np.abs(mesh.face_normals[:, 2]), 0.0, 1.0)))


def hill_starts(count: int):
    """
    Return ``count`` start poses (x, y, yaw) on rings around the hill's top, m and rad.

    ``count`` start poses (x, y, yaw): on rings 4 and 6.5 m from the top two by two, facing up the
    slope, across it to the left, down it and across it to the right in turn, m and rad.
    """
    starts = []
    for i in range(count):
        radius = (4.0, 6.5)[(i // 2) % 2]
        angle = 2 * np.pi * i / count
        facing = (angle + np.pi, angle + 0.5 * np.pi, angle, angle - 0.5 * np.pi)[i % 4]
        starts.append((radius * np.cos(angle), radius * np.sin(angle), facing))
    return starts


def weave(environment, start, duration: float, plan_upper_body: bool = True,
          body_collision=None):
    """
    Return the blocks of a weaving walk from ``start``, or None where the actor cannot stand.

    The blocks of a weaving walk from ``start`` (x, y, yaw) for ``duration`` s, or None when the
    actor cannot stand there (its legs in the ground at the start: the start pose's business, not
    the walk's). ``body_collision``: a :class:`collision.BodyCollision` of ``environment`` to share
    between walks.
    """
    collision = body_collision or BodyCollision(skeleton(), environment)
    actor = Actor(skeleton(), environment, ActorConfig(plan_upper_body=plan_upper_body),
                  start=start, body_collision=collision)
    if collision.first_collision(actor.configuration[None], LEG_LINKS)[0] >= 0:
        return None
    times = np.arange(0.0, duration, WEAVE_PERIOD)
    rates = WEAVE_RATE * (1 - 2 * (np.arange(times.size) % 2))
    return run_commands(actor, np.append(times, duration),
                        np.append(np.full(times.size, WEAVE_SPEED), 0.0), np.append(rates, 0.0))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--starts', type=int, default=16)
    parser.add_argument('--duration', type=float, default=16.0, help='s of weaving per walk')
    parser.add_argument('--list', action='store_true', help='print every walk')
    args = parser.parse_args(argv)
    if args.starts < 1 or args.duration <= 0:
        parser.error('--starts must be >= 1 and --duration > 0 s')
    mesh = heightmap_hill()
    face_slopes = slopes(mesh)
    environment = Environment([mesh])
    collision = BodyCollision(skeleton(), environment)
    stuck, failures, unstandable = [], [], []
    for start in hill_starts(args.starts):
        blocks = weave(environment, start, args.duration, body_collision=collision)
        if blocks is None:
            unstandable.append(start)
            if args.list:
                print(f'start ({start[0]:+.1f}, {start[1]:+.1f}, {start[2]:+.2f}): the actor '
                      'cannot stand there', flush=True)
            continue
        times = np.concatenate([b.times for b in blocks])
        frames = np.vstack([b.frames for b in blocks])
        report = check_trajectory(skeleton(), environment, times, frames)
        reasons = sorted({b.reason for b in blocks if b.status == 'stuck'})
        if reasons:
            stuck.append((start, reasons))
        if not report.ok:
            failures.append((start, report.failures()))
        if args.list:
            walked = float(np.hypot(*(frames[-1, :2] - frames[0, :2])))
            print(f'start ({start[0]:+.1f}, {start[1]:+.1f}, {start[2]:+.2f}): walked '
                  f'{walked:.1f} m, {"stuck: " + "; ".join(reasons) if reasons else "no stop"}'
                  f', checker {"ok" if report.ok else "; ".join(report.failures()[:2])}',
                  flush=True)
    print(f'\nHill {len(mesh.faces)} triangles, slopes median {np.median(face_slopes):.1f} / '
          f'max {face_slopes.max():.1f} deg; {args.starts} weaving walks of {args.duration:g} s '
          f'at {WEAVE_SPEED} m/s, +-{WEAVE_RATE} rad/s every {WEAVE_PERIOD:g} s\n')
    print('| starts | not standable | walks | with a stuck event | checker failures |')
    print('|---:|---:|---:|---:|---:|')
    print(f'| {args.starts} | {len(unstandable)} | {args.starts - len(unstandable)} | '
          f'{len(stuck)} | {len(failures)} |')
    for start, reasons in stuck:
        print(f'- stuck from ({start[0]:+.1f}, {start[1]:+.1f}, {start[2]:+.2f}): '
              f'{"; ".join(reasons)}')
    for start, reasons in failures:
        print(f'- checker from ({start[0]:+.1f}, {start[1]:+.1f}, {start[2]:+.2f}): '
              f'{"; ".join(reasons[:2])}')
    print_command(__file__, argv)
    return 0


if __name__ == '__main__':
    sys.exit(main())
