"""Upper-body compliant motion: objective motion patterns and prioritized planning (paper §5).

§5.1 defines the motion patterns O_x(t), x in {waist, left arm, right arm}, that the upper body
follows whenever it can: the waist kept erect, the arms swinging alternately in step with the
legs. §5 plans the branches in priority order, waist first, then the arms, each in its own
configuration-time space with the earlier branches fixed.
"""
from __future__ import annotations

import numpy as np

from digital_actor_planner.core.skeleton import Skeleton

#: Shoulder roll that keeps a hanging arm clear of the torso and the thigh, rad.
ARM_CLEARANCE_ROLL = 0.06
#: Elbow flexion of a relaxed walking arm, rad.
RELAXED_ELBOW = 0.25
#: Extra elbow flexion per radian of forward arm swing, rad/rad.
ELBOW_SWING_GAIN = 0.2
#: Half the hip-pitch difference of a normal stride, rad: the arm swing saturates around it.
NOMINAL_HIP_SWING = 0.35


def motion_patterns(skeleton: Skeleton, frames: np.ndarray,
                    swing_amplitude: float = 0.35) -> np.ndarray:
    """Fill the upper-body columns with the walking motion patterns O_x(t) (§5.1).

    The waist is erect (yaw = pitch = 0). Each arm swings opposite to the leg on its own side:
    the left shoulder pitch follows the right hip pitch and the right shoulder pitch the left,
    through half the hip-pitch difference so the swing is centred on the hanging arm. The
    shoulder roll stays at a small abduction that keeps the arm clear of the body, the shoulder
    yaw at 0, and the elbow slightly flexed, flexing a little more as the arm swings forward.

    Parameters
    ----------
    skeleton
        The actor model (joint order and limits).
    frames
        (k, 22) float64 configurations, rad or m; the leg columns drive the arm swing.
    swing_amplitude
        Largest shoulder-pitch swing, rad, in [0, 1].

    Returns
    -------
    numpy.ndarray
        (k, 22) float64: a copy of ``frames`` with the waist and arm columns replaced, clipped
        to the joint limits.

    """
    frames = np.asarray(frames, dtype=float)
    if frames.ndim != 2 or frames.shape[1] != len(skeleton.joint_names):
        raise ValueError(f'frames must have shape (k, {len(skeleton.joint_names)}), '
                         f'got {frames.shape}')
    if not np.all(np.isfinite(frames)):
        raise ValueError('frames contain NaN or infinite values')
    if not (np.isfinite(swing_amplitude) and 0.0 <= swing_amplitude <= 1.0):
        raise ValueError(f'swing_amplitude must be in [0, 1] rad, got {swing_amplitude}')
    out = frames.copy()
    index = skeleton.index
    out[:, skeleton.branch('waist')] = 0.0
    # Half the difference is zero-mean over a stride, so no per-block centring is needed and
    # successive blocks join continuously.
    stride = 0.5 * (frames[:, index['right_hip_pitch']] - frames[:, index['left_hip_pitch']])
    swing = swing_amplitude * np.tanh(stride / NOMINAL_HIP_SWING)
    for side, sign in (('left', 1.0), ('right', -1.0)):
        pitch = sign * swing
        out[:, index[f'{side}_shoulder_pitch']] = pitch
        out[:, index[f'{side}_shoulder_roll']] = ARM_CLEARANCE_ROLL
        out[:, index[f'{side}_shoulder_yaw']] = 0.0
        out[:, index[f'{side}_elbow']] = RELAXED_ELBOW + ELBOW_SWING_GAIN * pitch
    upper = np.concatenate([skeleton.branch(name)
                            for name in ('waist', 'left_arm', 'right_arm')])
    out[:, upper] = np.clip(out[:, upper], skeleton.lower[upper], skeleton.upper[upper])
    return out
