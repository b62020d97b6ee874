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

"""The actor pipeline: commands in, timed frames out, one block at a time (§3.2)."""
from course_runs import judged, scene, skeleton
from digital_actor_planner.core import actor as actor_module
from digital_actor_planner.core import gait as gait_module
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands, validate
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.gait import GaitConfig
from digital_actor_planner.core.settings import ConfigError
from digital_actor_planner.core.upper_body import UpperBodyPlan
import numpy as np
import pytest
from scene_helpers import box

#: The settings the steering walks below were recorded with: commands up to 1.2 m/s walked in
#: strides up to 0.8 m. A stride law that differs walks elsewhere, and the trap each test
#: replays is not met.
RECORDED_STRIDES = {'max_linear_speed': 1.2,
                    'gait': gait_module.GaitConfig(fast_step_length=0.8)}


@pytest.fixture
def actor():
    sc = scene('flat')
    return Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False), start=sc.start)


def test_blocks_are_contiguous_at_the_frame_rate(actor):
    actor.set_command(0.8, 0.0)
    blocks = [actor.plan_next() for _ in range(6)]
    times = np.concatenate([b.times for b in blocks])
    np.testing.assert_allclose(np.diff(times), 0.01, atol=1e-9)
    assert times[0] == pytest.approx(0.01)
    assert actor.time == pytest.approx(times[-1])
    np.testing.assert_array_equal(actor.configuration, blocks[-1].frames[-1])
    for b in blocks:
        assert b.frames.shape == (b.times.size, 22) and b.velocities.shape == b.frames.shape


def test_no_command_means_standing_still(actor):
    block = actor.plan_next()
    assert block.status == 'idle'
    assert np.ptp(block.frames, axis=0).max() == 0.0


def test_zero_command_stops_the_actor_within_one_step(actor):
    actor.set_command(0.6, 0.0)
    for _ in range(5):
        actor.plan_next()
    actor.set_command(0.0, 0.0)
    first = actor.plan_next()
    # The step landed in a split stance: the pelvis slows to rest there, no closing step.
    assert first.status == 'idle' and first.category == 'settling'
    assert first.times[-1] - first.times[0] < 0.1
    x = actor.configuration[0]
    still = actor.plan_next()
    assert still.category == '' and np.ptp(still.frames, axis=0).max() == 0.0
    assert still.frames[-1, 0] == pytest.approx(x)
    feet = skeleton().forward_kinematics(still.frames[-1])
    left = feet[skeleton().link_index['left_foot'], :3, 3]
    right = feet[skeleton().link_index['right_foot'], :3, 3]
    assert abs(left[0] - right[0]) > 0.1  # one foot ahead of the other
    assert min(left[0], right[0]) < x < max(left[0], right[0])


def test_commands_are_clamped_and_nan_is_refused(actor):
    warning = actor.set_command(9.0, -7.0)
    assert 'clamped' in warning and actor.command == (actor.config.max_linear_speed, -1.0)
    assert actor.set_command(0.5, 0.2) is None
    with pytest.raises(ValueError, match='finite'):
        actor.set_command(float('nan'), 0.0)
    assert actor.command == (0.5, 0.2)  # the bad command did not replace the good one
    # Backward no faster than max_backward_speed.
    assert (actor.set_command(-9.0, 0.0) is not None
            and actor.command[0] == -actor.config.max_backward_speed)


def test_speed_follows_the_command(actor):
    blocks = run_commands(actor, [0.0, 6.0], [0.5, 0.0], [0.0, 0.0])
    slow = actor.configuration[0]
    sc = scene('flat')
    fast_actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                       start=sc.start)
    run_commands(fast_actor, [0.0, 6.0], [1.1, 0.0], [0.0, 0.0])
    assert fast_actor.configuration[0] > slow + 0.8
    assert all(b.status in ('walking', 'idle') for b in blocks)


@pytest.mark.parametrize('field, value', [
    ('window_steps', 0), ('step_intervals', 0), ('max_linear_speed', 0.0),
    ('frame_rate', 5.0), ('step_length_min', 0.9), ('hold_time', float('nan')),
    ('check_budget', 0), ('follow_check_rise', -0.1), ('pivot_either_foot', 1),
])
def test_bad_configuration_names_the_field(field, value):
    with pytest.raises(ConfigError, match=field) as caught:
        ActorConfig.from_settings(**{field: value})
    assert caught.value.name == field
    assert caught.value.value == value or value != value


def test_the_footstep_window_asked_for_is_the_one_planned():
    sc = scene('flat')
    windows = {}
    for n in (1, 5):
        actor = Actor(skeleton(), sc.environment,
                      ActorConfig(plan_upper_body=False, footsteps=FootstepConfig(window_steps=n)),
                      start=sc.start)
        blocks = run_commands(actor, [0.0, 2.0], [0.8, 0.0], [0.0, 0.0])
        windows[n] = {len(b.footsteps) for b in blocks if b.status == 'walking' and b.category
                      in ('level', 'uphill', 'downhill')}
    assert windows == {1: {1}, 5: {5}}, windows


def test_the_gaits_frame_rate_is_the_rate_of_the_frames():
    sc = scene('flat')
    actor = Actor(skeleton(), sc.environment,
                  ActorConfig(plan_upper_body=False, gait=GaitConfig(frame_rate=50)),
                  start=sc.start)
    blocks = run_commands(actor, [0.0, 2.0], [0.6, 0.0], [0.0, 0.0])
    steps = np.diff(np.concatenate([b.times for b in blocks]))
    assert actor.config.frame_rate == 50
    assert np.allclose(steps, 0.02), np.unique(np.round(steps, 4))


class BlockedUpperBody:
    """
    An upper-body planner that is always blocked at a chosen frame; it counts its calls.

    ``blocked_at_end``: blocked at the last frame (in the preview when there is one), else at
    frame 5; ``after_step``: with a preview, blocked this many frames after the step's end.
    """

    def __init__(self, blocked_at_end, after_step=None):
        self.blocked_at_end = blocked_at_end
        self.after_step = after_step
        self.calls = []
        self.previews = []

    def plan(self, times, frames, preview_from=None):
        self.calls.append(len(times))
        self.previews.append(preview_from)
        frame = len(times) - 1 if self.blocked_at_end else 5
        if self.after_step is not None and preview_from is not None:
            frame = preview_from + self.after_step
        return UpperBodyPlan(frames=frames, ok=False, reason=f'waist blocked at frame {frame}',
                             deviation=0.0, planning_time=0.0, per_branch={},
                             blocked_frame=frame)


@pytest.mark.parametrize('blocked_at_end', [False, True])
def test_plan_without_preview_only_when_the_preview_blocked(blocked_at_end):
    sc = scene('flat')
    upper = BlockedUpperBody(blocked_at_end)
    # No pause-and-retry (upper_body_pause): only the footsteps tried count here.
    actor = Actor(skeleton(), sc.environment,
                  ActorConfig(upper_body_attempts=2, upper_body_pause=0.0),
                  start=sc.start, upper_body_planner=upper)
    actor.set_command(0.6, 0.0)
    block = actor.plan_next()
    assert block.status == 'stuck' and 'upper body blocked' in block.reason
    if blocked_at_end:
        # Blocked in the preview only: the step alone may still pass, so it is planned too.
        assert len(upper.calls) == 4
        assert upper.calls[0] > upper.calls[1] and upper.calls[2] > upper.calls[3]
        # The preview plan is told where the step's own frames end: where the plan without
        # the preview ends.
        assert upper.previews == [upper.calls[1], None, upper.calls[3], None]
    else:
        # Blocked within the step's own frames: without the preview it meets the same block.
        assert len(upper.calls) == 2, 'one plan per footstep tried'


@pytest.mark.parametrize('margin, plans_alone', [(0.1, False), (0.0, True), (0.02, True)])
def test_a_block_just_after_the_step_is_not_walked_into(margin, plans_alone):
    # Blocked 3 frames (0.03 s) after the step's end: taking the step would leave the upper
    # body where the next step cannot go on (an arm between a pillar and the body). Within the
    # margin the footstep fails as if blocked in the step; outside it the step alone is tried.
    sc = scene('flat')
    upper = BlockedUpperBody(blocked_at_end=False, after_step=3)
    actor = Actor(skeleton(), sc.environment,
                  ActorConfig(upper_body_attempts=2, upper_body_preview_margin=margin,
                              upper_body_pause=0.0),
                  start=sc.start, upper_body_planner=upper)
    actor.set_command(0.6, 0.0)
    block = actor.plan_next()
    assert block.status == 'stuck' and 'upper body blocked' in block.reason
    if plans_alone:
        assert upper.previews == [upper.calls[1], None, upper.calls[3], None]
        assert 'just after the step' not in block.reason
    else:
        assert all(p is not None for p in upper.previews) and len(upper.calls) == 2
        assert block.reason.endswith('just after the step')


@pytest.mark.parametrize('value', [-0.1, float('nan')])
def test_bad_preview_margin_names_the_field(value):
    with pytest.raises(ValueError, match='upper_body_preview_margin'):
        validate(ActorConfig(upper_body_preview_margin=value))


class NeedsAPause:
    """
    An upper-body planner that needs the pelvis to stand still first.

    An upper-body planner that passes a block only when the pelvis first stands still for
    ``frames`` frames (an arm that must get clear before the body moves).
    """

    def __init__(self, frames):
        self.frames = frames
        self.calls = 0

    def plan(self, times, frames, preview_from=None):
        self.calls += 1
        root = frames[:self.frames + 1, :4]
        still = np.all(root == root[0])
        blocked = -1 if still else 3
        return UpperBodyPlan(frames=frames, ok=still, reason='' if still else
                             'right_arm blocked at frame 3', deviation=0.0, planning_time=0.0,
                             per_branch={}, blocked_frame=blocked)


def test_a_footstep_the_upper_body_cannot_take_is_taken_after_a_pause():
    sc = scene('flat')
    upper = NeedsAPause(20)
    actor = Actor(skeleton(), sc.environment, ActorConfig(upper_body_attempts=2),
                  start=sc.start, upper_body_planner=upper)
    actor.set_command(0.6, 0.0)
    before = actor.configuration.copy()
    block = actor.plan_next()
    assert block.status == 'walking', block.reason
    # The block opens with 0.2 s of the body standing where it was, then the step, continuous
    # and at the frame rate.
    assert np.all(block.frames[:20] == before)
    assert not np.array_equal(block.frames[-1, :4], before[:4]), 'then it steps'
    assert np.allclose(np.diff(block.times), 0.01)
    # Two footsteps failed, then the first one was tried again after the pause.
    assert upper.calls >= 3
    # Without the pause the actor stops.
    stopped = Actor(skeleton(), sc.environment,
                    ActorConfig(upper_body_attempts=2, upper_body_pause=0.0), start=sc.start,
                    upper_body_planner=NeedsAPause(20))
    stopped.set_command(0.6, 0.0)
    assert stopped.plan_next().status == 'stuck'


@pytest.mark.parametrize('value', [-0.1, 2.5])
def test_bad_pause_names_the_field(value):
    with pytest.raises(ValueError, match='upper_body_pause'):
        validate(ActorConfig(upper_body_pause=value))


def test_bad_preview_distance_names_the_field():
    with pytest.raises(ValueError, match='upper_body_preview_distance'):
        validate(ActorConfig(upper_body_preview_distance=-0.5))


@pytest.mark.parametrize('value', [-0.1, 1.5, float('nan')])
def test_bad_pivot_turn_names_the_field(value):
    with pytest.raises(ValueError, match='pivot_turn'):
        validate(ActorConfig(pivot_turn=value))


def turn_on_the_spot(rate, config, start=(1.0, 1.5, np.pi / 3), speed=0.0, seconds=4.0):
    """
    Turn on the spot near the flat floor's edge.

    The actor 0.5 m from the flat floor's edge (y = 2 m), facing 60 degrees to it, told to turn at
    ``rate`` (towards the edge first when positive). Returns blocks and report.
    """
    sc = scene('flat')
    actor = Actor(skeleton(), sc.environment, config, start=start)
    blocks = run_commands(actor, [0.0, seconds], [speed, 0.0], [rate, 0.0])
    return blocks, judged(blocks, sc.environment)[2]


def test_a_turn_on_the_spot_facing_an_edge_pivots_instead_of_stopping():
    """
    A turn on the spot facing the floor's edge pivots instead of stopping.

    The tight arc of a turn on the spot reaches over the floor's edge and is refused; the actor
    pivots about its stance hip until the arc is clear, then walks its turn.
    """
    blocks, report = turn_on_the_spot(1.0, ActorConfig(plan_upper_body=False))
    assert report.ok, report.failures()
    assert any(b.category == 'pivot' for b in blocks)
    turned = blocks[-1].frames[-1, 3] - np.pi / 3
    assert turned > 2.0, turned
    assert not any(b.status == 'stuck' for b in blocks)
    # Without the pivot the same command stops it, stuck, before it has turned 1 rad.
    plain, _ = turn_on_the_spot(1.0, ActorConfig(plan_upper_body=False, pivot_turn=0.0))
    assert plain[-1].status == 'stuck' and plain[-1].frames[-1, 3] - np.pi / 3 < 1.0


def test_a_pivot_turns_no_faster_than_asked_and_only_in_tight_turns():
    blocks, report = turn_on_the_spot(0.3, ActorConfig(plan_upper_body=False))
    assert report.ok, report.failures()
    pivots = [b for b in blocks if b.category == 'pivot']
    assert pivots
    for block in pivots:
        turn = block.frames[-1, 3] - block.frames[0, 3]
        duration = block.times[-1] - block.times[0] + 0.01
        assert 0 < turn <= 0.3 * duration * 1.05, (turn, duration)
    # A wider turn (0.6 m radius: its feet clear each other on the arc) walks its arc or
    # stops; it does not pivot.
    walking, _ = turn_on_the_spot(1.0, ActorConfig(plan_upper_body=False), speed=0.6)
    assert not any(b.category == 'pivot' for b in walking)


def test_a_turn_reversed_at_low_speed_squares_the_feet_instead_of_stopping():
    """
    A turn reversed at low speed squares the feet instead of stopping.

    Walking a left arc, then told to turn right slowly (0.31 m/s, -1 rad/s: seed 2 of
    bench_steer_away.py's walks, which stopped here on every course): the right foot is down,
    pointing 0.35 rad further left than the left one, and the left foot must step first. On the arc
    it would pass into the right foot; a pivot keeping its heading turns the legs in until the
    thighs meet, and squaring it up to the right foot turns the pelvis back (left). The actor
    squares the feet, the pelvis turning back a little, rather than stand still until the mouse
    moves; its next steps turn right.
    """
    sc = scene('flat')
    actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                  start=sc.start)
    blocks = run_commands(actor, [0.0, 0.74, 3.0], [0.89, 0.31, 0.0], [0.74, -1.0, 0.0])
    _, _, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert not any(b.status == 'stuck' for b in blocks)
    turning = [b for b in blocks if b.category and b.times[0] > 0.74]
    pivot = turning[0]
    assert pivot.category == 'pivot'
    back = pivot.frames[-1, 3] - pivot.frames[0, 3]
    assert 0.0 < back < 0.2, back
    heading = max(b.frames[-1, 3] for b in turning)
    assert blocks[-1].frames[-1, 3] < heading - 0.5


def test_a_turn_on_the_spot_with_the_feet_on_two_levels_pivots_on_either_level():
    """
    A turn on the spot with the feet on two levels pivots on either level.

    Weaving onto the stairs (seed 9 of bench_steer_away.py's walks, rounded), the last step puts
    one foot on the first tread's nosing, the other stays on the floor, facing the flight at 0.95
    rad. Told to turn on the spot, the floor foot cannot land beside the tread foot on the tread's
    level (that is across the riser); it lands on the floor, its own level, and so on: each foot
    pivots on its level. (A pivot had to land within 5 cm of the stance foot's height: the actor
    stood there, and turning either way left it there, trapped.)
    """
    sc = scene('stairs_up')
    commands = [(0.0, 0.0, 0.85), (1.78, 0.5, -0.67), (2.57, 0.94, 1.11), (3.89, 0.0, -0.11),
                (5.51, 0.0, 0.44), (9.0, 0.0, 0.0)]
    actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                  start=sc.start)
    blocks = run_commands(actor, *zip(*commands))
    _, _, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert not any(b.status == 'stuck' for b in blocks)
    turning = [b for b in blocks if b.times[0] > 5.51 and b.category]
    assert len(turning) >= 4 and all(b.category == 'pivot' for b in turning)
    assert turning[-1].frames[-1, 3] - turning[0].frames[0, 3] > 0.7
    # The first pivot starts with the feet 0.15 m apart in height.
    first = skeleton().forward_kinematics(turning[0].frames[0])
    index = skeleton().link_index
    heights = [first[index[f'{side}_foot'], 2, 3] for side in ('left', 'right')]
    assert abs(heights[0] - heights[1]) > 0.1, heights


def test_a_pivot_at_a_stair_nosing_lands_on_the_tread_and_never_steps_on_the_spot(monkeypatch):
    """
    A pivot at a stair nosing lands on the tread and never steps on the spot.

    Standing on the first tread with the heels over its nosing, told to turn on the spot: beside
    the stance foot the turned foot would land across the riser, so it lands 10 cm ahead or behind
    (``PIVOT_SHIFTS``), on the tread, and the actor turns. Where no landing turns it any further,
    it stops rather than step on the spot: two pivots in a row turn the pelvis on by
    ``PIVOT_MIN_TURN`` at least.
    """
    sc = scene('stairs_up')

    def turn(either=True):
        actor = Actor(skeleton(), sc.environment,
                      ActorConfig(plan_upper_body=False, pivot_either_foot=either),
                      start=(1.55, 0.0, 0.0))
        return run_commands(actor, [0.0, 4.0], [0.0, 0.0], [1.0, 0.0])

    blocks = turn()
    _, frames, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert frames[-1, 3] > 0.5
    pivots = [b.frames[-1, 3] - b.frames[0, 3] for b in blocks if b.category == 'pivot']
    assert len(pivots) >= 2
    for first, second in zip(pivots[:-1], pivots[1:]):
        assert first + second > actor_module.PIVOT_MIN_TURN - 1e-9, pivots
    assert blocks[-1].status == 'stuck'
    # Landing only beside the stance foot, with the foot due to swing, it does not turn at all.
    monkeypatch.setattr(actor_module, 'PIVOT_SHIFTS', (0.0,))
    plain = turn(either=False)
    assert not any(b.category for b in plain)


def test_beside_the_tables_corner_the_foot_that_landed_last_pivots(monkeypatch):
    """
    Beside the table's corner the foot that landed last pivots.

    Weaving beside the table (seed 5 of bench_steer_away.py's walks), the actor stops beside its
    corner, the left thigh 4 cm from the edge: every step and every pivot of the left foot (the one
    due to swing) puts that thigh into the edge. Told to turn away on the spot, the right foot, the
    one that landed last, pivots instead, and the actor walks its turn. (Pivoting the left foot
    only, the actor would be trapped there.)
    """
    sc = scene('table')
    commands = [(0.0, 1.07, 0.179), (1.669, 0.427, -0.838), (3.342, 1.095, 0.538),
                (3.65, 0.0, -1.0), (7.65, 0.0, 0.0)]

    def walk(either=True):
        actor = Actor(skeleton(), sc.environment,
                      ActorConfig(pivot_either_foot=either, **RECORDED_STRIDES), start=sc.start)
        return run_commands(actor, *zip(*commands))

    blocks = walk()
    stop = next(b for b in blocks if b.status == 'stuck')
    assert 3.3 < stop.times[0] < 3.65 and 'the left thigh' in stop.reason
    away = [b for b in blocks if b.times[0] > 3.65 and b.category]
    assert away[0].category == 'pivot' and len(away) >= 4
    pivot = skeleton().forward_kinematics(away[0].frames[[0, -1]])
    moved = [np.hypot(*(pivot[1, index, :2, 3] - pivot[0, index, :2, 3]))
             for index in (skeleton().link_index['left_foot'],
                           skeleton().link_index['right_foot'])]
    assert moved[0] < 1e-6 and moved[1] > 0.1, moved
    assert away[-1].frames[-1, 3] < stop.frames[-1, 3] - 1.5
    _, _, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert not any(b.times[0] > 3.65 and b.category for b in walk(either=False))


def test_a_foot_behind_the_other_beside_the_table_turns_where_it_stands(monkeypatch):
    """
    A foot behind the other beside the table turns where it stands.

    Seed 7 of bench_steer_away.py's walks stops beside the table's far end, the left foot 0.43 m
    behind the right: any step of the left leg swings its thigh forward into the table's edge,
    wherever it lands beside the right foot. Told to turn away on the spot, the left foot turns
    where it stands (the last of ``PIVOT_SHIFTS``), and the actor walks its turn from there.
    Without that landing it stayed, trapped.
    """
    sc = scene('table')
    commands = [(0.0, 0.36, 0.014), (1.363, 0.813, -0.231), (3.188, 0.244, 0.83),
                (4.807, 0.236, -0.241), (5.489, 0.715, 0.443), (6.3, 0.666, -0.004),
                (8.085, 1.117, 0.996), (8.394, 0.829, -0.185), (8.6, 0.0, -1.0),
                (12.6, 0.0, 0.0)]

    def walk(either=True):
        actor = Actor(skeleton(), sc.environment, ActorConfig(pivot_either_foot=either),
                      start=sc.start)
        return run_commands(actor, *zip(*commands))

    blocks = walk()
    stop = next(b for b in blocks if b.status == 'stuck')
    assert 8.2 < stop.times[0] < 8.6
    away = [b for b in blocks if b.times[0] > 8.6 and b.category]
    assert away[0].category == 'pivot' and len(away) >= 4
    pivot = away[0].frames
    index = skeleton().link_index['left_foot']
    feet = skeleton().forward_kinematics(pivot[[0, -1]])[:, index, :2, 3]
    assert np.hypot(*(feet[1] - feet[0])) < 0.05
    assert away[-1].frames[-1, 3] < stop.frames[-1, 3] - 1.5
    _, _, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    monkeypatch.setattr(actor_module, 'PIVOT_SHIFTS', actor_module.PIVOT_SHIFTS[:-1])
    assert not any(b.times[0] > 8.6 and b.category for b in walk(either=False))


def test_a_foot_that_lands_away_from_its_foothold_must_rest_where_it_lands():
    """
    A foot that lands away from its foothold must rest where it lands.

    Weaving on the blocks course (seed 58 of bench_steer_away.py's walks, rounded): in a tight
    right turn the left foot's heading is bounded (``max_toe_in``), so its hip's plane puts it 0.19
    m from the foothold planned on the 0.2 m block, beside the block, where it came down at the
    block's height over the floor; the next lift-off then left no foot down (36.9 mm). A landing
    that far from its foothold must now rest on the ground where it is; this one is refused, the
    actor does something else, and the checker passes.
    """
    sc = scene('blocks')
    commands = [(0.0, 1.043, 0.588), (0.825, 0.354, -0.765), (2.621, 0.663, 0.259),
                (3.334, 0.236, -0.63), (3.989, 0.591, 0.568), (5.726, 0.566, -1.049),
                (6.265, 0.338, 0.566), (7.085, 0.472, -0.986), (7.62, 0.633, 0.899),
                (8.815, 0.0, -1.034), (10.688, 0.0, 0.0)]
    actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                  start=sc.start)
    blocks = run_commands(actor, *zip(*commands))
    _, _, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert sum(1 for b in blocks if b.category) >= 14


def walk_straight_past(environment, speed, seconds, x, case):
    """
    Walk straight along +x and assert that the pelvis gets past ``x``.

    Walk straight along +x from the origin (lower body) and assert that the pelvis gets past ``x``
    and the checker passes the walk; ``case`` labels a failure.
    """
    actor = Actor(skeleton(), environment, ActorConfig(plan_upper_body=False),
                  start=(0.0, 0.0, 0.0))
    blocks = run_commands(actor, [0.0, seconds], [speed, 0.0], [0.0, 0.0])
    stops = [b.reason for b in blocks if b.status == 'stuck']
    assert actor.stance.pelvis[0] > x, (case, stops[:1])
    _, _, report = judged(blocks, environment)
    assert report.ok, (case, report.failures())


def test_walking_straight_over_a_block_the_rear_foot_clears_its_near_face():
    """
    Walking straight over a block, the rear foot clears its near face.

    A block 0.5 m long and 0.18 or 0.21 m high across the path, 1.6-2.0 m ahead, walked straight at
    0.8 or 1.0 m/s. The footsteps often put the front foot on the block with the rear toe a few
    centimetres from its face; a cubic swing curve cannot rise that steeply and stay up over the
    block, so every step was refused and the actor stopped there for good (16 of these 20 walks).
    The swing then takes a flat-topped curve (degree 5): every walk crosses, and the checker passes
    each.
    """
    for height in (0.18, 0.21):
        for x in (1.6, 1.7, 1.8, 1.9, 2.0):
            environment = Environment([box([-1, -1, -0.1], [5, 1, 0]),
                                       box([x, -1, -0.1], [x + 0.5, 1, height])],
                                      resolution=0.02)
            for speed in (0.8, 1.0):
                walk_straight_past(environment, speed, 8.0, x + 1.0, (height, x, speed))


def test_walking_straight_over_high_short_blocks():
    """
    High, short blocks walked straight are passed.

    Blocks 0.22-0.28 m high (max_step_up is 0.30), 0.3 or 0.6 m long, walked straight: walks
    bench_terrain.py found stopped for good. Either a foot came to rest with its toe 2 cm from a
    block's face, where the conservative ground map puts the block under the toe at lift-off and
    only a swing that steps up at once clears it (FootstepConfig.lift_room), or the front foot
    strode over a short 0.28 m block and the rear foot could not follow over it (max_swing_height
    0.40 allowed the stride; 0.25 has the foot step onto the block), or the rear foot, 2 cm before
    a 0.28 m block's face, stepped up onto it and its knee passed its limit (lift_step_up). None of
    these 6 crossed before; now every one does, and the checker passes each.
    """
    for height, length, x, speed in ((0.22, 0.3, 1.75, 0.8), (0.22, 0.6, 2.05, 1.1),
                                     (0.28, 0.3, 1.6, 0.8), (0.28, 0.3, 1.9, 0.5),
                                     (0.28, 0.6, 1.6, 1.1), (0.28, 1.2, 2.05, 0.8)):
        environment = Environment([box([-1, -1, -0.1], [x + length + 4, 1, 0]),
                                   box([x, -1, -0.1], [x + length, 1, height])],
                                  resolution=0.02)
        walk_straight_past(environment, speed, (x + length + 1.0) / speed * 1.6 + 4.0,
                           x + length + 1.0, (height, length, x, speed))


def test_the_front_foot_does_not_stride_over_a_block_the_rear_foot_cannot_follow_over():
    """
    The front foot does not stride over a block the rear foot cannot follow over.

    A block 0.24 m high and 0.31 m long (low enough for a swing to pass over it), met in ten phases
    at 0.8 and 0.9 m/s. Where the front foot strode over it with the rear foot's toe just before
    its face, the rear foot could not follow: lifted from behind the hip its knee passed its limit,
    or its sole, tipped toes-down at the ankle's limit, could not clear the block, and with the
    front foot beyond it no step was left (9 of these 20 walks stopped so). The window's next
    footstep is now generated before such a step is taken (ActorConfig.check_follow), and a foot
    the window places keeps 5 cm ahead of its toe free of a face it cannot lift over
    (FootstepConfig.lift_room; with 3 cm one walk stopped before the block, every first footstep
    leaving a rear foot that could not follow). Every walk gets past, and the checker passes each.
    Without the check the first one still stops, with the rear foot behind the block.
    """
    height, length = 0.24, 0.31

    def course(x):
        return Environment([box([-1, -1, -0.1], [x + length + 4, 1, 0]),
                            box([x, -1, -0.1], [x + length, 1, height])], resolution=0.02)

    for x in np.arange(1.6, 2.0, 0.04):
        environment = course(x)
        for speed in (0.8, 0.9):
            walk_straight_past(environment, speed, 9.0, x + length + 1.0, (x, speed))
    x = 1.6
    actor = Actor(skeleton(), course(x), ActorConfig(plan_upper_body=False, check_follow=False),
                  start=(0.0, 0.0, 0.0))
    blocks = run_commands(actor, [0.0, 9.0], [0.9, 0.0], [0.0, 0.0])
    assert actor.stance.pelvis[0] < x + length
    feet_x = sorted(foot.xy[0] for foot in actor.stance.feet)
    assert feet_x[0] < x < x + length < feet_x[1]
    assert 'the legs cannot take the step' in next(b.reason for b in blocks if b.status == 'stuck')


def test_the_rear_foot_is_not_left_behind_a_bump_before_a_step_down_it_cannot_follow_over():
    """
    The rear foot is not left behind a bump before a step down.

    A bump 3.5 cm high and 0.29 m long across the path on a 0.19 m high platform, its far end 3 cm
    before the platform's edge and a step down to the floor, met in nine phases at 1.08 m/s (as on
    bench_terrain's random course 38). Where the front foot stepped down past the bump with the
    rear foot's toe just before it, lifting the rear foot over the bump and down passed its knee's
    limit (its sole tipped toes-down at the ankle's limit), and no step was left (3 of these 9
    walks stopped so). The follow check (ActorConfig.check_follow) now asks for that footstep from
    a rise of follow_check_rise (3 cm): every walk gets past, and the checker passes each.
    """
    top, speed = 0.186, 1.08
    for x in np.arange(1.96, 2.3, 0.04):
        edge = x + 0.32
        environment = Environment([box([-1, -1, -0.1], [edge, 1, top]),
                                   box([edge, -1, -0.1], [edge + 4, 1, 0.02]),
                                   box([x, -1, top - 0.01], [x + 0.29, 1, top + 0.035])],
                                  resolution=0.02)
        walk_straight_past(environment, speed, 9.0, edge + 1.0, x)


def test_walking_straight_past_low_bumps_beside_the_feet():
    """
    Low bumps beside the feet do not stop a straight walk.

    Low bumps (5 and 8 cm high, 0.2 m long) beside both foot tracks, their inner edges 5 mm outside
    the soles, one every 0.45 or 0.6 m on each side. The ground map answers for a point's whole 2
    cm cell: the swing's clearance, read under the sole's edges, saw the bumps, and the footholds,
    read 1 cm inside them, did not. A landing the footsteps had found fine then could not be
    reached, every step was refused, and none of these walks got past (as on random course 23 of
    bench_terrain.py). Both now read the same lines (footsteps.SOLE_LINES): every walk gets past,
    and the checker passes each.
    """
    leg = skeleton().leg
    inner = leg.hip_half_width + 0.5 * leg.foot_width + 0.005
    for height, spacing, speed in ((0.05, 0.45, 0.6), (0.08, 0.45, 0.9), (0.05, 0.6, 0.9),
                                   (0.08, 0.6, 0.6)):
        meshes = [box([-1, -1, -0.1], [8, 1, 0])]
        for x in np.arange(1.0, 5.5, spacing):
            meshes.append(box([x, inner, -0.1], [x + 0.2, inner + 0.15, height]))
            meshes.append(box([x + spacing / 2, -inner - 0.15, -0.1],
                              [x + spacing / 2 + 0.2, -inner, height]))
        walk_straight_past(Environment(meshes, resolution=0.02), speed, 12.0, 6.0,
                           (height, spacing, speed))


def test_walking_down_a_corridor_of_low_curbs_beside_the_feet():
    """
    A corridor of low curbs beside the feet is walked down.

    Curbs 5 or 10 cm high along both sides of the path, 3-8 mm outside the soles: read at the
    soles' edges, the swing's clearance saw them under every landing, and the actor could not take
    a single step. It now walks down the corridor, and the checker passes each walk.
    """
    leg = skeleton().leg
    for gap, height in ((0.003, 0.1), (0.008, 0.05)):
        inner = leg.hip_half_width + 0.5 * leg.foot_width + gap
        environment = Environment([box([-1, -1, -0.1], [8, 1, 0]),
                                   box([-1, inner, -0.1], [8, inner + 0.1, height]),
                                   box([-1, -inner - 0.1, -0.1], [8, -inner, height])],
                                  resolution=0.02)
        walk_straight_past(environment, 0.8, 4.0, 2.0, (gap, height))


def test_walking_straight_up_and_down_a_steep_flight():
    """
    A steep flight is walked straight up and down.

    Four steps, 0.2 m rise and 0.26 m treads (a sole is 0.25 m), from three distances at two
    speeds, up and then down. Going up, a heel must overhang the tread's nosing (the plane fitted
    through the lower tread under it was too steep for an edge placement, and the sample past the
    toe read the next riser) and the swinging knee would pass its limit over the tread in between;
    going down, a toe overhangs each nosing. Every one of these 24 walks gets to the top or the
    bottom, and the checker passes each.
    """
    rise, tread, steps = 0.2, 0.26, 4
    for going_up in (True, False):
        for x in (1.6, 1.75, 1.9):
            tops = [rise * (i + 1) for i in range(steps)]
            if not going_up:
                tops = tops[::-1][1:] + [0.0]
            end = x + steps * tread
            meshes = ([box([-1, -1, -0.1], [x, 1, 0.0 if going_up else rise * steps])]
                      + [box([x + i * tread, -1, -0.1], [x + (i + 1) * tread, 1, top])
                         for i, top in enumerate(tops)]
                      + [box([end, -1, -0.1], [end + 3, 1, tops[-1]])])
            environment = Environment(meshes, resolution=0.02)
            for speed in (0.5, 0.8):
                walk_straight_past(environment, speed, 9.0, end + 0.5, (going_up, x, speed))


def test_no_step_ends_with_a_knee_too_bent_for_the_next_one(monkeypatch):
    """
    No step ends with a knee too bent for the next one.

    Weaving on the blocks (seed 32 of bench_steer_away.py's walks, rounded): stepping down off the
    0.2 m block's far edge, the right foot left on the block with its heel up and the knee at 2.27
    rad, 0.03 from its limit. Every next step, pivot and turn then bent that knee past the limit:
    the actor stopped there and was trapped. A step may not end with a knee within
    ``END_KNEE_MARGIN`` of its limit; another footstep is taken, and the walk and both turns on the
    spot after it go on.
    """
    sc = scene('blocks')
    commands = [(0.0, 0.433, 0.392), (0.572, 0.808, -0.439), (1.845, 1.105, 0.71),
                (2.786, 0.209, -0.056), (3.635, 0.659, 1.109), (5.103, 1.013, -0.797),
                (7.055, 1.162, 0.643)]

    def steps_turning(turn):
        actor = Actor(skeleton(), sc.environment,
                      ActorConfig(plan_upper_body=False, **RECORDED_STRIDES), start=sc.start)
        blocks = run_commands(actor, *zip(*(commands + [(8.9, 0.0, turn), (12.9, 0.0, 0.0)])))
        _, _, report = judged(blocks, sc.environment)
        assert report.ok, report.failures()
        stopped = any(b.status == 'stuck' for b in blocks if b.times[0] < 8.9)
        return stopped, sum(1 for b in blocks if b.times[0] > 8.9 and b.category)

    for turn in (1.0, -1.0):
        stopped, steps = steps_turning(turn)
        assert not stopped and steps >= 3, (turn, stopped, steps)
    monkeypatch.setattr(gait_module, 'END_KNEE_MARGIN', -1.0)
    assert steps_turning(1.0) == (True, 0) and steps_turning(-1.0) == (True, 0)


def test_weaving_to_the_floors_edge_ends_where_turning_away_frees_the_actor(monkeypatch):
    """
    Seed 33 of bench_steer_away.py's walks (rounded) weaves to the floor's edge.

    With a step ending only 1 cm short of the legs touching, it stopped 0.37 m from the edge facing
    it, the feet pigeon-toed 0.35 rad and the left 0.25 m behind the right: the toe-off of any next
    step flexes the left knee forward into the right thigh, so every step and pivot either way was
    refused, trapped. Steps now end 2 cm short (``LEGS_LANDING_MARGIN``); the walk stops elsewhere,
    and turning away on the spot frees it, either way.
    """
    sc = scene('flat')
    commands = [(0.0, 0.0, 0.854), (1.054, 0.0, -0.848), (2.321, 0.604, 1.011),
                (4.164, 0.0, -0.918), (4.897, 0.451, 0.617), (6.198, 0.448, -0.831),
                (7.108, 0.0, 0.917), (8.694, 1.029, -0.231), (9.917, 1.008, 1.174),
                (10.561, 0.466, -0.646), (11.738, 0.0, 0.763), (12.45, 0.0, 0.0)]

    def walk(commands, either=True):
        actor = Actor(skeleton(), sc.environment,
                      ActorConfig(plan_upper_body=False, pivot_either_foot=either),
                      start=sc.start)
        return run_commands(actor, *zip(*commands))

    def steps_turning_away(either=True):
        blocks = walk(commands, either)
        _, _, report = judged(blocks, sc.environment)
        assert report.ok, report.failures()
        at = next(b for b in blocks if b.status == 'stuck').times[0] + 0.3
        kept = [c for c in commands if c[0] < at]
        return [sum(b.status == 'walking'
                    for b in walk(kept + [(at, 0.0, w), (at + 4, 0.0, 0.0)], either)
                    if b.times[0] > at) for w in (1.0, -1.0)]

    assert min(steps_turning_away()) >= 2
    monkeypatch.setattr(gait_module, 'LEGS_LANDING_MARGIN', 0.01)
    assert steps_turning_away(either=False) == [0, 0]


@pytest.mark.parametrize('value', [-0.1, 1.5, float('nan')])
def test_bad_max_toe_in_names_the_field(value):
    with pytest.raises(ValueError, match='max_toe_in'):
        validate(ActorConfig(max_toe_in=value))


def _feet_toe_in(skeleton, frames):
    """(k,) how far the feet point towards each other, rad (negative: toes out)."""
    transforms = skeleton.forward_kinematics(frames)
    left = transforms[:, skeleton.link_index['left_foot']]
    right = transforms[:, skeleton.link_index['right_foot']]
    turn = np.arctan2(right[:, 1, 0], right[:, 0, 0]) - np.arctan2(left[:, 1, 0], left[:, 0, 0])
    return (turn + np.pi) % (2 * np.pi) - np.pi


def test_weaving_lands_the_feet_toed_in_no_more_than_max_toe_in_and_keeps_walking():
    """
    Weaving lands the feet toed in no more than ``max_toe_in`` and keeps walking.

    A mouse weaving left and right (seed 25 of bench_steer_away.py's walks) reverses the turn every
    second or so. Each landing foot may turn in towards the other by at most ``max_toe_in``; the
    walk's steps end with the feet no more pigeon-toed than that, and the checker (which judges the
    legs against each other) passes. With the bound as wide as outwards (0.9 rad) the feet land
    further in. (With a step ending 1 cm short of the legs touching, a next step's thighs then met
    as the knees passed, and the generator refused 15 steps of this walk; ending 2 cm short,
    ``LEGS_LANDING_MARGIN``, refuses those landings instead and the walk goes on.)
    """
    sc = scene('flat')
    commands = [(0.0, 0.27, 0.76), (0.57, 0.0, -0.91), (0.87, 0.6, 0.7), (1.54, 0.39, -0.46),
                (2.47, 0.92, 1.03), (2.77, 0.87, -0.35), (3.4, 0.97, 0.22), (5.38, 0.22, -0.66),
                (7.02, 0.0, 0.15), (7.53, 0.44, -0.1), (8.21, 0.74, 1.13), (9.82, 0.28, -0.57),
                (11.67, 1.13, 0.27), (12.58, 0.0, 0.0)]

    def walk(config):
        actor = Actor(skeleton(), sc.environment, config, start=sc.start)
        return run_commands(actor, *zip(*commands))

    config = ActorConfig(plan_upper_body=False, **RECORDED_STRIDES)
    blocks = walk(config)
    ends = np.array([b.frames[-1] for b in blocks if b.category])
    assert len(ends) >= 18
    assert not any(b.status == 'stuck' for b in blocks)
    assert _feet_toe_in(skeleton(), ends).max() <= config.max_toe_in + 1e-6
    _, _, report = judged(blocks, sc.environment)
    assert report.ok and report.leg_contacts == (), report.failures()
    wide = walk(ActorConfig(plan_upper_body=False, max_toe_in=0.9, **RECORDED_STRIDES))
    _, _, report = judged(wide, sc.environment)
    assert report.ok, report.failures()
    ends = np.array([b.frames[-1] for b in wide if b.category])
    assert _feet_toe_in(skeleton(), ends).max() > 0.4


def test_on_bumpy_ground_the_actor_stands_on_it_and_turns_on_the_spot(monkeypatch):
    """
    On bumpy ground the actor stands on it and turns on the spot.

    Started on the rough course's bumps, each foot rests on the ground under it at its own height
    and pitch (standing both level on the lowest ground under them would put one 27 mm into a
    bump at x = 4 m, and every first step would collide). Told to turn on the spot it turns, its
    pivots landing on the bumps' slopes too (pivots that required level ground within 1 cm would
    be refused), also from a stance foot pitched 0.09 rad (a pivot that required it within
    0.05 rad of level would leave it standing at x = 8 m), and the checker passes. Landings
    seated on the ground where they land (``gait.SEAT_SHIFT``) take most of these turns as
    steps; without seating they are pivots, which this test looks at.
    """
    sc = scene('rough')
    monkeypatch.setattr(gait_module, 'SEAT_SHIFT', 0.0)
    for x, y, rate, pitched in ((4.0, 0.3, -1.0, 0.01), (5.0, 0.3, 1.0, 0.01),
                                (8.0, 0.0, 1.0, 0.09)):
        actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                      start=(x, y, 0.0))
        feet = actor.stance.feet
        assert max(abs(foot.pitch) for foot in feet) > pitched
        blocks = run_commands(actor, [0.0, 4.0], [0.0, 0.0], [rate, 0.0])
        _, frames, report = judged(blocks, sc.environment)
        assert report.ok, report.failures()
        assert not any(b.status == 'stuck' for b in blocks)
        assert abs(frames[-1, 3]) > 2.0
        pivots = [b for b in blocks if b.category == 'pivot']
        assert pivots
        transforms = skeleton().forward_kinematics(np.array([b.frames[-1] for b in pivots]))
        soles = transforms[:, [skeleton().link_index['left_foot'],
                               skeleton().link_index['right_foot']]]
        pitch = np.arcsin(np.clip(-soles[..., 2, 0], -1.0, 1.0))
        assert np.abs(pitch).max() > 0.01
