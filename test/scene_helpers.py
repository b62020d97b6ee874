"""Small builders shared by the planner tests."""
import numpy as np
import trimesh

from digital_actor_planner.core.ct_space import (
    BodyKinematics, BodyShapes, EnvironmentIndex, TimedBody)
from digital_actor_planner.core.upper_body import motion_patterns

RATE = 100.0


def box(lower, upper):
    """A closed box mesh spanning ``lower``..``upper`` ((3,) m each corner)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    mesh = trimesh.creation.box(extents=upper - lower)
    mesh.apply_translation((lower + upper) / 2)
    return mesh


def walk(skeleton, k, x0=-1.0, speed=0.9, swing_legs=True):
    """Times (k,) s and frames (k, 22) at RATE Hz: the pelvis along +x at ``speed`` m/s from
    ``x0``, root_z 0.92, the legs swinging (or straight), the upper body in its motion patterns."""
    times = np.arange(k) / RATE
    q = np.tile(skeleton.neutral(), (k, 1))
    q[:, skeleton.index['root_x']] = x0 + speed * times
    q[:, skeleton.index['root_z']] = 0.92
    if swing_legs:
        phase = 2 * np.pi * times / 1.2
        q[:, skeleton.index['left_hip_pitch']] = 0.3 * np.sin(phase)
        q[:, skeleton.index['right_hip_pitch']] = -0.3 * np.sin(phase)
    return times, motion_patterns(skeleton, q)


def timed_body(skeleton, environment, frames, padding=0.0):
    """The actor's body over ``frames`` in ``environment`` (an Environment), for CT-spaces."""
    return TimedBody(BodyKinematics(skeleton), BodyShapes(skeleton, padding),
                     EnvironmentIndex(environment.meshes, environment.objects), frames)
