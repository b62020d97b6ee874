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

"""Configuration-time space of a branch (paper §5.2): kinematics, validity, forward-only motion."""
from digital_actor_planner.core import body_model, convex, ct_space
from digital_actor_planner.core.body_model import (
    BodyKinematics, BodyShapes, EnvironmentIndex, TimedBody)
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.ct_space import CTSpace
from digital_actor_planner.core.environment import Environment
import fcl
import numpy as np
import pytest
from scene_helpers import box, timed_body, walk
import trimesh

TRUNK = ('waist', 'torso', 'head', 'left_shoulder', 'right_shoulder')
LEGS = ('pelvis', 'left_hip', 'right_hip', 'left_thigh', 'right_thigh', 'left_shank',
        'right_shank', 'left_foot', 'right_foot')


@pytest.fixture(scope='module')
def beam_world(skeleton):
    environment = Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0]),
                               box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80])], resolution=0.05)
    collision = BodyCollision(skeleton, environment)
    times, frames = walk(skeleton, 200)
    body = timed_body(skeleton, environment, frames)
    space = CTSpace('waist', body, times, frames[:, skeleton.branch('waist')], TRUNK, LEGS)
    return space, collision, frames


def _bumpy_table_and_beam(rng, subdivisions: int, top_y: float, beam_z: float) -> Environment:
    """
    Build a floor, a bumpy table top and a beam across the path.

    Floor, a table top of many small triangles with random bumps up to 3 cm (centred at x 0.4, y
    ``top_y``, z 0.85, ``subdivisions`` times subdivided) and a 20 cm beam at ``beam_z`` m across
    the path.
    """
    top = trimesh.creation.box(extents=[1.2, 1.6, 0.1])
    for _ in range(subdivisions):
        top = top.subdivide()
    top.vertices += [0.4, top_y, 0.85]
    top.vertices[:, 2] += rng.uniform(0.0, 0.03, len(top.vertices))
    return Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0]), top,
                        box([0.3, -1.0, beam_z], [0.5, 1.0, beam_z + 0.2])], resolution=0.05)


def test_kinematics_match_the_skeleton(skeleton):
    rng = np.random.default_rng(0)
    q = skeleton.lower + rng.random((40, 22)) * (np.minimum(skeleton.upper, 3)
                                                 - np.maximum(skeleton.lower, -3))
    q = np.clip(q, skeleton.lower, skeleton.upper)
    expected = skeleton.forward_kinematics(q)
    rotations, positions = BodyKinematics(skeleton).poses(q)
    assert np.allclose(rotations, expected[:, :, :3, :3], atol=1e-12)
    assert np.allclose(positions, expected[:, :, :3, 3], atol=1e-12)


@pytest.mark.parametrize('branch', ['waist', 'left_arm', 'right_arm'])
def test_chain_kinematics_give_the_same_numbers_as_the_whole_body(skeleton, branch):
    # A branch's checks evaluate only its few links; the plans stay the same only if the poses
    # are bit for bit those of the whole-body kinematics.
    rng = np.random.default_rng(1)
    q = skeleton.lower + rng.random((30, 22)) * (np.minimum(skeleton.upper, 3)
                                                 - np.maximum(skeleton.lower, -3))
    q = np.clip(q, skeleton.lower, skeleton.upper)
    kinematics = BodyKinematics(skeleton)
    rotations, positions = kinematics.poses(q)
    names = [skeleton.joint_names[i] for i in skeleton.branch(branch)]
    steps = kinematics.subtree_steps(names)
    chain = kinematics.chain(steps)
    moved = np.isin(chain.links, [step.child for step in steps])
    chain_rotations = rotations[:, chain.links]
    chain_positions = positions[:, chain.links]
    chain_rotations[:, moved] = np.nan
    chain_positions[:, moved] = np.nan
    kinematics.chain_poses(q, chain_rotations, chain_positions, chain)
    assert chain_rotations.tobytes() == rotations[:, chain.links].tobytes()
    assert chain_positions.tobytes() == positions[:, chain.links].tobytes()


@pytest.mark.parametrize('branch', ['waist', 'left_arm', 'right_arm'])
def test_branch_boxes_are_those_of_the_whole_body_posed_row_by_row(skeleton, branch):
    # The broad phase poses a branch's shapes in one kernel (_branch_boxes): rows where the
    # branch is where the body holds it copy the body's poses, the others run the chain's
    # kinematics. Either way, bit for bit the poses and boxes of the whole body built at that
    # row's configuration.
    from digital_actor_planner.core.upper_body import _ARM_LINKS, _LEG_LINKS, _TRUNK_LINKS
    checked = {'waist': _TRUNK_LINKS, 'left_arm': _ARM_LINKS['left'],
               'right_arm': _ARM_LINKS['right']}[branch]
    environment = Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])], resolution=0.05)
    times, frames = walk(skeleton, 40)
    body = timed_body(skeleton, environment, frames)
    indices = skeleton.branch(branch)
    space = CTSpace(branch, body, times, frames[:, indices], checked,
                    _LEG_LINKS + _TRUNK_LINKS)
    rng = np.random.default_rng(4)
    rows = rng.integers(0, 40, 25)
    q = frames[rows][:, indices] + rng.normal(0.0, 0.3, (25, len(indices))) * (
        np.arange(25) % 3 > 0)[:, None]
    rotation, centre, low, high, held = space._shape_boxes(q, rows)
    # Every third row is where the body holds the branch.
    assert held.tolist() == (np.arange(25) % 3 == 0).tolist()
    for row, (frame, values) in enumerate(zip(rows, q)):
        full = frames[frame].copy()
        full[indices] = values
        whole = timed_body(skeleton, environment, full[None])
        at = (0, space.checked)
        assert rotation[row].tobytes() == whole.shape_rotation[at].tobytes(), row
        assert centre[row].tobytes() == whole.shape_centre[at].tobytes(), row
        assert low[row].tobytes() == whole.shape_lower[at].tobytes(), row
        assert high[row].tobytes() == whole.shape_upper[at].tobytes(), row


def test_validity_agrees_with_body_collision(skeleton, beam_world):
    space, collision, frames = beam_world
    disagreements = []
    for frame in (60, 100, 133, 160):
        for pitch in np.arange(-0.3, 1.21, 0.15):
            q = np.array([0.0, pitch])
            full = frames[frame].copy()
            full[skeleton.index['waist_pitch']] = pitch
            expected = not (collision.collides(full, TRUNK)
                            or collision.self_collides(full, TRUNK, LEGS[1:]))
            if space.is_valid(q, frame) != expected:
                disagreements.append((frame, round(pitch, 2)))
    assert not disagreements
    # Both outcomes occur: upright hits the beam at frame 160, a deep bend passes under it.
    assert not space.is_valid(np.array([0.0, 0.0]), 160)
    assert space.is_valid(np.array([0.0, 0.9]), 160)


@pytest.mark.parametrize('kernel', [ct_space.illegal_rows, ct_space.illegal_rows.py_func])
def test_a_batch_is_illegal_where_its_pieces_say_so(skeleton, beam_world, kernel):
    # The one-kernel check of a batch against the kernels it stands for, called one by one:
    # the branch's boxes, the contacts (rows where the body holds the branch, before
    # clear_until, skipped), then the joint limits. Under the beam and beside it, upright and
    # bent, inside and outside the limits, rows where the body holds the waist.
    space, _, frames = beam_world
    rng = np.random.default_rng(12)
    rows = np.sort(rng.integers(0, space.frame_count, 120))
    q = space.objective[rows] + rng.normal(0.0, 0.5, (120, 2)) * (np.arange(120) % 4 > 0)[:, None]
    rotation, centre, low, high, held = space._shape_boxes(q, rows)
    answers = {}
    for clear_until in (0, space.frame_count):
        for swept in (True, False):
            known = held & (rows < clear_until)
            contact = ct_space._row_collisions(
                low, high, space._triangle_lower, space._triangle_upper, swept, rows,
                space._pair_column, space.body.shape_lower, space.body.shape_upper, rotation,
                centre, space._checked_box_half, space._triangle_corners,
                space.body.shape_rotation, space.body.shape_centre, space._pair_box_half,
                convex.SAT_MARGIN, space._checked_kinds, space._checked_half,
                space._pair_kinds, space._pair_half, space._pair_other, known)
            expected = contact | ~space.within_bounds(q)
            answers.setdefault(clear_until, expected)
            assert expected.tolist() == answers[clear_until].tolist()  # the cut changes nothing
        tables = list(space._check_tables)
        tables[2] = clear_until
        tables = tuple(tables)
        # The whole batch (its pairs cut by the swept boxes: many rows) and each row alone.
        assert ct_space._sweeps(len(rows), len(space.checked), len(space._triangle_lower))
        found = kernel(q, rows, tables, ct_space._empty_row_memo())
        assert found.tolist() == answers[clear_until].tolist(), clear_until
        alone = [kernel(q[i:i + 1], rows[i:i + 1], tables, ct_space._empty_row_memo())[0]
                 for i in range(len(rows))]
        assert alone == answers[clear_until].tolist(), clear_until
        # One memo for a space's calls: a row checked once is answered from it after, alone or
        # in a batch of remembered and new rows, the same as checked again.
        memo = ct_space._empty_row_memo()
        shared = [kernel(q[i:i + 1], rows[i:i + 1], tables, memo)[0] for i in range(len(rows))]
        assert shared == answers[clear_until].tolist(), clear_until
        assert len(memo) == len({(f, tuple(row)) for f, row in zip(rows.tolist(), q.tolist())})
        assert kernel(q[::-1], rows[::-1].copy(), tables, memo)[::-1].tolist() == shared
        mixed, mixed_rows = np.vstack([q[::3], q[::3] + 0.05]), np.concatenate([rows[::3]] * 2)
        assert (kernel(mixed, mixed_rows, tables, memo).tolist()
                == kernel(mixed, mixed_rows, tables, ct_space._empty_row_memo()).tolist())
    # Every kind of row occurred: legal, touching, outside the limits; and upright under the
    # beam, where the body holds the waist, a row that clear_until lets pass untested.
    expected = answers[0]
    assert expected.any() and not expected.all() and (~space.within_bounds(q)).any()
    assert (expected & space.within_bounds(q)).any()
    assert (held & expected & ~answers[space.frame_count]).any()
    # What the space reports, with its own clear_until.
    known = held & (rows < space._clear_until)
    contact = ct_space._row_collisions(
        low, high, space._triangle_lower, space._triangle_upper, True, rows,
        space._pair_column, space.body.shape_lower, space.body.shape_upper, rotation, centre,
        space._checked_box_half, space._triangle_corners, space.body.shape_rotation,
        space.body.shape_centre, space._pair_box_half, convex.SAT_MARGIN,
        space._checked_kinds, space._checked_half, space._pair_kinds, space._pair_half,
        space._pair_other, known)
    assert space.valid_rows(q, rows).tolist() == (~contact & space.within_bounds(q)).tolist()


def test_out_of_limits_is_invalid(beam_world):
    space, _, _ = beam_world
    assert not space.is_valid(np.array([0.0, 1.3]), 10)
    assert not space.is_valid(np.array([-0.9, 0.0]), 10)
    assert space.is_valid(np.array([0.0, 0.0]), 10)


def test_motion_must_go_forward_in_time(beam_world):
    space, _, frames = beam_world
    q = np.zeros(2)
    assert space.check_motion((q, 10), (q, 20))
    assert not space.check_motion((q, 20), (q, 10))
    assert not space.check_motion((q, 20), (q, 20))


def test_motion_must_respect_speed_limits(beam_world):
    space, _, _ = beam_world
    # 2.5 rad/s: 0.5 rad takes 0.2 s = 20 frames.
    assert space.check_motion((np.zeros(2), 10), (np.array([0.0, 0.5]), 30))
    assert not space.check_motion((np.zeros(2), 10), (np.array([0.0, 0.5]), 25))
    assert space.first_invalid_motion((np.zeros(2), 10), (np.array([0.0, 0.5]), 25)) == 11


def test_motion_through_an_obstacle_is_invalid_though_its_ends_are_legal(beam_world):
    space, _, _ = beam_world
    upright, bent = np.zeros(2), np.array([0.0, 0.9])
    assert space.is_valid(upright, 96) and space.is_valid(bent, 136)
    # Bending while the head is right before the beam sweeps the head into it.
    bad = space.first_invalid_motion((upright, 96), (bent, 136))
    assert 96 < bad < 136
    # Bending earlier passes.
    assert space.check_motion((upright, 40), (bent, 80))


def test_motion_rows_are_the_interpolated_motion_up_to_its_first_speed_violation(beam_world):
    # _motion_rows is one kernel (_motion_path); the reference is motion_frames and a NumPy
    # speed check over the whole motion: the same numbers to the last bit.
    space, _, _ = beam_world
    rng = np.random.default_rng(6)
    late_seen = set()
    for trial in range(200):
        ia = int(rng.integers(0, 190))
        ib = ia + int(rng.integers(1, 200 - ia))
        qa = space.objective[ia] + rng.normal(0.0, 0.3, 2)
        qb = space.objective[ib] + rng.normal(0.0, 0.3, 2) * (trial % 4 > 0)
        path = space.motion_frames((qa, ia), (qb, ib))
        speed = np.abs(np.diff(path, axis=0)) / np.diff(space.times[ia:ib + 1])[:, None]
        fast = np.flatnonzero((speed > space.speed_limit * (1 + 1e-6)).any(axis=1))
        end = ia + 1 + int(fast[0]) if len(fast) else ib + 1
        rows, late = space._motion_rows(qa, ia, qb, ib)
        assert rows.tobytes() == path[1:end - ia].tobytes(), trial
        assert late == (end if len(fast) else -1), trial
        if trial % 20 == 0:  # the kernel's own Python source gives the same
            plain = ct_space.motion_path.py_func(space.objective, space.times,
                                                 space.frame_step, space.speed_cap, qa,
                                                 ia, qb, ib)
            assert plain[0].tobytes() == rows.tobytes() and plain[1] == late
        late_seen.add(late < 0)
    assert late_seen == {True, False}  # motions within the limits and too fast ones
    # A batch of motions (one of them backwards in time) is their rows one after the other.
    motions = []
    for trial in range(6):
        ia, ib = sorted(int(f) for f in rng.integers(0, 200, 2))
        if trial == 3:
            ia, ib = ib, ia
        motions.append(((space.objective[ia] + rng.normal(0.0, 0.2, 2), ia),
                        (space.objective[ib] + rng.normal(0.0, 0.2, 2), ib)))
    q, frames, segments, early = space._motion_batch(motions)
    for ((qa, ia), (qb, ib)), (begin, end), late in zip(motions, segments, early):
        rows, expected_late = space._motion_rows(qa, ia, qb, ib)
        assert q[begin:end].tobytes() == rows.tobytes()
        assert frames[begin:end].tolist() == list(range(ia + 1, ia + 1 + len(rows)))
        assert late == expected_late
    assert segments[-1][1] == len(q) == len(frames)


def test_motion_between_objective_states_follows_the_objective(skeleton):
    times = np.arange(20) / 100.0
    objective = np.stack([0.3 * np.sin(times * 8), np.full(20, 0.06), np.zeros(20),
                          0.25 + 0.1 * np.sin(times * 8)], axis=1)
    q = np.tile(skeleton.neutral(), (20, 1))
    q[:, skeleton.branch('left_arm')] = objective
    environment = Environment([box([-1, -1, -0.1], [1, 1, 0])], resolution=0.05)
    body = TimedBody(BodyKinematics(skeleton), BodyShapes(skeleton),
                     EnvironmentIndex(environment.meshes), q)
    space = CTSpace('left_arm', body, times, objective, ('left_upper_arm',), ('torso',))
    path = space.motion_frames((objective[2], 2), (objective[15], 15))
    assert np.allclose(path, objective[2:16])
    offset = np.array([0.0, 0.0, 0.0, 0.4])
    path = space.motion_frames((objective[2] + offset, 2), (objective[15], 15))
    assert np.allclose(path[0] - objective[2], offset)
    assert np.allclose(path[-1], objective[15])
    q_mid, t_mid = space.interpolate((objective[2] + offset, 2), (objective[12], 12), 0.5)
    assert t_mid == pytest.approx(0.07)
    assert q_mid[3] == pytest.approx(np.interp(0.07, times, objective[:, 3]) + 0.2)
    assert space.distance((objective[2], 2), (objective[2], 12)) == pytest.approx(0.1)
    assert space.dimension == 4 and space.frame_count == 20


def test_bad_inputs_raise(skeleton, beam_world):
    space, _, frames = beam_world
    with pytest.raises(ValueError, match='padding'):
        BodyShapes(skeleton, padding=-0.01)
    with pytest.raises(ValueError, match='objective shape'):
        CTSpace('waist', space.body, space.times[:10], frames[:, :2], TRUNK, LEGS)


def _every_pair_collides(space, obstacle_links, q, frame):
    """Straightforward check of one configuration: FCL on every shape pair, no broad phase."""
    body = space.body
    full = body.frames[frame].copy()
    full[space.indices] = q
    rotations, positions = body.kinematics.poses(full[None])
    shapes = body.shapes
    rotation, centre = shapes.poses(rotations, positions, space.checked)
    column = {int(shape): n for n, shape in enumerate(space.checked)}
    for n, shape in enumerate(space.checked):
        for target in body.environment.objects:
            if shapes.collides(int(shape), rotation[0, n], centre[0, n], target):
                return True
    every = np.arange(len(shapes.kind))
    other_rotation, other_centre = shapes.poses(body.rotations[frame:frame + 1],
                                                body.positions[frame:frame + 1], every)
    obstacle = shapes.shapes_of(obstacle_links)
    for a, b in shapes.pairs(space.checked, obstacle):
        target = shapes.objects[int(b)]
        target.setTransform(fcl.Transform(other_rotation[0, b], other_centre[0, b]))
        if shapes.collides(int(a), rotation[0, column[int(a)]], centre[0, column[int(a)]],
                           target):
            return True
    return False


@pytest.mark.parametrize('branch', ['waist', 'left_arm'])
def test_batched_checks_agree_with_every_pair_checked_frame_by_frame(skeleton, branch):
    # Many small triangles (a bumpy table top in reach of the arm and of a bent trunk) and a
    # beam: broad-phase culling matters, and contacts graze a few small triangles.
    rng = np.random.default_rng(3)
    environment = _bumpy_table_and_beam(rng, 4, 0.6, 1.45)
    k = 120
    times, frames = walk(skeleton, k, x0=-0.6, swing_legs=False)
    body = timed_body(skeleton, environment, frames, padding=0.01)
    checked = TRUNK if branch == 'waist' else ('left_shoulder_roll_link', 'left_upper_arm',
                                               'left_forearm')
    obstacles = LEGS if branch == 'waist' else LEGS + TRUNK
    indices = skeleton.branch(branch)
    space = CTSpace(branch, body, times, frames[:, indices], checked, obstacles)
    rows = space.lower + rng.random((300, len(indices))) * (space.upper - space.lower)
    rows[:100] = frames[:100, indices] + rng.normal(0.0, 0.4, (100, len(indices)))
    rows = np.clip(rows, space.lower, space.upper)
    # Chunks of 30 rows at increasing, distinct frames (as motions are).
    at = np.concatenate([np.sort(rng.choice(k, 30, replace=False)) for _ in range(10)])
    # Some rows hold the branch where the body does (its poses are reused, no kinematics),
    # mixed with others in the same batches.
    held = np.arange(150, 300, 2)
    rows[held] = frames[at[held]][:, indices]
    expected = np.array([not _every_pair_collides(space, obstacles, row, frame)
                         for row, frame in zip(rows, at)])
    assert 0.1 < expected.mean() < 0.9  # both outcomes occur
    assert np.array_equal(space.valid_rows(rows, at), expected)
    assert np.array_equal([space.is_valid(row, frame) for row, frame in zip(rows, at)],
                          expected)
    for begin in range(0, len(rows), 30):
        chunk = slice(begin, begin + 30)
        bad = space.first_invalid(rows[chunk], at[chunk])
        want = np.flatnonzero(~expected[chunk])
        assert bad == (int(want[0]) if len(want) else -1)


def test_triangles_near_the_step_are_those_of_the_whole_environment(skeleton):
    # The per-step list of nearby triangles is a shortcut: any box, near the actor or not,
    # gives the same triangles as a scan of the whole environment.
    # Both are checked against a plain test of every triangle's box, on few and on many
    # (a subdivided bumpy floor) triangles.
    floor = trimesh.creation.box(extents=[5.5, 3.0, 0.1])
    for _ in range(4):
        floor = floor.subdivide()
    floor.vertices += [0.25, 0.0, -0.05]
    floor.vertices[:, 2] += np.random.default_rng(1).uniform(0.0, 0.02, len(floor.vertices))
    for ground in (box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0]), floor):
        environment = Environment([ground, box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80]),
                                   box([2.6, 1.0, 0.0], [2.9, 1.4, 2.0])], resolution=0.05)
        times, frames = walk(skeleton, 60)
        body = timed_body(skeleton, environment, frames)
        index = body.environment
        rng = np.random.default_rng(3)
        for _ in range(30):
            centre = rng.uniform([-1.5, -1.0, -0.2], [3.0, 1.5, 2.0])
            half = rng.uniform(0.01, 1.5, size=3)
            lower, upper = centre - half, centre + half
            expected = np.flatnonzero(np.all((index.upper >= lower) & (index.lower <= upper),
                                             axis=1))
            assert np.array_equal(index.triangles_near(lower, upper), expected)
            assert np.array_equal(body.triangles_near(lower, upper), expected)


def test_first_legal_motion_agrees_with_goals_checked_one_by_one(beam_world):
    space, _, _ = beam_world
    start = (np.array([0.0, 0.0]), 100)
    goals = [(np.array([0.0, 0.0]), 170), (np.array([0.0, 1.3]), 120),
             (np.array([0.0, 0.9]), 101), (np.array([0.0, 0.9]), 150),
             (np.array([0.0, 0.2]), 125), (np.array([0.0, 0.0]), 130)]
    one_by_one, rows = [], []
    spent = 0
    for goal in goals:
        before = space.checks
        one_by_one.append(space.first_invalid_motion(start, goal))
        rows.append(space.checks - before)
    for count in range(1, len(goals) + 1):
        legal = [i for i, bad in enumerate(one_by_one[:count]) if bad < 0]
        before = space.checks
        chosen, failures = space.first_legal_motion(start, goals[:count])
        assert chosen == (legal[0] if legal else -1)
        assert failures == one_by_one[:len(failures)]
        assert len(failures) == (chosen + 1 if legal else count)
        # The work counted is that of the first goal alone, then, if it fails, of the others
        # a few frames at a time: at most their whole motions.
        if one_by_one[0] < 0:
            assert space.checks - before == rows[0]
        else:
            assert rows[0] <= space.checks - before <= sum(rows[:count])
            spent = space.checks - before
    assert min(one_by_one) < 0 < max(one_by_one), 'both legal and illegal goals are tried'
    assert spent < sum(rows), 'motions blocked early are not boxed to their ends'


def test_a_planner_kernel_run_by_the_space_checks_as_its_methods_do(beam_world):
    # A planner's compiled kernel sees the space only through what run_checks hands it, passed
    # on to the space's compiled checks: the same answers as the space's methods, and the
    # configurations it checked counted as theirs are.
    space, _, _ = beam_world
    start = (np.array([0.0, 0.0]), 100)
    goals = [(np.array([0.0, 0.0]), 170), (np.array([0.0, 1.3]), 120),
             (np.array([0.0, 0.9]), 101), (np.array([0.0, 0.9]), 150),
             (np.array([0.0, 0.2]), 125), (np.array([0.0, 0.0]), 130)]
    rows = np.array([[0.0, 0.0], [0.0, 1.3], [0.0, 0.9]])
    frames = np.array([110, 120, 150], dtype=np.int64)

    def planner_kernel(targets, arrivals, q, rows_frames, objective, times, frame_step,
                       speed_cap, tables, memo):
        chosen, failures, checks = ct_space.first_legal_goal(
            objective, times, frame_step, speed_cap, start[0], start[1], targets, arrivals,
            -2, tables, memo)
        illegal = ct_space.illegal_rows(q, rows_frames, tables, memo)
        return chosen, failures.tolist(), ~illegal, checks + len(q)

    before = space.checks
    expected = space.first_legal_motion(start, goals)
    expected_rows = space.valid_rows(rows, frames)
    by_methods = space.checks - before
    targets = np.array([q for q, _ in goals])
    arrivals = np.array([frame for _, frame in goals], dtype=np.int64)
    before = space.checks
    chosen, failures, legal = space.run_checks(planner_kernel, targets, arrivals, rows, frames)
    assert (chosen, failures) == expected
    assert legal.tolist() == expected_rows.tolist()
    assert space.checks - before == by_methods
    assert min(failures) < 0 < max(failures) and not legal.all() and legal.any()


def _failures_written_out(space, motions, stop_at_legal, first):
    """
    Return each motion's first illegal frame, checked row by row and in waves.

    Each motion's first illegal frame (-1: legal), its rows checked one by one, and the rows
    checked in waves of ``first`` rows of every open motion, then twice as many each wave (all rows
    in one wave when first <= 0), up to the wave that answers the first legal one with
    ``stop_at_legal``.
    """
    paths = [space._motion_rows(qa, ia, qb, ib) if ib > ia else (np.zeros((0, 2)), ia)
             for (qa, ia), (qb, ib) in motions]
    answers, bad_rows = [], []
    for ((_, ia), _), (rows, late) in zip(motions, paths):
        bad = [r for r, q in enumerate(rows) if not space.is_valid(q, ia + 1 + r)]
        bad_rows.append(bad[0] if bad else None)
        answers.append(ia + 1 + bad[0] if bad else late if late >= 0 else -1)

    def waves(count, bad, last_wave=np.inf):
        # (rows read, the wave that answers the motion or last_wave)
        read, size, wave = 0, (first if first > 0 else max(count, 1)), 0
        while True:
            read = min(read + size, count)
            if (bad is not None and bad < read) or read == count or wave >= last_wave:
                return read, wave
            size, wave = 2 * size, wave + 1

    answered = [waves(len(rows), bad)[1] for (rows, _), bad in zip(paths, bad_rows)]
    stop = np.inf
    if stop_at_legal and -1 in answers:
        legal = answers.index(-1)
        answers = answers[:legal + 1]
        stop = max(answered[:legal + 1])
    counted = sum(waves(len(rows), bad, stop)[0] for (rows, _), bad in zip(paths, bad_rows))
    return answers, counted


@pytest.mark.parametrize('kernel', [ct_space._motion_failures, ct_space._motion_failures.py_func])
def test_motions_fail_where_their_rows_checked_one_by_one_do(beam_world, kernel):
    # The kernel that checks motions for first_legal_motion and first_invalid_path, at once
    # and in waves, against each row checked alone: the same answers, and in waves the rows
    # read up to each motion's answer (or the first legal one's). Motions under the beam and
    # beside it, too fast ones, ones backwards in time.
    space, _, _ = beam_world
    rng = np.random.default_rng(13)
    seen = set()
    for trial in range(40):
        motions = []
        for _ in range(rng.integers(1, 6)):
            ia = int(rng.integers(0, space.frame_count - 2))
            ib = int(rng.integers(ia + 1, min(ia + 60, space.frame_count)))
            if rng.random() < 0.1:
                ia, ib = ib, ia
            scale = 0.2 if rng.random() < 0.8 else 1.5
            motions.append(((space.objective[ia] + rng.normal(0.0, scale, 2), ia),
                            (space.objective[ib] + rng.normal(0.0, scale, 2), ib)))
        qa, qb = (np.array([m[end][0] for m in motions]) for end in (0, 1))
        ia, ib = (np.array([m[end][1] for m in motions], dtype=np.int64) for end in (0, 1))
        for stop_at_legal in (True, False):
            for first in (0, 1, 8):
                answers, checks = kernel(space.objective, space.times, space.frame_step,
                                         space.speed_cap, qa, ia, qb, ib, stop_at_legal,
                                         first, space._check_tables,
                                         ct_space._empty_row_memo())
                expected = _failures_written_out(space, motions, stop_at_legal, first)
                assert (answers.tolist(), checks) == expected, (trial, stop_at_legal, first)
                seen.update(('legal' if a < 0 else 'illegal', first > 0 and len(answers) > 1)
                            for a in answers)
    assert seen >= {('legal', True), ('illegal', True), ('legal', False), ('illegal', False)}


def test_rows_and_path_in_one_batch_agree_with_each_checked_alone(beam_world):
    # The CT-roadmap's first batch (the objective on a grid, and the way back to it from the
    # start): the same answers as valid_rows and first_invalid_path, with the same rows.
    space, _, _ = beam_world
    rng = np.random.default_rng(3)
    objective = space.objective
    outcomes = set()
    for trial in range(40):
        grid = np.sort(rng.choice(len(space.times), 12, replace=False))
        q = objective[grid] + rng.normal(0.0, 0.4, (12, 2)) * (trial % 2)
        here = int(rng.integers(0, 150))
        arrival = here + int(rng.integers(10, 20))
        end = arrival + int(rng.integers(1, 199 - arrival))
        waypoints = [(objective[here] + rng.normal(0.0, 0.1, 2), here),
                     (objective[arrival], arrival), (objective[end], end)]
        before = space.checks
        legal, bad = space.rows_and_path(q, grid, waypoints)
        batched = space.checks - before
        before = space.checks
        assert np.array_equal(legal, space.valid_rows(q, grid)), trial
        assert bad == space.first_invalid_path(waypoints), trial
        assert batched == space.checks - before
        outcomes.add((bool(legal.all()), bad < 0))
    assert len(outcomes) >= 3, outcomes  # legal and illegal rows and paths occur


def test_separating_axis_tests_never_part_shapes_that_fcl_finds_touching(skeleton):
    # The broad phase skips FCL for a pair whose oriented boxes are apart by more than
    # SAT_MARGIN: every shape kind of the actor (box, cylinder, sphere, padded) against the
    # others and against triangles, posed at random, often touching.
    shapes = BodyShapes(skeleton, padding=0.01)
    rng = np.random.default_rng(12)
    request, result = fcl.CollisionRequest(), fcl.CollisionResult()

    def rotation():
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        q = q * np.sign(np.diag(r))
        return q if np.linalg.det(q) > 0 else -q

    def touch(a, b) -> bool:
        hit = fcl.collide(a, b, request, result) > 0
        del result.contacts[:]
        return hit

    kinds = {kind: [i for i, k in enumerate(shapes.kind) if k == kind]
             for kind in ('box', 'cylinder', 'sphere')}
    assert all(kinds.values()), 'the actor has every kind of shape'
    parted = {'pairs': [0, 0], 'triangles': [0, 0]}
    for trial in range(3000):
        a = kinds[('box', 'cylinder', 'sphere')[trial % 3]][trial % 5 % len(
            kinds[('box', 'cylinder', 'sphere')[trial % 3]])]
        b = int(rng.integers(len(shapes.kind) - 1))
        b += b >= a  # another shape (another FCL object)
        pose_a = (rotation(), np.zeros(3))
        pose_b = (rotation(), rng.uniform(-0.4, 0.4, 3))
        shape_a, shape_b = shapes.objects[a], shapes.objects[b]
        shape_a.setTransform(fcl.Transform(*pose_a))
        shape_b.setTransform(fcl.Transform(*pose_b))
        apart = convex.boxes_apart(pose_a[0], pose_a[1], shapes.box_half[a], pose_b[0],
                                   pose_b[1], shapes.box_half[b], convex.SAT_MARGIN)
        touching = touch(shape_a, shape_b)
        assert not (apart and touching), (trial, shapes.kind[a], shapes.kind[b])
        parted['pairs'][0] += apart
        parted['pairs'][1] += not touching
        corners = rng.uniform(-0.4, 0.4, (3, 3))
        model = fcl.BVHModel()
        model.beginModel(3, 1)
        model.addSubModel(corners, np.array([[0, 1, 2]]))
        model.endModel()
        apart = convex.box_triangle_apart(pose_a[0], pose_a[1], shapes.box_half[a],
                                          corners, convex.SAT_MARGIN)
        touching = touch(shape_a, fcl.CollisionObject(model, fcl.Transform()))
        assert not (apart and touching), (trial, shapes.kind[a])
        parted['triangles'][0] += apart
        parted['triangles'][1] += not touching
    for name, (apart, free) in parted.items():
        # Both outcomes occur, and the test parts most pairs that do not touch (a sphere or
        # cylinder only down to the box that holds it).
        assert 0.5 * free < apart <= free < 3000, (name, apart, free)


def test_fixing_a_branch_moves_the_body_as_if_built_with_it(skeleton):
    environment = Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])], resolution=0.05)
    times, frames = walk(skeleton, 40)
    body = timed_body(skeleton, environment, frames)
    for branch in ('waist', 'left_arm', 'right_arm'):
        # A space built once per branch and one built again share the model-only data.
        first = CTSpace(branch, body, times, frames[:, skeleton.branch(branch)], TRUNK, LEGS)
        again = CTSpace(branch, body, times, frames[:, skeleton.branch(branch)], TRUNK, LEGS)
        assert np.array_equal(first.pairs, again.pairs)
        assert np.array_equal(first.checked, again.checked)
        values = frames[:, skeleton.branch(branch)] + np.linspace(0.0, 0.3, 40)[:, None]
        body.set_branch(skeleton.branch(branch), values, first.steps)
        frames[:, skeleton.branch(branch)] = values
        fresh = timed_body(skeleton, environment, frames)
        for name in ('frames', 'rotations', 'positions', 'shape_rotation', 'shape_centre',
                     'shape_lower', 'shape_upper', 'swept_lower', 'swept_upper'):
            # Bit for bit: the plans after a branch depend on these numbers.
            assert getattr(body, name).tobytes() == getattr(fresh, name).tobytes(), name
        # Fixing the branch again at the same values changes nothing.
        before = body.shape_lower.copy()
        body.shape_lower[:] = np.nan
        body.set_branch(skeleton.branch(branch), values, first.steps)
        assert np.isnan(body.shape_lower).all()
        body.shape_lower[:] = before


def test_the_body_poses_every_shape_as_the_shape_model_does(skeleton):
    """
    The timed body poses every shape as the shape model does.

    TimedBody's shape poses and boxes, written in place by one kernel, are those of
    BodyShapes.poses and .bounds, and its swept boxes their extremes over the frames.
    """
    environment = Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])], resolution=0.05)
    _, frames = walk(skeleton, 30)
    frames[:, skeleton.branch('left_arm')] += np.linspace(-0.5, 0.5, 30)[:, None]
    body = timed_body(skeleton, environment, frames)
    every = np.arange(len(body.shapes.kind))
    rotation, centre = body.shapes.poses(body.rotations, body.positions, every)
    lower, upper = body.shapes.bounds(rotation, centre, every)
    for name, expected in (('shape_rotation', rotation), ('shape_centre', centre),
                           ('shape_lower', lower), ('shape_upper', upper),
                           ('swept_lower', lower.min(axis=0)),
                           ('swept_upper', upper.max(axis=0))):
        assert getattr(body, name).tobytes() == expected.tobytes(), name


@pytest.mark.parametrize('kernel', [body_model._write_columns, body_model._write_columns.py_func])
def test_writing_a_branch_into_the_frames_says_what_changed(kernel):
    frames = np.arange(12.0).reshape(4, 3)
    columns = np.array([2, 0])
    changed = np.zeros(4, dtype=bool)
    assert not kernel(frames, columns, frames[:, [2, 0]].copy(), changed)
    assert not changed.any()
    values = frames[:, [2, 0]].copy()
    values[3, 1] = -1.0
    assert kernel(frames, columns, values, changed)
    assert changed.tolist() == [False, False, False, True]
    assert np.array_equal(frames[:, [2, 0]], values)
    assert np.array_equal(frames[:, 1], [1, 4, 7, 10])
    # As np.array_equal: a NaN never equals itself, so it is written again.
    values[0, 0] = np.nan
    assert kernel(frames, columns, values, changed)
    assert kernel(frames, columns, values, changed) and np.isnan(frames[0, 2])
    assert changed.tolist() == [True, False, False, True]


def test_first_collisions_per_group_agree_with_every_pair_checked_frame_by_frame(skeleton):
    # The upper body swings close to a bumpy table, a beam and its own legs: the one-batch
    # check (compiled broad phase and separating axis cut, FCL after) must find, per group of
    # shapes, the first frame a straightforward FCL check of every pair finds.
    rng = np.random.default_rng(11)
    environment = _bumpy_table_and_beam(rng, 3, 0.7, 1.50)
    k = 60
    times, frames = walk(skeleton, k, x0=-0.6)
    upper = np.concatenate([skeleton.branch(name)
                            for name in ('waist', 'left_arm', 'right_arm')])
    found_any = 0
    for trial in range(12):
        noisy = frames.copy()
        noisy[:, upper] += rng.normal(0.0, 0.5, (k, len(upper))) * rng.random() ** 2
        noisy[:, upper] = np.clip(noisy[:, upper], skeleton.lower[upper],
                                  skeleton.upper[upper])
        body = timed_body(skeleton, environment, noisy, padding=0.01)
        shapes = body.shapes
        groups = [shapes.shapes_of(TRUNK), shapes.shapes_of(('left_upper_arm', 'left_forearm')),
                  shapes.shapes_of(('right_upper_arm', 'right_forearm'))]
        checked = np.concatenate(groups)
        group = np.full(len(shapes.kind), -1)
        for g, members in enumerate(groups):
            group[members] = g
        pairs = shapes.pairs(checked, shapes.shapes_of(LEGS))
        touching = np.zeros((k, 3), dtype=bool)  # per frame and group, by FCL on every pair
        for frame in range(k):
            for shape in checked.tolist():
                targets = list(environment.objects) + [
                    body.posed_shape(frame, int(b)) for a, b in pairs if a == shape]
                if any(body.collides(frame, shape, target) for target in targets):
                    touching[frame, group[shape]] = True
        expected = [int(np.argmax(column)) if column.any() else -1 for column in touching.T]
        found_any += sum(e >= 0 for e in expected)
        assert body.first_collisions(checked, pairs, group, 3) == expected, trial
        anywhere = np.flatnonzero(touching.any(axis=1))
        assert body.first_collision(checked, pairs) == (anywhere[0] if len(anywhere) else -1)
        at = np.sort(rng.choice(k, 20, replace=False))
        hit = at[touching[at].any(axis=1)]
        assert body.first_collision(checked, pairs, at) == (hit[0] if len(hit) else -1), trial
    assert 6 <= found_any <= 30, found_any  # collisions and clear groups both occur


@pytest.mark.parametrize('branch', ['waist', 'left_arm', 'right_arm'])
def test_a_space_keeps_exactly_the_pairs_its_branch_can_reach(skeleton, branch):
    # The legs swing wide and the arms move, so some body shapes come within a branch's reach
    # during the step and others never do.
    environment = Environment([box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])], resolution=0.05)
    times, frames = walk(skeleton, 50)
    frames += np.random.default_rng(4).normal(0.0, 0.3, frames.shape)
    body = timed_body(skeleton, environment, frames)
    obstacles = LEGS + (TRUNK if branch != 'waist' else ())
    space = CTSpace(branch, body, times, frames[:, skeleton.branch(branch)], TRUNK
                    if branch == 'waist' else (f'{branch[:-4]}_upper_arm',
                                               f'{branch[:-4]}_forearm'), obstacles)
    every = body.shapes.pairs(space.checked, body.shapes.shapes_of(obstacles))
    centre = space._reach_centre
    gap = np.maximum(np.maximum(body.shape_lower - centre[:, None], 0.0),
                     centre[:, None] - body.shape_upper)
    near = (np.sqrt((gap ** 2).sum(axis=-1)) <= space._reach).any(axis=0)
    expected = every[near[every[:, 1]]]
    assert 0 < len(expected) < len(every) or branch == 'waist'
    assert np.array_equal(space.pairs, expected)
    assert np.array_equal(space._pair_other, expected[:, 1])
    assert np.array_equal(space._pair_column, np.searchsorted(space.checked, expected[:, 0]))
