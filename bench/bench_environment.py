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
Benchmark the environment and collision queries the planners call in their loops.

Prints: ground-map construction time for a 20 m x 6 m course, the cost of a 1000-point
ground_height query, BodyCollision.collides() for one leg and for the whole body, and
check_trajectory on 10 s at 100 Hz. Run: ``.venv/bin/python bench/bench_environment.py``.
"""
import argparse
import os
import time

from digital_actor_planner.core.actor import start_configuration
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.evaluation.trajectory_check import check_trajectory
import numpy as np
import trimesh


def _box(low, high):
    low, high = np.asarray(low, float), np.asarray(high, float)
    mesh = trimesh.creation.box(high - low)
    mesh.apply_translation((low + high) / 2)
    return mesh


def course_meshes(rng):
    """Build a 20 m x 6 m course: floor, stairs, blocks, a table, a beam and a rough patch."""
    meshes = [_box((0, -3, -0.1), (20, 3, 0.0))]
    meshes += [_box((3 + 0.3 * i, -3, 0), (3.3 + 0.3 * i, 3, 0.15 * (i + 1))) for i in range(4)]
    meshes += [_box((x, y, 0), (x + 0.4, y + 0.4, h)) for x, y, h in
               rng.uniform((6, -2.5, 0.05), (9, 2.5, 0.3), (12, 3))]
    meshes += [_box((10, 1, 0.7), (11, 2, 0.75)), _box((12, -3, 1.4), (12.2, 3, 1.6))]
    xs, ys = np.linspace(14, 20, 121), np.linspace(-3, 3, 121)
    gx, gy = np.meshgrid(xs, ys)
    gz = 0.05 + 0.04 * rng.standard_normal(gx.shape)
    vertices = np.column_stack([gx.ravel(), gy.ravel(), gz.ravel()])
    faces = []
    for j in range(len(ys) - 1):
        for i in range(len(xs) - 1):
            a = j * len(xs) + i
            faces += [[a, a + 1, a + len(xs) + 1], [a, a + len(xs) + 1, a + len(xs)]]
    meshes.append(trimesh.Trimesh(vertices, np.array(faces), process=False))
    return meshes


def _per_call(function, repeats):
    """
    Time a call: wall-clock and process CPU seconds per call.

    Wall-clock and process CPU seconds per call (CPU time is what a busy machine distorts least:
    the 2 cores are shared with other jobs).
    """
    function()
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(repeats):
        function()
    return ((time.perf_counter() - wall) / repeats, (time.process_time() - cpu) / repeats)


def _us(cost):
    return f'{cost[0] * 1e6:.0f} us wall, {cost[1] * 1e6:.0f} us CPU'


def main():
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--repeats', type=int, default=500)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    meshes = course_meshes(rng)
    triangles = sum(len(m.faces) for m in meshes)

    times = []
    for _ in range(3):
        wall, cpu = time.perf_counter(), time.process_time()
        environment = Environment(meshes)
        times.append((time.perf_counter() - wall, time.process_time() - cpu))
    wall, cpu = min(times)
    print(f'Environment construction, 20 m x 6 m, {len(meshes)} meshes, {triangles} '
          f'triangles, resolution {environment.resolution} m: {wall * 1000:.0f} ms wall, '
          f'{cpu * 1000:.0f} ms CPU (best of 3)')

    xy = rng.uniform((0, -3), (20, 3), (1000, 2))
    z_ref = rng.uniform(0.0, 2.0, 1000)
    cost = _per_call(lambda: environment.ground_height(xy, z_ref), args.repeats)
    print(f'ground_height, 1000 points: {_us(cost)} per query')

    skeleton = Skeleton()
    body = BodyCollision(skeleton, environment)
    standing = start_configuration(environment, (1.0, 0.0, 0.0), skeleton)
    configurations = standing + rng.normal(0.0, 0.02, (args.repeats, len(standing)))
    leg = ['left_thigh', 'left_shank', 'left_foot']
    for name, links in (('one leg (3 links)', leg), ('whole body (19 links)', None)):
        iterator = iter(np.concatenate([configurations, configurations]))
        cost = _per_call(lambda: body.collides(next(iterator), links), args.repeats)
        print(f'BodyCollision.collides, {name}, new configuration each call: {_us(cost)}')
    cost = _per_call(lambda: body.collides(standing, leg), args.repeats)
    print(f'BodyCollision.collides, one leg, same configuration (cached poses): {_us(cost)}')
    iterator = iter(np.concatenate([configurations, configurations]))
    cost = _per_call(lambda: body.penetration(next(iterator)), args.repeats // 5)
    print(f'BodyCollision.penetration, whole body: {_us(cost)}')

    times = np.arange(1000) / 100.0
    frames = np.tile(standing, (1000, 1))
    frames[:, skeleton.index['waist_pitch']] = 0.2 * np.sin(times)
    wall, cpu = time.perf_counter(), time.process_time()
    report = check_trajectory(skeleton, environment, times, frames)
    print(f'check_trajectory, 10 s at 100 Hz: {time.perf_counter() - wall:.2f} s wall, '
          f'{time.process_time() - cpu:.2f} s CPU (ok={report.ok})')
    print(f'load average during the run: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores')


if __name__ == '__main__':
    main()
