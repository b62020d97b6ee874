"""A zero command ends the walk at the earliest stable stance (the actor stops within a step)."""
from course_runs import judged, scene, skeleton
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.evaluation.trajectory_check import check_trajectory
from digital_actor_planner.nodes.actor_planner import HURRY_MAX_RATE
from digital_actor_planner.runtime.frame_buffer import FrameBuffer
from digital_actor_planner.runtime.retiming import hurry
import numpy as np
import pytest

#: From the zero command to a root that stays still, s of actor time.
STOP_WITHIN = 0.7
ROOT = [skeleton().index[name] for name in ('root_x', 'root_y', 'root_yaw')]


def _walk_then_stop(stop_at: float, resume_at=None, speed: float = 0.6):
    sc = scene('flat')
    actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False), start=sc.start)
    times, linear = [0.0, stop_at], [speed, 0.0]
    if resume_at is not None:
        times, linear = times + [resume_at], linear + [0.6]
    end = times[-1] + 2.0
    blocks = run_commands(actor, times + [end], linear + [0.0], [0.0] * (len(times) + 1))
    return sc, actor, blocks


def _still_since(times: np.ndarray, frames: np.ndarray) -> float:
    """Time of the first frame from which the root never moves again, s."""
    moving = np.nonzero(np.any(np.abs(np.diff(frames[:, ROOT], axis=0)) > 1e-9, axis=1))[0]
    return float(times[moving[-1] + 1]) if moving.size else float(times[0])


# Several phases of the step in progress (a step at 0.6 m/s takes about 0.65 s) and both feet.
@pytest.mark.parametrize('stop_at', [2.0, 2.2, 2.4, 2.55, 2.6, 3.0])
def test_zero_command_at_any_phase_stills_the_root_within_0_7_s(stop_at):
    sc, actor, blocks = _walk_then_stop(stop_at)
    times, frames, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    in_progress = [b for b in blocks if b.times[0] - 0.01 <= stop_at < b.times[-1]]
    assert in_progress and in_progress[0].status == 'walking'
    still = _still_since(times, frames)
    assert still - stop_at <= STOP_WITHIN, \
        f'still {still - stop_at:.2f} s after the zero command given at {stop_at} s'
    assert actor.status == 'idle'
    # It stopped where the step landed: the feet stay apart, the pelvis between them.
    left, right = actor.stance.feet
    heading = np.array([np.cos(frames[-1, ROOT[2]]), np.sin(frames[-1, ROOT[2]])])
    assert abs(float((left.xy - right.xy) @ heading)) > 0.1
    pelvis = frames[-1, ROOT[:2]]
    assert min(left.xy @ heading, right.xy @ heading) < pelvis @ heading < \
        max(left.xy @ heading, right.xy @ heading)


# From a walk of 0.6 m/s the actor stops in its split stance; from the long strides of one of
# 1.2 m/s it brings the feet together first. Either way it walks on.
@pytest.mark.parametrize('speed, stop', [(0.6, 'settling'), (1.2, 'closing')])
def test_the_actor_walks_on_after_a_stop(speed, stop):
    sc, actor, blocks = _walk_then_stop(1.6, resume_at=3.0, speed=speed)
    times, frames, report = judged(blocks, sc.environment)
    assert report.ok, report.failures()
    assert not [b.reason for b in blocks if b.status == 'stuck']
    stopped = [b for b in blocks if b.category == stop]
    assert stopped, f'the walk did not stop with a {stop} step'
    x = skeleton().index['root_x']
    assert frames[-1, x] > stopped[0].frames[-1, x] + 0.3  # walked on after the stop


def _hurried_walk(course: str, stop_at: float):
    """
    Walk, told to stop at ``stop_at``, the step in progress hurried as the node plays it.

    Returns (scene, times, frames, velocities, blocks, the step in progress, its peak rate).
    """
    sc = scene(course)
    limit = skeleton().velocity_limit
    actor = Actor(skeleton(), sc.environment, ActorConfig(), start=sc.start)
    blocks = run_commands(actor, [0.0, stop_at, stop_at + 2.5], [0.6, 0.0, 0.0], [0.0] * 3)
    times, velocities, saved, hurried, peak = [], [], 0.0, None, 1.0
    for block in blocks:
        t, v = np.asarray(block.times) - saved, np.asarray(block.velocities)
        if block.status == 'walking' and t[0] - 0.01 <= stop_at < t[-1]:
            h = hurry(t, v, stop_at, limit, HURRY_MAX_RATE)
            t, v, saved, hurried, peak = h.times, h.velocities, saved + h.saved, block, h.peak_rate
        times.append(t)
        velocities.append(v)
    frames = np.vstack([b.frames for b in blocks])
    return sc, np.concatenate(times), frames, np.vstack(velocities), blocks, hurried, peak


# Stops at several phases of a level step and of steps up the stairs, upper body planned.
@pytest.mark.parametrize('course, stop_at', [('flat', 2.0), ('flat', 2.55), ('flat', 3.3),
                                             ('stairs_up', 2.2), ('stairs_up', 3.0)])
def test_a_hurried_stop_keeps_every_check_and_stills_the_root_sooner(course, stop_at):
    sc, times, frames, velocities, blocks, hurried, peak = _hurried_walk(course, stop_at)
    assert hurried is not None, 'no walking step in progress at the stop'
    report = check_trajectory(skeleton(), sc.environment, times, frames)
    assert report.ok, report.failures()  # no contact, a foot down, no slip, within limits
    assert np.all(np.diff(times) > 0)
    planned = np.concatenate([b.times for b in blocks])
    sooner = _still_since(planned, frames) - _still_since(times, frames)
    remaining = hurried.times[-1] - stop_at
    assert 1.0 < peak <= HURRY_MAX_RATE + 1e-9
    # The rest of the step takes remaining / (1 + (peak - 1) / 2).
    assert sooner == pytest.approx(remaining - remaining / (0.5 + 0.5 * peak), abs=0.011)
    # Within the 0.7 s of actor time allowed for a stop, with room for the node's latency.
    assert _still_since(times, frames) - stop_at <= STOP_WITHIN - 0.05


def test_hurry_keeps_the_poses_and_joins_on_at_both_ends():
    sc, actor, blocks = _walk_then_stop(2.55)
    step = next(b for b in blocks if b.status == 'walking' and b.times[0] <= 2.55 < b.times[-1])
    limit = skeleton().velocity_limit
    h = hurry(step.times, step.velocities, 2.55, limit, HURRY_MAX_RATE)
    before = step.times <= 2.55
    assert np.array_equal(h.times[before], step.times[before])
    assert h.saved > 0.05 and h.times[-1] == pytest.approx(step.times[-1] - h.saved)
    # The speed is unchanged where the hurry begins and where the step ends.
    assert np.allclose(h.velocities[-1], step.velocities[-1])
    first = np.argmax(~before)
    assert np.allclose(h.velocities[first], step.velocities[first], rtol=0.02, atol=1e-6)
    # No joint driven above its velocity limit, measured between the frames.
    speed = np.abs(np.diff(step.frames, axis=0)) / np.diff(h.times)[:, None]
    assert np.all(speed <= 1.05 * limit)


def test_hurry_changes_nothing_when_a_joint_is_already_at_its_limit():
    sc, actor, blocks = _walk_then_stop(2.55)
    step = next(b for b in blocks if b.status == 'walking' and b.times[0] <= 2.55 < b.times[-1])
    fastest = np.abs(step.velocities[step.times > 2.55]).max(axis=0)
    at_limit = np.where(fastest > 0.0, fastest, 1.0)  # every moving joint at its limit
    h = hurry(step.times, step.velocities, 2.55, at_limit, HURRY_MAX_RATE)
    assert h.saved == 0.0 and h.peak_rate == 1.0
    assert np.array_equal(h.times, step.times)


def test_the_stream_buffer_hurries_only_what_it_has_not_shown():
    sc, actor, blocks = _walk_then_stop(2.55)
    step = next(b for b in blocks if b.status == 'walking' and b.times[0] <= 2.55 < b.times[-1])
    buffer = FrameBuffer(step.frames[0], step.times[0] - 0.01)
    buffer.append(step.times, step.frames, step.velocities, now=step.times[0])
    shown = [buffer.sample(t)[0] for t in np.arange(step.times[0], 2.55, 0.01)]
    saved = buffer.hurry(2.55, skeleton().velocity_limit, HURRY_MAX_RATE)
    assert saved > 0.05 and buffer.end_time == pytest.approx(step.times[-1] - saved)
    # What was on show before the hurry is unchanged; the step still lands where planned.
    again = [buffer.sample(t)[0] for t in np.arange(step.times[0], 2.55, 0.01)]
    assert np.allclose(shown, again)
    assert np.allclose(buffer.sample(buffer.end_time)[0], step.frames[-1])
    # At a rate of 1 nothing is hurried.
    end = buffer.end_time
    assert buffer.hurry(2.6, skeleton().velocity_limit, 1.0) == 0.0 and buffer.end_time == end
