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
Load time and memory of large scenes, against their triangles and against their area.

Each scene is loaded (and walked) in a fresh process, so its peak resident memory is the whole
process's (``resource.getrusage``), interpreter and compiled kernels included:

- the third-party scenes of ``bench/third_party_meshes.py`` (a 125 k-triangle game level and a
  143 k-triangle warehouse), loaded from their files as ``digital-actor simulate`` does and
  walked straight ahead at 0.5 m/s;
- generated ground planes of 2 triangles from 20 m to 2 km square (area alone grows);
- generated height-field terrains over one 60 m x 60 m area at finer and finer cells
  (triangles alone grow).

Run: ``.venv/bin/python bench/bench_large_scenes.py`` (``--walk 0`` skips the walks).
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_party_meshes  # noqa: E402

PLANES = (20.0, 200.0, 2000.0)
TERRAIN_CELLS = (1.0, 0.5, 0.25, 0.125)
TERRAIN_SIZE = 60.0


def plane(size: float):
    """Return a square ground plane of two triangles, ``size`` m a side, centred on the origin."""
    import trimesh
    h = size / 2
    return trimesh.Trimesh([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]],
                           [[0, 1, 2], [0, 2, 3]], process=False)


def terrain(size: float, cell: float, seed: int = 0):
    """
    Return a rolling height field centred on the origin, as an open upward-facing surface.

    A rolling height field ``size`` m square on ``cell`` m cells (slopes under about 6 degrees),
    centred on the origin, as an open upward-facing surface.
    """
    import trimesh
    count = int(round(size / cell)) + 1
    axis = np.linspace(-size / 2, size / 2, count)
    gx, gy = np.meshgrid(axis, axis)
    rng = np.random.default_rng(seed)
    phases = rng.uniform(0, 2 * np.pi, 4)
    gz = (0.5 * np.sin(gx / 5.0 + phases[0]) * np.cos(gy / 6.0 + phases[1])
          + 0.2 * np.sin(gx / 2.3 + phases[2]) + 0.15 * np.cos(gy / 1.9 + phases[3]))
    vertices = np.column_stack([gx.ravel(), gy.ravel(), gz.ravel()])
    index = np.arange(count * count).reshape(count, count)
    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()
    c, d = index[1:, 1:].ravel(), index[1:, :-1].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return trimesh.Trimesh(vertices, faces, process=False)


def peak_rss_mb() -> float:
    """Return this process's peak resident memory so far, MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def measure(spec: str, walk_seconds: float) -> dict:
    """Load (and walk) one scene in this process: its numbers as a dict."""
    from digital_actor_planner.core.actor import Actor, ActorConfig
    from digital_actor_planner.core.environment import Environment
    from digital_actor_planner.core.scene import load_scene
    from digital_actor_planner.core.skeleton import Skeleton
    skeleton = Skeleton()
    kind, _, argument = spec.partition(':')
    baseline = peak_rss_mb()
    start, cpu = time.perf_counter(), time.process_time()
    if kind == 'scene':
        scene = load_scene(third_party_meshes.scene_path(argument))
        environment, start_pose = scene.environment, scene.start
    else:
        mesh = plane(float(argument)) if kind == 'plane' else terrain(
            TERRAIN_SIZE, float(argument))
        environment, start_pose = Environment([mesh]), (0.0, 0.0, 0.0)
    load, load_cpu = time.perf_counter() - start, time.process_time() - cpu
    extent = environment.bounds[1, :2] - environment.bounds[0, :2]
    out = {'spec': spec, 'triangles': int(sum(len(m.faces) for m in environment.meshes)),
           'area_m2': float(extent[0] * extent[1]), 'load_s': load, 'load_cpu_s': load_cpu,
           'loaded_rss_mb': peak_rss_mb(), 'baseline_rss_mb': baseline}
    if walk_seconds > 0:
        actor = Actor(skeleton, environment, ActorConfig(), start=start_pose)
        actor.set_command(0.5, 0.0)
        x0 = actor.configuration[:2].copy()
        step_cpu = []
        while actor.time < walk_seconds and actor.status != 'stuck':
            clock = time.process_time()
            block = actor.plan_next()
            if block.status == 'walking':
                step_cpu.append(time.process_time() - clock)
        out.update(steps=len(step_cpu), status=actor.status,
                   step_p50_ms=1e3 * float(np.median(step_cpu)) if step_cpu else 0.0,
                   step_max_ms=1e3 * float(np.max(step_cpu)) if step_cpu else 0.0,
                   walked_m=float(np.linalg.norm(actor.configuration[:2] - x0)))
    out.update(peak_rss_mb=peak_rss_mb(), cache_mb=environment.cached_bytes() / 2 ** 20,
               tiles=environment.cached_tiles())
    return out


def run(spec: str, walk_seconds: float) -> dict:
    """:func:`measure` in a fresh interpreter."""
    done = subprocess.run([sys.executable, __file__, '--one', spec, '--walk', str(walk_seconds)],
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        return {'spec': spec, 'error': (done.stderr.strip().splitlines() or ['?'])[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _row(result: dict) -> str:
    if 'error' in result:
        return f'{result["spec"]:<22} failed: {result["error"]}'
    walk = ''
    if 'steps' in result:
        walk = (f'  walked {result["walked_m"]:4.1f} m, {result["steps"]:2d} steps '
                f'({result["status"]}), CPU a step p50 {result["step_p50_ms"]:.0f} ms, '
                f'max {result["step_max_ms"]:.0f} ms')
    return (f'{result["spec"]:<22} {result["triangles"]:>8d} tri {result["area_m2"]:>10.0f} m2  '
            f'load {result["load_s"]:5.2f} s ({result["load_cpu_s"]:5.2f} s CPU)  RSS loaded '
            f'{result["loaded_rss_mb"]:4.0f} MB, peak {result["peak_rss_mb"]:4.0f} MB '
            f'(imports {result["baseline_rss_mb"]:3.0f} MB), tiles {result["cache_mb"]:3.0f} MB'
            f'{walk}')


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--walk', type=float, default=20.0,
                        help='seconds of walking on the third-party scenes (0: none)')
    parser.add_argument('--one', help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.one, args.walk)))
        return 0
    third_party_meshes.fetch()
    print(f'load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs')
    print('third-party scenes (from their files; walked at 0.5 m/s):')
    for name in ('monastery', 'warehouse'):
        print(_row(run(f'scene:{name}', args.walk)), flush=True)
    print('area alone grows (2-triangle planes):')
    for size in PLANES:
        print(_row(run(f'plane:{size:g}', 0.0)), flush=True)
    print(f'triangles alone grow (terrains of {TERRAIN_SIZE:g} m x {TERRAIN_SIZE:g} m):')
    for cell in TERRAIN_CELLS:
        print(_row(run(f'terrain:{cell:g}', 0.0)), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
