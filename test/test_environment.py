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

"""Environment: scene loading, its errors, and the layered walkable-ground map."""
import math
import os

from digital_actor_planner.core.actor import start_configuration
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.scene import check_start, load_scene, SceneError
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest
import trimesh

SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'config',
                      'scenes')


def _box(low, high):
    low, high = np.asarray(low, float), np.asarray(high, float)
    mesh = trimesh.creation.box(high - low)
    mesh.apply_translation((low + high) / 2)
    return mesh


def _steps():
    """Three 0.15 m steps of 0.3 m tread starting at x = 2 (each a box from the floor)."""
    return [_box((2.0 + 0.3 * i, -1, 0), (2.0 + 0.3 * (i + 1), 1, 0.15 * (i + 1)))
            for i in range(3)]


def _steps_height(x):
    i = np.floor((np.asarray(x) - 2.0) / 0.3)
    return np.where((i >= 0) & (i < 3), 0.15 * (i + 1), 0.0)


@pytest.fixture(scope='module')
def world():
    """Floor, a table, a wall sunk 1 cm into the floor, an overhead beam, stairs."""
    meshes = [_box((-1, -2, -0.1), (9, 2, 0.0)),           # floor, top at 0
              _box((0.5, -0.5, 0.70), (1.5, 0.5, 0.75)),   # table top
              _box((5.0, -2, -0.01), (5.2, 2, 1.0)),       # wall
              _box((6.5, -2, 1.40), (6.7, 2, 1.60)),       # beam
              ] + _steps()
    return Environment(meshes)


def test_floor_is_walkable_and_open_to_the_sky(world):
    height, clearance = world.ground_height(np.array([[0.0, 0.0], [4.0, 1.0]]), 0.5)
    np.testing.assert_allclose(height, [0.0, 0.0], atol=1e-9)
    assert np.all(np.isinf(clearance))


def test_under_a_table_the_ground_is_the_floor_and_clearance_the_underside(world):
    height, clearance = world.ground_height(np.array([[1.0, 0.0]]), 0.5)
    assert height[0] == pytest.approx(0.0, abs=1e-9)
    assert clearance[0] == pytest.approx(0.70, abs=1e-9)
    # From above, the table top is the ground.
    height, clearance = world.ground_height(np.array([[1.0, 0.0]]), 1.0)
    assert height[0] == pytest.approx(0.75, abs=1e-9)
    assert np.isinf(clearance[0])
    # A reference height inside the table top is inside a solid.
    height, clearance = world.ground_height(np.array([[1.0, 0.0]]), 0.72)
    assert np.isnan(height[0]) and np.isnan(clearance[0])


def test_inside_a_wall_footprint_below_its_top_there_is_no_ground(world):
    height, _ = world.ground_height(np.array([[5.1, 0.0], [5.1, 1.5]]), 0.5)
    assert np.all(np.isnan(height))
    height, clearance = world.ground_height(np.array([[5.1, 0.0]]), 1.2)
    assert height[0] == pytest.approx(1.0, abs=1e-9)
    assert np.isinf(clearance[0])


def test_under_a_beam_the_clearance_is_the_beam_underside(world):
    height, clearance = world.ground_height(np.array([[6.6, 0.3]]), 0.3)
    assert height[0] == pytest.approx(0.0, abs=1e-9)
    assert clearance[0] == pytest.approx(1.40, abs=1e-9)


def test_off_the_meshes_there_is_no_ground(world):
    height, clearance = world.ground_height(np.array([[20.0, 0.0], [0.0, -5.0]]), 10.0)
    assert np.all(np.isnan(height)) and np.all(np.isnan(clearance))


def test_stairs_never_underestimate_and_are_exact_away_from_edges(world):
    rng = np.random.default_rng(3)
    x = rng.uniform(1.6, 3.4, 4000)
    xy = np.column_stack([x, rng.uniform(-0.9, 0.9, len(x))])
    height, _ = world.ground_height(xy, 1.0)
    true = _steps_height(x)
    assert not np.any(np.isnan(height))
    # A foot placed on the returned height never sinks into a tread or clips a step edge.
    assert np.all(height >= true - 1e-9)
    # Away from the risers (farther than one grid cell) the height is exact.
    edges = 2.0 + 0.3 * np.arange(4)
    far = np.min(np.abs(x[:, None] - edges[None, :]), axis=1) > world.resolution * 1.01
    np.testing.assert_allclose(height[far], true[far], atol=1e-9)


def test_vectorised_reference_heights(world):
    xy = np.array([[1.0, 0.0], [1.0, 0.0], [5.1, 0.0]])
    height, _ = world.ground_height(xy, np.array([0.3, 2.0, 0.3]))
    assert height[0] == pytest.approx(0.0, abs=1e-9)
    assert height[1] == pytest.approx(0.75, abs=1e-9)
    assert np.isnan(height[2])


def test_single_sided_terrain_is_solid_below_its_surface():
    """An open height-field mesh (no bottom) bounds a solid below it."""
    xs, ys = np.linspace(0, 4, 41), np.linspace(-1, 1, 21)
    gx, gy = np.meshgrid(xs, ys)

    def surface(x, y):
        return 0.1 * np.sin(1.5 * x) + 0.05 * np.cos(2.0 * y)

    vertices = np.column_stack([gx.ravel(), gy.ravel(), surface(gx, gy).ravel()])
    faces = []
    for j in range(len(ys) - 1):
        for i in range(len(xs) - 1):
            a = j * len(xs) + i
            faces += [[a, a + 1, a + len(xs) + 1], [a, a + len(xs) + 1, a + len(xs)]]
    terrain = trimesh.Trimesh(vertices, np.array(faces), process=False)
    assert not terrain.is_watertight
    env = Environment([terrain])
    rng = np.random.default_rng(5)
    xy = rng.uniform((0.05, -0.95), (3.95, 0.95), (2000, 2))
    height, clearance = env.ground_height(xy, 1.0)
    slope = math.hypot(0.15, 0.1)  # the largest gradient of surface()
    # The mesh is piecewise linear between its vertices; compare with its exact height.
    origins = np.column_stack([xy, np.full(len(xy), 5.0)])
    locations, index_ray, _ = terrain.ray.intersects_location(
        origins, np.tile([0.0, 0.0, -1.0], (len(xy), 1)))
    mesh_height = np.full(len(xy), np.nan)
    mesh_height[index_ray] = locations[:, 2]
    assert np.all(np.isfinite(height)) and np.all(np.isinf(clearance))
    assert np.all(height >= mesh_height - 1e-9)
    assert np.all(height <= mesh_height + slope * env.resolution * math.sqrt(2) + 1e-9)
    # Below the surface is solid: no walkable ground there.
    below, _ = env.ground_height(xy, mesh_height - 0.05)
    assert np.all(np.isnan(below))


def test_environment_rejects_bad_input():
    floor = _box((0, 0, -0.1), (1, 1, 0))
    with pytest.raises(ValueError, match='no mesh|at least one'):
        Environment([])
    with pytest.raises(ValueError, match='2 names'):
        Environment([floor], names=['a', 'b'])
    with pytest.raises(ValueError, match='resolution'):
        Environment([floor], resolution=0.0)
    broken = floor.copy()
    broken.vertices[3] = [np.nan, 0, 0]
    with pytest.raises(ValueError, match=r'mesh 1 \(lid\).*vertex 3'):
        Environment([floor, broken], names=['floor', 'lid'])
    with pytest.raises(ValueError, match='shape'):
        Environment([floor]).ground_height(np.zeros((3, 3)), 0.0)
    with pytest.raises(ValueError, match='z_ref'):
        Environment([floor]).ground_height(np.zeros((3, 2)), np.zeros(2))


# -- scene files -----------------------------------------------------------------------------
def _write_scene(tmp_path, text):
    path = tmp_path / 'scene.yaml'
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize('extension', ['stl', 'obj', 'ply', 'glb', 'dae'])
def test_load_scene_reads_every_mesh_format_with_poses(tmp_path, extension):
    _box((-1, -1, -0.1), (3, 1, 0.0)).export(tmp_path / f'floor.{extension}')
    _box((-0.1, -0.1, 0.0), (0.1, 0.1, 0.3)).export(tmp_path / f'block.{extension}')
    path = _write_scene(tmp_path, f"""
meshes:
  - {{file: floor.{extension}}}
  - {{file: block.{extension}, pose: [2.0, 0.0, 0.0, 0.0, 0.0, 0.7853981633974483]}}
start: [0.5, 0.0, 0.1]
description: a block on a floor
expect: {{reaches: true}}
""")
    scene = load_scene(path, skeleton=Skeleton())
    assert scene.start == (0.5, 0.0, 0.1)
    assert scene.description == 'a block on a floor'
    assert scene.expect == {'reaches': True}
    assert scene.source == path
    names = [p.rsplit('/', 1)[1] for p in scene.mesh_files]
    assert names == [f'floor.{extension}', f'block.{extension}']
    height, _ = scene.environment.ground_height(np.array([[2.0, 0.0], [0.5, 0.0]]), 1.0)
    np.testing.assert_allclose(height, [0.3, 0.0], atol=1e-6)
    # The pose rotated the block by 45 degrees about z: its corner now reaches x = 2 + 0.141.
    np.testing.assert_allclose(scene.environment.bounds[1, 0], 3.0, atol=1e-6)
    block = scene.environment.meshes[1]
    assert block.bounds[1, 0] == pytest.approx(2.0 + 0.1 * math.sqrt(2), abs=1e-6)


def test_bare_mesh_file_starts_at_the_origin(tmp_path):
    _box((-1, -1, -0.1), (1, 1, 0.0)).export(tmp_path / 'floor.stl')
    scene = load_scene(str(tmp_path / 'floor.stl'))
    assert scene.start == (0.0, 0.0, 0.0)
    assert scene.description == '' and scene.expect == {}


def test_glb_scene_with_several_geometries_is_flattened_to_world_triangles(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(_box((-1, -1, -0.1), (1, 1, 0.0)), node_name='floor')
    scene.add_geometry(_box((-0.1, -0.1, 0.0), (0.1, 0.1, 0.2)), node_name='box',
                       transform=trimesh.transformations.translation_matrix([0.5, 0.0, 0.0]))
    scene.export(tmp_path / 'world.glb')
    loaded = load_scene(str(tmp_path / 'world.glb'))
    height, _ = loaded.environment.ground_height(np.array([[0.5, 0.0], [-0.5, 0.0]]), 1.0)
    np.testing.assert_allclose(height, [0.2, 0.0], atol=1e-6)


@pytest.mark.parametrize('text, message', [
    ('meshes: [{file: floor.stl}\nstart: [0, 0, 0]\n', r'line \d+.*YAML syntax'),
    ('meshes: [{file: floor.stl}]\nstrat: [0, 0, 0]\n', r"unknown key.*'strat'"),
    ('meshes: [{file: floor.stl, pos: [0, 0, 0, 0, 0, 0]}]\n', r"meshes\[0\].*'pos'"),
    ('meshes: [{file: floor.stl, pose: [0, 0, 0]}]\n', r'meshes\[0\]\.pose.*6 finite'),
    ('meshes: [{file: floor.stl, pose: [0, 0, .nan, 0, 0, 0]}]\n', r'pose.*6 finite'),
    ('meshes: [{file: floor.stl}]\nstart: [0, 0]\n', r'start.*3 finite'),
    ('meshes: [{file: floor.stl}]\nstart: [0, .inf, 0]\n', r'start.*3 finite'),
    ('meshes: []\n', r'meshes must be a non-empty list'),
    ('- just a list\n', r'top level must be a mapping'),
    ('meshes: [{file: missing.stl}]\n', r'missing\.stl: no such mesh file'),
    ('meshes: [{file: floor.stl}]\ndescription: [1, 2]\n', r'description must be a string'),
])
def test_scene_yaml_errors_name_the_file_and_field(tmp_path, text, message):
    _box((-1, -1, -0.1), (1, 1, 0.0)).export(tmp_path / 'floor.stl')
    path = _write_scene(tmp_path, text)
    with pytest.raises(SceneError, match=message) as error:
        load_scene(path)
    assert 'scene.yaml' in str(error.value) or 'missing.stl' in str(error.value)


def test_bad_mesh_files_raise_scene_errors(tmp_path):
    with pytest.raises(SceneError, match='no such scene file'):
        load_scene(str(tmp_path / 'nothing.stl'))
    (tmp_path / 'empty.stl').write_bytes(b'')
    with pytest.raises(SceneError, match=r'empty\.stl: empty file'):
        load_scene(str(tmp_path / 'empty.stl'))
    (tmp_path / 'text.stl').write_text('this is not a mesh at all\n')
    with pytest.raises(SceneError, match=r'text\.stl'):
        load_scene(str(tmp_path / 'text.stl'))
    (tmp_path / 'nan.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n')
    with pytest.raises(SceneError, match=r'nan\.obj.*not finite'):
        load_scene(str(tmp_path / 'nan.obj'))
    (tmp_path / 'points.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\n')
    with pytest.raises(SceneError, match=r'points\.obj'):
        load_scene(str(tmp_path / 'points.obj'))
    (tmp_path / 'empty.yaml').write_text('\n')
    with pytest.raises(SceneError, match=r'empty\.yaml: empty file'):
        load_scene(str(tmp_path / 'empty.yaml'))


# -- start poses -----------------------------------------------------------------------------
def test_start_configuration_stands_on_the_ground(world):
    skeleton = Skeleton()
    q = start_configuration(world, (2.7, 0.0, 0.0), skeleton)   # on the top step
    assert q[skeleton.index['root_z']] == pytest.approx(
        0.45 + skeleton.leg.standing_height + 0.002, abs=1e-9)
    q = start_configuration(world, (3.5, 1.0, 0.4), skeleton)
    assert q[skeleton.index['root_z']] == pytest.approx(
        skeleton.leg.standing_height + 0.002, abs=1e-9)
    assert q[skeleton.index['root_yaw']] == pytest.approx(0.4)
    check_start(world, (3.5, 1.0, 0.4), skeleton)
    check_start(world, (2.7, 0.0, 0.0), skeleton)


def test_a_start_on_bumpy_ground_is_accepted():
    """
    On the rough course's bumps the feet rest on the ground under them.

    On the rough course's bumps (up to 4 cm) the feet rest on the ground under them, each at its
    own height and pitch; placed level on the lowest ground they were inside the bumps and the
    start was refused as inside an obstacle.
    """
    skeleton = Skeleton()
    scene = load_scene(os.path.join(SCENES, 'rough.yaml'), skeleton)
    for x in (3.0, 4.0, 5.0, 6.0, 7.0, 8.0):
        check_start(scene.environment, (x, 0.3, 0.0), skeleton)
    q = start_configuration(scene.environment, (4.0, 0.3, 0.0), skeleton)
    assert BodyCollision(skeleton, scene.environment).links_in_collision(q)


def test_start_inside_an_obstacle_or_without_ground_is_rejected(world):
    skeleton = Skeleton()
    with pytest.raises(SceneError, match='inside an obstacle'):
        check_start(world, (5.0, 0.0, 0.0), skeleton)      # in the wall
    with pytest.raises(SceneError, match='inside an obstacle'):
        check_start(world, (6.6, 0.0, 0.0), skeleton)      # head in the beam
    with pytest.raises(SceneError, match='inside an obstacle'):
        check_start(world, (1.0, 0.0, 0.0), skeleton)      # under the table
    with pytest.raises(SceneError, match='no ground'):
        check_start(world, (30.0, 0.0, 0.0), skeleton)
    with pytest.raises(SceneError, match='start'):
        check_start(world, (0.0, float('nan'), 0.0), skeleton)


def test_load_scene_with_a_skeleton_checks_the_start(tmp_path):
    _box((-1, -1, -0.1), (3, 1, 0.0)).export(tmp_path / 'floor.stl')
    _box((-0.1, -1, 0.0), (0.1, 1, 2.0)).export(tmp_path / 'wall.stl')
    path = _write_scene(tmp_path, 'meshes: [{file: floor.stl}, {file: wall.stl}]\n'
                                  'start: [0.0, 0.0, 0.0]\n')
    load_scene(path)  # no skeleton: no start check
    with pytest.raises(SceneError, match=r'scene\.yaml.*inside an obstacle'):
        load_scene(path, skeleton=Skeleton())


def test_a_closed_mesh_wound_inside_out_is_still_a_solid():
    floor = _box((-1, -1, -0.1), (2, 1, 0.0))
    block = _box((0.5, -0.5, 0.0), (1.0, 0.5, 0.3))
    block.faces = block.faces[:, ::-1]          # normals point inwards
    assert block.volume < 0
    env = Environment([floor, block])
    height, clearance = env.ground_height(np.array([[0.75, 0.0], [0.0, 0.0]]), 0.2)
    assert np.isnan(height[0])                  # inside the block
    assert height[1] == pytest.approx(0.0, abs=1e-9) and np.isinf(clearance[1])
    height, _ = env.ground_height(np.array([[0.75, 0.0]]), 1.0)
    assert height[0] == pytest.approx(0.3, abs=1e-9)


def test_one_reference_height_for_all_points_matches_one_per_point(world):
    """
    A scalar z_ref answers what the same height repeated per point answers.

    A scalar z_ref answers what the same height repeated per point answers, on and off the grid,
    for NaN points and for non-finite heights.
    """
    rng = np.random.default_rng(4)
    low, high = world.bounds[0, :2] - 0.5, world.bounds[1, :2] + 0.5
    xy = rng.uniform(low, high, (400, 2))
    xy[:5] = np.nan
    for z in (-0.5, 0.05, 0.3, 0.9, 2.0, np.inf, np.nan):
        scalar = world.ground_height(xy, z)
        repeated = world.ground_height(xy, np.full(len(xy), z))
        for a, b in zip(scalar, repeated):
            np.testing.assert_array_equal(a, b)
    assert np.all(np.isnan(world.ground_height(xy[:5], 0.3)[0]))


def test_top_height_bounds_every_mesh_and_is_exact_over_level_faces(world):
    """
    A box just above the bound is free; over level tops the bound is the top itself.

    A box just above the bound over any rectangle is free; over level tops the bound is the top
    itself.
    """
    import fcl
    rng = np.random.default_rng(5)
    centre = rng.uniform((-1.5, -2.5), (9.5, 2.5), (400, 2))
    half = rng.uniform(0.005, 0.3, (400, 2))
    tops = world.top_height(centre - half, centre + half)
    request = fcl.CollisionRequest()
    for c, h, top in zip(centre, half, tops):
        if not np.isfinite(top):
            assert not np.all((c + h > world.bounds[0, :2]) & (c - h < world.bounds[1, :2]))
            continue
        probe = fcl.CollisionObject(fcl.Box(2 * h[0], 2 * h[1], 0.01),
                                    fcl.Transform(np.array([c[0], c[1], top + 0.005 + 1e-7])))
        assert not any(fcl.collide(probe, o, request, fcl.CollisionResult())
                       for o in world.objects), (c, h, top)
    # Open floor, a stair tread, the wall's top (away from edges by more than a cell).
    level = world.top_height(np.array([[3.0, 0.5], [2.05, -0.5], [5.05, 0.0]]),
                             np.array([[3.5, 0.7], [2.25, -0.3], [5.15, 0.1]]))
    np.testing.assert_allclose(level, [0.0, 0.15, 1.0], atol=1e-9)
    # The one-lookup bound over squares is never below the rectangle's, and still exact on an
    # open floor.
    near = world.top_height_near(centre, np.max(half, axis=1))
    assert np.all(near >= tops)
    assert np.all(np.isinf(world.top_height_near(centre[:3], np.full(3, 0.02 * 33))))
    assert world.top_height_near(np.array([[3.2, 0.5]]), np.array([0.15]))[0] == 0.0
    beside = world.top_height(np.array([[20.0, 0.0], [0.0, -9.0]]),
                              np.array([[21.0, 1.0], [1.0, -8.0]]))
    assert np.all(beside == -np.inf)
    with pytest.raises(ValueError, match='same shape'):
        world.top_height(np.zeros((2, 2)), np.zeros((3, 2)))


def test_the_environment_is_a_foundation_and_scenes_the_top_floor_of_core():
    """
    The environment imports no other planning module; scene files live in scene.

    environment imports no other planning module (the actor stands on it, not the other way round);
    scene files and start checks, which need the actor, live in scene.
    """
    import ast
    import digital_actor_planner.core.environment as environment_module
    import digital_actor_planner.core.scene as scene_module

    def relative_imports(module):
        with open(module.__file__, encoding='utf-8') as source:
            tree = ast.parse(source.read())
        return {node.module for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and node.level == 1}

    assert relative_imports(environment_module) == {'jit'}
    assert {'actor', 'environment'} <= relative_imports(scene_module)
