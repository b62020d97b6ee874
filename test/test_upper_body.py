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

"""Upper-body compliant motion (paper §5): motion patterns and prioritized CT-roadmap planning."""
from digital_actor_planner.core import ct_roadmap
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.settings import ConfigError
from digital_actor_planner.core.upper_body import (
    motion_patterns, UpperBodyConfig, UpperBodyPlanner)
import numpy as np
import pytest
from scene_helpers import box, walk

UPPER_LINKS = ['waist', 'torso', 'head', 'left_shoulder', 'right_shoulder',
               'left_shoulder_roll_link', 'left_upper_arm', 'left_forearm',
               'right_shoulder_roll_link', 'right_upper_arm', 'right_forearm']


def ground():
    return box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])


def planner_for(skeleton, *obstacles, seed=3, config=None):
    environment = Environment([ground(), *obstacles], resolution=0.05)
    collision = BodyCollision(skeleton, environment)
    # Generous work budget: these tests judge behaviour, not speed.
    planner = UpperBodyPlanner(skeleton, collision,
                               config or UpperBodyConfig(check_budget=1_000_000),
                               rng=np.random.default_rng(seed))
    return planner, collision


def upper_columns(skeleton):
    return np.concatenate([skeleton.branch(b) for b in ('waist', 'left_arm', 'right_arm')])


def assert_collision_free(collision, frames):
    hits = [i for i, q in enumerate(frames) if collision.collides(q, UPPER_LINKS)]
    assert not hits, f'upper body in collision at frames {hits[:10]}'


def assert_limits_and_speeds(skeleton, times, frames):
    assert skeleton.within_limits(frames).all()
    speed = np.abs(np.diff(frames, axis=0)) / np.diff(times)[:, None]
    upper = upper_columns(skeleton)
    assert np.all(speed[:, upper] <= skeleton.velocity_limit[upper] * (1 + 1e-6))


# -- motion patterns (§5.1) -----------------------------------------------------------------
def test_arms_swing_opposite_to_the_legs_and_the_waist_stays_erect(skeleton):
    times, frames = walk(skeleton, 120)
    index = skeleton.index
    left_arm = frames[:, index['left_shoulder_pitch']]
    right_arm = frames[:, index['right_shoulder_pitch']]
    right_leg = frames[:, index['right_hip_pitch']]
    assert np.corrcoef(left_arm, right_leg)[0, 1] > 0.99
    assert np.corrcoef(right_arm, right_leg)[0, 1] < -0.99
    assert 0.15 < left_arm.max() <= 0.35 and abs(left_arm.mean()) < 0.05
    assert np.all(frames[:, skeleton.branch('waist')] == 0.0)
    assert np.all(frames[:, index['left_shoulder_roll']] > 0.0)
    assert skeleton.within_limits(frames).all()
    # The lower body and root are untouched and the input is not modified.
    legs = frames.copy()
    legs[:, upper_columns(skeleton)] = 1.0
    before = legs.copy()
    again = motion_patterns(skeleton, legs)
    lower = np.setdiff1d(np.arange(22), upper_columns(skeleton))
    assert np.array_equal(again[:, lower], before[:, lower])
    assert np.array_equal(legs, before)
    assert np.array_equal(again, frames)


@pytest.mark.parametrize('bad', [np.zeros((5, 21)), np.full((3, 22), np.nan)])
def test_motion_patterns_reject_bad_frames(skeleton, bad):
    with pytest.raises(ValueError, match='frames'):
        motion_patterns(skeleton, bad)


def test_motion_patterns_reject_bad_amplitude(skeleton):
    with pytest.raises(ValueError, match='swing_amplitude'):
        motion_patterns(skeleton, np.tile(skeleton.neutral(), (3, 1)), swing_amplitude=-0.1)


# -- planning (§5.2) ------------------------------------------------------------------------
def test_open_ground_returns_the_motion_pattern_exactly(skeleton):
    planner, collision = planner_for(skeleton)
    times, frames = walk(skeleton, 60)
    plan = planner.plan(times, frames)
    assert plan.ok and plan.reason == ''
    assert plan.deviation == 0.0
    assert np.array_equal(plan.frames, frames)
    assert set(plan.per_branch) == {'waist', 'left_arm', 'right_arm'}
    assert plan.planning_time < 0.5


def test_low_beam_makes_the_waist_bend_and_the_pattern_returns_after_it(skeleton):
    beam = box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80])
    planner, collision = planner_for(skeleton, beam)
    times, frames = walk(skeleton, 260)
    # Walking upright would hit the beam.
    assert any(collision.collides(q, UPPER_LINKS) for q in frames)
    plan = planner.plan(times, frames)
    assert plan.ok, plan.reason
    assert_collision_free(collision, plan.frames)
    assert_limits_and_speeds(skeleton, times, plan.frames)
    pitch = plan.frames[:, skeleton.index['waist_pitch']]
    assert pitch.max() > 0.7
    upper = upper_columns(skeleton)
    deviation = np.abs(plan.frames[:, upper] - frames[:, upper]).max(axis=1)
    assert deviation[:20].max() == 0.0, 'no bending long before the beam'
    assert deviation[-20:].max() < 0.02, 'back to the pattern after the beam'
    assert plan.deviation == pytest.approx(deviation.max())
    # Lower body and root are never changed.
    lower = np.setdiff1d(np.arange(22), upper)
    assert np.array_equal(plan.frames[:, lower], frames[:, lower])


def test_warming_the_kernels_up_changes_no_plan(skeleton, monkeypatch):
    # Each planner calls the search's kernels once on a throwaway space (numba's first look at
    # their arguments in a process, otherwise on the first step that searches); a planner that
    # warmed up plans exactly as one that did not.
    from digital_actor_planner.core import upper_body
    warmed = []
    monkeypatch.setattr(upper_body, 'warm_up', lambda *args: warmed.append(args[0]) or
                        ct_roadmap.warm_up(*args))
    beam = box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80])
    first, _ = planner_for(skeleton, beam)
    assert len(warmed) == 1
    monkeypatch.setattr(upper_body, 'warm_up', lambda *args: None)
    later, _ = planner_for(skeleton, beam)
    times, frames = walk(skeleton, 260)
    one, other = first.plan(times, frames), later.plan(times, frames)
    assert one.ok and other.ok
    assert not all(record['fast'] for record in one.per_branch.values())  # it searched
    assert np.array_equal(one.frames, other.frames)
    assert ({name: len(r.grown_nodes) for name, r in first.roadmaps.items()}
            == {name: len(r.grown_nodes) for name, r in later.roadmaps.items()})
    assert first.rng.bit_generator.state == later.rng.bit_generator.state


def test_table_beside_the_path_makes_that_arm_flex(skeleton):
    table = box([0.0, 0.21, 0.0], [0.8, 1.0, 0.78])
    planner, collision = planner_for(skeleton, table)
    times, frames = walk(skeleton, 200)
    assert any(collision.collides(q, ['left_forearm']) for q in frames)
    plan = planner.plan(times, frames)
    assert plan.ok, plan.reason
    assert_collision_free(collision, plan.frames)
    assert_limits_and_speeds(skeleton, times, plan.frames)
    elbow = skeleton.index['left_elbow']
    assert (plan.frames[:, elbow] - frames[:, elbow]).max() > 0.2
    assert plan.per_branch['right_arm']['deviation'] == 0.0
    assert plan.per_branch['waist']['deviation'] == 0.0


@pytest.mark.parametrize('seeded', [False, True])
def test_branches_off_their_pattern_go_straight_back_as_their_searches_would(
        skeleton, seeded):
    """
    Branches off their pattern go straight back as their searches would.

    After an obstacle a branch starts off its motion pattern, too far to join it at once; its
    search first tries going straight back. The plan tries that for every such branch in one batch
    with the whole body first: wherever it takes it, the plan is the one the searches make (the
    same frames), and where the way back is not legal, or the search would go another way first,
    the searches plan as before.
    """
    obstacles = {'beam': [box([0.6, -1.0, 1.60], [0.8, 1.0, 1.80])],
                 'table': [box([0.3, 0.21, 0.0], [1.1, 1.0, 0.78])],
                 'pillars': [box([0.6, 0.235, 0.0], [0.75, 0.6, 2.2]),
                             box([0.6, -0.6, 0.0], [0.75, -0.235, 2.2])]}
    times, frames = walk(skeleton, 320)
    taken = attempted = 0
    for name, meshes in obstacles.items():
        reference = planner_for(skeleton, *meshes, seed=0)[0].plan(times, frames)
        assert reference.ok, reference.reason
        config = UpperBodyConfig()
        planners = [planner_for(skeleton, *meshes, config=config)[0] for _ in range(2)]
        planners[1]._plan_returning = lambda *args: None  # the searches only
        checks = planners[0].pattern_checks
        calls = []
        # The batches checked (the input motion's check is given the limits it knows).
        planners[0].pattern_checks = lambda times, body, *limits: (
            calls.append(not limits) or checks(times, body, *limits))
        for begin in range(0, 260, 10):
            window = slice(begin, begin + 61)
            step = frames[window].copy()
            step[0] = reference.frames[begin]
            seeds = {}
            if seeded:
                # The reference plan from here on, for the branches it moves off the pattern.
                rest = reference.frames[window] - frames[window]
                seeds = {branch: rest[:, skeleton.branch(branch)]
                         for branch in ('waist', 'left_arm', 'right_arm')
                         if rest[:, skeleton.branch(branch)].any()}
            plans = [planner.plan(times[window], step, seeds=seeds) for planner in planners]
            assert plans[0].ok == plans[1].ok and plans[0].reason == plans[1].reason
            assert np.array_equal(plans[0].frames, plans[1].frames), (name, begin)
            returned = [b for b, r in plans[0].per_branch.items() if r.get('returned')]
            taken += bool(returned)
            for branch in returned:
                # Straight back to the pattern, then on it to the end.
                columns = skeleton.branch(branch)
                off = np.abs(plans[0].frames[1:, columns] - step[1:, columns]).max(axis=1)
                back = np.flatnonzero(off == 0.0)[0]
                assert back > 0 and off[back:].max() == 0.0
                assert np.all(np.diff(off[:back]) < 0)
                assert plans[1].per_branch[branch]['nodes'] == 0
        attempted += sum(calls)
    assert taken >= 2 and attempted > taken, (taken, attempted)


def test_beam_at_waist_height_is_reported_blocked(skeleton):
    beam = box([0.3, -1.0, 1.05], [0.5, 1.0, 1.30])
    planner, _ = planner_for(skeleton, beam)
    times, frames = walk(skeleton, 200)
    plan = planner.plan(times, frames)
    assert not plan.ok
    assert plan.reason.startswith('waist blocked at t=')
    blocked_at = float(plan.reason.split('t=')[1].split()[0])
    # The waist reaches the beam's near face at about x = 0.3 - 0.09 (t ~ 1.3 s).
    assert 1.0 < blocked_at < 1.6
    assert plan.planning_time < 5.0


def test_upper_body_starting_in_collision_is_reported(skeleton):
    # A box around the head at the start position only.
    block = box([-1.1, -0.2, 1.55], [-0.9, 0.2, 1.8])
    planner, _ = planner_for(skeleton, block)
    times, frames = walk(skeleton, 60)
    plan = planner.plan(times, frames)
    assert not plan.ok
    assert 'waist start in collision at t=0.00 s' in plan.reason
    assert 'head' in plan.reason


def test_successive_steps_join_continuously_and_are_deterministic(skeleton):
    table = box([0.0, 0.21, 0.0], [0.8, 1.0, 0.78])
    times, frames = walk(skeleton, 241)
    results = []
    for seed in (5, 5):
        planner, collision = planner_for(skeleton, table, seed=seed)
        planned = frames.copy()
        for begin in range(0, 240, 60):
            block = planned[begin:begin + 61].copy()
            plan = planner.plan(times[begin:begin + 61], block)
            assert plan.ok, plan.reason
            assert np.array_equal(plan.frames[0], block[0]), 'frame 0 is the start'
            planned[begin:begin + 61] = plan.frames
        results.append(planned)
    assert np.array_equal(results[0], results[1]), 'deterministic for a seeded rng'
    assert_collision_free(collision, results[0])
    assert_limits_and_speeds(skeleton, times, results[0])


@pytest.mark.parametrize('field, value', [
    ('roadmap_radius', 0.0), ('node_budget', 0), ('max_backtracks', -1),
    ('speed_fraction', 1.5), ('hold_frames', 2.5), ('arm_weights', (1.0, 1.0, 1.0)),
    ('waist_weights', (1.0, -1.0)), ('time_weight', float('nan')), ('max_roadmap_nodes', 3),
    ('time_budget', -1.0), ('check_budget', 0), ('check_budget', 2.5),
    ('preview_backtracks', -1), ('lasting_branches', ('left_arm', 'torso')),
    ('lasting_branches', 'waist'), ('lasting_branches', None)])
def test_bad_config_names_the_field(field, value):
    with pytest.raises(ConfigError, match=field) as caught:
        UpperBodyConfig(**{field: value})
    assert caught.value.name == field


def test_objective_outside_limits_names_the_joint(skeleton):
    planner, _ = planner_for(skeleton)
    times, frames = walk(skeleton, 30)
    frames[10, skeleton.index['right_elbow']] = -0.5
    with pytest.raises(ValueError, match='right_elbow'):
        planner.plan(times, frames)


def test_times_must_increase(skeleton):
    planner, _ = planner_for(skeleton)
    times, frames = walk(skeleton, 30)
    times[5] = times[4]
    with pytest.raises(ValueError, match='times'):
        planner.plan(times, frames)


def _start_and_objective(space, start) -> tuple:
    """
    Check the start and the objective on the CT-space, as a reference.

    Reference on the CT-space's own checks: whether the start is legal at frame 0, and whether the
    start, then the objective at frames 1..k-1, is a legal motion (one batch).
    """
    path = np.vstack([start[None], space.objective[1:]])
    speed = np.abs(np.diff(path, axis=0)) / np.diff(space.times)[:, None]
    if np.any(speed > space.speed_limit * (1 + 1e-6)):
        return space.is_valid(start, 0), False
    bad = space.first_invalid(path, np.arange(len(path)))
    return bad != 0, bad < 0


def _objective_is_legal(space, start) -> bool:
    """Check, as a reference, whether start then the objective is a legal motion."""
    path = np.vstack([start[None], space.objective[1:]])
    speed = np.abs(np.diff(path, axis=0)) / np.diff(space.times)[:, None]
    if np.any(speed > space.speed_limit * (1 + 1e-6)):
        return False
    return space.first_invalid(path[1:], np.arange(1, len(path))) < 0


def test_one_batch_pattern_check_agrees_with_the_branch_fast_paths(skeleton):
    # Offset postures held over 0.6 s windows walking past a low beam and a table: the one-batch
    # check of the whole pattern must give each branch the answer its own check gives.
    from digital_actor_planner.core.body_model import TimedBody
    from digital_actor_planner.core.ct_space import CTSpace
    from digital_actor_planner.core.upper_body import BRANCH_ORDER
    planner, _ = planner_for(skeleton, box([0.6, -1.0, 1.55], [0.8, 1.0, 1.75]),
                             box([1.3, 0.2, 0.0], [2.0, 1.0, 0.8]))
    times, frames = walk(skeleton, 320)
    rng = np.random.default_rng(5)
    upper = upper_columns(skeleton)
    outcomes, mixed = [], []
    for trial in range(60):
        begin = int(rng.integers(0, 320 - 61))
        window = frames[begin:begin + 61].copy()
        offset = rng.normal(0.0, 0.25, len(upper)) * (trial % 3 > 0)
        window[:, upper] = np.clip(window[:, upper] + offset, skeleton.lower[upper],
                                   skeleton.upper[upper])
        body = TimedBody(planner.kinematics, planner.shapes, planner.environment, window)
        expected = True
        legality = planner.pattern_checks(times[:61], body)
        for name in BRANCH_ORDER:
            indices = planner.indices[name]
            space = CTSpace(name, body, times[:61], window[:, indices], planner._checked[name],
                            planner._obstacles[name])
            start = window[0, indices]
            start_legal = space.is_valid(start, 0)
            objective_legal = _objective_is_legal(space, start)
            # The plan's single batch check of both says the same, on the CT-space and on the
            # poses the body already holds.
            assert _start_and_objective(space, start) == (
                start_legal, start_legal and objective_legal)
            assert planner.start_and_objective(times[:61], body, name) == (
                start_legal, start_legal and objective_legal)
            # And the one batch over all three branches says it of each.
            assert legality[name] == (start_legal, start_legal and objective_legal), (
                trial, name)
            expected &= start_legal and objective_legal
        got = all(start and motion for start, motion in legality.values())
        assert got == expected, (trial, begin, offset)
        outcomes.append(got)
        mixed.append(len(set(legality.values())) > 1)
    assert 0 < np.mean(outcomes) < 1  # both outcomes occur
    assert any(mixed)  # and branches with different answers in one batch


def test_rechecking_a_branch_after_others_moved_agrees_with_a_fresh_check(skeleton):
    # After the pattern check, fixing the waist or an arm away from its pattern over part of
    # the step changes the other branches' surroundings only there: their re-check looks at
    # those frames and the ones from their first contact on, and must answer what a full
    # check of a body built with the new frames answers (and know the same clear frames).
    from digital_actor_planner.core.body_model import TimedBody
    from digital_actor_planner.core.ct_space import CTSpace
    from digital_actor_planner.core.upper_body import BRANCH_ORDER
    planner, _ = planner_for(skeleton, box([0.6, -1.0, 1.55], [0.8, 1.0, 1.75]),
                             box([1.3, 0.2, 0.0], [2.0, 1.0, 0.8]))
    times, frames = walk(skeleton, 320)
    rng = np.random.default_rng(8)
    partial, answers = 0, set()
    for trial in range(40):
        begin = int(rng.integers(0, 320 - 61))
        window = frames[begin:begin + 61].copy()
        body = TimedBody(planner.kinematics, planner.shapes, planner.environment, window)
        planner.pattern_checks(times[:61], body)
        moved = BRANCH_ORDER[:int(rng.integers(1, 3))]
        for name in moved:
            indices = planner.indices[name]
            span = np.zeros(61)
            first, last = sorted(rng.integers(0, 61, 2))
            span[first:last + 1] = rng.normal(0.0, 0.4)
            values = np.clip(window[:, indices] + span[:, None] * rng.normal(size=len(indices)),
                             skeleton.lower[indices], skeleton.upper[indices])
            space = CTSpace(name, body, times[:61], window[:, indices], planner._checked[name],
                            planner._obstacles[name])
            body.set_branch(indices, values, space.steps)
            window[:, indices] = values
        for name in BRANCH_ORDER[len(moved):]:
            partial += body.frames_to_recheck(name) is not None
            got = planner.start_and_objective(times[:61], body, name)
            fresh = TimedBody(planner.kinematics, planner.shapes, planner.environment, window)
            assert got == planner.start_and_objective(times[:61], fresh, name), (trial, name)
            assert body.clear_until.get(name) == fresh.clear_until.get(name), (trial, name)
            answers.add(got)
            # Once re-checked, nothing about it is stale.
            assert body.frames_to_recheck(name) is None
    assert partial > 10
    assert len(answers) >= 2  # legal and illegal motions both occur


def test_a_branch_space_answers_the_same_with_the_pattern_checks_clear_frames(skeleton):
    # The CT-spaces do not test again the rows where the body holds a branch at frames the
    # pattern check found clear: every batch must answer as a space that knows nothing.
    from digital_actor_planner.core.body_model import TimedBody
    from digital_actor_planner.core.ct_space import CTSpace
    from digital_actor_planner.core.upper_body import BRANCH_ORDER
    planner, _ = planner_for(skeleton, box([0.6, -1.0, 1.55], [0.8, 1.0, 1.75]),
                             box([1.3, 0.2, 0.0], [2.0, 1.0, 0.8]))
    times, frames = walk(skeleton, 320)
    rng = np.random.default_rng(12)
    skipped = contacts = 0
    for trial in range(30):
        begin = int(rng.integers(0, 320 - 61))
        window = frames[begin:begin + 61]
        knowing = TimedBody(planner.kinematics, planner.shapes, planner.environment, window)
        planner.pattern_checks(times[:61], knowing)
        plain = TimedBody(planner.kinematics, planner.shapes, planner.environment, window)
        for name in BRANCH_ORDER:
            indices = planner.indices[name]
            spaces = [CTSpace(name, body, times[:61], window[:, indices],
                              planner._checked[name], planner._obstacles[name])
                      for body in (knowing, plain)]
            rows = rng.integers(0, 61, 40)
            # Half the rows where the body holds the branch, half moved off it.
            q = window[rows][:, indices] + rng.normal(0.0, 0.4, (40, len(indices))) * (
                np.arange(40) % 2)[:, None]
            answers = [space.valid_rows(q, rows) for space in spaces]
            assert answers[0].tolist() == answers[1].tolist(), (trial, name)
            held = np.arange(40) % 2 == 0
            skipped += int((held & (rows < knowing.clear_until[name])).sum())
            contacts += int((~answers[1]).sum())
    assert skipped > 100 and contacts > 20


def test_arm_roadmap_starts_with_the_arm_held_in_against_the_side(skeleton):
    # Between two pillars with the waist turned, a flexed or abducted arm sticks out sideways;
    # the roadmap starts with the arm held in, nearly straight, legal at any swing (§5.2).
    planner, _ = planner_for(skeleton)
    _, frames = walk(skeleton, 120)
    for side in ('left', 'right'):
        indices = skeleton.branch(f'{side}_arm')
        roll = skeleton.index[f'{side}_shoulder_roll'] - indices[0]
        elbow = skeleton.index[f'{side}_elbow'] - indices[0]
        objective = frames[:, indices]
        held_in = [node for node in planner.roadmaps[f'{side}_arm'].nodes
                   if np.all(skeleton.lower[indices] <= objective + node)
                   and np.all(objective + node <= skeleton.upper[indices])
                   and np.all(objective[:, roll] + node[roll] == skeleton.lower[indices][roll])
                   and np.all(objective[:, elbow] + node[elbow] < 0.2)]
        assert held_in, f'no {side} arm node held in against the side'


def test_a_branch_blocked_in_the_preview_is_reported_there(skeleton):
    # The waist must start to bend before the beam (one backtrack from frame ~151). With no
    # backtracking allowed in the preview, a preview from frame 100 gives up at once; a
    # preview that starts after the block leaves the plan as it is without one.
    beam = box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80])
    times, frames = walk(skeleton, 260)
    config = UpperBodyConfig(check_budget=1_000_000, preview_backtracks=0)
    plans = {}
    for preview_from in (None, 100, 200):
        planner, _ = planner_for(skeleton, beam, config=config)
        plans[preview_from] = planner.plan(times, frames, preview_from=preview_from)
    assert plans[None].ok and plans[200].ok
    assert np.array_equal(plans[None].frames, plans[200].frames)
    stuck = plans[100]
    assert not stuck.ok and stuck.blocked_frame >= 100
    assert stuck.reason.startswith('waist blocked at t=') and stuck.reason.endswith(
        '(in the preview)')
    with pytest.raises(ValueError, match='preview_from'):
        planner.plan(times, frames, preview_from=len(times))


def test_steps_seeded_with_the_last_plan_go_on_along_it_and_check_less(skeleton):
    # Receding horizon as the actor plans it: each step (60 frames) plus a preview (40), the
    # next step starting at the last one's end with the rest of its plan as the seed.
    beam = box([0.3, -1.0, 1.60], [0.5, 1.0, 1.80])
    times, frames = walk(skeleton, 301)
    waist = skeleton.branch('waist')
    runs = {}
    for seeded in (False, True):
        planner, collision = planner_for(skeleton, beam)
        planned, checks, followed, seeds = frames.copy(), [], [], {}
        for begin in range(0, 200, 60):
            window = slice(begin, begin + 101)
            block = planned[window].copy()
            plan = planner.plan(times[window] - times[begin], block, preview_from=61,
                                seeds=seeds if seeded else None)
            assert plan.ok, plan.reason
            planned[begin:begin + 61] = plan.frames[:61]
            checks.append(sum(r.get('checks', 0) for r in plan.per_branch.values()))
            followed.append(plan.per_branch['waist'].get('seeded', 0))
            # The rest of the plan as deviations from the motion pattern (``frames``).
            rest = plan.frames[60:] - frames[begin + 60:begin + 101]
            seeds = {name: rest[:, skeleton.branch(name)]
                     for name, record in plan.per_branch.items() if not record['fast']}
        runs[seeded] = (planned[:241], checks, followed)
        assert_collision_free(collision, planned[:241])
        assert_limits_and_speeds(skeleton, times[:241], planned[:241])
        assert planned[:241, waist[1]].max() > 0.7, 'bent under the beam'
    plain, seeded = runs[False], runs[True]
    assert max(plain[2]) == 0 and max(seeded[2]) > 0, 'a later step went on along its seed'
    # The first step that meets the beam is planned alike; the next one checks far less.
    first = next(i for i, c in enumerate(plain[1]) if c)
    assert seeded[1][first] == plain[1][first]
    assert seeded[1][first + 1] < 0.5 * plain[1][first + 1]


@pytest.mark.parametrize('seeds, match', [
    ({'torso': np.zeros((5, 2))}, "unknown branch 'torso'"),
    ({'waist': np.zeros((5, 3))}, r'waist seed must have shape \(s, 2\)'),
    ({'left_arm': np.zeros((40, 4))}, r'left_arm seed must have shape \(s, 4\) with 1 <= s <= 30'),
    ({'waist': np.zeros((0, 2))}, r'got \(0, 2\)'),
    ({'right_arm': np.full((5, 4), np.inf)}, 'right_arm seed contains NaN or infinite')])
def test_bad_seeds_name_the_branch_and_the_shape(skeleton, seeds, match):
    planner, _ = planner_for(skeleton)
    times, frames = walk(skeleton, 30)
    with pytest.raises(ValueError, match=match):
        planner.plan(times, frames, seeds=seeds)


def test_limit_checks_of_a_motion_per_group_of_columns():
    # Starts and motions inside the limits, a start outside them, a later frame outside them
    # and a joint too fast, per group: the kernel against NumPy over the whole motion.
    from digital_actor_planner.core.upper_body import _within_limits
    rng = np.random.default_rng(12)
    times = np.arange(30) / 100.0
    lower, upper, cap = -np.ones(6), np.ones(6), np.full(6, 2.0)
    groups = np.array([0, 2, 6])
    seen = set()
    for trial in range(300):
        path = np.cumsum(rng.normal(0.0, 0.005, (30, 6)), axis=0) + rng.uniform(-0.9, 0.9, 6)
        kind = trial % 4
        if kind == 1:
            path[0, rng.integers(6)] = 1.5
        elif kind == 2:
            path[rng.integers(1, 30), rng.integers(6)] = -1.2
        elif kind == 3:
            frame = rng.integers(1, 30)
            path[frame:, rng.integers(6)] += 0.05
        inside = (path >= lower) & (path <= upper)
        fast = np.vstack([np.zeros((1, 6), dtype=bool),
                          np.abs(np.diff(path, axis=0)) / np.diff(times)[:, None] > cap])
        start, legal = _within_limits(path, times, (lower, upper, cap, groups))
        for g in range(2):
            columns = slice(groups[g], groups[g + 1])
            assert start[g] == inside[0, columns].all(), trial
            assert legal[g] == (inside[:, columns].all() and not fast[:, columns].any()), trial
            seen.add((bool(start[g]), bool(legal[g])))
    assert seen == {(True, True), (True, False), (False, False)}


@pytest.mark.parametrize('where', ['time', 'leg', 'arm'])
@pytest.mark.parametrize('value', [np.nan, np.inf])
def test_non_finite_input_is_refused_wherever_it_is(skeleton, where, value):
    planner, _ = planner_for(skeleton)
    times, frames = walk(skeleton, 30)
    if where == 'time':
        times[29] = value
    else:
        frames[17, skeleton.index['left_knee' if where == 'leg' else 'left_elbow']] = value
    with pytest.raises(ValueError, match='NaN or infinite'):
        planner.plan(times, frames)


def test_objective_outside_limits_at_either_end_names_the_joint(skeleton):
    planner, _ = planner_for(skeleton)
    for frame, joint in ((0, 'waist_pitch'), (29, 'left_shoulder_roll')):
        times, frames = walk(skeleton, 30)
        frames[frame, skeleton.index[joint]] = skeleton.upper[skeleton.index[joint]] + 0.01
        with pytest.raises(ValueError, match=joint):
            planner.plan(times, frames)
