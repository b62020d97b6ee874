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

"""BodyCollision: the URDF's collision shapes against meshes and against each other."""
import time

from digital_actor_planner.core.actor import start_configuration
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.environment import Environment
import numpy as np
import pytest
from scene_helpers import box


@pytest.fixture(scope='module')
def floor_world():
    return Environment([box((-3, -3, -0.2), (3, 3, 0.0))])


@pytest.fixture(scope='module')
def body(skeleton, floor_world):
    return BodyCollision(skeleton, floor_world)


@pytest.fixture(scope='module')
def standing(skeleton, floor_world):
    """Neutral stance with the soles 2 mm above the floor."""
    return start_configuration(floor_world, (0.0, 0.0, 0.3), skeleton)


def test_shapes_are_placed_by_the_skeletons_kinematics(skeleton, body):
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.uniform(np.maximum(skeleton.lower, -4), np.minimum(skeleton.upper, 4))
        expected = skeleton.shape_transforms(skeleton.forward_kinematics(q))
        poses = body.shape_poses(q)
        for (rotation, position), transform in zip(poses, expected):
            np.testing.assert_allclose(rotation, transform[:3, :3], atol=1e-12)
            np.testing.assert_allclose(position, transform[:3, 3], atol=1e-12)


def test_standing_actor_is_free_and_sunk_feet_report_their_depth(skeleton, body, standing):
    assert not body.collides(standing)
    assert body.links_in_collision(standing) == []
    assert all(depth == 0.0 for depth in body.penetration(standing).values())
    for sink in (0.005, 0.05):
        q = standing.copy()
        q[skeleton.index['root_z']] -= 0.002 + sink
        assert body.collides(q)
        assert sorted(body.links_in_collision(q)) == ['left_foot', 'right_foot']
        depth = body.penetration(q)
        assert depth['left_foot'] == pytest.approx(sink, abs=0.001)
        assert depth['right_foot'] == pytest.approx(sink, abs=0.001)
        assert depth['head'] == 0.0 and depth['left_shank'] == 0.0


def test_penetration_at_a_step_edge_is_the_small_overlap(skeleton):
    """A foot overlapping a step's top edge by 1 mm is 1 mm deep, not a foot length."""
    step = box((0.0, -1, 0.0), (1.0, 1, 0.15))
    env = Environment([box((-2, -1, -0.1), (2, 1, 0.0)), step])
    body = BodyCollision(skeleton, env)
    q = start_configuration(env, (0.3, 0.0, 0.0), skeleton)      # standing on the step
    assert q[skeleton.index['root_z']] == pytest.approx(0.15 + skeleton.leg.standing_height
                                                        + 0.002)
    q[skeleton.index['root_x']] = -0.1                           # toes over the edge
    q[skeleton.index['root_z']] -= 0.003                         # soles 1 mm too low
    depth = body.penetration(q, ['left_foot', 'right_foot'])
    assert depth['left_foot'] == pytest.approx(0.001, abs=0.0005)
    # Walking into the riser at floor level: the toes are 30 mm into it.
    q = start_configuration(env, (-0.5, 0.0, 0.0), skeleton)
    q[skeleton.index['root_x']] = -0.15
    depth = body.penetration(q, ['right_foot'])
    assert depth['right_foot'] == pytest.approx(0.03, abs=0.001)


def test_distance_and_link_subsets(skeleton):
    beam = box((0.3, -1, 1.6), (0.5, 1, 1.8))                 # at head height
    env = Environment([box((-2, -1, -0.1), (2, 1, 0.0)), beam])
    body = BodyCollision(skeleton, env)
    q = start_configuration(env, (-0.5, 0.0, 0.0), skeleton)
    q[skeleton.index['root_z']] += 0.1
    distance = body.distance(q, ['left_foot', 'head'])
    assert distance['left_foot'] == pytest.approx(0.102, abs=1e-4)
    assert distance['head'] > 0.5
    q[skeleton.index['root_x']] = 0.4
    assert body.collides(q, ['head'])
    assert not body.collides(q, ['left_foot', 'right_foot', 'left_shank'])
    assert body.links_in_collision(q, ['pelvis', 'head']) == ['head']
    assert body.distance(q, ['head'])['head'] == 0.0


def test_padding_inflates_every_shape(skeleton, floor_world, standing):
    padded = BodyCollision(skeleton, floor_world, padding=0.01)
    assert padded.collides(standing, ['left_foot'])
    assert not BodyCollision(skeleton, floor_world, padding=0.001).collides(standing)


def test_self_collision_between_chosen_links(skeleton, body, standing):
    assert not body.self_collides(standing, ['left_foot'], ['right_foot'])
    assert not body.self_collides(standing, ['left_forearm', 'left_upper_arm'],
                                  ['torso', 'pelvis', 'left_thigh'])
    q = standing.copy()
    q[skeleton.index['left_hip_yaw']] = -0.25                  # toes turned in: feet overlap
    q[skeleton.index['right_hip_yaw']] = 0.25
    assert body.self_collides(q, ['left_foot'], ['right_foot'])
    assert not body.self_collides(q, ['left_foot'], ['head'])


def test_bad_input_is_rejected(skeleton, floor_world, body, standing):
    with pytest.raises(ValueError, match='padding'):
        BodyCollision(skeleton, floor_world, padding=-0.1)
    with pytest.raises(ValueError, match=r'shape \(22,\)'):
        body.collides(np.zeros(21))
    with pytest.raises(ValueError, match="unknown link 'elbow'"):
        body.collides(standing, ['elbow'])
    with pytest.raises(ValueError, match='string'):
        body.collides(standing, 'left_foot')


def test_collision_queries_are_fast_enough_for_planning_loops(skeleton, body, standing):
    rng = np.random.default_rng(1)
    configurations = standing + rng.normal(0.0, 0.01, (300, len(standing)))
    start = time.perf_counter()
    for q in configurations:
        body.collides(q, ['left_foot', 'left_shank', 'left_thigh'])
    per_call = (time.perf_counter() - start) / len(configurations)
    assert per_call < 0.005  # generous; bench/bench_environment.py measures it


def _reference_half_extents(body, shape, rotation):
    """World axis-aligned half extents of one shape from its own corners or its axis."""
    kind, half = body._half_extent[shape]
    if kind == 'box':
        corners = np.array(np.meshgrid(*[[-h, h] for h in half])).reshape(3, -1)
        return np.max(np.abs(rotation @ corners), axis=1)
    if kind == 'cylinder':
        axis = rotation[:, 2]
        return half[0] * np.sqrt(np.clip(1.0 - axis * axis, 0.0, 1.0)) + half[1] * np.abs(axis)
    return np.full(3, half[0])


def test_batched_half_extents_match_each_shape_alone(skeleton, body):
    rng = np.random.default_rng(5)
    shapes = list(range(len(body.shapes)))
    rng.shuffle(shapes)
    assert {body._half_extent[s][0] for s in shapes} == {'box', 'cylinder', 'sphere'}
    q = rng.uniform(np.maximum(skeleton.lower, -3), np.minimum(skeleton.upper, 3), (6, 22))
    rotations = skeleton.shape_transforms(skeleton.forward_kinematics(q),
                                          shapes=shapes)[..., :3, :3]
    extents = body._aabb_half_extents(shapes, rotations)
    for k in range(q.shape[0]):
        for column, shape in enumerate(shapes):
            np.testing.assert_allclose(
                extents[k, column], _reference_half_extents(body, shape, rotations[k, column]),
                atol=1e-12)


def test_first_collision_is_the_first_frame_any_link_touches(skeleton):
    """
    The batched check answers what testing every frame answers.

    The batched check with its broad phase and height bound answers what testing every frame
    answers, and what it answers without the height bound.
    """
    world = Environment([box((-3, -3, -0.2), (3, 3, 0.0)), box((0.25, -3, 0.0), (3, 3, 0.12)),
                         box((-3, 0.3, 0.0), (3, 3, 0.6))])
    body = BodyCollision(skeleton, world)
    plain = BodyCollision(skeleton, world, top_bound=False)
    legs = ['pelvis', 'left_hip', 'left_thigh', 'left_shank', 'left_foot', 'right_hip',
            'right_thigh', 'right_shank', 'right_foot']
    start = start_configuration(world, (0.0, 0.0, 0.0), skeleton)
    rng = np.random.default_rng(3)
    outcomes = set()
    for trial in range(40):
        goal = start.copy()
        goal[skeleton.index['root_x']] += rng.uniform(-0.2, 0.4)
        goal[skeleton.index['root_y']] += rng.uniform(-0.1, 0.25)
        goal[skeleton.index['root_z']] += rng.uniform(-0.08, 0.05)
        goal[skeleton.index['root_yaw']] += rng.uniform(-0.5, 0.5)
        for name in ('left_hip_pitch', 'right_hip_pitch', 'left_knee', 'right_knee',
                     'left_ankle', 'right_ankle', 'left_hip_yaw'):
            goal[skeleton.index[name]] += rng.uniform(-0.3, 0.3)
        frames = start + np.linspace(0.0, 1.0, 30)[:, None] * (goal - start)
        if trial % 4 == 0:
            frames[10:] = frames[10]  # a still tail: the unmoved shortcut must not hide a hit
        expected_frame, expected_links = -1, []
        for j, q in enumerate(frames):
            touching = body.links_in_collision(q, legs)
            if touching:
                expected_frame, expected_links = j, sorted(touching)
                break
        frame, links = body.first_collision(frames, legs)
        assert (frame, links) == (expected_frame, expected_links), trial
        assert plain.first_collision(frames, legs) == (frame, links), trial
        outcomes.add(frame >= 0)
    assert outcomes == {True, False}


def test_a_post_through_a_lifted_foot_is_found(skeleton):
    """
    A thin post through a lifted foot is found.

    A thin post (2-3 cm square, 1 m tall) through a foot lifted 3-8 cm off the floor, at points of
    the sole away from its centre and its corners: the batched check finds the foot in collision,
    with the height bound and without it. A broad phase that read the ground map only at the
    centre and the four corners of each footprint, where the floor is clear, would let the foot go
    (a swinging foot would pass 62 mm into a post of the low beam's frame).
    """
    floor = box((-3, -3, -0.2), (3, 3, 0.0))
    start = start_configuration(Environment([floor]), (0.0, 0.0, 0.0), skeleton)
    foot = next(i for i, shape in enumerate(skeleton.collision_shapes)
                if shape.link == 'right_foot')
    pose = skeleton.shape_transforms_at(start[None], [foot])[0, 0]
    centre, rotation = pose[:3, 3], pose[:3, :3]
    for along, across, lift, width in ((0.07, 0.0, 0.05, 0.02), (-0.06, 0.02, 0.03, 0.03),
                                       (0.09, -0.02, 0.08, 0.02)):
        post_xy = centre[:2] + rotation[:2, 0] * along + rotation[:2, 1] * across
        post = box((post_xy[0] - width / 2, post_xy[1] - width / 2, 0.0),
                   (post_xy[0] + width / 2, post_xy[1] + width / 2, 1.0))
        world = Environment([floor, post])
        lifted = start.copy()
        lifted[skeleton.index['root_z']] += lift
        case = (along, across, lift)
        # The exact test of the one shape: the post really is through the foot.
        assert BodyCollision(skeleton, world).links_in_collision(
            lifted, ['left_foot', 'right_foot']) == ['right_foot'], case
        frames = np.repeat(lifted[None], 3, axis=0)
        for checker in (BodyCollision(skeleton, world),
                        BodyCollision(skeleton, world, top_bound=False)):
            assert checker.first_collision(frames, ['left_foot', 'right_foot']) == (
                0, ['right_foot']), case


def test_motions_that_start_where_a_free_one_ended_are_checked_alike(skeleton):
    """
    Chained motions are checked alike, without testing unmoved shapes again.

    Chained motions (each starts at the last frame of the one before, as steps do): the shapes not
    moved since the last free motion's end are not tested again, and the answers stay those of
    testing every frame.
    """
    world = Environment([box((-3, -3, -0.2), (3, 3, 0.0)), box((0.2, -3, 0.0), (3, 3, 0.1))])
    body = BodyCollision(skeleton, world)
    plain = BodyCollision(skeleton, world, top_bound=False)
    legs = ['left_thigh', 'left_shank', 'left_foot', 'right_thigh', 'right_shank', 'right_foot']
    start = start_configuration(world, (0.0, 0.0, 0.0), skeleton)
    rng = np.random.default_rng(9)
    previous, outcomes = start, set()
    for trial in range(120):
        goal = start.copy()
        goal[skeleton.index['root_x']] += rng.uniform(-0.1, 0.1)
        goal[skeleton.index['root_z']] += rng.uniform(-0.006, 0.02)
        for name in ('left_hip_pitch', 'left_knee', 'left_ankle', 'right_ankle'):
            goal[skeleton.index[name]] += rng.uniform(-0.3, 0.3)
        frames = previous + np.linspace(0.0, 1.0, 12)[:, None] * (goal - previous)
        frames[:, skeleton.branch('right_leg')] = previous[skeleton.branch('right_leg')]
        expected = (-1, [])
        for j, q in enumerate(frames):
            touching = body.links_in_collision(q, legs)
            if touching:
                expected = (j, sorted(touching))
                break
        assert body.first_collision(frames, legs) == expected, trial
        assert plain.first_collision(frames, legs) == expected, trial
        outcomes.add(expected[0] >= 0)
        previous = frames[-1] if expected[0] < 0 else start
    assert outcomes == {True, False}


def test_the_height_bound_never_clears_a_shape_that_touches(skeleton):
    """
    The height bound never clears a shape that touches.

    Random leg poses over stairs, a slope and a ledge: every shape the height bound calls clear is
    free by FCL, and the bound does clear a foot resting on level ground.
    """
    slope = box((-0.5, -3, -0.6), (0.5, 3, 0.0))
    slope.apply_transform(np.array([[np.cos(0.25), 0, -np.sin(0.25), 1.5],
                                    [0, 1, 0, 0], [np.sin(0.25), 0, np.cos(0.25), 0.0],
                                    [0, 0, 0, 1]]))
    world = Environment([box((-3, -3, -0.2), (3, 3, 0.0)), box((0.25, -3, 0.0), (0.55, 3, 0.12)),
                         box((0.55, -3, 0.0), (0.85, 3, 0.24)), slope,
                         box((-3, 0.3, 0.0), (-1, 3, 0.6))])
    body = BodyCollision(skeleton, world)
    start = start_configuration(world, (0.0, 0.0, 0.0), skeleton)
    rng = np.random.default_rng(11)
    cleared = touching = 0
    for trial in range(300):
        q = start.copy()
        q[skeleton.index['root_x']] += rng.uniform(-1.5, 2.0)
        q[skeleton.index['root_y']] += rng.uniform(-0.6, 0.6)
        q[skeleton.index['root_z']] += rng.uniform(-0.1, 0.3)
        q[skeleton.index['root_yaw']] += rng.uniform(-np.pi, np.pi)
        for name in ('left_hip_pitch', 'right_hip_pitch', 'left_knee', 'right_knee',
                     'left_ankle', 'right_ankle', 'left_hip_yaw', 'right_hip_yaw'):
            q[skeleton.index[name]] += rng.uniform(-0.4, 0.4)
        if trial % 3 == 0:
            q = start.copy()  # feet resting 2 mm above the floor
        transforms = skeleton.shape_transforms(skeleton.forward_kinematics(q[None, :]))[0]
        shapes = list(range(len(body.shapes)))
        extent = body._aabb_half_extents(shapes, transforms[None, :, :3, :3])[0]
        centre = transforms[:, :3, 3]
        tops = world.top_height_near(centre[:, :2], np.max(extent[:, :2], axis=1))
        clear = centre[:, 2] - extent[:, 2] > tops
        body.collides(q)  # place every shape at q
        for shape in shapes:
            hit = body._shape_collides(shape)
            touching += hit
            assert not (clear[shape] and hit), (trial, body.shapes[shape].link)
            cleared += bool(clear[shape] and body.shapes[shape].link.endswith('_foot'))
    assert touching > 50 and cleared > 100
