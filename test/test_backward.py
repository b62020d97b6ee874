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
Backward walking: a downward mouse drag (negative linear speed) steps the actor backward.

Every walk here is judged by the independent checker (evaluation/trajectory_check.py): no link
penetrates, a foot is always down, a stance foot slides <= 1 cm, joint limits hold.
"""
from course_runs import judged, scene, simulate, skeleton
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands, validate
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.path import predict_path
import numpy as np
import pytest
from scene_helpers import box

LEGS_ONLY = ActorConfig(plan_upper_body=False)


def walk(environment, start, commands, config=LEGS_ONLY):
    """
    Walk ``commands`` from ``start``; return (actor, blocks, frames, report).

    (actor, blocks, frames, report) of ``commands`` ((time s, linear m/s, angular rad/s) rows, the
    last one's time the end) from ``start``.
    """
    actor = Actor(skeleton(), environment, config, start=start)
    blocks = run_commands(actor, *zip(*commands))
    _, frames, report = judged(blocks, environment)
    return actor, blocks, frames, report


def assert_judged_ok(report):
    assert report.ok, '; '.join(report.failures()[:6])
    assert max(report.slip.values()) <= 0.010


@pytest.mark.parametrize('angular', [0.0, 0.6, -0.4])
def test_backward_path_is_the_arc_cmd_vel_means(angular):
    """The predicted path of (v < 0, w) is where a mobile base driven by that twist goes."""
    v, heading = -0.4, 0.3
    path = predict_path(1.0, 2.0, heading, v, angular, 2.0)
    assert path.backward
    # The twist integrated in small time steps: the pose moves along its facing at v.
    dt, x, y, yaw, points = 1e-3, 1.0, 2.0, heading, []
    for _ in range(3000):
        x += v * np.cos(yaw) * dt
        y += v * np.sin(yaw) * dt
        yaw += angular * dt
        points.append((x, y, yaw))
    points = np.array(points)
    s = abs(v) * dt * np.arange(1, len(points) + 1)
    poses = path.poses(s)
    np.testing.assert_allclose(poses[:, :2], points[:, :2], atol=2e-3)
    # The path's heading is the travel direction, half a turn from the facing.
    np.testing.assert_allclose(poses[:, 2] + path.facing_offset, points[:, 2], atol=2e-3)


def test_backward_speed_is_its_own_limit_and_the_paper_actor_walks_forward_only():
    environment = scene('flat').environment
    actor = Actor(skeleton(), environment, LEGS_ONLY)
    warning = actor.set_command(-2.0, 0.0)
    assert 'clamped' in warning and actor.command[0] == -LEGS_ONLY.max_backward_speed
    assert LEGS_ONLY.max_backward_speed < LEGS_ONLY.max_linear_speed
    paper = Actor(skeleton(), environment, ActorConfig(plan_upper_body=False,
                                                       allow_backward=False))
    assert paper.set_command(-0.3, 0.0) is not None and paper.command[0] == 0.0
    block = paper.plan_next()
    assert block.status == 'idle' and np.ptp(block.frames[:, 0]) == 0.0
    with pytest.raises(ValueError, match='max_backward_speed'):
        validate(ActorConfig(max_backward_speed=1.5))
    with pytest.raises(ValueError, match='backward'):
        validate(ActorConfig(backward_step_length_max=0.05))


@pytest.mark.slow
def test_backward_walk_on_the_flat_course():
    sc = scene('flat')
    speed = -0.4
    actor, blocks, frames, report = walk(sc.environment, (4.0, 0.0, 0.0),
                                         [(0.0, speed, 0.0), (6.0, 0.0, 0.0), (8.0, 0.0, 0.0)])
    assert_judged_ok(report)
    walking = [b for b in blocks if b.status == 'walking']
    assert len(walking) >= 6 and not any(b.status == 'stuck' for b in blocks)
    # It went backward, still facing forward, at about the commanded speed.
    assert frames[-1, 0] < 4.0 - 1.2
    assert abs(frames[-1, 1]) < 0.05 and np.abs(frames[:, 3]).max() < 0.05
    moving = np.concatenate([b.frames[:, 0] for b in walking])
    duration = sum(b.times[-1] - b.times[0] for b in walking)
    assert 0.5 * abs(speed) < (moving[0] - moving[-1]) / duration < 1.2 * abs(speed)
    # Backward steps are shorter than forward ones and land behind the stance foot.
    windowed = [b for b in walking if len(b.footsteps)]
    assert len(windowed) >= 6
    for block in windowed:
        window = block.footsteps
        assert np.all(window[:, 0] < block.frames[0, 0])
        assert np.all(np.diff(window[:, 0]) < 0)
        assert np.abs(np.diff(window[:, 0])).max() <= LEGS_ONLY.backward_step_length_max + 1e-9
        assert np.all(np.abs(window[:, 3]) < 0.05), 'the feet face forward'
    assert LEGS_ONLY.backward_step_length_max < LEGS_ONLY.footsteps.step_length_max
    # The arms swing in counter-phase to the legs: each shoulder against its own hip.
    index = skeleton().index
    for side in ('left', 'right'):
        hip = frames[:, index[f'{side}_hip_pitch']]
        shoulder = frames[:, index[f'{side}_shoulder_pitch']]
        assert np.corrcoef(hip, shoulder)[0, 1] < -0.5
    # A released drag stills it.
    assert blocks[-1].status == 'idle' and actor.stance.at_rest


@pytest.mark.slow
@pytest.mark.parametrize('angular', [0.6, -0.6])
def test_turning_while_walking_backward_follows_the_commanded_arc(angular):
    sc = scene('flat')
    speed = -0.4
    _, blocks, frames, report = walk(sc.environment, (6.0, 0.0, 0.0),
                                     [(0.0, speed, angular), (6.0, 0.0, 0.0)])
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in blocks)
    # cmd_vel's arc: centre speed / rate to the left of the start, the facing turning at the
    # rate (backward and turning left the pelvis swings to the right).
    centre = np.array([6.0, speed / angular])
    radius = abs(speed / angular)
    distance = np.hypot(frames[:, 0] - centre[0], frames[:, 1] - centre[1])
    assert np.abs(distance - radius).max() < 0.2, (distance.min(), distance.max(), radius)
    assert np.sign(angular) * frames[-1, 3] > 1.2
    travelled = np.unwrap(np.arctan2(frames[:, 1] - centre[1], frames[:, 0] - centre[0]))
    assert np.sign(angular) * (travelled[-1] - travelled[0]) > 1.2


@pytest.mark.slow
def test_the_actor_stops_before_it_walks_the_other_way():
    sc = scene('flat')
    commands = [(0.0, 0.8, 0.0), (3.0, -0.4, 0.0), (7.0, 0.6, 0.0), (10.0, 0.0, 0.0),
                (11.0, 0.0, 0.0)]
    _, blocks, frames, report = walk(sc.environment, (4.0, 0.0, 0.0), commands)
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in blocks)
    times = np.concatenate([b.times for b in blocks])
    x = frames[:, 0]
    turned_back, turned_on = x[times <= 3.5].max(), x[(times > 3.5) & (times <= 7.5)].min()
    assert turned_back - turned_on > 0.8 and x[-1] - turned_on > 0.8
    # Each reversal brings the feet side by side first.
    for at in (3.0, 7.0):
        following = [b for b in blocks if b.times[0] >= at - 0.05][0]
        assert following.category == 'closing', following.category


@pytest.mark.slow
def test_backward_into_the_wall_stops_cleanly_and_a_forward_drag_frees_it():
    sc = scene('wall')
    actor = Actor(skeleton(), sc.environment, ActorConfig(), start=(4.6, 0.0, 0.0))
    before = run_commands(actor, [0.0, 5.0], [-0.4, -0.4], [0.0, 0.0])
    assert before[-1].status == 'stuck' and 'behind the actor' in before[-1].reason
    stuck_x = actor.configuration[0]
    assert 3.2 < stuck_x < 4.0
    last = np.vstack([b.frames for b in before if b.times[0] > before[-1].times[-1] - 1.0])
    assert np.ptp(last, axis=0).max() < 1e-9
    actor.set_command(0.5, 0.0)
    after = [actor.plan_next() for _ in range(4)]
    assert all(b.status == 'walking' for b in after), [b.reason for b in after]
    _, frames, report = judged(before + after, sc.environment)
    assert_judged_ok(report)
    assert frames[-1, 0] > stuck_x + 0.5


@pytest.mark.slow
@pytest.mark.parametrize('name, branch', [('low_beam', 'waist'), ('table', 'left_arm')])
def test_backward_past_an_obstacle_the_upper_body_clears(name, branch):
    """
    The CT-roadmap plans the upper body walking backward too.

    The CT-roadmap plans the upper body walking backward too: under the low beam the waist bends,
    beside the table the left arm keeps clear of its top.
    """
    sc = scene(name)
    _, blocks, frames, report = walk(sc.environment, (5.0, 0.0, 0.0),
                                     [(0.0, -0.4, 0.0), (13.0, 0.0, 0.0)], ActorConfig())
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in blocks)
    assert frames[-1, 0] < 1.0, 'it went past the obstacle'
    # Off the motion pattern near the obstacle (the pattern keeps the waist erect and the
    # elbows within 0.3 rad).
    index = skeleton().index
    if branch == 'waist':
        assert frames[:, index['waist_pitch']].max() > 0.2
    else:
        assert frames[:, index['left_elbow']].max() > 0.6


@pytest.mark.slow
def test_backward_up_and_down_the_ramps_and_over_the_bumps():
    """
    Feet land pitched with the ground behind the actor.

    Feet land pitched with the ground behind the actor: up the 12 degree ramp to the plateau and
    down the other one, and back over the rough course's bumps.
    """
    sc = scene('slope')
    plateau = skeleton().leg.standing_height + 0.6
    _, blocks, frames, report = walk(sc.environment, (0.5, 0.0, np.pi),
                                     [(0.0, -0.4, 0.0), (20.0, 0.0, 0.0), (21.0, 0.0, 0.0)])
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in blocks)
    assert frames[:, 2].max() > plateau - 0.05 and frames[-1, 2] < plateau - 0.2
    sc = scene('rough')
    _, blocks, frames, report = walk(sc.environment, (9.0, 0.0, 0.0),
                                     [(0.0, -0.4, 0.0), (16.0, -0.4, 0.3), (20.0, 0.0, 0.0)])
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in blocks)
    assert frames[-1, 0] < 2.0


def step_scene(height):
    """Flat ground with a step ``height`` m up at x = 1 m, its top running on to x = 4 m."""
    return Environment([box((-2, -2, -0.2), (4, 2, 0.0)), box((1.0, -2, -0.2), (4, 2, height))])


@pytest.mark.slow
def test_down_the_stairs_backward():
    sc = scene('stairs_up')
    # On the landing (0.75 m), facing away from the flight, stepping back down it.
    _, blocks, frames, report = walk(sc.environment, (3.6, 0.0, 0.0),
                                     [(0.0, -0.4, 0.0), (12.0, 0.0, 0.0)])
    assert_judged_ok(report)
    assert sum(b.category == 'downhill' for b in blocks) >= 5
    assert frames[-1, 0] < 1.2 and frames[-1, 2] < 1.0, 'it reached the floor below'
    assert not any(b.status == 'stuck' for b in blocks)


@pytest.mark.slow
def test_up_a_curb_backward_and_a_clean_stop_before_a_flight():
    # A curb the legs can step up backward.
    environment = step_scene(0.1)
    _, blocks, frames, report = walk(environment, (0.0, 0.0, np.pi),
                                     [(0.0, -0.4, 0.0), (7.0, 0.0, 0.0)])
    assert_judged_ok(report)
    assert any(b.category == 'uphill' for b in blocks)
    assert frames[-1, 0] > 1.5 and frames[-1, 2] > 0.95
    # Backward up 0.15 m risers the landing ankle would pass its limit: the actor stops
    # before the first one, still, with the reason, and goes on when steered away.
    sc = scene('stairs_up')
    actor, blocks, frames, report = walk(sc.environment, (0.5, 0.0, np.pi),
                                         [(0.0, -0.4, 0.0), (6.0, -0.4, 0.0)])
    assert_judged_ok(report)
    assert blocks[-1].status == 'stuck' and 'behind the actor' in blocks[-1].reason
    assert frames[:, 0].max() < 1.5 and frames[:, 2].max() < 0.95
    last = frames[np.concatenate([b.times for b in blocks]) > blocks[-1].times[-1] - 1.0]
    assert np.ptp(last, axis=0).max() < 1e-9
    actor.set_command(0.5, 0.0)
    assert all(actor.plan_next().status == 'walking' for _ in range(3))


def escape(name, stuck_commands, config, start=None, backward=-0.4, duration=4.0):
    """
    Walk course ``name`` until the actor is stuck, then drag it backward.

    Walk course ``name`` with ``stuck_commands`` until the actor is stuck, then drag it backward
    for ``duration`` s. Returns (position when stuck (2,), blocks after, frames, report of the
    whole walk).
    """
    sc = scene(name)
    actor = Actor(skeleton(), sc.environment, config,
                  start=sc.start if start is None else start)
    before = run_commands(actor, *zip(*stuck_commands))
    assert before[-1].status == 'stuck', f'{name}: not stuck ({before[-1].status})'
    stuck_at = actor.configuration[:2].copy()
    actor.set_command(backward, 0.0)
    after = []
    while actor.time < before[-1].times[-1] + duration:
        after.append(actor.plan_next())
    _, frames, report = judged(before + after, sc.environment)
    return stuck_at, after, frames, report


def assert_freed(stuck_at, after, frames, report, name):
    assert_judged_ok(report)
    assert not any(b.status == 'stuck' for b in after), [b.reason for b in after][:3]
    assert sum(b.status == 'walking' for b in after) >= 3
    back = (stuck_at - frames[-1, :2]) @ np.array([np.cos(frames[-1, 3]), np.sin(frames[-1, 3])])
    assert back > 0.5, f'{name}: {back:.2f} m back'


@pytest.mark.slow
@pytest.mark.parametrize('name', ['wall', 'beam_too_low'])
def test_a_backward_drag_frees_the_actor_stuck_at_an_impassable_obstacle(name):
    # Stuck as the course stops it (the upper body's planner included: the beam stops the
    # waist, not the legs).
    stuck_at, after, frames, report = escape(name, [(0.0, 0.8, 0.0), (8.0, 0.8, 0.0)],
                                             ActorConfig())
    assert_freed(stuck_at, after, frames, report, name)


@pytest.mark.slow
def test_a_backward_drag_frees_the_actor_at_the_floor_edge():
    # The flat course's floor ends at x = 16 m.
    stuck_at, after, frames, report = escape('flat', [(0.0, 0.8, 0.0), (6.0, 0.8, 0.0)],
                                             LEGS_ONLY, start=(13.0, 0.0, 0.0))
    assert stuck_at[0] > 14.5
    assert_freed(stuck_at, after, frames, report, 'flat')


@pytest.mark.slow
def test_a_backward_drag_frees_the_one_step_window_stuck_in_figure8s_trap():
    """
    Paper Figure 8: a backward drag frees a one-step window stuck in the pit.

    Paper Figure 8: a window of one footstep steps into the pit and is stuck there, one foot down
    in it, the other on the walkway (0.33 m higher) behind; dragged backward, the foot in the pit
    steps back up past the other and the actor walks back along the walkway.
    """
    sc, _, _, blocks = simulate('figure8_trap', window_steps=1, greedy_restart=False)
    assert blocks[-1].status == 'stuck'
    config = ActorConfig(plan_upper_body=False,
                         footsteps=FootstepConfig(window_steps=1, greedy_restart=False))
    stuck_at, after, frames, report = escape('figure8_trap', [(0.0, 0.8, 0.0), (10.0, 0.8, 0.0)],
                                             config)
    x0, x1 = sc.expect['trap_x']
    assert x0 - 0.2 < stuck_at[0] < x1
    assert_freed(stuck_at, after, frames, report, 'figure8_trap')
    walkway = skeleton().leg.standing_height + 0.33
    assert frames[-1, 2] > walkway - 0.1, 'back up on the walkway'


def test_node_parameters_set_the_backward_limits_and_name_a_bad_one():
    from digital_actor_planner.nodes.planner_params import ConfigurationError, \
        default_scene_path, parameter_declarations, read_node_config, validate_node_config
    declared = {name: default for name, default, _ in parameter_declarations()}
    assert declared['allow_backward'] is True
    assert declared['max_backward_speed'] < declared['max_linear_speed']
    values = dict(declared, scene=default_scene_path(), start_pose=None,
                  max_backward_speed=0.3, allow_backward=False)
    config = read_node_config(values.get)
    validate_node_config(config)
    actor_config = ActorConfig.from_settings(**config.actor_config_fields())
    assert actor_config.max_backward_speed == 0.3 and not actor_config.allow_backward
    with pytest.raises(ConfigurationError, match='max_backward_speed') as caught:
        validate_node_config(read_node_config(dict(values, max_backward_speed=2.0).get))
    assert caught.value.parameter == 'max_backward_speed'
