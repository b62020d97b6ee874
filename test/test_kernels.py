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
The compiled kernels (core/jit.py) give what their own Python source gives, to the last bit.

An installation without numba runs that source: it then plans the same frames, only slower.
Each kernel is run compiled and as plain Python on the inputs the planners give it, including
the awkward ones (off the map, NaN, holes, a table over the floor).
"""
import importlib
import os
import pkgutil
import subprocess
import sys

from digital_actor_planner import core as core_package
from digital_actor_planner.core import (body_model, collision, convex, ct_space, environment,
                                        footstep_search, gait, path as path_module)
from digital_actor_planner.core import skeleton as skeleton_module, upper_body
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.jit import COMPILED, direct, float_array
from digital_actor_planner.core.scene import start_configuration
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest
from scene_helpers import box


def same(compiled, plain):
    """Assert two kernel results (an array or a tuple of arrays and numbers) are identical."""
    if not isinstance(compiled, tuple):
        compiled, plain = (compiled,), (plain,)
    assert len(compiled) == len(plain)
    for a, b in zip(compiled, plain):
        np.testing.assert_array_equal(a, b)


def near(compiled, numpy_result):
    """
    Assert a kernel result matches NumPy code that calls NumPy's trigonometry, to 1e-12.

    Kernels call the C library's sin, cos, acos and atan2; NumPy calls the same ones on the
    development machine (an AVX2 build dispatch: the same bits, so every course plans the same
    frames), but its AVX-512 versions may differ in the last bit.
    """
    if not isinstance(compiled, tuple):
        compiled, numpy_result = (compiled,), (numpy_result,)
    assert len(compiled) == len(numpy_result)
    for a, b in zip(compiled, numpy_result):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


@pytest.fixture(scope='module')
def skeleton():
    return Skeleton()


@pytest.fixture(scope='module')
def world():
    """Make a floor, a step, a table (a surface with another under it) and a post."""
    return Environment([box((-3, -3, -0.2), (3, 3, 0.0)), box((0.5, -3, 0.0), (3, 3, 0.15)),
                        box((-1.5, -0.5, 0.7), (-0.7, 0.5, 0.75)),
                        box((1.0, 0.3, 0.15), (1.1, 0.4, 1.5))])


def _kernels():
    """Every kernel of the core (what ``jit.kernel`` made: it keeps ``py_func``), by name."""
    found = {}
    for info in pkgutil.iter_modules(core_package.__path__):
        module = importlib.import_module(f'{core_package.__name__}.{info.name}')
        for name, value in vars(module).items():
            if callable(value) and hasattr(value, 'py_func') and value.__module__ == \
                    module.__name__:
                found[f'{info.name}.{name}'] = value
    return found


def test_numba_is_installed_and_the_kernels_are_compiled():
    """
    The kernels are compiled: numba is installed.

    requirements.txt pins numba: without it every kernel runs as Python, many times slower, and the
    planning-time numbers in the README would not hold.
    """
    assert COMPILED
    kernels = _kernels()
    # The stages that run compiled: the footstep search, the ground map, the gait, the 3D
    # check, the CT-space and the roadmap's search.
    stages = {name.split('.')[0] for name in kernels}
    assert {'footstep_search', 'environment', 'gait', 'collision', 'ct_space',
            'ct_roadmap'} <= stages
    for name, kernel in kernels.items():
        assert kernel.py_func is not kernel, name


def test_a_kernel_called_without_numbas_dispatch_answers_alike():
    """
    A kernel called without numba's dispatch answers alike.

    ``jit.direct``: the footstep search as the planner calls it (its compiled code, not numba's
    dispatcher) answers exactly what the dispatcher's call answers; a plain function, or a kernel
    of more than one signature, is handed back as it is.
    """
    from digital_actor_planner.core import footsteps
    from digital_actor_planner.core.footsteps import FootstepPlanner, GroundProfile
    assert footsteps.window_search is not footstep_search.window_search
    assert footsteps.window_search is direct(footstep_search.window_search)
    planner = FootstepPlanner(FootstepConfig(), Skeleton().leg)
    s = -0.3 + 0.02 * np.arange(200)
    height = np.vstack([np.where(s > 0.6, 0.12, 0.0)] * 2)
    profile = GroundProfile(s0=-0.3, ds=0.02, height=height, low=height.copy(),
                            headroom=np.full_like(height, np.inf),
                            obstacle=np.full_like(height, np.nan))
    none_banned = np.zeros(14, dtype=bool)
    none_banned.setflags(write=False)
    arguments = (6 * 14 + 6) * 14 + 6, none_banned, none_banned, True, \
        planner.search_profile(profile, 1, 0.0, 0.0, -0.1, 0.0, 0.5, 0.5)
    through, direct_answer = (footstep_search.window_search(*arguments),
                              footsteps.window_search(*arguments))
    assert through[0] >= 0 and through[0] == direct_answer[0]
    np.testing.assert_array_equal(through[1], direct_answer[1])
    assert through[2:] == direct_answer[2:]

    def plain(x):
        return x
    assert direct(plain) is plain


def test_footholds(skeleton):
    """On ground with holes, steps, slopes and low headroom."""
    leg = skeleton.leg
    rng = np.random.default_rng(11)
    count = 300
    steps = np.repeat(rng.choice([0.0, 0.1, 0.25, -0.15], size=count // 15), 15)
    high = np.vstack([steps + 0.1 * np.sin(np.arange(count) * 0.07), steps])
    high += rng.normal(0.0, 0.002, high.shape)
    low = high - np.abs(rng.normal(0.0, 0.004, high.shape))
    high[1, 100:105] = low[1, 100:105] = np.nan
    headroom = np.where(rng.random(high.shape) < 0.01, 0.3, np.inf)
    s = rng.uniform(-0.5, 0.02 * count, 2000)
    side = rng.integers(0, 2, s.size)
    config = FootstepConfig()
    arguments = (high, low, headroom, -0.3, 0.02, side, s, float(leg.heel), float(leg.toe),
                 config.min_headroom, config.max_foot_pitch, config.flatness_tolerance,
                 config.min_support_fraction)
    compiled = footstep_search.judge_footholds(*arguments)
    same(compiled, footstep_search.judge_footholds.py_func(*arguments))
    assert 0 < compiled[0].sum() < s.size


def test_shape_transforms(skeleton):
    rng = np.random.default_rng(1)
    qs = rng.uniform(np.maximum(skeleton.lower, -3), np.minimum(skeleton.upper, 3), (30, 22))
    shapes = tuple(range(len(skeleton.collision_shapes)))
    for chosen in (shapes, shapes[::4], (shapes[-1],)):
        skeleton.shape_transforms_at(qs[:1], chosen)
        layout = skeleton._shape_chains[chosen]
        same(skeleton_module._shape_transforms(qs, *layout),
             skeleton_module._shape_transforms.py_func(qs, *layout))


def test_ground_heights_and_top_bounds(world):
    rng = np.random.default_rng(2)
    xy = rng.uniform(-3.5, 3.5, (3000, 2))
    xy[:20, 0] = np.nan
    z = rng.uniform(-0.5, 1.2, xy.shape[0])
    z[20:30] = np.inf
    grid = world.ground_grid()
    assert grid[8].max() > 1  # the table over the floor: more than one layer in a tile
    compiled = environment._ground_heights(xy, z, *grid)
    same(compiled, environment._ground_heights.py_func(xy, z, *grid))
    assert np.isfinite(compiled[0]).sum() > 1000 and np.isnan(compiled[0]).sum() > 30
    half = rng.uniform(0.0, 0.8, xy.shape[0])
    half[30:40] = np.nan
    layout = (*world.top_near_grid(), xy, half)
    tops = environment._tops_near(*layout)
    same(tops, environment._tops_near.py_func(*layout))
    assert np.isinf(tops).sum() > 30 and np.isfinite(tops).sum() > 1000


def test_the_broad_phase_of_the_3d_check(skeleton, world):
    rng = np.random.default_rng(3)
    body = BodyCollision(skeleton, world)
    start = start_configuration(world, (0.0, 0.0, 0.0), skeleton)
    # A walk-like motion: the root moving over the step and the legs swinging, with frames
    # repeated (shapes that have not moved) and some in the table and the post.
    frames = np.repeat(start[None], 40, axis=0)
    frames[:, skeleton.index['root_x']] += np.linspace(-1.0, 1.6, 40)
    frames[::3, skeleton.index['left_knee']] += rng.uniform(0.0, 1.0, 14)
    frames[10:20, skeleton.index['root_z']] -= 0.3
    shapes = tuple(range(len(body.shapes)))
    transforms = skeleton.shape_transforms_at(frames, shapes)
    index = np.array(shapes)
    for free_end in (False, True):
        arguments = (transforms, body._kind_codes[index], body._halves[index], True,
                     *world.top_near_grid(),
                     transforms[5, :, :3, :].copy(), free_end, body._reach_array[index],
                     body._mesh_low, body._mesh_high)
        pairs, near = collision._suspects(*arguments)
        same((pairs, near), collision._suspects.py_func(*arguments))
        assert 0 < pairs.shape[0] < transforms.shape[0] * transforms.shape[1]
        assert near.any() and not near.all()
    rotations = float_array(transforms[..., :3, :3])
    same(collision.half_extents(body._kind_codes[index], body._halves[index], rotations),
         collision.half_extents.py_func(body._kind_codes[index], body._halves[index],
                                        rotations))


def test_the_upper_body_kinematics_and_boxes(skeleton):
    """
    The upper-body kinematics and boxes, compiled and as Python.

    Every link's pose over frames (the CT-space's kinematics), the shapes placed on them and their
    boxes.
    """
    rng = np.random.default_rng(6)
    q = rng.uniform(np.maximum(skeleton.lower, -3), np.minimum(skeleton.upper, 3), (25, 22))
    kinematics = body_model.BodyKinematics(skeleton)
    shapes = body_model.BodyShapes(skeleton)
    poses = []
    for kernel in (body_model.link_poses, body_model.link_poses.py_func):
        rotations = np.zeros((25, kinematics.link_count, 3, 3))
        positions = np.zeros((25, kinematics.link_count, 3))
        rotations[:, 0] = np.eye(3)
        kernel(q, rotations, positions, *kinematics._step_arrays(kinematics.steps))
        poses.append((rotations, positions))
    same(poses[0], poses[1])
    every = np.arange(len(shapes.kind))
    assert set(shapes.kind) == {'box', 'cylinder', 'sphere'}
    # The model's shapes are not turned on their links: every other one is turned here.
    turns = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in every])
    arguments = (*poses[0], every, shapes.origin_translation, turns, every % 2 == 0)
    placed = []
    for kernel in (body_model.place_shapes, body_model.place_shapes.py_func):
        rotation, centre = np.empty((25, every.size, 3, 3)), np.empty((25, every.size, 3))
        kernel(*arguments, every, rotation, centre)
        placed.append((rotation, centre))
    same(placed[0], placed[1])
    # Written at other slots (a body's arrays hold every shape; a branch moves some of them).
    slots = every[::-1].copy()
    rotation, centre = np.empty((25, every.size, 3, 3)), np.empty((25, every.size, 3))
    body_model.place_shapes(*arguments, slots, rotation, centre)
    same((rotation[:, slots], centre[:, slots]), placed[0])
    extents = [kernel(shapes.kind_code, shapes.half, placed[0][0])
               for kernel in (collision.half_extents, collision.half_extents.py_func)]
    same(extents[0], extents[1])
    lower, upper = shapes.bounds(*placed[0], every)
    assert (upper > lower).all()
    # The narrow phase poses shapes by quaternion: each branch of the conversion is taken
    # (the placed rotations, and half turns about each axis).
    rotation = np.concatenate([placed[0][0].reshape(1, -1, 3, 3), np.array(
        [[np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]])],
        axis=1)
    quaternions = collision._quaternions(rotation)
    same(quaternions, collision._quaternions.py_func(rotation))
    for r, q in zip(rotation[0], quaternions[0]):
        assert tuple(q) == collision._quaternion(r.ravel().tolist())


def _rotation(rng) -> np.ndarray:
    """Make a random rotation matrix."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_the_separating_axis_tests():
    """Oriented boxes against boxes and triangles, parallel edges included, compiled and not."""
    rng = np.random.default_rng(9)
    count = 400
    rotation_a = np.array([_rotation(rng) for _ in range(count)])
    rotation_b = np.array([_rotation(rng) if i % 4 else rotation_a[i] for i in range(count)])
    centre_a, centre_b = np.zeros((count, 3)), rng.uniform(-0.6, 0.6, (count, 3))
    half_a, half_b = rng.uniform(0.02, 0.3, (count, 3)), rng.uniform(0.02, 0.3, (count, 3))
    apart = []
    for i in range(count):
        box = (rotation_a[i], centre_a[i], half_a[i], rotation_b[i], centre_b[i], half_b[i],
               1e-3)
        apart.append(convex.boxes_apart(*box))
        assert apart[-1] == convex.boxes_apart.py_func(*box)
    assert 0 < sum(apart) < count
    corners = rng.uniform(-0.6, 0.6, (count, 3, 3))
    apart = []
    for i in range(count):
        box = (rotation_a[i], centre_a[i], half_a[i], corners[i], 1e-3)
        apart.append(convex.box_triangle_apart(*box))
        assert apart[-1] == convex.box_triangle_apart.py_func(*box)
    assert 0 < sum(apart) < count


def test_the_contacts_of_a_branch_batch():
    """
    The contacts of a branch batch, compiled, as Python and by FCL.

    Per row, whether a shape touches a triangle or its pair's other shape: compiled, as Python,
    with and without the cut by the swept boxes, and by FCL on every pair.
    """
    import fcl
    rng = np.random.default_rng(10)
    m, n, k, pairs = 40, 4, 30, 6
    kinds = np.array([0, 1, 2, 1])
    shape_half = np.array([[0.03, 0.02, 0.05], [0.02, 0.06, 0.0], [0.03, 0.0, 0.0],
                           [0.015, 0.04, 0.0]])
    box_half = np.array([h if kind == 0 else (h[0], h[0], h[1]) if kind == 1
                         else (h[0], h[0], h[0]) for kind, h in zip(kinds, shape_half)])
    centre = rng.uniform(0.0, 0.6, (m, n, 3))
    rotation = np.array([[_rotation(rng) for _ in range(n)] for _ in range(m)])
    extent = np.abs(rotation) @ box_half[:, :, None]
    low, high = centre - extent[..., 0], centre + extent[..., 0]
    corners = rng.uniform(0.0, 0.6, (60, 1, 3)) + rng.uniform(-0.05, 0.05, (60, 3, 3))
    triangle_lower, triangle_upper = corners.min(axis=1), corners.max(axis=1)
    frames = rng.integers(0, k, m)
    pair_column = rng.integers(0, n, pairs)
    pair_kinds = np.array([0, 1, 2, 0, 1, 2])
    pair_shape_half = np.array([[0.02, 0.03, 0.04], [0.03, 0.05, 0.0], [0.04, 0.0, 0.0],
                                [0.05, 0.01, 0.02], [0.02, 0.08, 0.0], [0.02, 0.0, 0.0]])
    pair_half = np.array([h if kind == 0 else (h[0], h[0], h[1]) if kind == 1
                          else (h[0], h[0], h[0]) for kind, h in zip(pair_kinds,
                                                                     pair_shape_half)])
    # The other shapes near the branch's, so that many meet (body shapes 2 + p of 2 + P: the
    # kernel reads the pairs' other shapes where the body holds them).
    pair_other = np.arange(2, 2 + pairs)
    pair_centre = (centre[rng.integers(0, m, (k, pairs)), pair_column]
                   + rng.normal(0.0, 0.06, (k, pairs, 3)))
    pair_rotation = np.array([[_rotation(rng) for _ in range(pairs)] for _ in range(k)])
    pair_extent = (np.abs(pair_rotation) @ pair_half[:, :, None])[..., 0]
    pair_lower, pair_upper = pair_centre - pair_extent, pair_centre + pair_extent
    body = [np.concatenate([rng.normal(size=(k, 2) + a.shape[2:]), a], axis=1)
            for a in (pair_lower, pair_upper, pair_rotation, pair_centre)]

    def fcl_object(kind, half, r, c):
        geometry = (fcl.Box(*(2 * half)) if kind == 0 else fcl.Cylinder(half[0], 2 * half[1])
                    if kind == 1 else fcl.Sphere(half[0]))
        return fcl.CollisionObject(geometry, fcl.Transform(r, c))

    triangles = []
    for corner in corners:
        model = fcl.BVHModel()
        model.beginModel(3, 1)
        model.addSubModel(corner, np.array([[0, 1, 2]]))
        model.endModel()
        triangles.append(fcl.CollisionObject(model, fcl.Transform()))
    expected = np.zeros(m, dtype=bool)
    for r in range(m):
        for c in range(n):
            shape = fcl_object(kinds[c], shape_half[c], rotation[r, c], centre[r, c])
            targets = triangles + [
                fcl_object(pair_kinds[p], pair_shape_half[p], pair_rotation[frames[r], p],
                           pair_centre[frames[r], p]) for p in range(pairs)
                if pair_column[p] == c]
            expected[r] |= any(fcl.collide(shape, target, fcl.CollisionRequest(),
                                           fcl.CollisionResult()) for target in targets)
    assert 0.2 < expected.mean() < 0.8
    for swept in (True, False):
        arguments = (low, high, triangle_lower, triangle_upper, swept, frames, pair_column,
                     body[0], body[1], rotation, centre, box_half, corners, body[2], body[3],
                     pair_half, 1e-3, kinds, shape_half, pair_kinds, pair_shape_half,
                     pair_other)
        found = ct_space._row_collisions(*arguments, np.zeros(m, dtype=bool))
        same(found, ct_space._row_collisions.py_func(*arguments, np.zeros(m, dtype=bool)))
        same(found, expected)
        # Rows known to touch nothing are reported so, untested; the others as before.
        skip = np.arange(m) % 3 == 0
        found = ct_space._row_collisions(*arguments, skip)
        same(found, ct_space._row_collisions.py_func(*arguments, skip))
        same(found, expected & ~skip)


def test_the_leg_triangle():
    """Ankles within reach, beyond it and at the hip itself."""
    rng = np.random.default_rng(5)
    forward = rng.uniform(-1.0, 1.0, 500)
    down = rng.uniform(-0.2, 1.2, 500)
    forward[:3] = down[:3] = 0.0
    same(gait._leg_triangle(forward, down, 0.45, 0.43),
         gait._leg_triangle.py_func(forward, down, 0.45, 0.43))


def test_the_leg_in_its_plane(skeleton):
    """
    The leg in its plane, compiled and as Python, to the last bit.

    The in-plane leg solution, compiled and as Python, to the last bit, for a sole pitch per frame
    and one for all; and against the same formulas in NumPy (arccos, arctan2), to 1e-12 rad (the
    same bits where NumPy calls the C library, as on the development machine).
    """
    rng = np.random.default_rng(6)
    leg = skeleton.leg
    forward = rng.uniform(-0.6, 0.6, 300)
    down = rng.uniform(-0.1, 1.0, 300)
    forward[:2] = down[:2] = 0.0
    for pitch in (rng.uniform(-0.4, 0.4, 300), np.float64(0.1), 0.0):
        wide = np.asarray(pitch, dtype=float).reshape(-1)
        step = int(np.ndim(pitch) > 0)
        compiled, plain = np.zeros((300, 4)), np.zeros((300, 4))
        reach = gait._sagittal_joints(forward, down, wide, step, leg.thigh, leg.shank, compiled)
        same((reach, compiled), (gait._sagittal_joints.py_func(
            forward, down, wide, step, leg.thigh, leg.shank, plain), plain))
        through = np.zeros((300, 4))
        same(gait._sagittal_leg(leg, forward, down, pitch, through), reach)
        same(through, compiled)
        _, cos_knee, cos_beta = gait._leg_triangle(forward, down, leg.thigh, leg.shank)
        knee = np.pi - np.arccos(cos_knee)
        hip_pitch = np.arctan2(forward, down) + np.arccos(cos_beta)
        np.testing.assert_allclose(compiled[:, 1], hip_pitch, rtol=0, atol=1e-12)
        np.testing.assert_allclose(compiled[:, 2], knee, rtol=0, atol=1e-12)
        np.testing.assert_allclose(compiled[:, 3], pitch - (hip_pitch - knee), rtol=0,
                                   atol=1e-12)


def test_the_gait_checks_and_the_sole_points():
    """
    The gait checks and the sole points, compiled and as Python.

    The feet's separating-axis test and the leg's limits (both outcomes), and the points and
    heights under a swinging sole.
    """
    rng = np.random.default_rng(7)
    met, violations = set(), set()
    for trial in range(200):
        k = 30
        swing_xy = rng.uniform(-0.4, 0.4, (k, 2))
        heading = rng.uniform(-np.pi, np.pi, k)
        direction = np.stack([np.cos(heading), np.sin(heading)], axis=1)
        swing_z = rng.uniform(0.0, 0.2, k)
        arguments = (swing_xy, direction, swing_z, 0.0, 0.0, 0.1, 1.0, 0.0, 0.05, 0.13,
                     0.05, 4.0 * (0.13 ** 2 + 0.05 ** 2))
        meet = gait._feet_meet(*arguments)
        assert meet == gait._feet_meet.py_func(*arguments)
        met.add(meet)
        joints = rng.uniform(-1.2, 1.2, (k, 4)) * (1.0 if trial % 3 else 0.9)
        reach = rng.uniform(0.5, 1.0, k)
        if trial % 7 == 0:
            reach[5] = 1.01
        low, high = np.full(4, -1.19), np.full(4, 1.19)
        found = gait._leg_violation(joints, reach, low, high)
        assert found == gait._leg_violation.py_func(joints, reach, low, high)
        violations.add(found[0] if found[0] < 0 else 'joint')
    assert met == {True, False} and violations == {-2, -1, 'joint'}
    samples = np.arange(0, 30, 3)
    along, across = np.linspace(-0.07, 0.18, 9), np.array([-0.04, 0.04])
    arguments = (swing_xy, direction, samples, along, across)
    points = gait._sole_points(*arguments)
    same(points, gait._sole_points.py_func(*arguments))
    assert points.shape == (samples.size * 9 * 2, 2)
    heights = rng.uniform(0.0, 0.3, points.shape[0])
    heights[::7] = np.nan
    same(gait._across_sole(heights, 9, 2), gait._across_sole.py_func(heights, 9, 2))


def test_the_swing_height_kernels():
    rng = np.random.default_rng(4)
    outcomes = set()
    for trial in range(50):
        count = int(rng.integers(3, 30))
        b = np.sort(rng.uniform(0.0, 1.0, count))
        basis = ((1 - b) ** 3, 3 * b * (1 - b) ** 2, 3 * b * b * (1 - b), b ** 3)
        # Ground well below the sole at lift-off and touchdown, up to 0.6 m high between.
        hump = np.sin(np.pi * b)[:, None] ** 2 * rng.uniform(0.0, 0.6)
        tops = -0.12 + hump * rng.uniform(0.5, 1.0, (count, 9))
        tops[rng.random(tops.shape) < 0.2] = -np.inf
        along = np.linspace(-0.07, 0.18, 9)
        pitch = rng.uniform(-0.5, 0.5, count)
        clearance = rng.uniform(0.0, 0.03, count)
        arguments = (tops, along, np.sin(pitch), np.cos(pitch), 0.08, clearance)
        need = gait._swing_need(*arguments)
        same(need, gait._swing_need.py_func(*arguments))
        slack = rng.uniform(0.0, 0.015, count)
        arguments = (*basis, b, need, slack, 0.0, float(rng.uniform(-0.2, 0.2)), 0.05, 0.05, 0.6)
        raised = gait._raise_swing(*arguments)
        same(raised, gait._raise_swing.py_func(*arguments))
        outcomes.add((raised[2], raised[:2] == (0.05, 0.05)))
    # Cleared at once, cleared after raising the curve, and not cleared under the cap.
    assert outcomes == {(True, True), (True, False), (False, False)}


def test_without_numba_the_actor_walks_the_same_frames(tmp_path):
    """
    Without numba the actor walks the same frames.

    The kernels' fallback: in a process where numba cannot be imported every kernel runs as Python,
    and the actor climbs the stairs (lower body) and passes the table, flexing an arm (whole body),
    with the same frames to the last bit.
    """
    from course_runs import simulate
    courses = (('stairs_up', False), ('table', True))
    code = '\n'.join([
        'import sys',
        'sys.modules["numba"] = None',
        f'sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r})',
        'import numpy as np',
        'from digital_actor_planner.core import jit',
        'assert not jit.COMPILED',
        'from course_runs import simulate',
        f'for i, (name, upper) in enumerate({courses!r}):',
        '    np.save(f"{sys.argv[1]}/{i}.npy", simulate(name, upper_body=upper)[2])'])
    subprocess.run([sys.executable, '-c', code, str(tmp_path)], check=True, timeout=300)
    for i, (name, upper) in enumerate(courses):
        frames = simulate(name, upper_body=upper)[2]
        assert frames.shape[0] > 300
        np.testing.assert_array_equal(np.load(tmp_path / f'{i}.npy'), frames, err_msg=name)


def test_a_kernel_compiles_without_a_cache_when_numba_can_cache_it_nowhere(monkeypatch):
    """
    A kernel compiles without a cache when numba can cache it nowhere.

    numba refuses ``cache=True`` when neither the package nor the user's cache directory is
    writable: the kernel is then compiled for the process alone, not an import error.
    """
    from digital_actor_planner.core import jit
    real = jit.numba.njit

    def no_cache(*args, **kwargs):
        if kwargs.get('cache'):
            raise RuntimeError('cannot cache function: no locator available')
        return real(*args, **kwargs)

    monkeypatch.setattr(jit.numba, 'njit', no_cache)

    @jit.kernel('f8(f8[::1])')
    def total(values):
        out = 0.0
        for value in values:
            out += value
        return out

    assert total(np.arange(4.0)) == 6.0
    assert total.py_func is not total


def test_an_inline_kernel_is_compiled_into_the_kernels_that_call_it():
    """
    An inline kernel is compiled into the kernels that call it.

    ``kernel(..., inline=True)``: numba compiles it into its callers (no call between them); the
    same answers compiled and as Python.
    """
    from digital_actor_planner.core import jit

    @jit.kernel('f8(f8, f8)', inline=True)
    def weighted_square(weight, x):
        return weight * x * x

    @jit.kernel('f8(f8[::1])')
    def total(values):
        out = 0.0
        for value in values:
            out += weighted_square(0.5, value)
        return out

    assert total(np.arange(4.0)) == total.py_func(np.arange(4.0)) == 7.0
    assert weighted_square(2.0, 3.0) == 18.0
    if COMPILED:
        assert weighted_square.targetoptions['inline'] == 'always'
        assert total.targetoptions['inline'] == 'never'


def test_motion_patterns_kernel(skeleton):
    """
    The motion patterns kernel, compiled and as Python, against NumPy.

    The patterns' columns, compiled and as Python, against the pattern written in NumPy (each
    column of each arm, then np.clip's arithmetic over the upper body), to the last bit: strides
    past the tanh's knee, one frame, a Fortran array; and with limits narrow enough that the clip
    cuts every arm column (the skeleton's own never cut the pattern).
    """
    rng = np.random.default_rng(5)
    index = skeleton.index
    upper = np.concatenate([skeleton.branch(name)
                            for name in ('waist', 'left_arm', 'right_arm')])
    waist, arms, _, _, lower, upper_limit = upper_body._pattern_layout(skeleton)
    narrow_lower, narrow_upper = lower.copy(), upper_limit.copy()
    narrow_lower[arms] = [-0.1, 0.08, 0.01, 0.3] * 2
    narrow_upper[arms] = [0.1, 0.5, 0.5, 0.28] * 2
    for k, spread in ((1, 0.3), (61, 0.3), (127, 3.0)):
        frames = rng.uniform(-spread, spread, (k, 22))
        for amplitude in (0.0, 0.35, 1.0):
            stride = 0.5 * (frames[:, index['right_hip_pitch']]
                            - frames[:, index['left_hip_pitch']])
            swing = amplitude * np.tanh(stride / upper_body.NOMINAL_HIP_SWING)
            for low, high in ((lower, upper_limit), (narrow_lower, narrow_upper)):
                expected = frames.copy()
                expected[:, waist] = 0.0
                for side, sign in (('left', 1.0), ('right', -1.0)):
                    pitch = sign * swing
                    expected[:, index[f'{side}_shoulder_pitch']] = pitch
                    expected[:, index[f'{side}_shoulder_roll']] = upper_body.ARM_CLEARANCE_ROLL
                    expected[:, index[f'{side}_shoulder_yaw']] = 0.0
                    expected[:, index[f'{side}_elbow']] = (
                        upper_body.RELAXED_ELBOW + upper_body.ELBOW_SWING_GAIN * pitch)
                expected[:, upper] = np.minimum(np.maximum(expected[:, upper], low[upper]),
                                                high[upper])
                for run in (upper_body._write_patterns, upper_body._write_patterns.py_func):
                    got = frames.copy()
                    run(got, swing, waist, arms, low, high)
                    assert got.tobytes() == expected.tobytes()
                if low is lower:
                    got = upper_body.motion_patterns(skeleton, np.asfortranarray(frames),
                                                     amplitude)
                    assert got.tobytes() == expected.tobytes()
                elif amplitude == 1.0 and k > 1:
                    # The narrow limits did cut: every arm column sits on a bound somewhere.
                    for j in arms:
                        assert np.isin(expected[:, j], (low[j], high[j])).any()


def _swing_plane_in_numpy(progress, plane_turn, pinned, release, take, swing_hip, yaw, foot_x,
                          foot_y, foot_yaw, turn, landing_x, landing_y, turning, inward,
                          stance_yaw, toe_in, low, high, lift_pitch, landing_pitch):
    """
    Compute the swing foot's plane as WalkGenerator.step does in NumPy.

    The swing foot's plane as WalkGenerator.step computes it in NumPy (the reference of
    gait._swing_plane); also says which corrections applied.
    """
    wrap = gait._wrap
    foot_xy, landing_xy = np.array([foot_x, foot_y]), np.array([landing_x, landing_y])
    plane_yaw = foot_yaw + turn * plane_turn
    wanted_xy = foot_xy + progress[:, None] * (landing_xy - foot_xy)
    direction = np.empty((len(yaw), 2))
    direction[:, 0] = np.cos(plane_yaw)
    direction[:, 1] = np.sin(plane_yaw)
    applied = set()
    if turning:
        toward = wanted_xy - swing_hip
        length = np.hypot(toward[:, 0], toward[:, 1])
        sign = np.where(toward[:, 0] * direction[:, 0] + toward[:, 1] * direction[:, 1] < 0,
                        -1.0, 1.0)
        through = toward * (sign / np.maximum(length, 1e-9))[:, None]
        weight = pinned * np.minimum(np.maximum((length - 0.15) / 0.1, 0.0), 1.0)
        direction = direction + weight[:, None] * (through - direction)
        direction /= np.hypot(direction[:, 0], direction[:, 1])[:, None]
        plane_yaw = np.arctan2(direction[:, 1], direction[:, 0])
        excess = inward * wrap(plane_yaw - stance_yaw) - toe_in
        if excess.max() > 0.0:
            applied.add('toe in')
            plane_yaw = plane_yaw - inward * np.maximum(excess, 0.0) * (1.0 - pinned)
            direction[:, 0] = np.cos(plane_yaw)
            direction[:, 1] = np.sin(plane_yaw)
        hip_yaw = wrap(plane_yaw - yaw)
        if hip_yaw.min() < low or hip_yaw.max() > high:
            applied.add('hip range')
            plane_yaw = yaw + hip_yaw + ((np.clip(hip_yaw, low, high) - hip_yaw)
                                         * (1.0 - pinned))
            direction[:, 0] = np.cos(plane_yaw)
            direction[:, 1] = np.sin(plane_yaw)
    reach_xy = wanted_xy - swing_hip
    forward = reach_xy[:, 0] * direction[:, 0] + reach_xy[:, 1] * direction[:, 1]
    swing_xy = swing_hip + forward[:, None] * direction
    pitch = lift_pitch * release + landing_pitch * take
    return (plane_yaw, direction, forward, swing_xy, pitch), applied


def test_the_pelvis_track_and_the_swing_plane():
    """
    The pelvis track and the swing foot's plane, compiled and as Python.

    The pelvis and the swing foot's plane over a step, compiled and as Python to the last bit, and
    against the NumPy code they replace (see near): straight steps and turns, with and without the
    toe-in bound and the hip yaw range cutting in, and the angle wrap at exact multiples.
    """
    rng = np.random.default_rng(12)
    k = 64
    ramp = np.linspace(1.0 / k, 1.0, k)
    for angle in (-3 * np.pi, -np.pi, 0.0, np.pi, 2 * np.pi, -0.0, 7.5, -7.5):
        assert gait._wrapped(angle) == gait._wrapped.py_func(angle) == gait._wrap(angle)
    applied = []
    for trial in range(60):
        turn_rate = rng.uniform(-0.9, 0.9) * (trial % 3 > 0)
        yaw0 = rng.uniform(-np.pi, np.pi)
        yaw1 = yaw0 + turn_rate
        args = (np.clip(ramp * 1.3 - 0.15, 0.0, 1.0), ramp ** 2, yaw0, yaw1,
                rng.uniform(-0.3, 0.0), rng.uniform(0.2, 0.5), rng.uniform(-2, 2),
                rng.uniform(-2, 2), np.cos(yaw0), np.sin(yaw0), 0.1, -0.1)
        track = gait._pelvis_track(*args)
        same(track, gait._pelvis_track.py_func(*args))
        yaw, lam = args[2] + (args[3] - args[2]) * args[0], args[4] + (args[5] - args[4]) * args[1]
        hip = np.array([args[6], args[7]]) + lam[:, None] * np.array([args[8], args[9]])
        pelvis = np.stack([hip[:, 0] - -np.sin(yaw) * 0.1, hip[:, 1] - np.cos(yaw) * 0.1], axis=1)
        swing_hip = np.stack([pelvis[:, 0] + -np.sin(yaw) * -0.1,
                              pelvis[:, 1] + np.cos(yaw) * -0.1], axis=1)
        near(track, (yaw, lam, hip, pelvis, swing_hip))
        pinned = np.clip(1.0 - 4.0 * np.minimum(ramp, 1.0 - ramp), 0.0, 1.0)
        inward = 1.0 if trial % 2 else -1.0
        plane = (np.clip(ramp * 1.2 - 0.1, 0.0, 1.0), ramp ** 1.5, pinned, 1.0 - ramp, ramp,
                 swing_hip, yaw, float(swing_hip[0, 0] - 0.2), float(swing_hip[0, 1]),
                 yaw0 + rng.uniform(-0.5, 0.5), float(gait._wrap(turn_rate * 1.5)),
                 float(swing_hip[-1, 0] + 0.3), float(swing_hip[-1, 1] + rng.uniform(-0.1, 0.1)),
                 turn_rate != 0.0, inward, yaw0 + rng.uniform(-0.6, 0.6),
                 rng.uniform(0.05, 0.3), -rng.uniform(0.1, 0.5), rng.uniform(0.1, 0.6),
                 rng.uniform(-0.3, 0.0), rng.uniform(-0.1, 0.1))
        expected, used = _swing_plane_in_numpy(*plane)
        compiled = gait._swing_plane(*plane)
        same(compiled, gait._swing_plane.py_func(*plane))
        near(compiled, expected)
        applied.append(used)
    # Every branch of the turn was taken somewhere, and straight steps skipped it.
    assert any('toe in' in used for used in applied)
    assert any('hip range' in used for used in applied)
    assert any(not used for used in applied)


def test_the_swing_passes(skeleton):
    """
    The swing passes, compiled and as Python, against NumPy.

    The swing's shared bounds and one swing pass, compiled and as Python, against the NumPy code
    they replace, to the last bit: with and without the pelvis raised over the swing, passes that
    converge and that do not, and a hip out of reach.
    """
    rng = np.random.default_rng(13)
    leg = skeleton.leg
    k = 64
    ramp = np.linspace(1.0 / k, 1.0, k)
    hump = np.sin(np.pi * ramp) ** 2
    fade = 1.0 - ramp ** 3
    r = 0.97 * (leg.thigh + leg.shank)
    closest = 0.25
    seen = set()
    for trial in range(60):
        lam = np.linspace(-0.3, 0.3, k) * rng.uniform(0.5, 3.0 if trial % 10 == 0 else 1.2)
        forward = np.linspace(-0.35, 0.4, k) * rng.uniform(0.5, 1.2)
        swing_hip = rng.normal(0.0, 1.0, (k, 2))
        yaw = rng.uniform(-np.pi, np.pi) + 0.2 * ramp
        plane_yaw = yaw + rng.uniform(-0.4, 0.4)
        direction = np.stack([np.cos(plane_yaw), np.sin(plane_yaw)], axis=1)
        swing_xy = swing_hip + forward[:, None] * direction + rng.normal(0, 0.01, (k, 2))
        weight = np.clip(ramp * 1.5 - 0.2, 0.0, 1.0)
        z0, nominal, stance_z = 0.9, rng.uniform(0.8, 1.0), rng.uniform(-0.05, 0.05)
        args = (lam, forward, swing_xy, swing_hip, direction, plane_yaw, yaw, weight, z0,
                nominal, r, stance_z, closest)
        bounds = gait._swing_bounds(*args)
        same(bounds, gait._swing_bounds.py_func(*args))
        stance_bound = stance_z + np.sqrt(np.maximum(r * r - lam * lam, 0.0))
        swing_x = swing_xy[:, 0] - swing_hip[:, 0]
        swing_y = swing_xy[:, 1] - swing_hip[:, 1]
        swing_forward = swing_x * direction[:, 0] + swing_y * direction[:, 1]
        expected = ((np.abs(lam) > r).any() or (np.abs(forward) > r).any(), stance_bound,
                    np.minimum(z0 + (nominal - z0) * weight, stance_bound),
                    np.sqrt(np.maximum(r * r - forward * forward, 0.0)), swing_forward,
                    gait._wrap(plane_yaw - yaw),
                    np.sqrt(np.maximum(closest * closest - swing_forward * swing_forward, 0.0)),
                    float(swing_x[-1]) * -direction[-1, 1] + float(swing_y[-1]) * direction[-1, 0])
        same(bounds, expected)
        seen.add('out of reach' if bounds[0] else 'in reach')
        _, stance_bound, z_bound, swing_reach, swing_forward, hip_yaw, hip_over_ankle, _ = bounds
        swing_z = rng.uniform(0.05, 0.15) + rng.uniform(0.0, 0.25) * hump
        swing_pitch = rng.uniform(-0.6, 0.6) * np.ones(k)
        low, high = -0.7, 0.6
        args = (swing_z, z_bound, swing_reach, hip_over_ankle, hump, stance_bound, hip_yaw,
                swing_forward, swing_pitch, fade, low, high, leg.thigh, leg.shank)
        result = gait._swing_pass(*args)
        same(result, gait._swing_pass.py_func(*args))
        z = np.minimum(z_bound, swing_z + swing_reach)
        short = swing_z + hip_over_ankle - z
        if short.max() > 0.0:
            seen.add('raised')
            scale = float((short / np.maximum(hump, 1e-3)).max())
            z = np.minimum(z + scale * hump, np.maximum(z, stance_bound))
        joints = np.empty((k, 4))
        joints[:, 0] = hip_yaw
        reach = gait._sagittal_leg(leg, swing_forward, -(swing_z - z), swing_pitch, joints)
        correction = (np.minimum(np.maximum(joints[:, 3], low), high) - joints[:, 3]) * fade
        converged = bool(np.abs(correction).max() < 0.005)
        seen.add('converged' if converged else 'corrected')
        same(result, (z, joints, reach, converged, swing_pitch + correction))
    assert seen == {'out of reach', 'in reach', 'raised', 'converged', 'corrected'}


def test_the_stance_leg_and_the_ankle_fade(skeleton):
    """
    The stance leg and the ankle fade, compiled and as Python, against NumPy.

    The stance leg over a step and the swinging ankle's fade into its range, compiled and as
    Python, against the NumPy code they replace, to the last bit; a heel-off is flagged where the
    ankle passes its limit, and only there.
    """
    rng = np.random.default_rng(14)
    leg = skeleton.leg
    k = 64
    ramp = np.linspace(1.0 / k, 1.0, k)
    flagged = set()
    for trial in range(40):
        foot_yaw = rng.uniform(-np.pi, np.pi)
        cos_s, sin_s = np.cos(foot_yaw), np.sin(foot_yaw)
        foot = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2)])
        lam = -0.25 + 0.6 * ramp * rng.uniform(0.8, 1.2)
        hip = foot + lam[:, None] * np.array([cos_s, sin_s]) + rng.normal(0, 0.01, (k, 2))
        yaw = foot_yaw + rng.uniform(-0.3, 0.3) * ramp
        foot_z, pitch = rng.uniform(0.0, 0.3), rng.uniform(-0.2, 0.2)
        z = foot_z + 0.8 + 0.03 * np.sin(np.pi * ramp)
        limit = rng.uniform(0.2, 0.6)
        args = (hip, yaw, z, foot[0], foot[1], foot_yaw, foot_z, pitch, cos_s, sin_s,
                leg.thigh, leg.shank, limit)
        result = gait._stance_leg(*args)
        same(result, gait._stance_leg.py_func(*args))
        stance_x, stance_y = foot[0] - hip[:, 0], foot[1] - hip[:, 1]
        joints = np.empty((k, 4))
        joints[:, 0] = gait._wrap(foot_yaw - yaw)
        reach = gait._sagittal_leg(leg, stance_x * cos_s + stance_y * sin_s, -(foot_z - z),
                                   pitch, joints)
        lateral = float(stance_x[-1]) * -sin_s + float(stance_y[-1]) * cos_s
        over = bool((joints[:, 3] > limit).any())
        same(result, (joints, reach, lateral, over))
        flagged.add(over)
        fade = 1.0 - ramp ** 2
        low, high = -0.2, 0.1
        compiled, plain = joints.copy(), joints.copy()
        gait._fade_ankle(compiled, low, high, fade)
        gait._fade_ankle.py_func(plain, low, high, fade)
        wanted = np.minimum(np.maximum(joints[:, 3], low), high)
        joints[:, 3] += (wanted - joints[:, 3]) * fade
        same((compiled, plain), (joints, joints))
    assert flagged == {True, False}


def test_points_beside_the_path():
    """
    Points beside the path, compiled and as Python, against NumPy.

    Points beside a predicted path, compiled and as Python to the last bit, and against the NumPy
    code they replace (the centre line and the offset along the normal; see near): straight and
    curved paths, arc lengths past both ends, one offset for all points, one per point, and one per
    track.
    """
    rng = np.random.default_rng(15)
    for curvature in (0.0, 1e-10, 0.8, -2.5):
        path = path_module.PredictedPath(rng.uniform(-3, 3), rng.uniform(-3, 3),
                                         rng.uniform(-np.pi, np.pi), curvature, 2.0)
        s = rng.uniform(-0.5, 2.5, 40)
        # The same arithmetic in NumPy: the centre line, then the offset along the normal.
        heading = path.heading + path.curvature * s
        sin, cos = np.sin(heading), np.cos(heading)
        if abs(path.curvature) < 1e-9:
            x = path.x + s * np.cos(path.heading)
            y = path.y + s * np.sin(path.heading)
        else:
            x = path.x + (sin - np.sin(path.heading)) / path.curvature
            y = path.y - (cos - np.cos(path.heading)) / path.curvature
        for lateral in (np.float64(0.0), np.float64(0.09), rng.uniform(-0.1, 0.1, 40)):
            expected = np.stack([x - lateral * sin, y + lateral * cos, heading], axis=1)
            near(path.offset_poses(s, lateral), expected)
            paired = np.asarray(lateral).reshape(-1).copy()
            args = (s, paired, True, path.x, path.y, path.heading, path.curvature)
            same(path_module._arc_offsets(*args), path_module._arc_offsets.py_func(*args))
            near(path_module._arc_offsets(*args)[0], expected)
        tracks = rng.uniform(-0.2, 0.2, 6)[:, None]
        expected = np.stack([x - tracks * sin, y + tracks * cos], axis=-1)
        near(path.offset_points(s, tracks), expected)
        args = (s, tracks.ravel().copy(), False, path.x, path.y, path.heading, path.curvature)
        same(path_module._arc_offsets(*args), path_module._arc_offsets.py_func(*args))
        near(path_module._arc_offsets(*args)[:, :, :2], expected)
        # Other shapes broadcast as NumPy would.
        near(path.offset_points(s, 0.05), np.stack([x - 0.05 * sin, y + 0.05 * cos], axis=-1))
        grid = path.offset_poses(s[:4, None] * np.ones((4, 3)), np.array([0.0, 0.1, -0.1]))
        assert grid.shape == (4, 3, 3)
        near(grid[:, 1], path.offset_poses(s[:4], 0.1))
        assert path.offset_points(s, np.array([[0.05]])).shape == (1, 40, 2)
        assert path.offset_poses(s[:0], 0.1).shape == (0, 3)


def _heel_off_in_numpy(leg, hip, foot, pelvis_yaw, joints, limit, toe):
    """WalkGenerator._heel_off written in NumPy (the reference of gait._rolled_stance)."""
    direction = np.array([np.cos(foot.yaw), np.sin(foot.yaw)])
    p0 = foot.pitch
    toe_xy = foot.xy + (toe * np.cos(p0) + leg.ankle_height * np.sin(p0)) * direction
    toe_z = foot.z + toe * np.sin(p0) - leg.ankle_height * np.cos(p0)
    over = joints[:, 3] > limit
    shank = joints[over, 1] - joints[over, 2]
    plane = np.full(int(np.count_nonzero(over)), foot.yaw)
    for _ in range(5):
        p = np.minimum(limit + shank, p0)
        ankle = np.column_stack([
            toe_xy - (toe * np.cos(p) + leg.ankle_height * np.sin(p))[:, None] * direction,
            toe_z - (toe * np.sin(p) - leg.ankle_height * np.cos(p))])
        solved, _, _ = gait.leg_inverse_kinematics(leg, hip[over], ankle, plane,
                                                   pelvis_yaw[over], p)
        shank = solved[:, 1] - solved[:, 2]
    joints = joints.copy()
    joints[over] = solved
    return joints, ankle[-1], float(p[-1])


def test_the_heel_off_roll(skeleton):
    """
    The heel-off roll, compiled and as Python, against NumPy.

    A stance foot rolling about its toe where its ankle would pass its limit, compiled and as
    Python to the last bit, and against the NumPy code it replaces (see near): joints, the last
    rolled frame's ankle and pitch, with the roll reaching the last frame and not.
    """
    rng = np.random.default_rng(16)
    leg = skeleton.leg
    k = 64
    ramp = np.linspace(1.0 / k, 1.0, k)
    for trial in range(20):
        yaw = rng.uniform(-np.pi, np.pi)
        foot = gait.FootPose(np.array([rng.uniform(-1, 1), rng.uniform(-1, 1)]),
                             rng.uniform(0.05, 0.3), float(yaw), float(rng.uniform(-0.1, 0.1)),
                             0.0)
        pelvis_yaw = yaw + rng.uniform(-0.2, 0.2) * ramp
        lam = -0.1 + 0.5 * ramp
        hip = np.column_stack([foot.xy[0] + lam * np.cos(yaw), foot.xy[1] + lam * np.sin(yaw),
                               foot.z + 0.8 - 0.05 * ramp])
        joints = np.empty((k, 4))
        joints[:, 0] = gait._wrap(foot.yaw - pelvis_yaw)
        v = np.array([foot.xy[0], foot.xy[1], foot.z]) - hip
        gait._sagittal_leg(leg, v[:, 0] * np.cos(yaw) + v[:, 1] * np.sin(yaw), -v[:, 2],
                           foot.pitch, joints)
        # The ankle rises over the step; the limit cuts it from some frame on (or mid-way).
        limit = float(np.quantile(joints[:, 3], rng.uniform(0.5, 0.9)))
        if trial % 4 == 0:
            joints[-5:, 3] = limit - 0.01
        toe = leg.toe
        expected = _heel_off_in_numpy(leg, hip, foot, pelvis_yaw, joints, limit, toe)
        over = np.flatnonzero(joints[:, 3] > limit)
        args = (hip, pelvis_yaw, joints, over, limit, foot.pitch, foot.yaw,
                float(np.cos(foot.yaw)), float(np.sin(foot.yaw)),
                *(foot.xy + (toe * np.cos(foot.pitch) + leg.ankle_height * np.sin(foot.pitch))
                  * np.array([np.cos(foot.yaw), np.sin(foot.yaw)])).tolist(),
                foot.z + toe * np.sin(foot.pitch) - leg.ankle_height * np.cos(foot.pitch),
                toe, leg.ankle_height, leg.thigh, leg.shank)
        compiled = gait._rolled_stance(*args)
        same(compiled, gait._rolled_stance.py_func(*args))
        near(compiled, expected)
        rolled, end = gait.WalkGenerator._heel_off(leg, hip, foot, pelvis_yaw, joints, limit,
                                                   toe)
        same(rolled, compiled[0])
        if over[-1] == k - 1:
            same((end.xy, end.z, end.pitch), (compiled[1][:2], compiled[1][2], compiled[2]))
        else:
            assert end is foot
