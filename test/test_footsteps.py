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

"""The sliding-window footstep planner (§4.2) on synthetic ground profiles."""
from digital_actor_planner.core import footstep_search, footsteps
from digital_actor_planner.core.footstep_window import (
    configuration_effort, FootholdTable, search_footstep_window, WindowFeet)
from digital_actor_planner.core.footsteps import (
    FootstepConfig, FootstepPlanner, GroundProfile, LEFT, RIGHT, validate_footstep_config)
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest

DS = 0.02
#: Where the tests' windows start: the right foot standing at 0, the left one 5 cm behind it.
FEET = WindowFeet(stance_s=0.0, stance_height=0.0, swing_s=-0.05, swing_height=0.0, s_init=0.5,
                  previous_length=0.45)
#: The compiled search's functions (footstep_search), each calling the ones before.
SEARCH_KERNELS = ('_judge_sole', 'judge_footholds', '_entry_sides', '_unjudged_tables',
                  'foothold_tables',
                  '_empty_memos', '_digits', '_step_cost', '_rise_ahead',
                  '_swing_clear', '_effort', '_footholds_of', 'window_search',
                  'exhaustive_search')


@pytest.fixture(scope='module')
def leg():
    return Skeleton().leg


@pytest.fixture(params=['compiled', 'plain'])
def search_kind(request, monkeypatch):
    """
    Return the footstep search compiled, or as plain Python.

    The footstep search compiled, or as the plain Python it runs as without numba (every kernel's
    ``py_func``, calling each other).
    """
    if request.param == 'plain':
        for name in SEARCH_KERNELS:
            plain = getattr(footstep_search, name).py_func
            monkeypatch.setattr(footstep_search, name, plain)
            if hasattr(footsteps, name):
                monkeypatch.setattr(footsteps, name, plain)
    return request.param


def profile_from(height_of, length=4.0, s0=-0.3):
    """Make a two-track profile from a height function of arc length (NaN = hole)."""
    s = s0 + DS * np.arange(int(length / DS))
    h = np.array([height_of(v) for v in s], dtype=float)
    both = np.vstack([h, h])
    obstacle = both.copy()
    return GroundProfile(s0=s0, ds=DS, height=both, low=both.copy(),
                         headroom=np.full_like(both, np.inf), obstacle=obstacle)


def plan(planner, profile, s_init=0.5, start=None, banned=()):
    return planner.plan(profile, RIGHT, 0.0, 0.0, 0.0, 0.0, s_init, 0.5, start=start,
                        banned_first=banned)


def readable_effort(planner, table, configuration, feet=FEET, banned=frozenset()):
    """Return the readable search's effort of a configuration, None where it collides."""
    return configuration_effort(tuple(int(j) for j in configuration), table,
                                planner.window_limits, feet, frozenset(banned))


def test_a_profile_keeps_its_samples_stacked_for_the_search_and_refuses_mismatched_ones():
    """
    A profile keeps its samples stacked for the search and refuses mismatched ones.

    The search reads the profile's samples as one (4, 2, K) array: height, low and headroom are
    views of it, the obstacle is there with -inf over empty space (NaN in the profile's own), and
    the sampler's profile (which writes the array itself) is the same as one made from its four
    arrays. Sample arrays of different shapes are refused, naming the shapes.
    """
    profile = profile_from(lambda s: np.nan if 0.5 < s < 0.7 else 0.1 * s)
    stacked = profile.stacked
    assert stacked.shape == (4,) + profile.height.shape and stacked.flags.c_contiguous
    for k, name in enumerate(('height', 'low', 'headroom')):
        assert np.shares_memory(getattr(profile, name), stacked[k]), name
    empty = np.isnan(profile.obstacle)
    assert empty.any() and np.all(stacked[3][empty] == -np.inf)
    np.testing.assert_array_equal(stacked[3][~empty], profile.obstacle[~empty])
    remade = GroundProfile(s0=profile.s0, ds=profile.ds, height=profile.height.copy(),
                           low=profile.low.copy(), headroom=profile.headroom.copy(),
                           obstacle=profile.obstacle.copy())
    np.testing.assert_array_equal(remade.stacked, stacked)
    with pytest.raises(ValueError, match=r'\(2, 200\).*\(2, 199\)'):
        GroundProfile(s0=0.0, ds=DS, height=np.zeros((2, 200)), low=np.zeros((2, 200)),
                      headroom=np.zeros((2, 200)), obstacle=np.zeros((2, 199)))
    with pytest.raises(ValueError, match='must all be'):
        GroundProfile(s0=0.0, ds=DS, height=np.zeros(200), low=np.zeros(200),
                      headroom=np.zeros(200), obstacle=np.zeros(200))
    # Samples handed over already stacked are read by the search without numba's checks of
    # its arguments: one of another layout or type is refused, not read as if it were right.
    views = {'height': stacked[0], 'low': stacked[1], 'headroom': stacked[2],
             'obstacle': profile.obstacle}
    for bad, named in ((stacked[:, :, ::2], r'\(4, 2, 100\)'),
                       (stacked.astype(np.float32), 'float32'),
                       (stacked[:3], r'\(3, 2, 200\)'), (stacked.tolist(), 'list')):
        with pytest.raises(ValueError, match='stacked ground profile samples.*' + named):
            GroundProfile(s0=0.0, ds=DS, stacked=bad, **views)
    frozen = stacked.copy()
    frozen.setflags(write=False)
    with pytest.raises(ValueError, match='writable'):
        GroundProfile(s0=0.0, ds=DS, stacked=frozen, **views)


def test_the_sampled_profile_writes_the_stacked_samples_itself():
    """
    The sampled profile writes the stacked samples itself.

    sample_ground_profile hands its (4, 2, K) array to the profile; the profile made from the same
    four arrays stacks them alike.
    """
    from digital_actor_planner.core.environment import Environment
    from digital_actor_planner.core.path import predict_path
    import trimesh
    near = trimesh.creation.box(extents=(4.6, 6.0, 0.2))
    near.apply_translation((-0.7, 0.0, -0.1))  # to x = 1.6, then a gap of 0.3 m
    far = trimesh.creation.box(extents=(2.0, 6.0, 0.2))
    far.apply_translation((2.9, 0.0, -0.1))
    step = trimesh.creation.box(extents=(0.4, 6.0, 0.15))
    step.apply_translation((1.0, 0.0, 0.075))
    environment = Environment([near, far, step])
    path = predict_path(0.0, 0.0, 0.0, 0.8, 0.0, 3.0)
    profile = footsteps.sample_ground_profile(environment, path, -0.3, 2.5, DS, 0.1, 0.1,
                                              0.0, 0.2, 3)
    assert np.shares_memory(profile.height, profile.stacked)
    assert np.isnan(profile.obstacle).any()  # over the gap
    remade = GroundProfile(s0=profile.s0, ds=profile.ds, height=profile.height.copy(),
                           low=profile.low.copy(), headroom=profile.headroom.copy(),
                           obstacle=profile.obstacle.copy())
    np.testing.assert_array_equal(remade.stacked, profile.stacked)
    assert np.nanmax(profile.height) == pytest.approx(0.15, abs=1e-6)


def test_flat_ground_keeps_the_neutral_length(leg):
    planner = FootstepPlanner(FootstepConfig(), leg)
    window = plan(planner, profile_from(lambda s: 0.0), s_init=0.55)
    assert window is not None
    assert len(window.lengths) == 3
    np.testing.assert_allclose(window.lengths, window.lengths[0])
    assert abs(window.lengths[0] - 0.55) <= FootstepConfig().step_increment / 2 + 1e-9
    assert list(window.sides) == [LEFT, RIGHT, LEFT]


def test_a_hole_is_strided_over_and_no_foot_lands_in_it(leg):
    hole = (0.9, 1.3)
    planner = FootstepPlanner(FootstepConfig(), leg)
    window = plan(planner, profile_from(lambda s: np.nan if hole[0] < s < hole[1] else 0.0))
    assert window is not None
    for s in window.arc_lengths:
        assert s + leg.toe <= hole[0] + 1e-9 or s - leg.heel >= hole[1] - 1e-9


def test_a_footstep_with_nowhere_to_land_ends_the_search_at_once(leg, search_kind):
    """
    A footstep with nowhere to land ends the search at once.

    Where the ground ends a little ahead, the second and third footsteps have no foothold in reach:
    the search answers none having judged the start alone, not the breadth-first search through all
    2,744 configurations (it looks for a footstep without footholds only once the start is not
    free).
    """
    planner = FootstepPlanner(FootstepConfig(), leg)
    cliff = profile_from(lambda s: 0.0 if s < 0.4 else np.nan)
    arguments = (cliff, RIGHT, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5)
    assert planner.plan(*arguments) is None
    config, footholds, effort, judged = footstep_search.window_search(
        (6 * 14 + 6) * 14 + 6, planner._none_banned, planner._none_banned, True,
        planner.search_profile(*arguments))
    assert config == -1 and footholds.shape == (4, 0) and np.isnan(effort)
    assert judged == 1
    # The exhaustive search agrees that no configuration is free.
    assert planner.plan_exhaustive(*arguments) is None


def test_a_step_up_higher_than_allowed_makes_the_window_infeasible(leg):
    planner = FootstepPlanner(FootstepConfig(), leg)
    wall = profile_from(lambda s: 0.0 if s < 0.6 else 0.5)
    window = plan(planner, wall)
    assert window is None
    stairs = profile_from(lambda s: 0.0 if s < 0.6 else 0.15)
    window = plan(planner, stairs)
    assert window is not None and max(window.heights) == pytest.approx(0.15, abs=0.02)


def test_a_foot_placed_before_a_face_keeps_room_to_lift_off(leg):
    # A 0.22 m block's face 0.71 m ahead of the stance toe, 0.6 m long, the ground beyond it at
    # 0.0: footstep 0 must not end with its toe within lift_room of the face unless the window's
    # footstep 2 then steps up (bench_terrain: the rear foot 2 cm from a block's face, no swing
    # can lift it over the block).
    face, top = 0.89, 0.22
    profile = profile_from(lambda s: top if face <= s < face + 0.6 else 0.0)
    planner = FootstepPlanner(FootstepConfig(), leg)
    room = planner.config.lift_room
    memo = planner.foothold_table(profile, RIGHT, 0.0)
    s = 0.0 + planner.config.lengths()
    rise = np.array(memo.rise_ahead[0])
    toe_gap = face - (s + leg.toe)
    near = (toe_gap >= 0) & (toe_gap <= room - 0.01 + 1e-9)
    far = toe_gap > room + DS
    assert near.any() and far.any()
    assert np.all(rise[near] > top - 0.01) and np.all(np.abs(rise[far]) < 1e-9)
    j0 = int(np.flatnonzero(near)[0])
    for j1 in range(14):
        for j2 in range(14):
            config = (j0, j1, j2)
            effort = readable_effort(planner, memo, config)
            # Footstep 2 swings from footstep 0's foothold: only onto the block.
            if effort is not None:
                assert memo.height[2][j0 + j1 + j2] > top - 0.02, config
    # Without the room (lift_room 0) the same footstep 0 has windows that stride on.
    loose = FootstepPlanner(FootstepConfig(lift_room=0.0), leg)
    plain = loose.foothold_table(profile, RIGHT, 0.0)
    assert any(readable_effort(loose, plain, (j0, j1, j2)) is not None
               and plain.height[2][j0 + j1 + j2] < 0.01
               for j1 in range(14) for j2 in range(14))
    # Before a 0.28 m face the foot may not even step up onto it (lift_step_up 0.25: the knee
    # of a foot that close could not fold that far), before a 0.2 m riser it may.
    for height, steps_up in ((0.28, False), (0.2, True)):
        block = profile_from(lambda s: height if face <= s < face + 0.6 else 0.0)
        tables = planner.foothold_table(block, RIGHT, 0.0)
        assert steps_up == any(readable_effort(planner, tables, (j0, j1, j2)) is not None
                               for j1 in range(14) for j2 in range(14)), height
    # A ramp ahead of the toe is the sole's plane carried on, and a low bump is within
    # lift_rise: neither is a face.
    ramp = profile_from(lambda s: 0.25 * s)
    ok, height, pitch = planner.footholds(ramp, LEFT, np.array([0.6]))
    assert ok[0] and planner.rise_ahead(ramp, LEFT, np.array([0.6]), height, pitch)[0] < 0.005
    bump = profile_from(lambda s: 0.02 if 0.99 < s < 1.1 else 0.0)
    s = np.array([1.0 - leg.toe - 0.01])
    ok, height, pitch = planner.footholds(bump, LEFT, s)
    assert planner.rise_ahead(bump, LEFT, s, height, pitch)[0] <= planner.config.lift_rise


def test_window_slides_from_the_previous_solution(leg):
    planner = FootstepPlanner(FootstepConfig(), leg)
    profile = profile_from(lambda s: 0.0)
    first = plan(planner, profile)
    slid = tuple(first.indices[1:]) + (first.indices[0],)
    second = plan(planner, profile, start=slid)
    assert second.indices == slid  # already optimal: hill-climbing keeps it
    # Itself and its neighbours: each footstep one interval longer or shorter (2 n), and each
    # adjacent pair moved in opposite directions (2 (n - 1)).
    assert second.evaluated <= 2 * 3 + 2 * 2 + 1


def test_banned_first_step_is_avoided(leg):
    planner = FootstepPlanner(FootstepConfig(), leg)
    profile = profile_from(lambda s: 0.0)
    first = plan(planner, profile)
    other = plan(planner, profile, banned=(first.indices[0],))
    assert other.indices[0] != first.indices[0]

    def shortest(banned=()):  # the neutral and the previous length both the shortest
        return planner.plan(profile, RIGHT, 0.0, 0.0, 0.0, 0.0, 0.15, 0.15,
                            banned_first=banned).indices[0]

    # Any sequence of indices bans them, an array too (index 0 included: not read as False).
    assert shortest() == 0
    for banned in (np.array([0]), [0], np.array([0, 1])):
        assert shortest(banned) not in banned


def test_search_is_near_optimal_and_much_cheaper_than_exhaustive(leg):
    """BFS + hill-climbing vs the exhaustive optimum of the same window."""
    rng = np.random.default_rng(7)
    planner = FootstepPlanner(FootstepConfig(), leg)
    ratios, evaluated = [], []
    for _ in range(15):
        holes = np.sort(rng.uniform(0.3, 2.6, size=2))
        levels = rng.choice([0.0, 0.1, 0.2], size=3)

        def height(s, holes=holes, levels=levels):
            if holes[0] < s < holes[0] + 0.3 or holes[1] < s < holes[1] + 0.25:
                return np.nan
            return levels[int(np.clip(s // 1.2, 0, 2))]

        profile = profile_from(height)
        s_init = float(rng.uniform(0.3, 0.7))
        window = plan(planner, profile, s_init=s_init)
        best = planner.plan_exhaustive(profile, RIGHT, 0.0, 0.0, 0.0, 0.0, s_init, 0.5)
        assert (window is None) == (best is None)
        if window is None:
            continue
        assert window.effort >= best.effort - 1e-12
        ratios.append((window.effort + 1e-3) / (best.effort + 1e-3))
        evaluated.append(window.evaluated / best.evaluated)
    assert len(ratios) >= 5, 'too few feasible random profiles for the comparison to mean much'
    assert np.median(ratios) <= 1.05
    assert np.median(evaluated) < 0.1


def test_greedy_restart_finds_the_stair_by_stair_optimum(leg):
    """
    The greedy restart finds the stair-by-stair optimum.

    On stairs the paper's search settles on long strides that skip treads; the second climb from a
    footstep-by-footstep start finds the optimum (one tread per footstep).
    """
    paper = FootstepPlanner(FootstepConfig(greedy_restart=False), leg)
    planner = FootstepPlanner(FootstepConfig(), leg)
    paper_ratios, ratios = [], []
    for tread in (0.3, 0.32, 0.35):
        stairs = profile_from(
            lambda s, tread=tread: 0.12 * (np.floor((s - 0.4) / tread) + 1) if s > 0.4 else 0.0)
        best = planner.plan_exhaustive(stairs, RIGHT, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5)
        window = plan(planner, stairs)
        ratios.append((window.effort + 1e-3) / (best.effort + 1e-3))
        paper_ratios.append((plan(paper, stairs).effort + 1e-3) / (best.effort + 1e-3))
        # The stair-by-stair configuration: every later foothold one tread further.
        assert np.allclose(np.diff(window.arc_lengths), tread, atol=0.05)
    assert max(ratios) <= 1.05
    assert min(paper_ratios) > 1.2


def test_config_validation_names_the_field(leg):
    with pytest.raises(ValueError, match='window_steps'):
        validate_footstep_config(FootstepConfig(window_steps=0))
    with pytest.raises(ValueError, match='step_length_min'):
        validate_footstep_config(FootstepConfig(step_length_min=0.9, step_length_max=0.8))
    with pytest.raises(ValueError, match='step_intervals'):
        FootstepPlanner(FootstepConfig(step_intervals=0), leg)
    with pytest.raises(ValueError, match=r'lift_room must be .*>= 0 m, got -0.01'):
        FootstepPlanner(FootstepConfig(lift_room=-0.01), leg)
    with pytest.raises(ValueError, match=r'lift_rise must be .*>= 0 m, got nan'):
        FootstepPlanner(FootstepConfig(lift_rise=float('nan')), leg)
    with pytest.raises(ValueError, match=r'lift_step_up must be .*>= 0 m, got inf'):
        FootstepPlanner(FootstepConfig(lift_step_up=float('inf')), leg)


def test_bad_plan_arguments_are_named(leg):
    planner = FootstepPlanner(FootstepConfig(), leg)
    profile = profile_from(lambda s: 0.0)
    with pytest.raises(ValueError, match=r'stance side 2 '):
        planner.plan(profile, 2, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5)
    with pytest.raises(ValueError, match=r'start configuration \(1, 2, 14\)'):
        plan(planner, profile, start=(1, 2, 14))
    # Both feet planned after the errors, as before them.
    assert plan(planner, profile) is not None


def _reference_foothold(config, leg, profile, side, s):
    """
    Evaluate one sole on its own with slices.

    One sole evaluated on its own with slices: (ok, height, pitch), the rules of
    :meth:`FootstepPlanner.footholds` written out sole by sole.
    """
    # The samples under the sole, heel to toe (none beyond its ends).
    i0 = int(np.ceil((s - leg.heel - profile.s0) / profile.ds - 1e-9))
    i1 = int(np.floor((s + leg.toe - profile.s0) / profile.ds + 1e-9))
    if i0 < 0 or i1 >= profile.samples:
        return False, np.nan, 0.0
    high = profile.height[side, i0:i1 + 1]
    if np.any(np.isnan(high)) or np.min(profile.headroom[side, i0:i1 + 1]) < config.min_headroom:
        return False, np.nan, 0.0
    low = profile.low[side, i0:i1 + 1]
    x = profile.s0 + profile.ds * np.arange(i0, i1 + 1) - s
    xc = x - x.mean()
    slope = float(np.dot(xc, high) / np.dot(xc, xc)) if x.size > 2 else 0.0
    pitch = float(np.arctan(slope))
    lift = float(np.max(high - slope * x))
    if (abs(pitch) <= config.max_foot_pitch
            and lift - float(np.min(low - slope * x)) <= config.flatness_tolerance):
        return True, lift, pitch
    # An edge: the sole rests level on the top, whatever the plane through all its samples.
    top = float(np.max(high))
    level = top - config.flatness_tolerance
    supported = (high >= level) & (low >= level)
    ankle = int(np.argmin(np.abs(x)))
    if (supported[max(ankle - 1, 0):ankle + 2].all()
            and supported.mean() >= config.min_support_fraction):
        return True, top, 0.0
    return False, np.nan, pitch


def test_batched_footholds_agree_with_the_single_foothold(leg):
    """The planner's batched foothold table gives what one sole evaluated alone gives."""
    rng = np.random.default_rng(7)
    planner = FootstepPlanner(FootstepConfig(), leg)
    count = 200
    s0 = -0.3
    steps = np.repeat(rng.choice([0.0, 0.12, 0.3, -0.2], size=count // 10), 10)
    rough = steps + rng.normal(0.0, 0.002, count) + 0.2 * np.sin(np.arange(count) * 0.05)
    high = np.vstack([rough, rough + rng.normal(0.0, 0.003, count)])
    low = high - np.abs(rng.normal(0.0, 0.002, high.shape))
    high[0, 60:64] = np.nan
    low[0, 60:64] = np.nan
    headroom = np.where(rng.random(high.shape) < 0.005, 0.5, np.inf)
    profile = GroundProfile(s0=s0, ds=DS, height=high, low=low, headroom=headroom,
                            obstacle=high.copy())
    s = np.concatenate([np.linspace(s0 - 0.2, s0 + DS * count + 0.2, 700),
                        rng.uniform(s0, s0 + DS * count, 300)])
    kinds = set()
    for side in (LEFT, RIGHT):
        ok, height, pitch = planner.footholds(profile, side, s)
        for k, value in enumerate(s):
            single_ok, single_height, single_pitch = _reference_foothold(
                planner.config, leg, profile, side, float(value))
            assert ok[k] == single_ok, (side, value)
            one = planner.foothold(profile, side, float(value))
            assert one.ok == single_ok
            if single_ok:
                assert height[k] == pytest.approx(single_height, abs=1e-12)
                assert pitch[k] == pytest.approx(single_pitch, abs=1e-12)
                assert one.height == pytest.approx(single_height, abs=1e-12)
                kinds.add('flat' if single_pitch != 0.0 else 'edge or level')
            else:
                assert np.isnan(height[k])
                kinds.add('refused')
    assert kinds == {'flat', 'edge or level', 'refused'}


def _memos(n=3, m=13, prefix_rows=None, swings=True):
    """
    Return empty prefix and swing memos as a search makes them.

    Empty prefix and swing memos as a search of a window of ``n`` footsteps and ``m`` intervals
    makes them (``footstep_search._empty_memos``), the prefix memo cut to its first ``prefix_rows``
    rows (the prefixes of fewer footsteps) and the swing memo left out if asked: the effort must
    come out the same with less remembered.
    """
    _, prefixes, swing_memo = footstep_search._empty_memos(n, m, True)
    if prefix_rows is not None:
        prefixes = np.ascontiguousarray(prefixes[:prefix_rows])
    return prefixes, swing_memo if swings else swing_memo[:0].copy()


@pytest.mark.parametrize('memo', ['whole', 'one-footstep prefixes, no swings', 'none'])
def test_the_compiled_effort_from_prefixes_is_the_readable_effort(leg, search_kind, memo):
    """
    The compiled effort from prefixes is the readable effort.

    The compiled search's effort, resumed from the prefixes of the configurations judged before it,
    is the readable search's (footstep_window.configuration_effort) to the last bit (NaN where
    that is None), feasible or not, whatever order the configurations come in; also where the
    memos hold only the prefixes of one footstep and no swing (as in a window with too many to
    keep) or nothing (as the exhaustive search judges).
    """
    rng = np.random.default_rng(5)
    planner = FootstepPlanner(FootstepConfig(), leg)
    terrain = {'steps': lambda s: 0.15 * np.floor(max(s - 0.5, 0.0) / 0.35),
               'hole': lambda s: np.nan if 0.7 < s < 1.1 else 0.0,
               'bumps': lambda s: 0.3 if 1.2 < s < 1.25 else 0.02 * np.sin(7 * s)}
    answers = set()
    arguments = (0.0, 0.0, -0.05, 0.0, 0.5, 0.45)
    for name, height_of in terrain.items():
        profile = profile_from(height_of)
        plain = planner.foothold_table(profile, RIGHT, 0.0)
        tables = planner.search_tables(profile, RIGHT, *arguments)
        configs = [tuple(int(j) for j in c) for c in rng.integers(0, 14, (600, 3))]
        configs += [c[:2] + (int(j),) for c in configs[:200] for j in rng.integers(0, 14, 2)]
        for banned in (set(), {5}):
            banned_first = np.isin(np.arange(14), list(banned))
            prefixes, swings = {'whole': _memos(),
                                'one-footstep prefixes, no swings': _memos(prefix_rows=14,
                                                                           swings=False),
                                'none': _memos(prefix_rows=0, swings=False)}[memo]
            for config in configs:
                expected = readable_effort(planner, plain, config, banned=banned)
                got = footstep_search._effort(np.array(config), banned_first, tables,
                                              prefixes, swings)
                if expected is None:
                    assert np.isnan(got), (name, config)
                else:
                    assert got == expected, (name, config)
                answers.add(expected is None)
            # Resumed, not judged afresh, wherever there is room to remember.
            remembered = (prefixes[:, 5] != 0).sum()
            assert remembered > {'whole': 100, 'none': -1}.get(memo, 10), memo
            assert (swings >= 0).sum() > 20 or memo != 'whole'
    assert answers == {True, False}


def test_the_compiled_effort_is_the_readable_effort_on_random_tables(leg, search_kind):
    """
    The compiled effort is the readable effort on random tables.

    The same on random foothold tables (heights, pitches, holes), obstacles (faces near the toes,
    gaps) and walking speeds: tens of thousands of distinct values in every term of the effort and
    in the swing test. Its squares computed as x * x (what numba makes of a constant square)
    instead of Python's x ** 2 change about 12 of these efforts in the last bit (checked: the test
    fails then).
    """
    rng = np.random.default_rng(17)
    planner = FootstepPlanner(FootstepConfig(lift_room=0.1), leg)
    step, offsets, _ = planner._table_layout
    sides = np.array([LEFT, RIGHT, LEFT])
    profile = profile_from(lambda s: 0.0)
    answers = []
    for _ in range(600):
        arguments = (0.0, float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.4, -0.1)),
                     float(rng.uniform(-0.05, 0.05)), float(rng.uniform(0.2, 0.8)),
                     float(rng.uniform(0.2, 0.8)))
        tables = list(planner.search_tables(profile, RIGHT, *arguments))
        count = tables[0].size
        ok = rng.random(count) < 0.85
        height = np.where(ok, rng.uniform(-0.15, 0.15, count), np.nan)
        pitch = np.where(ok, rng.uniform(-0.3, 0.3, count), 0.0)
        obstacle = rng.uniform(-0.3, 0.12, tables[5].shape)
        obstacle[rng.random(obstacle.shape) < 0.01] = 0.45
        obstacle[rng.random(obstacle.shape) < 0.1] = -np.inf
        tables[0], tables[1], tables[2], tables[5] = ok, height, pitch, obstacle
        # The same footholds and obstacles for the readable search (NaN over empty space).
        ground = GroundProfile(s0=profile.s0, ds=profile.ds, height=profile.height,
                               low=profile.low, headroom=profile.headroom,
                               obstacle=np.where(np.isinf(obstacle), np.nan, obstacle))
        rise = planner.rise_ahead(ground, sides[step], 0.0 + offsets, height, pitch)
        bounds = tables[3]

        def rows(values):
            return tuple(tuple(values[a:b].tolist()) for a, b in zip(bounds[:-1], bounds[1:]))

        plain = FootholdTable(ok=rows(ok), height=rows(height), pitch=rows(pitch),
                              rise_ahead=rows(rise), sides=tuple(sides.tolist()),
                              swing_top=ground.swing_top, toe=float(leg.toe),
                              heel=float(leg.heel))
        feet = WindowFeet(*arguments)
        for config in rng.integers(0, 14, (150, 3)):
            config = tuple(int(j) for j in config)
            expected = readable_effort(planner, plain, config, feet=feet)
            # Nothing remembered: the swing memo keeps the first answer for a foothold, and
            # footstep lengths of one sum can place its heel either side of a sample boundary
            # (resumed from the memos on terrain: the test above).
            prefixes, swings = _memos(prefix_rows=0, swings=False)
            got = footstep_search._effort(np.array(config), np.zeros(14, dtype=bool),
                                          tuple(tables), prefixes, swings)
            if expected is None:
                assert np.isnan(got), config
            else:
                assert got == expected, config
            answers.append(expected is not None)
    assert 0.1 < np.mean(answers) < 0.9


def test_the_exhaustive_search_is_the_least_readable_effort(leg, search_kind):
    """
    The exhaustive search finds the least readable effort.

    The benchmarks' exhaustive optimum (compiled) is the configuration of least readable effort
    over every configuration of the window, the first of equals in their order.
    """
    planner = FootstepPlanner(FootstepConfig(), leg)
    for height_of in (lambda s: 0.15 * np.floor(max(s - 0.5, 0.0) / 0.35),
                      lambda s: np.nan if 0.7 < s < 1.1 else 0.02 * np.sin(7 * s)):
        profile = profile_from(height_of)
        plain = planner.foothold_table(profile, RIGHT, 0.0)
        efforts = {}
        for config in np.ndindex(14, 14, 14):
            effort = readable_effort(planner, plain, config)
            if effort is not None:
                efforts[config] = effort
        best = min(efforts, key=efforts.get)
        window = planner.plan_exhaustive(profile, RIGHT, 0.0, 0.0, -0.05, 0.0, 0.5, 0.45)
        assert window.indices == best and window.effort == efforts[best]
        assert window.evaluated == 14 ** 3 and len(efforts) > 100


def test_another_attempt_at_a_step_plans_as_a_fresh_planner_would(leg):
    # The actor retries a step with the first length banned; the planner must answer exactly
    # as a planner seeing the window first (nothing of the first search is left over).
    profile = profile_from(lambda s: 0.1 if 0.6 < s < 1.1 else 0.0)
    planner = FootstepPlanner(FootstepConfig(), leg)
    first = plan(planner, profile)
    assert first is not None
    retry = plan(planner, profile, banned=(first.indices[0],))
    fresh = plan(FootstepPlanner(FootstepConfig(), leg), profile, banned=(first.indices[0],))
    assert retry is not None and retry.indices != first.indices
    assert retry.indices == fresh.indices and retry.effort == fresh.effort
    np.testing.assert_array_equal(retry.heights, fresh.heights)


def _paper_search(planner, profile, start, s_init, previous_length):
    """
    Search the window with the core's readable §4.2 search, the right foot standing at 0.

    ``footstep_window.search_footstep_window``, the code of record: breadth-first search from
    ``start`` to the first collision-free configuration, then hill-climbing (and, with
    ``greedy_restart``, the climb from the greedy configuration). Returns (configuration,
    effort, configurations judged), or (None, None, 0).
    """
    table = planner.foothold_table(profile, RIGHT, 0.0)
    feet = WindowFeet(0.0, 0.0, 0.0, 0.0, float(s_init), float(previous_length))
    found = search_footstep_window(table, planner.window_limits, feet, tuple(start))
    if found is None:
        return None, None, 0
    return found.configuration, found.effort, found.evaluated


@pytest.mark.parametrize('greedy_restart', [False, True])
def test_the_search_is_the_papers_breadth_first_search_and_hill_climbing(leg, greedy_restart,
                                                                         search_kind):
    """
    The search is the paper's breadth-first search and hill-climbing.

    The planner's search finds the configuration the plain §4.2 search finds (and, with the greedy
    restart, the better of that and the climb from the greedy configuration), with the same effort,
    having judged the same configurations, from starts far from any free one on stairs, holes and
    bumps; compiled and as plain Python.
    """
    rng = np.random.default_rng(11)
    planner = FootstepPlanner(FootstepConfig(greedy_restart=greedy_restart), leg)
    terrain = {'stairs': lambda s: 0.12 * (np.floor((s - 0.4) / 0.3) + 1) if s > 0.4 else 0.0,
               'holes': lambda s: np.nan if 0.5 < s < 0.85 or 1.5 < s < 1.8 else 0.0,
               'bumps': lambda s: 0.25 if 0.9 < s < 0.96 else 0.03 * np.sin(9 * s)}
    searched = 0
    for name, height_of in terrain.items():
        profile = profile_from(height_of)
        for _ in range(12):
            start = tuple(int(j) for j in rng.integers(0, 14, 3))
            s_init = float(rng.uniform(0.3, 0.7))
            expected, effort, judged = _paper_search(planner, profile, start, s_init, 0.5)
            window = plan(planner, profile, s_init=s_init, start=start)
            if expected is None:
                assert window is None, (name, start)
                continue
            assert window.indices == expected, (name, start)
            assert window.effort == effort
            assert window.evaluated == judged, (name, start)
            searched += judged > 14
    assert searched >= 10, 'too few searches that had to go far for the test to mean much'


def test_the_greedy_configuration_does_not_displace_a_better_one_found(leg, search_kind):
    """
    The greedy configuration does not displace a better one found.

    Started at the window's optimum, the search keeps it: the greedy configuration, built footstep
    by footstep, is collision-free but worse there, and the climb from it ends elsewhere (on these
    stairs on a configuration 2-50 % dearer, over these holes 35 %; had the search climbed from it
    alone); the configurations judged are the plain search's.
    """
    planner = FootstepPlanner(FootstepConfig(), leg)
    terrain = {'stairs': lambda s: 0.15 * np.floor(max(s - 0.5, 0.0) / 0.35),
               'holes': lambda s: np.nan if 0.5 < s < 0.85 or 1.5 < s < 1.8 else 0.0}
    cases = [('stairs', 0.3), ('stairs', 0.5), ('stairs', 0.6), ('stairs', 0.7), ('holes', 0.7)]
    for name, s_init in cases:
        profile = profile_from(terrain[name])
        best = planner.plan_exhaustive(profile, RIGHT, 0.0, 0.0, 0.0, 0.0, s_init, 0.5)
        window = plan(planner, profile, s_init=s_init, start=best.indices)
        expected, effort, judged = _paper_search(planner, profile, best.indices, s_init, 0.5)
        assert window.indices == best.indices == expected, (name, s_init)
        assert window.effort == effort and window.evaluated == judged, (name, s_init)


def test_a_window_of_many_configurations_keeps_its_memo_in_a_dictionary_and_searches_alike(
        leg, search_kind):
    """
    A window of many configurations keeps its memo in a dictionary.

    Past ``DENSE_CONFIGURATIONS`` configurations (five footsteps: 14 ** 5) the search remembers
    what it judged in a dictionary instead of arrays: the same configuration, effort and
    configurations judged as the plain §4.2 search, on stairs from starts far from any free one.
    """
    config = FootstepConfig(window_steps=5)
    assert (config.step_intervals + 1) ** 5 > footstep_search.DENSE_CONFIGURATIONS
    planner = FootstepPlanner(config, leg)
    profile = profile_from(
        lambda s: 0.12 * (np.floor((s - 0.4) / 0.3) + 1) if s > 0.4 else 0.0, length=6.0)
    rng = np.random.default_rng(5)
    searched = 0
    for _ in range(6):
        start = tuple(int(j) for j in rng.integers(0, 14, 5))
        s_init = float(rng.uniform(0.3, 0.7))
        expected, effort, judged = _paper_search(planner, profile, start, s_init, 0.5)
        window = plan(planner, profile, s_init=s_init, start=start)
        assert expected is not None and window is not None, start
        assert window.indices == expected and window.effort == effort, start
        assert window.evaluated == judged, start
        searched += judged > 30
    assert searched >= 3, 'too few searches that had to go far for the test to mean much'
