"""A zero command ends the walk at the earliest stable stance (the actor stops within a step)."""
from course_runs import judged, scene, skeleton
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
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
