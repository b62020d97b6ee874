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
Large scenes: memory, loading, third-party meshes, starts on natural ground, bad meshes.

Large scenes: memory that follows the geometry and not the area, loading bounded in time and
memory, real third-party meshes walked and judged, starts on natural ground, bad meshes.

Memory and time are measured in a fresh interpreter (``resource.getrusage``: the whole
process, interpreter and compiled kernels included) and asserted with generous bounds; the
benchmark (``bench/bench_large_scenes.py``) gives the numbers.
"""
import json
import os
import subprocess
import sys
import textwrap

from digital_actor_planner.core import environment
from digital_actor_planner.core.actor import start_configuration
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.scene import check_start, load_scene, SceneError
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest
import trimesh

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
THIRD_PARTY = os.path.join(ROOT, '.cache', 'third_party')
FETCHED = os.path.isfile(os.path.join(THIRD_PARTY, 'pybullet==3.2.7.done'))
# Away from CI a machine without the registry may skip them; CI must walk them.
needs_third_party = pytest.mark.skipif(
    not FETCHED and not os.environ.get('CI'),
    reason='third-party meshes not fetched (./quickstart.sh setup fetches them)')
# A whole process that loads and walks a scene stays under this, MB (the target: 1 GB).
PEAK_MB = 1024


def _plane(size, z=0.0):
    h = size / 2
    return trimesh.Trimesh([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]],
                           [[0, 1, 2], [0, 2, 3]], process=False)


def _terrain(size, cell, seed=0):
    """Return a height field ``size`` m square on ``cell`` m cells, slopes under 8 degrees."""
    count = int(round(size / cell)) + 1
    axis = np.linspace(-size / 2, size / 2, count)
    gx, gy = np.meshgrid(axis, axis)
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, 3)
    gz = (0.5 * np.sin(gx / 5.0 + phase[0]) * np.cos(gy / 6.0 + phase[1])
          + 0.15 * np.sin(gx / 2.3 + phase[2]))
    index = np.arange(count * count).reshape(count, count)
    a, b = index[:-1, :-1].ravel(), index[:-1, 1:].ravel()
    c, d = index[1:, 1:].ravel(), index[1:, :-1].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return trimesh.Trimesh(np.column_stack([gx.ravel(), gy.ravel(), gz.ravel()]), faces,
                           process=False)


def _in_fresh_process(body):
    """
    Run ``body`` in a fresh interpreter and return its ``out`` with peak memory figures.

    Run ``body`` (Python; it sets ``out``, a dict) in a fresh interpreter after imports; returns
    ``out`` with ``peak_mb`` and ``baseline_mb`` (peak resident memory after and before ``body``).
    """
    script = textwrap.dedent("""
        import json, resource, sys, time
        import numpy as np
        sys.path.insert(0, {test!r})
        from test_large_scenes import _plane, _terrain
        from digital_actor_planner.core.environment import Environment
        from digital_actor_planner.core.scene import load_scene
        baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        out = {{}}
    """).format(test=os.path.dirname(os.path.abspath(__file__))) + textwrap.dedent(body) + \
        textwrap.dedent("""
        out['peak_mb'] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        out['baseline_mb'] = baseline
        print(json.dumps(out))
    """)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=900, cwd=ROOT, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_200_m_plane_loads_at_once_and_its_far_corners_are_ground():
    """Two triangles over 200 m x 200 m: the dense map of old needed more than 12 GB."""
    out = _in_fresh_process("""
        start = time.perf_counter()
        world = Environment([_plane(200.0)])
        out['load_s'] = time.perf_counter() - start
        xy = np.array([[-99.9, -99.9], [99.9, 99.9], [0.0, 0.0], [-99.9, 99.9], [50, -70]])
        height, clearance = world.ground_height(xy, 0.5)
        out['height'] = height.tolist()
        out['open'] = bool(np.all(np.isinf(clearance)))
        out['cache_mb'] = world.cached_bytes() / 2 ** 20
    """)
    assert out['height'] == [0.0] * 5 and out['open']
    assert out['load_s'] < 5.0
    # A handful of tiles, not the area.
    assert out['cache_mb'] < 50
    assert out['peak_mb'] - out['baseline_mb'] < 200


@pytest.mark.slow
def test_memory_and_load_time_follow_the_triangles_not_the_area():
    """
    Large planes and terrains load in bounded memory, and the ground cache keeps its bound.

    Planes of 20 m and 2 km take the same memory; a large terrain loads in bounded memory and a
    walk's worth of ground queries across it keeps the cache within its bound.
    """
    out = _in_fresh_process("""
        for size in (20.0, 2000.0):
            start = time.perf_counter()
            world = Environment([_plane(size)])
            world.ground_height(np.zeros((1, 2)), 0.1)
            out[f'plane_{size:g}_s'] = time.perf_counter() - start
            out[f'plane_{size:g}_mb'] = world.cached_bytes() / 2 ** 20
        start = time.perf_counter()
        world = Environment([_terrain(100.0, 0.5)], cache_bytes=48 * 2 ** 20)
        out['terrain_s'] = time.perf_counter() - start
        line = np.linspace(-49.0, 49.0, 4000)
        for offset in (-20.0, 0.0, 20.0):
            height, _ = world.ground_height(np.column_stack([line, line * 0 + offset]), 5.0)
            out.setdefault('found', []).append(float(np.isfinite(height).mean()))
        out['cache_mb'] = world.cached_bytes() / 2 ** 20
        out['tiles'] = world.cached_tiles()
    """)
    assert out['plane_2000_mb'] == pytest.approx(out['plane_20_mb'], abs=1.0)
    assert out['plane_2000_s'] < 5.0
    assert out['terrain_s'] < 60.0
    assert min(out['found']) == 1.0
    # The cache holds at most its bound (its ground pool may be up to twice its values).
    assert out['cache_mb'] <= 2 * 48
    assert out['peak_mb'] < PEAK_MB


def test_tiles_built_evicted_and_built_again_answer_as_a_cache_holding_every_tile():
    """
    A ground cache smaller than the terrain answers every query as a full one does.

    A cache of 10 MB (8 tiles) over a terrain of 25 tiles, read all over in random order, gives
    every query the exact answer of a cache that holds the whole terrain.
    """
    mesh = _terrain(12.0, 0.25, seed=3)
    steps = [trimesh.creation.box((1.0, 1.0, 0.3)) for _ in range(3)]
    for i, box in enumerate(steps):
        box.apply_translation((-4.0 + 4.0 * i, 2.0, 0.8))
    whole = Environment([mesh] + steps)
    small = Environment([mesh] + steps, cache_bytes=10 * 2 ** 20)
    rng = np.random.default_rng(5)
    for _ in range(2):
        xy = rng.uniform(-6.5, 6.5, (1500, 2))
        z = rng.uniform(-1.0, 2.0, len(xy))
        for a, b in zip(whole.ground_height(xy, z), small.ground_height(xy, z)):
            np.testing.assert_array_equal(a, b)
        half = rng.uniform(0.0, 0.6, len(xy))
        np.testing.assert_array_equal(whole.top_height_near(xy, half),
                                      small.top_height_near(xy, half))
        np.testing.assert_array_equal(whole.lowest_ground(xy), small.lowest_ground(xy))
        low, high = xy[:40] - half[:40, None], xy[:40] + half[:40, None]
        np.testing.assert_array_equal(whole.top_height(low, high), small.top_height(low, high))
    assert whole.cached_tiles() == 25 and small.cached_tiles() <= 8
    assert small.cached_bytes() <= 2 * small.cache_bytes


@pytest.mark.slow
@needs_third_party
@pytest.mark.parametrize('name, seconds', [('monastery', 12.0), ('warehouse', 8.0)])
def test_a_third_party_scene_loads_and_is_walked_within_a_gigabyte(name, seconds):
    """
    Third-party meshes load, are walked and judged, the process under 1 GB.

    pybullet_data's game level (125 k triangles, 125 m x 121 m) and a warehouse of its shelf pods
    (143 k triangles): loaded from their files, walked straight ahead from their start (the level's
    has none: the ground over the origin), the walk judged by the independent checker, the whole
    process under 1 GB.
    """
    out = _in_fresh_process(f"""
        from digital_actor_planner.core.actor import Actor, ActorConfig
        from digital_actor_planner.core.skeleton import Skeleton
        from digital_actor_planner.evaluation.trajectory_check import check_trajectory
        skeleton = Skeleton()
        start = time.perf_counter()
        scene = load_scene({os.path.join(THIRD_PARTY, name + '.yaml')!r}, skeleton)
        out['load_s'] = time.perf_counter() - start
        actor = Actor(skeleton, scene.environment, ActorConfig(), start=scene.start)
        actor.set_command(0.5, 0.0)
        blocks = []
        while actor.time < {seconds!r} and actor.status != 'stuck':
            blocks.append(actor.plan_next())
        times = np.concatenate([b.times for b in blocks])
        frames = np.vstack([b.frames for b in blocks])
        report = check_trajectory(skeleton, scene.environment, times, frames)
        out['failures'] = report.failures()[:6]
        out['walked_m'] = float(np.linalg.norm(frames[-1, :2] - frames[0, :2]))
        out['walking'] = sum(b.status == 'walking' for b in blocks)
    """)
    assert out['failures'] == []
    assert out['walking'] >= 5 and out['walked_m'] > 1.5
    assert out['load_s'] < 60.0
    assert out['peak_mb'] < PEAK_MB


# -- starts on natural ground -----------------------------------------------------------------
@pytest.fixture(scope='module')
def hill():
    return Environment([_terrain(30.0, 0.25, seed=1)])


@pytest.mark.slow
def test_starts_over_a_gentle_hill_are_accepted(hill):
    """
    Each foot rests at its own height and pitch on the slopes of a hill.

    Each foot rests at its own height and pitch: on slopes of a few degrees, starts all over the
    hill and at several headings stand (placed level at the lowest ground under both feet, the
    uphill foot was inside the hill).
    """
    skeleton = Skeleton()
    accepted, tried = 0, 0
    for x in np.linspace(-11.0, 11.0, 4):
        for y in np.linspace(-11.0, 11.0, 4):
            tried += 1
            try:
                check_start(hill, (x, y, 0.7 * x + 0.3 * y), skeleton)
                accepted += 1
            except SceneError as error:
                assert 'inside an obstacle' not in str(error)
    assert accepted >= 0.8 * tried


def test_a_bare_mesh_starts_on_the_ground_over_the_origin_at_any_height(tmp_path):
    path = tmp_path / 'high.obj'
    _plane(30.0, z=35.0).export(path)
    skeleton = Skeleton()
    scene = load_scene(str(path), skeleton)
    q = start_configuration(scene.environment, scene.start, skeleton)
    assert q[skeleton.index['root_z']] == pytest.approx(35.0 + skeleton.leg.standing_height,
                                                        abs=0.01)


def test_a_refused_start_says_why_and_where_the_actor_can_stand():
    skeleton = Skeleton()
    floor = trimesh.creation.box((12.0, 6.0, 0.1))
    floor.apply_translation((2.0, 0.0, -0.05))
    wall = trimesh.creation.box((0.2, 6.0, 2.0))
    wall.apply_translation((3.0, 0.0, 1.0))
    world = Environment([floor, wall])
    with pytest.raises(SceneError, match=r'start pose \(3, 0, yaw 0\) is inside an obstacle: '
                                         r'links .* collide; the nearest standable start is '
                                         r'\[(\S+), (\S+), 0\]') as caught:
        check_start(world, (3.0, 0.0, 0.0), skeleton)
    x, y = (float(v) for v in str(caught.value).rsplit('[', 1)[1].split(',')[:2])
    assert abs(x - 3.0) <= 1.0
    check_start(world, (x, y, 0.0), skeleton)
    with pytest.raises(SceneError, match=r'has no ground below it; no standable start within '
                                         r'3 m'):
        check_start(world, (40.0, 0.0, 0.0), skeleton)


def test_ground_too_steep_across_a_sole_is_named_with_its_rise():
    """A 12 degree bank: a sole across it would have one edge 2 cm above the ground."""
    skeleton = Skeleton()
    bank = trimesh.creation.box((8.0, 8.0, 0.1))
    bank.apply_transform(trimesh.transformations.rotation_matrix(np.radians(12), (1, 0, 0)))
    flat = trimesh.creation.box((4.0, 8.0, 0.1))
    flat.apply_translation((6.0, 0.0, -1.5))
    world = Environment([bank, flat])
    with pytest.raises(SceneError, match=r'is not standable: the ground under the (left|right) '
                                         r'foot rises \d\.\d cm across the sole \(a sole rests '
                                         r'on ground level across within 1\.5 cm\)'):
        check_start(world, (0.0, 0.0, 0.0), skeleton)


# -- bad input ----------------------------------------------------------------------------------
def test_a_mesh_file_too_large_for_the_memory_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / 'huge.stl'
    with open(path, 'wb') as out:
        out.truncate(1 << 40)  # sparse: a terabyte that takes no disk
    with pytest.raises(SceneError, match=r'huge\.stl: a mesh file of 1048576 MB, up to \d+ '
                                         r'triangles needs about \d+\.\d GB to load, but this '
                                         r'machine has \d+\.\d GB available'):
        load_scene(str(path))


def test_degenerate_and_broken_meshes_are_refused_with_the_file_and_the_reason(tmp_path):
    (tmp_path / 'line.obj').write_text('v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 3 2\n')
    with pytest.raises(SceneError, match=r'line\.obj: degenerate mesh: none of its 2 '
                                         r'triangle\(s\) has an area'):
        load_scene(str(tmp_path / 'line.obj'))
    (tmp_path / 'noise.ply').write_bytes(np.random.default_rng(0).bytes(4000))
    with pytest.raises(SceneError, match=r'noise\.ply: not a readable mesh'):
        load_scene(str(tmp_path / 'noise.ply'))
    (tmp_path / 'words.stl').write_text('a mesh this is not\n' * 40)
    with pytest.raises(SceneError, match=r'words\.stl'):
        load_scene(str(tmp_path / 'words.stl'))


def test_the_cli_exits_2_with_the_file_and_reason_for_a_mesh_too_large(tmp_path):
    path = tmp_path / 'huge.stl'
    with open(path, 'wb') as out:
        out.truncate(1 << 40)
    commands = tmp_path / 'commands.csv'
    commands.write_text('time,linear_x,angular_z\n0,0.5,0\n2,0,0\n')
    done = subprocess.run([sys.executable, '-m', 'digital_actor_planner.cli', 'simulate',
                           '--scene', str(path), '--commands', str(commands),
                           '--out', str(tmp_path / 'out.csv')],
                          capture_output=True, text=True, timeout=300, cwd=ROOT, check=False)
    assert done.returncode == 2
    assert 'huge.stl' in done.stderr and 'GB available' in done.stderr
    assert 'Traceback' not in done.stderr


def test_the_compiled_corner_intersection_is_the_pairwise_one():
    """
    The compiled tile intersection gives the readable pairwise one's intervals.

    The tiles intersect their cells' corners in one compiled pass; the readable pairwise
    intersection (``_intersect``, three times) gives the same intervals in the same order.
    """
    rng = np.random.default_rng(0)

    def corner(count, layers):
        ground = np.sort(rng.choice([0.0, 0.1, 0.2, 0.5, 1.0], (count, layers))
                         + rng.uniform(0, 0.05, (count, layers)), axis=1)
        ceiling = np.full_like(ground, np.inf)
        ceiling[:, :-1] = ground[:, 1:] - rng.uniform(0.0, 0.1, (count, layers - 1))
        empty = ~(ceiling >= ground) | (rng.random(ground.shape) < 0.3)
        ground[empty], ceiling[empty] = np.inf, np.inf
        return environment._compact(ground, ceiling)

    for layers in (1, 3, 6):
        corners = [corner(3000, layers) for _ in range(4)]
        width = max(g.shape[1] for g, _ in corners)
        grounds = [np.pad(g, ((0, 0), (0, width - g.shape[1])), constant_values=np.inf)
                   for g, _ in corners]
        ceilings = [np.pad(c, ((0, 0), (0, width - c.shape[1])), constant_values=np.inf)
                    for _, c in corners]
        ground, ceiling = grounds[0], ceilings[0]
        for g, c in zip(grounds[1:], ceilings[1:]):
            ground, ceiling = environment._intersect(ground, ceiling, g, c)
        compiled = environment._intersect_corners(grounds, ceilings)
        assert np.isfinite(ground).sum() > 100
        np.testing.assert_array_equal(compiled[0], ground)
        np.testing.assert_array_equal(compiled[1], ceiling)
