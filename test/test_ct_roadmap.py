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

"""The CT-roadmap best-first planner (paper §5.2, Figure 5)."""
from digital_actor_planner.core import ct_roadmap
from digital_actor_planner.core.ct_roadmap import _Horizon, _neighbour_table, _State, CTRoadmap, \
    direct_return
from digital_actor_planner.core.ct_space import CTSpace
from digital_actor_planner.core.environment import Environment
import numpy as np
import pytest
from scene_helpers import box, timed_body, walk

TRUNK = ('waist', 'torso', 'head', 'left_shoulder', 'right_shoulder')
LEGS = ('pelvis', 'left_hip', 'right_hip', 'left_thigh', 'right_thigh', 'left_shank',
        'right_shank', 'left_foot', 'right_foot')
PATTERNS = np.array([(0.0, 0.3), (0.0, 0.6), (0.0, 0.9), (0.4, 0.0), (-0.4, 0.0)])


def waist_space(skeleton, beam_bottom, frame_count=220):
    meshes = [box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0])]
    if beam_bottom is not None:
        meshes.append(box([0.3, -1.0, beam_bottom], [0.5, 1.0, beam_bottom + 0.2]))
    environment = Environment(meshes, resolution=0.05)
    times, frames = walk(skeleton, frame_count, swing_legs=False)
    body = timed_body(skeleton, environment, frames)
    return CTSpace('waist', body, times, frames[:, skeleton.branch('waist')], TRUNK, LEGS)


@pytest.fixture(scope='module')
def beam_space(skeleton):
    return waist_space(skeleton, 1.60)


def roadmap(seed=0, patterns=PATTERNS, max_nodes=32):
    return CTRoadmap(patterns, np.ones(2), radius=0.3, max_nodes=max_nodes,
                     rng=np.random.default_rng(seed))


def test_open_space_follows_the_objective(skeleton):
    space = waist_space(skeleton, None)
    result = roadmap().solve(space, np.zeros(2))
    assert result.ok and result.blocked_frame == -1
    assert np.array_equal(result.path, space.objective)
    assert result.backtracks == 0


def test_search_passes_under_the_beam_forward_in_time(beam_space):
    space = beam_space
    result = roadmap().solve(space, np.zeros(2))
    assert result.ok
    path = result.path
    assert path.shape == (space.frame_count, 2)
    # Every frame legal, every step within the speed limit.
    assert space.first_invalid(path[1:], np.arange(1, space.frame_count)) == -1
    speed = np.abs(np.diff(path, axis=0)) / np.diff(space.times)[:, None]
    assert np.all(speed <= space.speed_limit * (1 + 1e-6))
    assert path[:, 1].max() > 0.7
    # Best first: it stays on the objective until it must leave it, and comes back.
    assert np.all(path[:30] == 0.0)
    assert np.abs(path[-10:]).max() < 1e-9
    assert result.backtracks >= 1, 'the bend has to start before the search meets the beam'


def test_search_is_deterministic_for_a_seed(beam_space):
    first = roadmap(seed=7).solve(beam_space, np.zeros(2))
    second = roadmap(seed=7).solve(beam_space, np.zeros(2))
    assert np.array_equal(first.path, second.path)
    assert first.nodes == second.nodes


def test_roadmap_grows_when_its_patterns_are_not_enough(beam_space):
    # Only turns in the initial roadmap: the bend must come from grown nodes.
    graph = roadmap(patterns=np.array([(0.4, 0.0), (-0.4, 0.0)]), max_nodes=40)
    result = graph.solve(beam_space, np.zeros(2), node_budget=600, max_backtracks=200)
    assert result.grown > 0
    assert len(graph.nodes) == len(graph.patterns) + len(graph.grown_nodes)
    assert len(graph.nodes) <= 40
    if result.ok:
        assert beam_space.first_invalid(result.path[1:],
                                        np.arange(1, beam_space.frame_count)) == -1
    else:
        # Random growth at r = 0.3 rad rarely reaches the deep bend; the failure is reported
        # where the head meets the beam.
        assert 100 < result.blocked_frame < 170
    # The grown nodes are kept for the next plan.
    again = graph.solve(beam_space, np.zeros(2), node_budget=50, max_backtracks=10)
    assert len(graph.grown_nodes) >= min(result.grown, 40 - len(graph.patterns))
    assert again.nodes <= 51


def test_impassable_beam_fails_at_the_beam(skeleton):
    space = waist_space(skeleton, 1.05)
    result = roadmap().solve(space, np.zeros(2))
    assert not result.ok
    # The torso reaches x = 0.3 with the pelvis at about x = 0.19 (frame ~132).
    assert 110 < result.blocked_frame < 160


def test_roadmap_rejects_bad_parameters():
    with pytest.raises(ValueError, match='radius'):
        CTRoadmap(PATTERNS, np.ones(2), radius=0.0, max_nodes=10, rng=np.random.default_rng())
    with pytest.raises(ValueError, match='weights'):
        CTRoadmap(PATTERNS, np.array([1.0, 0.0]), radius=0.3, max_nodes=10,
                  rng=np.random.default_rng())
    with pytest.raises(ValueError, match='joints'):
        CTRoadmap(PATTERNS, np.ones(3), radius=0.3, max_nodes=10, rng=np.random.default_rng())
    # Tried neighbours are keyed by at most four joints.
    with pytest.raises(ValueError, match='1 to 4 joints.*5 joints'):
        CTRoadmap(np.zeros((2, 5)), np.ones(5), radius=0.3, max_nodes=10,
                  rng=np.random.default_rng())


def test_check_budget_stops_the_search_the_same_way_every_time(beam_space):
    # A work budget, unlike a wall-clock one, does not depend on the machine's load.
    results, spent = [], []
    for _ in range(2):
        before = beam_space.checks
        results.append(roadmap(seed=7).solve(beam_space, np.zeros(2), check_budget=50))
        spent.append(beam_space.checks - before)
    first, second = results
    assert not first.ok and first.blocked_frame > 0
    # Over the budget by at most one motion check and the one-off table of where the objective
    # is legal (k configurations each).
    assert spent[0] == spent[1] and spent[0] < 50 + 2 * beam_space.frame_count + 40
    assert np.array_equal(first.path, second.path) and first.nodes == second.nodes
    full = roadmap(seed=7).solve(beam_space, np.zeros(2), check_budget=1_000_000)
    assert full.ok


def test_a_posture_is_held_past_the_blocked_stretch():
    free = np.ones(40, dtype=bool)
    free[12:25] = False
    horizon = _Horizon(free, hold_frames=5)
    assert horizon.hold_end(0) == 5, 'open ground ahead: held for hold_frames'
    assert horizon.hold_end(8) == 25, 'the objective blocked at 13: held until it is free'
    assert horizon.hold_end(20) == 25
    assert horizon.hold_end(30) == 35 and horizon.hold_end(37) == 39
    assert horizon.run_start[20] == 12 and horizon.run_start[30] == 30
    free[30:] = False
    assert _Horizon(free, hold_frames=5).hold_end(28) == 39, 'blocked to the end: to the end'


def test_the_bend_is_held_under_the_beam_in_one_advance_not_hold_frames_at_a_time(beam_space):
    space = beam_space
    blocked = np.count_nonzero(~space.valid_rows(space.objective, np.arange(space.frame_count)))
    assert blocked > 30
    for hold_frames in (1, 5):
        result = roadmap().solve(space, np.zeros(2), hold_frames=hold_frames)
        assert result.ok
        assert space.first_invalid(result.path[1:], np.arange(1, space.frame_count)) == -1
        # Creeping one frame at a time would take a state per blocked frame.
        assert result.nodes < blocked


def test_following_the_objective_reaches_the_states_holding_it_would_in_one_check(skeleton):
    # The step ends under the beam: the objective is blocked at the last frame.
    space = waist_space(skeleton, 1.60, frame_count=150)
    first_blocked = space.first_invalid(space.objective[1:], np.arange(1, space.frame_count)) + 1
    assert first_blocked > 20
    horizon = _Horizon(roadmap()._objective_free(space, 5), 5)
    before = space.checks
    child = roadmap()._follow(space, _State(np.zeros(2), 3), horizon)
    assert space.checks - before <= space.frame_count, 'one motion check'
    states = child.via + [child]
    # Every hold_frames frames, on the objective, up to the last such frame before it is blocked.
    assert [s.frame for s in states] == list(range(8, first_blocked, 5))
    assert all(s.followed and not np.any(s.deviation) for s in states)
    # Open ground to the end: nothing to shortcut, the regular advance follows the objective.
    open_space = waist_space(skeleton, None, frame_count=150)
    open_horizon = _Horizon(roadmap()._objective_free(open_space, 5), 5)
    assert roadmap()._follow(open_space, _State(np.zeros(2), 0), open_horizon) is None


def test_a_long_hold_ends_in_time_to_be_back_on_the_objective_after_the_beam(beam_space):
    space = beam_space
    blocked = np.flatnonzero(~space.valid_rows(space.objective, np.arange(space.frame_count)))
    result = roadmap().solve(space, np.zeros(2))
    assert result.ok
    off = np.flatnonzero(np.abs(result.path - space.objective).max(axis=1) > 1e-9)
    # Held under the beam, but not past it: back on the pattern within one hold.
    assert off[0] < blocked[0] and off[-1] < blocked[-1] + 5


def test_a_search_stuck_in_the_preview_gives_up_within_its_small_budget(beam_space):
    # Only turns in the roadmap: getting under the beam (the head meets it after frame 100)
    # takes many backtracks (see above). With the frames from 90 on a preview, backtracking
    # from there has its own small budget.
    space = beam_space
    turns = np.array([(0.4, 0.0), (-0.4, 0.0)])
    limits = {'node_budget': 600, 'max_backtracks': 200}
    before = space.checks
    full = roadmap(seed=2, patterns=turns).solve(space, np.zeros(2), **limits)
    full_checks, before = space.checks - before, space.checks
    preview = roadmap(seed=2, patterns=turns).solve(space, np.zeros(2), preview_from=90,
                                                    preview_backtracks=1, **limits)
    preview_checks = space.checks - before
    assert not full.gave_up_in_preview and full.backtracks > 2
    assert not preview.ok and preview.gave_up_in_preview
    assert preview.blocked_frame >= 90, 'reported as blocked in the preview'
    assert preview.preview_backtracks == 2, 'gives up at the first backtrack over the budget'
    assert preview.backtracks < full.backtracks and preview_checks < full_checks
    again = roadmap(seed=2, patterns=turns).solve(space, np.zeros(2), preview_from=90,
                                                  preview_backtracks=1, **limits)
    assert np.array_equal(again.path, preview.path) and again.nodes == preview.nodes


def test_a_preview_past_the_block_leaves_the_search_unchanged(beam_space):
    # Blocks before the preview are the step's own: the preview budget does not apply to them.
    plain = roadmap(seed=7).solve(beam_space, np.zeros(2))
    late = roadmap(seed=7).solve(beam_space, np.zeros(2), preview_from=beam_space.frame_count - 1,
                                 preview_backtracks=0)
    assert plain.ok and late.ok and late.preview_backtracks == 0
    assert np.array_equal(plain.path, late.path) and plain.nodes == late.nodes


@pytest.mark.parametrize('preview_from, preview_backtracks, match', [
    (0, 1, 'preview_from'), (500, 1, 'preview_from'), (100, -1, 'preview_backtracks')])
def test_bad_preview_settings_name_the_value(beam_space, preview_from, preview_backtracks,
                                             match):
    with pytest.raises(ValueError, match=match):
        roadmap().solve(beam_space, np.zeros(2), preview_from=preview_from,
                        preview_backtracks=preview_backtracks)


def test_only_the_deep_bend_lasts_under_the_beam(beam_space):
    horizon = _Horizon(CTRoadmap._objective_free(beam_space, 5), 5)
    blocked = np.flatnonzero(~horizon.free)
    assert 100 < blocked[0] < blocked[-1] < beam_space.frame_count - 1
    targets = np.array([(0.4, 0.0), (-0.4, 0.0), (0.0, 0.3), (0.0, 0.6), (0.0, 0.9), (0, 0)])
    for here in (blocked[0] - 40, blocked[0] + 10):
        arrivals = np.full(len(targets), here + 10)
        lasting = CTRoadmap._lasting(beam_space, horizon, here, targets, arrivals)
        # Checked on its own: the deep bend, held, is legal all along the beam; the others are
        # not (the objective is blocked there by definition).
        frames = np.arange(max(here + 10, blocked[0]), blocked[-1] + 1)
        for target, lasts in zip(targets, lasting):
            held = beam_space.valid_rows(beam_space.objective[frames] + target, frames)
            assert lasts == held.all(), (here, target)
        if here < blocked[0]:
            assert lasting.tolist() == [False, False, False, False, True, False]
    # Past the beam every posture lasts: nothing is blocked ahead.
    past = blocked[-1] + 1
    assert CTRoadmap._lasting(beam_space, horizon, past, targets,
                              np.full(len(targets), past + 5)).all()


def test_a_search_preferring_lasting_postures_passes_under_the_beam(beam_space):
    graph = CTRoadmap(PATTERNS, np.ones(2), radius=0.3, max_nodes=32,
                      rng=np.random.default_rng(0), prefer_lasting=True)
    result = graph.solve(beam_space, np.zeros(2))
    assert result.ok
    path = result.path
    assert beam_space.first_invalid(path[1:], np.arange(1, beam_space.frame_count)) == -1
    speed = np.abs(np.diff(path, axis=0)) / np.diff(beam_space.times)[:, None]
    assert np.all(speed <= beam_space.speed_limit * (1 + 1e-6))
    assert np.all(path[:30] == 0.0) and np.abs(path[-10:]).max() < 1e-9


def test_a_search_seeded_with_a_legal_plan_follows_it_and_checks_far_less(beam_space):
    # Receding horizon: the previous step's plan, from where this step starts, is its seed.
    space = beam_space
    before = space.checks
    plain = roadmap(seed=3).solve(space, np.zeros(2))
    plain_checks, before = space.checks - before, space.checks
    seeded = roadmap(seed=3).solve(space, np.zeros(2), seed=plain.path - space.objective)
    seeded_checks = space.checks - before
    assert plain.ok and seeded.ok and plain.seeded == 0
    # Followed to the end of the blocked stretch under the beam, then on to the goal.
    blocked = np.flatnonzero(~_Horizon(CTRoadmap._objective_free(space, 5), 5).free)
    assert seeded.seeded > blocked[-1]
    assert seeded.backtracks == 0 and seeded_checks < plain_checks / 3
    path = seeded.path
    assert space.first_invalid(path[1:], np.arange(1, space.frame_count)) == -1
    speed = np.abs(np.diff(path, axis=0)) / np.diff(space.times)[:, None]
    assert np.all(speed <= space.speed_limit * (1 + 1e-6))
    assert np.abs(path[:seeded.seeded + 1] - plain.path[:seeded.seeded + 1]).max() < 0.05
    assert np.abs(path[-10:]).max() < 1e-9, 'back on the objective after the beam'


def test_a_seed_that_becomes_illegal_is_followed_only_while_it_is_legal(beam_space):
    # Upright all the way: legal until the head meets the beam, not after.
    space = beam_space
    blocked = np.flatnonzero(~_Horizon(CTRoadmap._objective_free(space, 5), 5).free)
    result = roadmap(seed=3).solve(space, np.zeros(2), seed=np.zeros_like(space.objective))
    assert result.ok and 0 < result.seeded < blocked[0]
    assert space.first_invalid(result.path[1:], np.arange(1, space.frame_count)) == -1


def test_a_seed_is_not_followed_where_the_objective_is_free(skeleton):
    # Nothing blocks the objective: a seed held off it (the last plan's deviation) is left,
    # the search returns to the objective as it would without one.
    space = waist_space(skeleton, None)
    held = np.tile([0.0, 0.3], (space.frame_count, 1))
    start = space.objective[0] + held[0]
    plain = roadmap().solve(space, start)
    seeded = roadmap().solve(space, start, seed=held)
    assert seeded.ok and seeded.seeded == 0
    assert np.array_equal(seeded.path, plain.path)
    assert np.abs(seeded.path[-10:] - space.objective[-10:]).max() < 1e-9


@pytest.mark.parametrize('seed, match', [
    (np.zeros((10, 3)), r'shape \(s, 2\)'), (np.zeros((0, 2)), r'shape \(s, 2\)'),
    (np.full((10, 2), np.nan), 'NaN')])
def test_bad_seeds_name_the_value(beam_space, seed, match):
    with pytest.raises(ValueError, match=match):
        roadmap().solve(beam_space, np.zeros(2), seed=seed)


def with_and_without_going_back_directly(space, start, monkeypatch):
    """Search from ``start``, then without _return_directly: (result, checks) of each."""
    out = []
    for shortcut in (True, False):
        if not shortcut:
            monkeypatch.setattr(CTRoadmap, '_return_directly', lambda *args: False)
        before = space.checks
        out.append((roadmap().solve(space, start), space.checks - before))
    return out


def test_a_start_off_the_objective_goes_back_to_it_in_one_check_where_it_is_free(
        skeleton, monkeypatch):
    # The start of a step after an obstacle is still off the pattern: best-first's first path
    # (back to the objective, then along it) is checked in one batch, without ranking.
    space = waist_space(skeleton, None, frame_count=100)
    start = space.objective[0] + np.array([0.0, 0.5])
    (direct, direct_checks), (searched, searched_checks) = \
        with_and_without_going_back_directly(space, start, monkeypatch)
    assert direct.ok and searched.ok
    assert direct.nodes == 0 and searched.nodes > 0
    assert np.allclose(direct.path, searched.path, atol=1e-12), 'the same path'
    assert direct_checks < searched_checks
    # Back on the objective as soon as the search's speed (0.8 of the limit) allows.
    step = space.times[1] - space.times[0]
    arrival = int(np.ceil(0.5 / (0.8 * space.speed_limit[1]) / step - 1e-9))
    off = np.flatnonzero(np.abs(direct.path - space.objective).max(axis=1) > 1e-9)
    assert off[-1] == arrival - 1


def test_the_way_straight_back_is_the_searchs_path_from_a_start_off_the_objective(skeleton):
    # direct_return gives the path the search takes when going back directly is legal (the
    # upper-body planner checks it for all branches in one batch before any search).
    space = waist_space(skeleton, None, frame_count=100)
    rate = 0.8 * space.speed_limit
    for change in ([0.0, 0.5], [0.3, -0.2], [1e-3, 0.0]):
        start = space.objective[0] + np.array(change)
        arrival, path = direct_return(space.objective, space.times, start, rate)
        result = roadmap().solve(space, start)
        assert result.ok and result.nodes == 0
        assert np.array_equal(path, result.path), 'the same numbers'
        step = space.times[1] - space.times[0]
        assert arrival == max(1, int(np.ceil(np.max(np.abs(change) / rate) / step - 1e-9)))
        off = np.abs(path - space.objective).max(axis=1)
        assert np.all(np.diff(off[:arrival + 1]) < 0) and off[arrival:].max() == 0.0
    # On the objective, or back only at the final frame: the search does something else.
    assert direct_return(space.objective, space.times, space.objective[0], rate) is None
    far = space.objective[0] + np.array([0.0, 50.0])
    assert direct_return(space.objective, space.times, far, rate) is None


def test_a_start_off_the_objective_is_searched_from_as_before_where_the_objective_is_blocked(
        beam_space, monkeypatch):
    start = beam_space.objective[0] + np.array([0.0, 0.5])
    (plain, plain_checks), (searched, searched_checks) = \
        with_and_without_going_back_directly(beam_space, start, monkeypatch)
    assert plain.ok and plain.nodes == searched.nodes and plain_checks == searched_checks
    assert np.array_equal(plain.path, searched.path)


def test_a_lasting_posture_is_held_up_to_the_blocked_stretch_in_one_advance(beam_space):
    # Bent deep enough to pass the beam: a search preferring lasting postures keeps the bend
    # (the objective does not last under the beam) and gets to the beam in one advance, not
    # hold_frames at a time re-ranking the same neighbours.
    space = beam_space
    blocked = np.flatnonzero(~_Horizon(CTRoadmap._objective_free(space, 5), 5).free)
    advances = []
    advance = CTRoadmap._advance

    def recording(self, space, state, *args):
        child = advance(self, space, state, *args)
        advances.append((state.frame, None if child is None else child.frame))
        return child

    graph = CTRoadmap(PATTERNS, np.ones(2), radius=0.3, max_nodes=32,
                      rng=np.random.default_rng(0), prefer_lasting=True)
    CTRoadmap._advance = recording
    try:
        result = graph.solve(space, space.objective[0] + np.array([0.0, 0.9]))
    finally:
        CTRoadmap._advance = advance
    assert result.ok and result.nodes < 8
    assert advances[0] == (0, blocked[0] - 1)
    held = result.path[:blocked[0]] - space.objective[:blocked[0]]
    assert np.abs(held - [0.0, 0.9]).max() < 1e-9
    assert space.first_invalid(result.path[1:], np.arange(1, space.frame_count)) == -1


@pytest.mark.parametrize('longest', [ct_roadmap._longest_hold,
                                     ct_roadmap._longest_hold.py_func])
def test_a_held_posture_goes_on_to_where_a_longer_hold_of_it_failed(longest):
    bend, other = np.array([0.0, 0.6]), np.array([0.0, 0.3])

    def hold(arrival, before, failures):
        return longest(bend, arrival, np.array([t for t, _ in before]),
                       np.array([a for _, a in before], dtype=np.int64),
                       np.array(failures, dtype=np.int64))

    # The long hold to frame 80 failed at frame 52: the chosen short hold to 35 goes to 51.
    assert hold(35, [(other, 40), (bend, 80)], [38, 52]) == 51
    # Not from a hold of another posture, nor from a failure sooner than the chosen arrival.
    assert hold(35, [(other, 80)], [52]) == 35
    assert hold(35, [(bend, 80)], [33]) == 35
    # Longer holds one after the other: each goes on from where the one before got it.
    assert hold(35, [(bend, 50), (bend, 80)], [45, 60]) == 59


@pytest.mark.parametrize('ranking', [ct_roadmap._ranking, ct_roadmap._ranking.py_func])
def test_neighbours_rank_as_numpy_lexsort_ranks_them(ranking):
    # The expansion kernel's order of the neighbours: lasting ones first (where the roadmap
    # prefers them), then by rounded closeness, then by ranked arrival; ties in row order.
    rng = np.random.default_rng(8)
    for trial in range(300):
        m = int(rng.integers(1, 30))
        frames = rng.integers(-6, 6, m).astype(np.int64)
        closeness = np.round(rng.choice([0.0, 0.25, 0.5, 1.0], m) + (trial % 2) * rng.random(m)
                             * (rng.random(m) < 0.5), 6)
        lasting = rng.random(m) < 0.5
        assert ranking(frames, closeness, False, lasting).tolist() == np.lexsort(
            (frames, closeness)).tolist()
        assert ranking(frames, closeness, True, lasting).tolist() == np.lexsort(
            (frames, closeness, ~lasting)).tolist()


def test_a_zero_of_either_sign_keys_the_same_tried_neighbour_and_posture():
    # numba's dictionaries compare float keys bit by bit; a target rounded from a tiny
    # negative deviation is -0.0 and must find the neighbour tried as 0.0 (it did not, and a
    # moved-pillars walk tried a motion twice and planned another path than the Python did).
    rows = np.array([[-0.0, -0.06, 0.0, -0.15], [0.0, -0.06, -0.0, -0.15]])
    assert ct_roadmap._padded(rows, 0) == ct_roadmap._padded(rows, 1)
    padded = np.array(ct_roadmap._padded(rows, 0))
    assert not (np.signbit(padded) & (padded == 0.0)).any()  # no -0.0 left
    visited = ct_roadmap._empty_visited()
    visited[ct_roadmap._visited_key(16, rows, 0)] = True
    assert ct_roadmap._visited_key(16, rows, 1) in visited
    assert ct_roadmap._visited_key(17, rows, 1) not in visited
    postures = ct_roadmap._empty_postures()
    postures[ct_roadmap._padded(rows, 1)] = 0
    assert ct_roadmap._padded(rows, 0) in postures


@pytest.mark.parametrize('prefer_lasting', [False, True])
def test_a_search_plans_the_same_with_its_expansion_kernel_as_plain_python(
        beam_space, prefer_lasting, monkeypatch):
    # Without numba the expansion runs as Python (its tried neighbours and postures in plain
    # dicts): the same search, node for node and check for check, from starts that bend,
    # backtrack and grow.
    def search(seed, start):
        graph = CTRoadmap(PATTERNS, np.ones(2), radius=0.3, max_nodes=32,
                          rng=np.random.default_rng(seed), prefer_lasting=prefer_lasting)
        before = beam_space.checks
        result = graph.solve(beam_space, beam_space.objective[0] + start)
        return result, beam_space.checks - before

    # (A start a hair off the pattern holds a target that rounds to -0.0: its key must meet
    # the 0.0 of the pattern's node, as in Python.)
    starts = [np.zeros(2), np.array([0.0, 0.9]), np.array([0.3, 0.2]), np.array([-0.4, 0.5]),
              np.array([-2e-4, 0.9]), np.array([-2e-4, 0.3])]
    compiled = [search(seed, start) for seed, start in enumerate(starts)]
    for name in ('_expand', '_lasting_from', '_empty_visited', '_empty_postures'):
        monkeypatch.setattr(ct_roadmap, name, getattr(ct_roadmap, name).py_func)
    plain = [search(seed, start) for seed, start in enumerate(starts)]
    for (a, a_checks), (b, b_checks) in zip(compiled, plain):
        assert (a.ok, a.nodes, a.backtracks, a.grown, a_checks) == (
            b.ok, b.nodes, b.backtracks, b.grown, b_checks)
        assert np.array_equal(a.path, b.path)
    # The searches did more than follow the pattern: they ranked, backtracked, grew.
    assert sum(result.nodes for result, _ in compiled) > 10
    assert any(result.backtracks for result, _ in compiled)


def test_horizon_tables_follow_their_definitions():
    # Where the objective is free next, and where each blocked stretch starts, frame by frame.
    rng = np.random.default_rng(2)
    for k in (1, 2, 7, 61, 127):
        for density in (0.0, 0.3, 0.8, 1.0):
            free = rng.random(k) >= density
            horizon = _Horizon(free, 5)
            last = k - 1
            for i in range(k + 1):
                ahead = [j for j in range(i, k) if free[j]]
                assert horizon.next_free[i] == (ahead[0] if ahead else last)
            for i in range(k):
                start = i
                while start > 0 and not free[start] and not free[start - 1]:
                    start -= 1
                assert horizon.run_start[i] == start, (k, density, i)


def test_the_path_along_a_stack_is_its_motions_then_the_last_state_held(beam_space):
    # The path kernel against motion_frames motion by motion, bit for bit: states off the
    # objective, two at the same frame, one beyond the joint limits (clipped).
    space = beam_space
    rng = np.random.default_rng(7)
    last = space.frame_count - 1
    for trial in range(20):
        frames = np.unique(np.concatenate([[0], rng.integers(1, last, rng.integers(1, 6))]))
        if trial % 5 == 0:
            frames = np.append(frames, frames[-1])  # a hold of zero length
        stack = [_State(rng.normal(0.0, 0.3 if trial % 3 else 2.0, 2), int(f)) for f in frames]
        expected = np.array(space.objective, dtype=float)
        expected[0] = space.objective[0] + stack[0].deviation
        for a, b in zip(stack[:-1], stack[1:]):
            expected[a.frame:b.frame + 1] = space.motion_frames(
                (space.objective[a.frame] + a.deviation, a.frame),
                (space.objective[b.frame] + b.deviation, b.frame))
        expected[stack[-1].frame:] = space.objective[stack[-1].frame:] + stack[-1].deviation
        expected = np.clip(expected, space.lower, space.upper)
        assert CTRoadmap._path(space, stack).tobytes() == expected.tobytes(), trial


def test_travel_frames_follow_the_slowest_joint(beam_space):
    # Frames to change a deviation at a fraction of the joint speed limits: the kernel
    # against the NumPy definition, for one change and for a batch (zero changes included).
    space = beam_space
    rng = np.random.default_rng(8)
    step = (space.times[-1] - space.times[0]) / (space.frame_count - 1)
    changes = rng.normal(0.0, 0.4, (200, 2)) * (rng.random((200, 1)) > 0.1)
    for fraction in (0.8, 1.0):
        seconds = np.max(np.abs(changes) / (fraction * space.speed_limit), axis=-1)
        expected = np.maximum(1, np.ceil(seconds / step - 1e-9).astype(int))
        found = CTRoadmap._travel_frames(space, 0, changes, fraction)
        assert found.tolist() == expected.tolist()
        assert [CTRoadmap._travel_frames(space, 0, c, fraction) for c in changes[:20]] == (
            expected[:20].tolist())
    assert set(expected.tolist()) > {1}  # some changes take one frame, others several


def _neighbours_written_out(road, space, state, horizon, fraction, sub_goal):
    """
    Rank the neighbours as _candidates does, in plain NumPy.

    The neighbours _candidates ranks, in plain NumPy: (targets, frames, closeness, index of the
    hold up to the next blocked stretch or None).
    """
    last, here, hold_frames = space.frame_count - 1, state.frame, horizon.hold_frames
    on_objective = not np.any(state.deviation)
    targets, frames = [], []
    if on_objective and not sub_goal:
        targets.append(np.zeros_like(state.deviation))
        frames.append(last)
    nodes = state.allowed if sub_goal else road.nodes
    change = nodes - state.deviation
    travels = np.atleast_1d(road._travel_frames(space, here, change, fraction))
    travels[~np.any(change, axis=1)] = hold_frames
    arrivals = here + travels
    steer = np.flatnonzero(arrivals > last)
    nodes = nodes.copy()
    share = (last - here) / travels[steer]
    nodes[steer] = state.deviation + share[:, None] * change[steer]
    arrivals[steer] = last
    targets.extend(nodes)
    frames.extend(arrivals.tolist())
    hold_end, approach = horizon.hold_end(here), None
    if hold_end > min(here + hold_frames, last) and not on_objective:
        back = road._travel_frames(space, here, state.deviation, fraction)
        hold_end = hold_end - back if hold_end < last else hold_end
        if hold_end > here + hold_frames:
            targets.append(state.deviation.copy())
            frames.append(hold_end)
    elif road.prefer_lasting and not state.relaxed and not on_objective:
        ahead = np.flatnonzero(~horizon.free[here:])
        if len(ahead) and ahead[0] - 1 > hold_frames:
            approach = len(targets)
            targets.append(state.deviation.copy())
            frames.append(here + int(ahead[0]) - 1)
    targets.append(state.deviation.copy())
    frames.append(min(here + hold_frames, last))
    targets = np.array(targets)
    return targets, np.array(frames), road.closeness(targets), approach


@pytest.mark.parametrize('table', [_neighbour_table, _neighbour_table.py_func])
def test_the_neighbour_table_is_the_neighbours_written_out(beam_space, table):
    # The kernel _candidates ranks from (compiled, and as plain Python without numba), bit for
    # bit against NumPy: on and off the objective, nodes the remaining time cannot reach
    # (steered), sub-goals, holds past a blocked stretch and up to one, with and without the
    # lasting preference.
    space = beam_space
    rng = np.random.default_rng(11)
    last = space.frame_count - 1
    seen = set()
    for trial in range(300):
        road = CTRoadmap(PATTERNS, np.array([1.0, 0.5]), radius=0.3, max_nodes=32,
                         rng=np.random.default_rng(trial), prefer_lasting=trial % 2 == 0)
        for _ in range(trial % 4):
            road._add(rng.normal(0.0, 0.5, 2))
        free = rng.random(last + 1) >= (0.0, 0.2, 0.6)[trial % 3]
        free[rng.integers(0, last + 1, 3)] = False
        horizon = _Horizon(free, 5)
        here = int(rng.choice([0, rng.integers(0, last + 1), last - rng.integers(1, 8)]))
        deviation = (np.zeros(2) if trial % 5 == 0 else
                     PATTERNS[trial % len(PATTERNS)].copy() if trial % 5 == 1 else
                     rng.normal(0.0, 0.4, 2))
        state = _State(deviation, here, relaxed=trial % 7 == 0)
        sub_goal = trial % 6 == 0
        if sub_goal:
            state.allowed, state.until = road.nodes[rng.random(len(road.nodes)) < 0.5], last
        fraction = (0.8, 1.0)[trial % 2]
        expected = _neighbours_written_out(road, space, state, horizon, fraction, sub_goal)
        (targets, frames, closeness, approach, holds, ranked_frames, ranked_closeness,
         rounded, q) = table(
            state.allowed if sub_goal else road.nodes, state.deviation, here, last,
            horizon.hold_frames, not np.any(deviation) and not sub_goal,
            not np.any(deviation), road.prefer_lasting and not state.relaxed, space.times,
            fraction * space.speed_limit, horizon.hold_end(here), horizon.free, road.weights,
            space.objective)
        assert targets.tobytes() == expected[0].tobytes(), trial
        assert frames.tolist() == expected[1].tolist(), trial
        assert closeness.tobytes() == expected[2].tobytes(), trial
        assert (None if approach < 0 else approach) == expected[3], trial
        # What _candidates ranks them by, and checks.
        expected_holds = ~np.any(expected[0] != state.deviation, axis=1)
        assert holds.tolist() == expected_holds.tolist(), trial
        assert ranked_frames.tolist() == np.where(expected_holds | (not np.any(deviation)),
                                                  -expected[1], expected[1]).tolist(), trial
        assert ranked_closeness.tobytes() == np.round(expected[2], 6).tobytes(), trial
        assert rounded.tobytes() == np.round(expected[0], 3).tobytes(), trial
        assert q.tobytes() == (space.objective[expected[1]] + expected[0]).tobytes(), trial
        seen.add(('hold', bool(holds.any()), bool((~holds).any())))
        seen.add((len(frames) > len(road.nodes) + 1, expected[3] is not None,
                  bool((frames == last).any())))
    # Long holds, approach holds and steered nodes all occurred.
    assert ('hold', True, True) in seen
    seen = {flags for flags in seen if flags[0] != 'hold'}
    assert {flags[0] for flags in seen} == {True, False}
    assert True in {flags[1] for flags in seen} and True in {flags[2] for flags in seen}


def _lasting_written_out(space, horizon, held, here, targets, arrivals):
    """
    Tell whether each target lasts through the blocked stretch, in plain Python.

    Whether each target, held from its arrival, lasts through the blocked stretch ahead, in plain
    Python with a dict cache ``held`` of (frame, rounded posture) -> legal: (lasting,
    configurations checked).
    """
    lasting = np.ones(len(targets), dtype=bool)
    blocked = np.flatnonzero(~horizon.free[here:])
    if not len(blocked):
        return lasting, 0
    begin = here + int(blocked[0])
    end = int(horizon.next_free[begin])
    spacing, grids, checks = horizon.hold_frames, {}, 0
    for i, arrival in enumerate(arrivals.tolist()):
        if arrival > end:
            continue
        if not targets[i].any():
            lasting[i] = bool(horizon.free[arrival:end + 1].all())
            continue
        grid = [begin] if arrival < begin else []
        grid += list(range(max(arrival, begin) // spacing * spacing + spacing, end, spacing))
        grids[i] = (tuple(np.round(targets[i], 4).tolist()), grid + [end])
    for coarse in (True, False):
        rows, frames, keys = [], [], []
        for i, (posture, grid) in grids.items():
            if not lasting[i]:
                continue
            for frame in (grid[::-1][::ct_roadmap.COARSE_STRIDE] if coarse else grid):
                known = held.get((frame, posture))
                if known is None:
                    rows.append(i)
                    frames.append(frame)
                    keys.append((frame, posture))
                elif not known:
                    lasting[i] = False
        if rows:
            legal = space.valid_rows(space.objective[frames] + targets[rows], np.array(frames))
            checks += len(rows)
            for key, is_legal, row in zip(keys, legal.tolist(), rows):
                held[key] = is_legal
                lasting[row] &= is_legal
    return lasting, checks


@pytest.mark.parametrize('table', [ct_roadmap._lasting_table, ct_roadmap._lasting_table.py_func])
def test_the_lasting_check_is_written_out_with_its_cache(beam_space, table, monkeypatch):
    # Successive states of a search share what is known of a posture at a frame: the kernel
    # and its cache (a table of postures by frame) against plain Python with a dict, over a
    # sequence of calls on one horizon: the same answers, the same configurations checked.
    # Targets repeat (also within a call, equal to 1e-4 rad), arrive before, inside and after
    # the blocked stretch, or do not move.
    monkeypatch.setattr(ct_roadmap, '_lasting_table', table)
    space = beam_space
    rng = np.random.default_rng(21)
    horizon = _Horizon(CTRoadmap._objective_free(space, 5), 5)
    blocked = np.flatnonzero(~horizon.free)
    held = {}
    pool = np.vstack([PATTERNS, rng.normal(0.0, 0.4, (6, 2)), np.zeros((1, 2))])
    outcomes = set()
    for call in range(60):
        here = int(rng.integers(0, blocked[-1] + 1))
        targets = pool[rng.integers(0, len(pool), rng.integers(1, 9))]
        if call % 3 == 0:
            targets = np.vstack([targets, targets[:1] + 2e-5])  # the same rounded posture
        arrivals = here + rng.integers(1, 60, len(targets))
        before = space.checks
        found = CTRoadmap._lasting(space, horizon, here, np.ascontiguousarray(targets),
                                   arrivals.astype(np.int64))
        checked = space.checks - before
        expected, expected_checks = _lasting_written_out(space, horizon, held, here, targets,
                                                         arrivals)
        assert found.tolist() == expected.tolist(), call
        assert checked == expected_checks, call
        outcomes.update(found.tolist())
        outcomes.add(('checked', checked > 0))
    assert outcomes == {True, False, ('checked', True), ('checked', False)}


@pytest.mark.parametrize('grown', [ct_roadmap._grown_node, ct_roadmap._grown_node.py_func])
def test_a_grown_node_is_the_numpy_written_out(beam_space, grown):
    # _grow's node (the state moved r along a random direction of unit weighted norm, timed at
    # a fraction of the speed limits, kept within the limits), bit for bit against NumPy;
    # nodes clipped at the limits and nodes arriving at the final frame both occur.
    space = beam_space
    rng = np.random.default_rng(31)
    weights = np.array([1.0, 0.5])
    last = space.frame_count - 1
    clipped = capped = False
    for trial in range(300):
        direction = rng.normal(size=2)
        deviation = rng.normal(0.0, 0.6, 2)
        frame = int(rng.integers(0, last + 1))
        radius = float(rng.choice([0.3, 1.5]))
        rate = (0.8, 1.0)[trial % 2] * space.speed_limit
        unit = direction / np.sqrt(np.sum(weights * direction * direction))
        moved = deviation + radius * unit
        travel = max(1, int(np.ceil(np.max(np.abs(moved - deviation) / rate)
                                    / ((space.times[-1] - space.times[0]) / last) - 1e-9)))
        arrival = min(frame + travel, last)
        q = np.clip(space.objective[arrival] + moved, space.lower, space.upper)
        found, found_arrival = grown(direction, deviation, frame, radius, weights, space.times,
                                     rate, space.objective, space.lower, space.upper)
        assert found_arrival == arrival, trial
        assert found.tobytes() == (q - space.objective[arrival]).tobytes(), trial
        clipped |= bool(np.any(q != space.objective[arrival] + moved))
        capped |= frame + travel > last
    assert clipped and capped
