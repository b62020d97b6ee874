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
The shipped courses: files well-formed, and the upper-body courses geometrically as designed.

The upper-body courses are checked with the URDF's own collision shapes placed by
forward kinematics and tested against the course meshes with python-fcl, independently of the
planners: an obstacle must block the posture the motion pattern would use and let through the
posture the planner is meant to find.
"""
import csv
import glob
import importlib.util
import math
import os

from digital_actor_planner.core.skeleton import Skeleton
import fcl
import numpy as np
import pytest
import trimesh
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')
WALKING = ('flat', 'slope', 'stairs_up', 'stairs_down', 'gap', 'figure8_trap', 'blocks',
           'rough', 'turn', 'wall')
UPPER_BODY = ('low_beam', 'beam_too_low', 'table', 'pillars', 'uneven_beam')
COURSES = WALKING + UPPER_BODY
LIFT = 0.005   # m: stand the test postures this far above the ground so soles do not touch it


def scene_path(name):
    return os.path.join(SCENES, f'{name}.yaml')


def read_scene(name):
    with open(scene_path(name)) as stream:
        return yaml.safe_load(stream)


def pose_matrix(pose):
    """(4, 4) from [x, y, z, roll, pitch, yaw] (URDF convention: R = Rz Ry Rx)."""
    x, y, z, roll, pitch, yaw = pose
    matrix = trimesh.transformations.euler_matrix(roll, pitch, yaw, 'sxyz')
    matrix[:3, 3] = (x, y, z)
    return matrix


def load_meshes(name):
    """Read the course's meshes in the world frame straight from the files with trimesh."""
    scene = read_scene(name)
    meshes = []
    for entry in scene['meshes']:
        mesh = trimesh.load(os.path.join(SCENES, entry['file']), force='mesh')
        if 'pose' in entry:
            mesh.apply_transform(pose_matrix(entry['pose']))
        meshes.append(mesh)
    return meshes


@pytest.fixture(scope='module')
def skeleton():
    return Skeleton()


class World:
    """Course meshes as FCL BVHs plus a ground-height probe."""

    def __init__(self, name):
        self.meshes = load_meshes(name)
        self.objects = []
        for mesh in self.meshes:
            model = fcl.BVHModel()
            model.beginModel(len(mesh.vertices), len(mesh.faces))
            model.addSubModel(np.asarray(mesh.vertices, dtype=float),
                              np.asarray(mesh.faces, dtype=np.int32))
            model.endModel()
            self.objects.append(fcl.CollisionObject(model, fcl.Transform()))
        self.combined = trimesh.util.concatenate(self.meshes)

    def ground(self, x, y, below=5.0):
        """Highest surface at (x, y) at or below z = ``below``, m (NaN if none)."""
        hits, _, _ = self.combined.ray.intersects_location([[x, y, below]], [[0.0, 0.0, -1.0]])
        return float(np.max(hits[:, 2])) if len(hits) else math.nan

    def colliding_links(self, skeleton, q):
        """Return the set of link names whose collision shapes touch any course mesh."""
        shapes = skeleton.shape_transforms(skeleton.forward_kinematics(q))
        hit = set()
        request = fcl.CollisionRequest()
        for shape, transform in zip(skeleton.collision_shapes, shapes):
            if shape.kind == 'box':
                geometry = fcl.Box(*shape.size)
            elif shape.kind == 'cylinder':
                geometry = fcl.Cylinder(*shape.size)
            else:
                geometry = fcl.Sphere(*shape.size)
            body = fcl.CollisionObject(geometry, fcl.Transform(transform[:3, :3],
                                                               transform[:3, 3]))
            for world in self.objects:
                if fcl.collide(body, world, request, fcl.CollisionResult()):
                    hit.add(shape.link)
                    break
        return hit


def posture(skeleton, x, y, ground, yaw=0.0, **joints):
    """Return a standing configuration at (x, y) on ground height ``ground``, joints overridden."""
    q = skeleton.neutral()
    q[skeleton.index['root_x']] = x
    q[skeleton.index['root_y']] = y
    q[skeleton.index['root_z']] = ground + skeleton.leg.standing_height + LIFT
    q[skeleton.index['root_yaw']] = yaw
    for name, value in joints.items():
        q[skeleton.index[name]] = value
    return q


# -- files -------------------------------------------------------------------------------
def test_every_course_has_a_scene_and_commands():
    shipped = {os.path.splitext(os.path.basename(p))[0]
               for p in glob.glob(os.path.join(SCENES, '*.yaml'))}
    assert set(COURSES) <= shipped
    for name in shipped:
        assert os.path.isfile(os.path.join(SCENES, f'{name}.csv')), name


def test_config_scenes_stay_small():
    total = sum(os.path.getsize(p) for p in glob.glob(os.path.join(SCENES, '**', '*'),
                                                      recursive=True) if os.path.isfile(p))
    assert total < 5e6


@pytest.mark.parametrize('name', COURSES)
def test_scene_yaml_has_the_keys(name):
    scene = read_scene(name)
    assert isinstance(scene['description'], str) and scene['description']
    assert len(scene['meshes']) >= 1
    for entry in scene['meshes']:
        assert os.path.isfile(os.path.join(SCENES, entry['file'])), entry
        if 'pose' in entry:
            assert len(entry['pose']) == 6 and np.all(np.isfinite(entry['pose']))
    assert len(scene['start']) == 3 and np.all(np.isfinite(scene['start']))
    expect = scene['expect']
    if expect.get('stuck'):
        assert 'stop_before_x' in expect
    else:
        assert 'reach_x' in expect or 'reach_y' in expect


def test_mesh_formats_are_varied():
    files = {entry['file'] for name in COURSES for entry in read_scene(name)['meshes']}
    assert {os.path.splitext(f)[1] for f in files} >= {'.stl', '.obj', '.ply', '.glb'}


@pytest.mark.parametrize('name', COURSES)
def test_meshes_load_finite_and_closed(name):
    for mesh in load_meshes(name):
        assert len(mesh.faces) > 0
        assert np.all(np.isfinite(mesh.vertices))
        assert mesh.is_watertight


@pytest.mark.parametrize('name', COURSES)
def test_commands_are_well_formed(name):
    with open(os.path.join(SCENES, f'{name}.csv'), newline='') as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == ['time', 'linear_x', 'angular_z']
    values = np.array(rows[1:], dtype=float)
    assert values.shape[0] >= 2 and values.shape[1] == 3
    assert np.all(np.isfinite(values))
    assert values[0, 0] == 0.0
    assert np.all(np.diff(values[:, 0]) > 0)
    assert np.all(values[-1, 1:] == 0.0)
    assert 5.0 <= values[-1, 0] <= 15.0
    walking = values[:-1, 1]
    assert np.all((walking >= 0.5) & (walking <= 1.0))


# -- geometry ----------------------------------------------------------------------------
@pytest.mark.parametrize('name', COURSES)
def test_standing_actor_at_start_is_free_and_supported(skeleton, name):
    scene = read_scene(name)
    x, y, yaw = scene['start']
    world = World(name)
    ground = world.ground(x, y)
    assert np.isfinite(ground)
    q = posture(skeleton, x, y, ground, yaw)
    assert world.colliding_links(skeleton, q) == set()
    # Both soles fully supported: the ground under each sole's corners is level with it.
    links = skeleton.forward_kinematics(q)
    for foot in ('left_foot', 'right_foot'):
        transform = links[skeleton.link_index[foot]]
        for dx in (-skeleton.leg.heel, skeleton.leg.toe):
            for dy in (-skeleton.leg.foot_width / 2, skeleton.leg.foot_width / 2):
                corner = transform[:3, :3] @ [dx, dy, -skeleton.leg.ankle_height]
                corner += transform[:3, 3]
                assert world.ground(corner[0], corner[1]) == pytest.approx(ground, abs=2e-3)


def test_walking_courses_have_the_designed_heights():
    world = World('stairs_up')
    treads = [world.ground(x, 0.0) for x in (1.0, 1.65, 1.95, 2.25, 2.55, 3.5)]
    assert treads == pytest.approx([0.0, 0.15, 0.30, 0.45, 0.60, 0.75], abs=1e-6)
    world = World('figure8_trap')
    trap = read_scene('figure8_trap')['expect']['trap_x']
    assert trap[1] - trap[0] == pytest.approx(0.5)
    assert world.ground(trap[0] - 0.1, 0.0) == pytest.approx(0.33)
    assert world.ground(sum(trap) / 2, 0.0) == pytest.approx(0.0)
    assert world.ground(trap[1] + 0.1, 0.0) == pytest.approx(0.33)
    world = World('gap')
    assert world.ground(3.2, 0.0) == pytest.approx(-1.0)
    assert world.ground(2.95, 0.0) == pytest.approx(0.0)
    assert world.ground(3.5, 0.0) == pytest.approx(0.0)
    world = World('slope')
    assert world.ground(1.5 + 1.0, 0.0) == pytest.approx(math.tan(math.radians(12.0)), abs=1e-6)
    assert world.ground(5.5, 0.0) == pytest.approx(0.6)


def test_rough_terrain_is_bumpy_but_smooth_on_the_scale_of_a_foot():
    world = World('rough')
    xs = np.arange(1.0, 9.0, 0.05)
    heights = np.array([world.ground(x, y) for x in xs for y in (-0.09, 0.09)])
    assert np.ptp(heights) > 0.04
    assert np.max(np.abs(heights)) <= 0.04 + 1e-6
    # Over a sole length the surface deviates from level by less than 2.5 cm.
    profile = heights[::2]
    sole = int(round(0.25 / 0.05))
    spans = [np.ptp(profile[i:i + sole + 1]) for i in range(len(profile) - sole)]
    assert max(spans) < 0.025


def test_wall_and_too_low_beam_leave_room_for_a_clean_stop(skeleton):
    for name in ('wall', 'beam_too_low'):
        world = World(name)
        stop = read_scene(name)['expect']['stop_before_x']
        q = posture(skeleton, stop - 0.1, 0.0, 0.0)
        assert world.colliding_links(skeleton, q) == set(), name


def test_wall_blocks_the_legs(skeleton):
    world = World('wall')
    q = posture(skeleton, 3.1, 0.0, 0.0)
    assert {'left_foot', 'right_foot'} <= world.colliding_links(skeleton, q)


def test_low_beams_pass_only_with_the_waist_bent(skeleton):
    for name, beam_x, ground_z in (('low_beam', 3.0, 0.0), ('uneven_beam', 3.6, 0.12)):
        world = World(name)
        assert world.ground(beam_x, 0.0, below=1.0) == pytest.approx(ground_z, abs=1e-6)
        standing = posture(skeleton, beam_x, 0.0, ground_z)
        assert 'head' in world.colliding_links(skeleton, standing), name
        # Half bent (0.5 rad), the head still meets the beam somewhere on the way under.
        sweep = np.arange(beam_x - 0.8, beam_x + 0.5, 0.05)
        assert any(world.colliding_links(
            skeleton, posture(skeleton, x, 0.0, ground_z, waist_pitch=0.5)) for x in sweep)
        # Bent forward 0.8 rad the actor clears the beam all the way under it.
        for x in sweep:
            bent = posture(skeleton, x, 0.0, ground_z, waist_pitch=0.8)
            assert world.colliding_links(skeleton, bent) == set(), (name, x)


def test_beam_too_low_blocks_every_waist_posture(skeleton):
    world = World('beam_too_low')
    for pitch in np.linspace(skeleton.lower[skeleton.index['waist_pitch']],
                             skeleton.upper[skeleton.index['waist_pitch']], 7):
        for yaw in (-0.8, 0.0, 0.8):
            q = posture(skeleton, 3.0, 0.0, 0.0, waist_pitch=pitch, waist_yaw=yaw)
            assert world.colliding_links(skeleton, q) & {'torso', 'head', 'waist'}, (pitch, yaw)


def test_table_needs_the_left_elbow_flexed(skeleton):
    world = World('table')
    sweep = np.arange(2.1, 3.6, 0.1)
    # Turning the waist away does not help: somewhere along the table the hand still hits.
    assert any('left_forearm' in world.colliding_links(
        skeleton, posture(skeleton, x, 0.0, 0.0, waist_yaw=0.8)) for x in sweep)
    for x in sweep:
        hanging = posture(skeleton, x, 0.0, 0.0)
        assert world.colliding_links(skeleton, hanging) == {'left_forearm'}, x
        for swing in (-0.3, 0.0, 0.3):
            flexed = posture(skeleton, x, 0.0, 0.0, left_elbow=1.2, left_shoulder_pitch=swing)
            assert world.colliding_links(skeleton, flexed) == set(), (x, swing)
    # The swinging arm also hits the things on the table, not only its top.
    objects = World('table')
    objects.objects = objects.objects[2:]
    hits = [x for x in sweep for swing in (-0.3, 0.3)
            if objects.colliding_links(skeleton, posture(skeleton, x, 0.0, 0.0,
                                                         left_shoulder_pitch=swing))]
    assert len(hits) >= 4


def test_pillars_pass_only_with_the_waist_turned(skeleton):
    world = World('pillars')
    square = posture(skeleton, 3.0, 0.0, 0.0)
    assert {'left_shoulder', 'right_shoulder'} <= world.colliding_links(skeleton, square)
    arms_in = posture(skeleton, 3.0, 0.0, 0.0, left_shoulder_roll=0.0, right_shoulder_roll=0.0)
    assert world.colliding_links(skeleton, arms_in), 'narrower than the shoulders'
    for x in np.arange(2.4, 3.7, 0.05):
        turned = posture(skeleton, x, 0.0, 0.0, waist_yaw=0.6, left_shoulder_roll=0.0,
                         right_shoulder_roll=0.0)
        assert world.colliding_links(skeleton, turned) == set(), x
        fully = posture(skeleton, x, 0.0, 0.0, waist_yaw=0.8)
        assert world.colliding_links(skeleton, fully) == set(), x


def test_committed_courses_are_what_the_script_makes(tmp_path):
    spec = importlib.util.spec_from_file_location(
        'make_courses', os.path.join(ROOT, 'scripts', 'make_courses.py'))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.main(['--out', str(tmp_path)])
    made = sorted(os.path.relpath(p, tmp_path)
                  for p in glob.glob(str(tmp_path / '**' / '*.*'), recursive=True))
    assert len(made) > 2 * len(COURSES)
    for relative in made:
        with open(tmp_path / relative, 'rb') as new, \
                open(os.path.join(SCENES, relative), 'rb') as committed:
            assert new.read() == committed.read(), relative
