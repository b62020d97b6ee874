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
Walk generation for one step (§4.1): key frames, sagittal leg IK, Bezier swing, pelvis motion.

The legs are planned in their sagittal planes (§4): each leg has hip yaw, hip pitch, knee and
ankle, so a foot on the ground must stay in the vertical plane of its hip. The pelvis trajectory
is therefore built from the stance foot: the stance hip slides along the stance foot's plane while
the pelvis yaw turns towards the new heading, and the hip yaw takes up the difference (§4, last
paragraph). The landing foot is placed in the swing hip's plane at touchdown, so the next step
starts consistent again.

Key frames differ by the level of the next step (Figure 4): on level ground the pelvis moves
evenly; uphill the front leg is bent first (the pelvis rises late, after the foot is up);
downhill the rear leg is bent first (the pelvis lowers early, before the foot lands). The key
frames and the Bezier swing are written out in core/key_frames.py, which :meth:`WalkGenerator.step`
runs as they are.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import functools
import math
from typing import Tuple

import numpy as np

from .footsteps import FootstepConfig, LEFT, RIGHT, SOLE_LINES
from .jit import kernel
from .key_frames import (bezier_swing, GaitError, smoothstep, step_key_frames, SwingFootprint,
                         SwingLimits)
from .settings import check_settings, require, setting
from .skeleton import LegGeometry, Skeleton

SOLE_CLEARANCE = 0.002  # a resting sole floats this far above the surface, m


#: Gap the legs' collision cylinders keep at the end of a step, beyond touching, m. The next
#: step's toe-off flexes the rear knee forward in its plane: from pigeon-toed feet (0.35 rad)
#: with the rear one 0.25 m behind that closed a 1 cm gap in 4 frames, and every step and pivot
#: from there was refused (bench_steer_away seed 33, facing the floor's edge: trapped).
LEGS_LANDING_MARGIN = 0.02
#: A step ends with both knees at least this far below their limit, rad: the next step bends
#: one of them further. A rear foot left on a block's far edge, the knee at 2.27 rad, could not
#: lift: every next step passed 2.30 (bench_steer_away seed 32 on the blocks: trapped).
END_KNEE_MARGIN = 0.1
#: Points along a stance sole, ankle to toe tip, as fractions of its toe length (1 cm apart on
#: the model's 18 cm toe), on its middle line and its two long edges: a point within
#: _TOE_SUPPORT_TOLERANCE (m) of the ground under it rests on support.
_TOE_SAMPLES = np.linspace(1.0 / 18.0, 1.0, 18)
_TOE_ACROSS = np.array([0.0, -0.5, 0.5])
_TOE_SUPPORT_TOLERANCE = 0.015
#: How far a landing sole may be moved up or down from its planned foothold onto the ground
#: under it, m, and how much that ground may vary under the sole from the sole's plane (see
#: WalkGenerator._seated_sole): a landing 14 cm downhill of it on a 10-degree slope, a foot
#: pointing across it (1.8 cm from edge to edge) turned from the path.
SEAT_SHIFT = 0.03


@dataclass(frozen=True)
class GaitConfig:
    """
    Walk generation settings. Lengths in m, times in s, angles in rad.

    Why each rule and default is as it is: docs/LOWER_BODY.md.
    """

    frame_rate: float = setting(100.0, 10.0, 1000.0, 'Rate of the planned frames.', 'Hz')
    reach_fraction: float = setting(
        0.975, 0.5, 1.0, 'Fraction of thigh + shank the hip-to-ankle distance may reach.',
        low_open=True, high_open=True)
    pelvis_height_drop: float = setting(
        0.035, 0.0, None, 'How far the pelvis walks below the height of straight legs.', 'm')
    swing_lift: float = setting(
        0.07, 0.0, None, 'Lift of the swing curve above its footholds.', 'm')
    swing_clearance: float = setting(
        0.035, 0.0, None, 'Clearance the swing keeps above the ground it passes.', 'm')
    max_swing_lift: float = setting(
        0.55, 0.0, None, 'Highest the swing curve rises above the higher foothold.', 'm')
    min_step_time: float = setting(0.5, 0.0, None, 'Quickest step.', 's', low_open=True)
    max_step_time: float = setting(0.9, 0.0, None, 'Slowest step.', 's')
    time_per_rise: float = setting(
        1.5, 0.0, None, 'Step time added per metre of height change.', 's/m')
    min_turn_speed: float = setting(
        0.25, 0.0, None, 'Slowest speed a step is timed for (slower commands step no slower).',
        'm/s')
    max_heading_change: float = setting(
        0.5, 0.0, None, 'Half the largest pelvis turn in one step.', 'rad')
    turn_ease_heading: float = setting(
        0.5, 0.0, None, 'Angle between the feet at which the pelvis slows to rest as a foot '
        'lifts or lands (0: never).', 'rad')
    swing_toe_in: float = setting(
        0.15, 0.0, None, 'How far a foot in the air may turn in.', 'rad')
    # The longest step a walk prefers once its speed would ask more at nominal cadence, m:
    # faster, the steps come quicker instead (down to min_step_time), as people's do. Longer
    # steps swing the leg faster than its joints allow in that time, and the step is slowed
    # down: a 0.6 m step needs 0.67 s, a 0.8 m one 2 s, so striding out walked slower
    # (ActorConfig.max_linear_speed is the speed these steps walk at their quickest).
    fast_step_length: float = setting(
        0.55, 0.0, None, 'Longest step a fast walk prefers.', 'm')

    def __post_init__(self):
        """Check every field against its declaration and the step times against each other."""
        check_settings(self)
        require(self.min_step_time <= self.max_step_time, 'min_step_time', self.min_step_time,
                f'need min_step_time <= max_step_time, got {self.min_step_time}, '
                f'{self.max_step_time}')


def validate_gait_config(config: GaitConfig) -> None:
    """Raise :class:`ConfigError` naming the first bad field of ``config``."""
    config.__post_init__()


@dataclass(frozen=True)
class FootPose:
    """
    A foot resting on the ground: ankle position, yaw, sole pitch and sole height.

    A foot resting on the ground: ankle joint xy (m), ankle height (m), yaw and sole pitch (rad,
    toes up positive), and the sole height under the ankle (m).
    """

    xy: np.ndarray
    z: float
    yaw: float
    pitch: float
    sole: float


@dataclass(frozen=True)
class Stance:
    """
    Double-support state between two steps.

    ``pelvis`` is (x, y, z, yaw) with yaw unwrapped (continuous); ``feet`` is (left, right);
    ``stance_side`` is the foot that stays down during the next step (the one that landed last).
    """

    pelvis: np.ndarray
    feet: Tuple[FootPose, FootPose]
    stance_side: int
    at_rest: bool = True


@dataclass(frozen=True)
class StepMotion:
    """
    One generated step: frames (k, 22) at times (k,) s, the stance after it, its category.

    One generated step: frames (k, 22) at times (k,) s relative to the step start (the last frame
    is at the step's duration), the stance after it, and its category.
    """

    times: np.ndarray
    frames: np.ndarray
    stance: Stance
    category: str
    swing_lift: float
    lateral_error: float


# (start, length) of the ramps in a step's time shapes (see WalkGenerator._timing): over the
# normalised time (the plain smoothstep, the pelvis turn; the pelvis height's ramps are the key
# frames', key_frames.PELVIS_RAMPS) and over the swing curve's parameter (lift-off without and
# with delay, the swing foot's turn, the release of the lift-off pitch, the take-up of the
# landing pitch).
_TIME_RAMPS = np.array([[0.0, 1.0], [0.2, 0.8]])
_SWING_RAMPS = np.array([[0.0, 0.88 - 0.0], [0.12, 0.88 - 0.12], [0.2, 0.55], [0.15, 0.35],
                         [0.65, 0.35]])


@functools.lru_cache(maxsize=256)
def _step_timing(k: int, swing_clearance: float) -> _StepTiming:
    """
    Return the time shapes of a k-frame step, remembered and read-only.

    The time shapes of a k-frame step: a function of its arguments alone, remembered (a handful of
    step durations recur) and shared by every generator, so read-only.
    """
    tau = np.arange(1, k + 1) / k
    # The ramps over time through one smoothstep call, the ramps over the swing curve's
    # parameter through another (each row is the formula's own (x - start) / length).
    level, turn = smoothstep(
        (tau - _TIME_RAMPS[:, :1]) / _TIME_RAMPS[:, 1:])
    bezier = 0.5 * (tau + level)
    lift_now, lift_late, plane_turn, release, take = smoothstep(
        (bezier - _SWING_RAMPS[:, :1]) / _SWING_RAMPS[:, 1:])
    samples = np.arange(0, tau.size, max(1, tau.size // 24))
    if samples[-1] != tau.size - 1:
        samples = np.append(samples, tau.size - 1)
    timing = _StepTiming(
        tau=tau,
        ease={(False, False): tau, (False, True): _ease(tau, False, True),
              (True, False): _ease(tau, True, False), (True, True): level},
        ease_in=-tau * (1.0 - tau) ** 2,
        ease_out=tau * tau * (1.0 - tau),
        turn=turn,
        bezier=bezier,
        lift={0.0: lift_now, 0.12: lift_late},
        plane_turn=plane_turn,
        pitch_release=1.0 - release,
        pitch_take=take,
        fade=np.minimum(1.0, 6.0 * (1 - tau)),
        samples=samples,
        bezier_terms=_bezier_terms(bezier, samples, swing_clearance),
        pinned=np.maximum(1.0 - smoothstep((bezier - 0.04) / 0.12),
                          smoothstep((bezier - 0.84) / 0.12)),
        hump=np.sin(np.pi * bezier) ** 2)
    # Shared by every step of k frames: nothing may change them in place.
    _read_only((timing.tau, timing.ease, timing.ease_in, timing.ease_out, timing.turn,
                timing.bezier, timing.lift, timing.plane_turn, timing.pitch_release,
                timing.pitch_take, timing.fade, timing.samples,
                timing.bezier_terms, timing.pinned, timing.hump))
    return timing


def _bezier_terms(tau, samples, swing_clearance: float):
    """
    Return the swing curve's parameter, clearance and slack at the sampled frames, each (s,).

    The parts of :class:`key_frames.SwingFootprint` fixed by the number of frames alone.
    """
    b = tau[samples]
    ramp = np.minimum(1.0, 10.0 * np.minimum(b, 1.0 - b))
    # Near lift-off and touchdown the sole is by definition at its foothold: the
    # conservative map may read a few mm high there (the 3D check is exact).
    slack = 0.015 * (1.0 - ramp)
    # The clearance the sole keeps at each sample (full away from lift-off and touchdown).
    return b, swing_clearance * ramp, slack


def _wrap(angle):
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def _lateral(yaw, offset):
    """World xy of a point ``offset`` m to the left of a heading ``yaw``: (..., 2)."""
    yaw = np.asarray(yaw, dtype=float)
    out = np.empty(yaw.shape + (2,))
    out[..., 0] = -np.sin(yaw) * offset
    out[..., 1] = np.cos(yaw) * offset
    return out


def _points(xy: np.ndarray, z) -> np.ndarray:
    """(k, 3) points from (k, 2) xy and heights z (scalar or (k,)), m."""
    out = np.empty((xy.shape[0], 3))
    out[:, :2] = xy
    out[:, 2] = z
    return out


def foot_pose_on(xy, yaw, sole, pitch, leg: LegGeometry) -> FootPose:
    """
    Return the resting foot pose whose sole lies on a plane of ``pitch``.

    The resting foot pose whose sole lies on a plane of ``pitch`` at height ``sole`` under the
    ankle.
    """
    z = sole + leg.ankle_height / np.cos(pitch) + SOLE_CLEARANCE
    return FootPose(np.asarray(xy, dtype=float).copy(), float(z), float(yaw), float(pitch),
                    float(sole))


def standing_stance(skeleton: Skeleton, x: float, y: float, yaw: float, sole: float,
                    stance_side: int = RIGHT) -> Stance:
    """Both feet side by side under the hips on level ground at sole height ``sole``."""
    leg = skeleton.leg
    feet = []
    for side in (LEFT, RIGHT):
        offset = leg.hip_half_width if side == LEFT else -leg.hip_half_width
        xy = np.array([x, y]) + _lateral(yaw, offset)
        feet.append(foot_pose_on(xy, yaw, sole, 0.0, leg))
    z = feet[0].z + leg.thigh + leg.shank - 0.03
    return Stance(np.array([x, y, z, yaw], dtype=float), (feet[0], feet[1]), stance_side, True)


def leg_inverse_kinematics(leg: LegGeometry, hip: np.ndarray, ankle: np.ndarray,
                           plane_yaw: np.ndarray, pelvis_yaw: np.ndarray,
                           foot_pitch: np.ndarray, plane_direction=None):
    """
    Sagittal-plane IK of one leg for k frames (§4: legs move in their sagittal planes).

    Parameters
    ----------
    leg
        The leg's sagittal-plane dimensions, m.
    hip, ankle
        (k, 3) world positions of the hip and ankle joints, m.
    plane_yaw
        (k,) heading of the leg's plane (= the foot's yaw), rad.
    pelvis_yaw
        (k,) pelvis yaw, rad.
    foot_pitch
        (k,) sole pitch, rad, toes up positive.
    plane_direction
        Optional (cos, sin) of ``plane_yaw``, each (k,), when the caller has them already.

    Returns
    -------
    tuple
        (joints (k, 4) hip_yaw, hip_pitch, knee, ankle in rad; lateral (k,) out-of-plane
        distance of the ankle, m; reach (k,) hip-ankle distance over the maximum).

    """
    # Few frames per call and many calls: minimum/maximum instead of clip and no stacking
    # keep the NumPy call overhead down (the values are the same).
    v = ankle - hip
    if plane_direction is None:
        cos_yaw, sin_yaw = np.cos(plane_yaw), np.sin(plane_yaw)
    else:
        cos_yaw, sin_yaw = plane_direction
    forward = v[:, 0] * cos_yaw + v[:, 1] * sin_yaw
    lateral = v[:, 0] * -sin_yaw + v[:, 1] * cos_yaw
    joints = np.empty((v.shape[0], 4))
    joints[:, 0] = _wrap(plane_yaw - pelvis_yaw)
    reach = _sagittal_leg(leg, forward, -v[:, 2], foot_pitch, joints)
    return joints, lateral, reach


def _sagittal_leg(leg: LegGeometry, forward: np.ndarray, down: np.ndarray,
                  foot_pitch: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """
    Return the in-plane part of :func:`leg_inverse_kinematics`.

    The ankle lies ``forward`` (k,) and ``down`` (k,) m from the hip in the leg's plane; hip
    pitch, knee and ankle (rad) go to columns 1..3 of ``joints`` (k, 4). Returns the reach
    (k,), the hip-ankle distance over the maximum. The hip yaw and the out-of-plane distance
    do not depend on the heights: the swing leg's passes, which change only those, solve
    just this part.
    """
    forward = np.asarray(forward, dtype=np.float64)
    down = np.asarray(down, dtype=np.float64)
    # A sole pitch for every frame, or one for all (the stance foot's): read with stride 0.
    pitch = np.asarray(foot_pitch, dtype=np.float64)
    return _sagittal_joints(forward, down, pitch.reshape(-1), int(pitch.ndim > 0),
                            float(leg.thigh), float(leg.shank), joints)


@kernel('Tuple((f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1]))(readonly(f8[::1]), '
        'readonly(f8[::1]), f8, f8, f8, f8, f8, f8, f8, f8, f8, f8)')
def _pelvis_track(turn, progress, yaw0, yaw1, lam0, lam1, foot_x, foot_y, along_x, along_y,
                  stance_offset, swing_offset):
    """
    Return :meth:`WalkGenerator.step`'s pelvis over a step: yaw and the stance hip's place.

    :meth:`WalkGenerator.step`'s pelvis over a step: the yaw (k,) turning from ``yaw0`` to ``yaw1``
    as ``turn`` and the stance hip's place (k,) along its foot's line from ``lam0`` to ``lam1`` as
    ``progress``, m, then the stance hip (k, 2) on that line (from the foot at (``foot_x``,
    ``foot_y``) along (``along_x``, ``along_y``)), the pelvis (k, 2) ``stance_offset`` m to its
    right of the heading and the swing hip (k, 2) ``swing_offset`` m to the pelvis' left (what
    _lateral gives, from one sine and cosine of the yaw).
    """
    count = turn.shape[0]
    yaw, lam = np.empty(count), np.empty(count)
    stance_hip, pelvis, swing_hip = np.empty((count, 2)), np.empty((count, 2)), np.empty(
        (count, 2))
    for i in range(count):
        yaw[i] = yaw0 + (yaw1 - yaw0) * turn[i]
        lam[i] = lam0 + (lam1 - lam0) * progress[i]
        stance_hip[i, 0] = foot_x + lam[i] * along_x
        stance_hip[i, 1] = foot_y + lam[i] * along_y
        sin_yaw, cos_yaw = math.sin(yaw[i]), math.cos(yaw[i])
        pelvis[i, 0] = stance_hip[i, 0] - -sin_yaw * stance_offset
        pelvis[i, 1] = stance_hip[i, 1] - cos_yaw * stance_offset
        swing_hip[i, 0] = pelvis[i, 0] + -sin_yaw * swing_offset
        swing_hip[i, 1] = pelvis[i, 1] + cos_yaw * swing_offset
    return yaw, lam, stance_hip, pelvis, swing_hip


@kernel('f8(f8)')
def _wrapped(angle):
    """:func:`_wrap` of one angle (Python's and NumPy's remainder: the divisor's sign)."""
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


@kernel('Tuple((f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[::1]))(readonly(f8[::1]), '
        'readonly(f8[::1]), readonly(f8[::1]), readonly(f8[::1]), readonly(f8[::1]), '
        'f8[:, ::1], f8[::1], f8, f8, f8, f8, f8, f8, b1, f8, f8, f8, f8, f8, f8, f8)')
def _swing_plane(progress, plane_turn, pinned, pitch_release, pitch_take, swing_hip, yaw,
                 foot_x, foot_y, foot_yaw, turn, landing_x, landing_y, turning, inward,
                 stance_yaw, toe_in, low, high, lift_pitch, landing_pitch):
    """
    Return :meth:`WalkGenerator.step`'s swing foot over a step, before its heights.

    :meth:`WalkGenerator.step`'s swing foot over a step, before its heights: the leg's plane
    heading (k,), its direction (k, 2) as cosine and sine, the ankle's reach along it from the hip
    (k,), the ankle (k, 2) and the sole pitch (k,).

    The foot (at (``foot_x``, ``foot_y``), heading ``foot_yaw``) travels to the landing
    (``landing_x``, ``landing_y``) as ``progress`` and turns by ``turn`` as ``plane_turn``
    (once it is off the ground, §4: hip yaw); the ankle lies in the plane through the swing
    hip (``swing_hip`` (k, 2)). In a turn (``turning``) near lift-off and touchdown, as
    ``pinned``, the plane turns through the foot instead of carrying it sideways (where the
    foot is farther from the hip than the sole's ends are from the ankle); in the air the
    foot points at most ``toe_in`` towards the stance foot (heading ``stance_yaw``; ``inward``
    +1 for a right swing foot, -1 for a left), as the thighs would meet; and where the hip
    yaw off the pelvis ``yaw`` passes [``low``, ``high``] in mid-swing the foot lags, as
    far as the hip allows. Each correction, when some frame needs it, recomputes every
    frame's direction from its heading, as the NumPy code did. The sole levels out early in
    the swing (after a heel-off) and takes the landing pitch late: ``lift_pitch`` x
    ``pitch_release`` + ``landing_pitch`` x ``pitch_take``.
    """
    count = yaw.shape[0]
    plane = np.empty(count)
    direction = np.empty((count, 2))
    wanted = np.empty((count, 2))
    step_x, step_y = landing_x - foot_x, landing_y - foot_y
    for i in range(count):
        plane[i] = foot_yaw + turn * plane_turn[i]
        wanted[i, 0] = foot_x + progress[i] * step_x
        wanted[i, 1] = foot_y + progress[i] * step_y
        direction[i, 0] = math.cos(plane[i])
        direction[i, 1] = math.sin(plane[i])
    if turning:
        # Turning the plane swings the sole about the ankle: that moves its ends less than
        # carrying it sideways only where the foot is farther from the hip than they are from
        # the ankle.
        worst = -np.inf
        for i in range(count):
            toward_x = wanted[i, 0] - swing_hip[i, 0]
            toward_y = wanted[i, 1] - swing_hip[i, 1]
            length = np.hypot(toward_x, toward_y)
            sign = -1.0 if toward_x * direction[i, 0] + toward_y * direction[i, 1] < 0 else 1.0
            scale = sign / max(length, 1e-9)
            through_x, through_y = toward_x * scale, toward_y * scale
            weight = pinned[i] * min(max((length - 0.15) / 0.1, 0.0), 1.0)
            x = direction[i, 0] + weight * (through_x - direction[i, 0])
            y = direction[i, 1] + weight * (through_y - direction[i, 1])
            norm = np.hypot(x, y)
            direction[i, 0], direction[i, 1] = x / norm, y / norm
            plane[i] = math.atan2(direction[i, 1], direction[i, 0])
            worst = max(worst, inward * _wrapped(plane[i] - stance_yaw) - toe_in)
        # Toes in, both thighs turn in, and as the swinging knee passes the stance knee with
        # both hips flexed the two would meet: in the air the swinging foot points at most
        # toe_in towards the stance foot (it turns further in as it lands).
        if worst > 0.0:
            for i in range(count):
                excess = inward * _wrapped(plane[i] - stance_yaw) - toe_in
                plane[i] = plane[i] - inward * (excess if excess >= 0.0 else 0.0) * (
                    1.0 - pinned[i])
                direction[i, 0] = math.cos(plane[i])
                direction[i, 1] = math.sin(plane[i])
        # The foot turns on its own ramp and the pelvis on another: in a large turn the hip
        # yaw between them overshoots the range in mid-swing though it starts and ends inside
        # it (after a zigzag, 0.44 -> 0.74 -> 0.45 rad was seen). In the air the foot may lag:
        # it points as far as the hip allows. Not near the ground (where the plane turns
        # through the foot), so it still leaves and lands as planned.
        outside = False
        for i in range(count):
            hip_yaw = _wrapped(plane[i] - yaw[i])
            outside = outside or hip_yaw < low or hip_yaw > high
        if outside:
            for i in range(count):
                hip_yaw = _wrapped(plane[i] - yaw[i])
                clipped = min(max(hip_yaw, low), high)
                plane[i] = yaw[i] + hip_yaw + (clipped - hip_yaw) * (1.0 - pinned[i])
                direction[i, 0] = math.cos(plane[i])
                direction[i, 1] = math.sin(plane[i])
    forward = np.empty(count)
    ankle = np.empty((count, 2))
    pitch = np.empty(count)
    for i in range(count):
        # A two-term dot product written out.
        forward[i] = ((wanted[i, 0] - swing_hip[i, 0]) * direction[i, 0]
                      + (wanted[i, 1] - swing_hip[i, 1]) * direction[i, 1])
        ankle[i, 0] = swing_hip[i, 0] + forward[i] * direction[i, 0]
        ankle[i, 1] = swing_hip[i, 1] + forward[i] * direction[i, 1]
        pitch[i] = lift_pitch * pitch_release[i] + landing_pitch * pitch_take[i]
    return plane, direction, forward, ankle, pitch


@kernel('b1(f8[:, :], f8[:, :], f8[:], f8, f8, f8, f8, f8, f8, f8, f8, f8)')
def _feet_meet(swing_xy, direction, swing_z, stance_x, stance_y, top, ux, uy, shift,
               half_length, half_width, far):
    """
    Return whether the swinging sole meets the stance sole at any frame.

    Whether the swinging sole (ankle ``swing_xy`` (k, 2), heading ``direction`` (k, 2) as cosine
    and sine, ankle height ``swing_z`` (k,)) meets the stance sole (ankle at (``stance_x``,
    ``stance_y``), heading (``ux``, ``uy``)) seen from above at a frame where it is below the
    stance foot's ``top``: a separating-axis test of the two boxes, ``shift`` from the ankle to the
    middle of a sole, ``half_length`` and ``half_width`` its half sizes. Sole middles farther apart
    than ``far`` squared (two half-diagonals) cannot meet.
    """
    for f in range(swing_xy.shape[0]):
        if not swing_z[f] < top:
            continue
        dx, dy = direction[f, 0], direction[f, 1]
        gap_x = swing_xy[f, 0] + shift * dx - (stance_x + shift * ux)
        gap_y = swing_xy[f, 1] + shift * dy - (stance_y + shift * uy)
        if not gap_x * gap_x + gap_y * gap_y < far:
            continue
        # |cos| and |sin| of the angle between the feet: the projections of one sole's axes
        # (along, across) on the other's.
        along = abs(dx * ux + dy * uy)
        across = abs(dy * ux - dx * uy)
        long_reach = half_length + half_length * along + half_width * across
        wide_reach = half_width + half_length * across + half_width * along
        if not (abs(gap_x * ux + gap_y * uy) > long_reach
                or abs(gap_y * ux - gap_x * uy) > wide_reach
                or abs(gap_x * dx + gap_y * dy) > long_reach
                or abs(gap_y * dx - gap_x * dy) > wide_reach):
            return True
    return False


@kernel('f8[:, ::1](f8[:, :], f8[:, :], readonly(i8[::1]), f8[::1], f8[::1])')
def _sole_points(swing_xy, direction, samples, along, across):
    """
    Return the points under the swinging sole at the sampled frames.

    Points under the swinging sole at the sampled frames: for each sample, each offset ``along``
    the sole from the ankle and each line ``across`` it (m, left positive), the point (x, y);
    (samples x along x across, 2), m, in that order.
    """
    out = np.empty((samples.shape[0] * along.shape[0] * across.shape[0], 2))
    row = 0
    for i in samples:
        dx, dy = direction[i, 0], direction[i, 1]
        for a in range(along.shape[0]):
            x = swing_xy[i, 0] + along[a] * dx
            y = swing_xy[i, 1] + along[a] * dy
            for c in range(across.shape[0]):
                out[row, 0] = x + across[c] * -dy
                out[row, 1] = y + across[c] * dx
                row += 1
    return out


@kernel('f8[:, ::1](f8[::1], i8, i8)')
def _across_sole(heights, along, across):
    """
    Return the highest of ``across`` heights at each point along the sole, m.

    The highest of ``across`` heights at each point along the sole: (samples, along), m; NaN
    (nothing to clear) read as -inf.
    """
    out = np.empty((heights.shape[0] // (along * across), along))
    for i in range(out.shape[0]):
        for a in range(along):
            most = -np.inf
            for c in range(across):
                value = heights[(i * along + a) * across + c]
                if value > most:
                    most = value
            out[i, a] = most
    return out


@kernel('UniTuple(i8, 2)(f8[:, :], f8[:], f8[::1], f8[::1])')
def _leg_violation(joints, reach, low, high):
    """
    Return where a leg's (k, 4) ``joints`` first leave their bounds.

    Where a leg's (k, 4) ``joints`` first leave their bounds [``low``, ``high``]: (-2, -1) when
    some ``reach`` (hip-ankle distance over the leg's length) passes 1, else (the first frame with
    a joint out of bounds, the first joint out of bounds in any frame), or (-1, -1).
    """
    for f in range(reach.shape[0]):
        if reach[f] > 1.0 + 1e-9:
            return -2, -1
    row, column = -1, joints.shape[1]
    for f in range(joints.shape[0]):
        for j in range(joints.shape[1]):
            if joints[f, j] < low[j] or joints[f, j] > high[j]:
                if row < 0:
                    row = f
                column = min(column, j)
    return row, (column if row >= 0 else -1)


@kernel('UniTuple(f8[::1], 3)(f8[:], f8[:], f8, f8)')
def _leg_triangle(forward, down, l1, l2):
    """
    Return the leg's triangle for ankles ``forward`` and ``down`` of the hip.

    The leg's triangle for ankles ``forward`` and ``down`` of the hip (m): the reach (the hip-ankle
    distance over the leg's length), and the cosines of the knee's inner angle and of the thigh's
    angle off the hip-ankle line (law of cosines, the distance kept within (0, l1 + l2]).
    """
    count = forward.shape[0]
    reach, cos_knee, cos_beta = np.empty(count), np.empty(count), np.empty(count)
    for i in range(count):
        # NumPy's hypot (the C library's): Python's math.hypot rounds differently.
        distance = np.hypot(forward[i], down[i])
        reach[i] = distance / (l1 + l2)
        d = min(max(distance, 1e-6), l1 + l2)
        squared = d * d
        cos_knee[i] = min(max((l1 * l1 + l2 * l2 - squared) / (2 * l1 * l2), -1.0), 1.0)
        cos_beta[i] = min(max((l1 * l1 + squared - l2 * l2) / (2 * l1 * d), -1.0), 1.0)
    return reach, cos_knee, cos_beta


@kernel('f8[::1](f8[:], f8[:], f8[:], i8, f8, f8, f8[:, :])')
def _sagittal_joints(forward, down, foot_pitch, pitch_step, l1, l2, joints):
    """
    Return :func:`_sagittal_leg`'s joints from the leg's triangle, per frame.

    :func:`_sagittal_leg`'s arithmetic: :func:`_leg_triangle`, then per frame the knee (pi less the
    triangle's inner angle), the hip pitch (the hip-ankle line's angle off the vertical plus the
    thigh's off that line) and the ankle that gives the sole pitch ``foot_pitch[i * pitch_step]``,
    into columns 1..3 of ``joints``; returns the reach. The C library's acos and atan2: on the
    development machine NumPy's float64 arccos and arctan2 give the same bits (every course's
    frames are unchanged); a NumPy built with other vector maths may differ in the last bit.
    """
    reach, cos_knee, cos_beta = _leg_triangle(forward, down, l1, l2)
    for i in range(forward.shape[0]):
        knee = np.pi - math.acos(cos_knee[i])
        hip_pitch = math.atan2(forward[i], down[i]) + math.acos(cos_beta[i])
        joints[i, 1] = hip_pitch
        joints[i, 2] = knee
        joints[i, 3] = foot_pitch[i * pitch_step] - (hip_pitch - knee)
    return reach


@kernel('Tuple((f8[:, ::1], f8[::1], f8))(f8[:, :], f8[::1], f8[:, :], i8[::1], f8, f8, f8, f8, '
        'f8, f8, f8, f8, f8, f8, f8, f8)')
def _rolled_stance(hip, pelvis_yaw, joints, over, limit, p0, foot_yaw, direction_x,
                   direction_y, toe_x, toe_y, toe_z, toe, ankle_height, l1, l2):
    """
    Roll the sole about the toe line where the ankle passes ``limit``.

    :meth:`WalkGenerator._heel_off`'s roll: at the frames ``over`` (where the ankle of ``joints``
    (k, 4) passes ``limit``) the sole pitches about the toe line at (``toe_x``, ``toe_y``,
    ``toe_z``), ``toe`` m ahead of the ankle along the foot's heading, by as much as brings the
    ankle back to its limit (at most to the foot's own pitch ``p0``): five rounds of the pitch from
    the last round's shank angle and the leg solved again (leg_inverse_kinematics written out, hips
    ``hip`` (k, 3), pelvis ``pelvis_yaw``). Returns a copy of the joints with those frames
    replaced, the ankle of the last of them (3,) and its sole pitch.
    """
    count = over.shape[0]
    shank = np.empty(count)
    for m in range(count):
        shank[m] = joints[over[m], 1] - joints[over[m], 2]
    solved = np.empty((count, 4))
    pitch = np.empty(count)
    ankle = np.empty((count, 3))
    forward, down = np.empty(count), np.empty(count)
    cos_yaw, sin_yaw = math.cos(foot_yaw), math.sin(foot_yaw)
    for _ in range(5):
        for m in range(count):
            f = over[m]
            p = min(limit + shank[m], p0)
            pitch[m] = p
            along = toe * math.cos(p) + ankle_height * math.sin(p)
            ankle[m, 0] = toe_x - along * direction_x
            ankle[m, 1] = toe_y - along * direction_y
            ankle[m, 2] = toe_z - (toe * math.sin(p) - ankle_height * math.cos(p))
            vx, vy = ankle[m, 0] - hip[f, 0], ankle[m, 1] - hip[f, 1]
            forward[m] = vx * cos_yaw + vy * sin_yaw
            down[m] = -(ankle[m, 2] - hip[f, 2])
            solved[m, 0] = _wrapped(foot_yaw - pelvis_yaw[f])
        _sagittal_joints(forward, down, pitch, 1, l1, l2, solved)
        for m in range(count):
            shank[m] = solved[m, 1] - solved[m, 2]
    out = joints.copy()
    for m in range(count):
        for c in range(4):
            out[over[m], c] = solved[m, c]
    last = np.empty(3)
    end_pitch = p0
    if count:
        last[:] = ankle[count - 1]
        end_pitch = pitch[count - 1]
    return np.ascontiguousarray(out), last, end_pitch


@kernel('Tuple((f8[:, ::1], f8[::1], f8, b1))(f8[:, ::1], f8[::1], f8[::1], f8, f8, f8, f8, f8, '
        'f8, f8, f8, f8, f8)')
def _stance_leg(stance_hip, yaw, z, foot_x, foot_y, foot_yaw, foot_z, foot_pitch, cos_s, sin_s,
                l1, l2, limit):
    """
    Return the stance leg's joints over a step (leg inverse kinematics written out).

    The stance leg over a step (leg_inverse_kinematics written out): its ankle at (``foot_x``,
    ``foot_y``, ``foot_z``), its plane along (``cos_s``, ``sin_s``) heading ``foot_yaw`` and its
    sole pitch ``foot_pitch`` stay put while the hip moves (``stance_hip`` (k, 2) at pelvis heights
    ``z``, pelvis ``yaw``). Returns the joints (k, 4), the reach, the ankle's distance from the
    hip's plane at the last frame, and whether the ankle passes ``limit`` anywhere (a heel-off).
    """
    count = yaw.shape[0]
    joints = np.empty((count, 4))
    forward, down = np.empty(count), np.empty(count)
    for i in range(count):
        joints[i, 0] = _wrapped(foot_yaw - yaw[i])
        forward[i] = (foot_x - stance_hip[i, 0]) * cos_s + (foot_y - stance_hip[i, 1]) * sin_s
        down[i] = -(foot_z - z[i])
    pitch = np.empty(1)
    pitch[0] = foot_pitch
    reach = _sagittal_joints(forward, down, pitch, 0, l1, l2, joints)
    last = count - 1
    lateral = (foot_x - stance_hip[last, 0]) * -sin_s + (foot_y - stance_hip[last, 1]) * cos_s
    over = False
    for i in range(count):
        over = over or joints[i, 3] > limit
    return joints, reach, lateral, over


@kernel('f8(f8, f8, f8, f8)')
def _ankle_correction(ankle, low, high, fade):
    """
    Return what brings a swinging foot's ``ankle`` (rad) into [``low``, ``high``].

    What brings a swinging foot's ``ankle`` (rad) into [``low``, ``high``], by the share ``fade``
    (none at touchdown).
    """
    return (min(max(ankle, low), high) - ankle) * fade


@kernel('void(f8[:, :], f8, f8, readonly(f8[::1]))')
def _fade_ankle(joints, low, high, fade):
    """
    Apply :func:`_ankle_correction` to a swinging foot's ankle at each frame, in place.

    :func:`_ankle_correction` of a swinging foot's ankle (column 3 of ``joints``) at each frame,
    applied in place.
    """
    for i in range(joints.shape[0]):
        joints[i, 3] = joints[i, 3] + _ankle_correction(joints[i, 3], low, high, fade[i])


@kernel('Tuple((b1, f8[::1], f8[::1], f8[::1], f8[::1], f8[::1], f8[::1], f8))(f8[::1], '
        'f8[::1], f8[:, ::1], f8[:, ::1], f8[:, ::1], f8[::1], f8[::1], readonly(f8[::1]), f8, '
        'f8, f8, f8, f8)')
def _swing_bounds(lam, forward, swing_xy, swing_hip, direction, plane_yaw, yaw, weight, z0,
                  nominal, r, stance_z, closest):
    """
    Return what :meth:`WalkGenerator.step`'s swing passes share.

    What :meth:`WalkGenerator.step`'s swing passes share: whether either hip is farther than ``r``
    from its ankle along the legs' lines (``lam``, ``forward``: out of reach); the highest pelvis
    the stance leg allows (its ankle at ``stance_z``); the pelvis height bound of both legs' reach
    and the key frames' height (``z0`` + (``nominal`` - ``z0``) x ``weight``); how far above the
    swing ankle its leg reaches; the swing ankle's reach in the leg's plane, the hip yaw of that
    plane off the pelvis ``yaw``, and how far above the ankle the hip must stay so the knee bends
    no more than the knee's limit allows (``closest``: the hip-ankle distance there); and the
    ankle's distance from the plane at the last frame.
    """
    count = lam.shape[0]
    out_of_reach = False
    for i in range(count):
        out_of_reach = out_of_reach or abs(lam[i]) > r or abs(forward[i]) > r
    stance_bound, z_bound = np.empty(count), np.empty(count)
    swing_reach, swing_forward = np.empty(count), np.empty(count)
    hip_yaw, hip_over_ankle = np.empty(count), np.empty(count)
    for i in range(count):
        stance_bound[i] = stance_z + math.sqrt(max(r * r - lam[i] * lam[i], 0.0))
        swing_reach[i] = math.sqrt(max(r * r - forward[i] * forward[i], 0.0))
        wanted = z0 + (nominal - z0) * weight[i]
        z_bound[i] = min(wanted, stance_bound[i])
        swing_x = swing_xy[i, 0] - swing_hip[i, 0]
        swing_y = swing_xy[i, 1] - swing_hip[i, 1]
        swing_forward[i] = swing_x * direction[i, 0] + swing_y * direction[i, 1]
        hip_yaw[i] = _wrapped(plane_yaw[i] - yaw[i])
        hip_over_ankle[i] = math.sqrt(max(closest * closest
                                          - swing_forward[i] * swing_forward[i], 0.0))
    last = count - 1
    lateral = ((swing_xy[last, 0] - swing_hip[last, 0]) * -direction[last, 1]
               + (swing_xy[last, 1] - swing_hip[last, 1]) * direction[last, 0])
    return (out_of_reach, stance_bound, z_bound, swing_reach, swing_forward, hip_yaw,
            hip_over_ankle, lateral)


@kernel('Tuple((f8[::1], f8[:, ::1], f8[::1], b1, f8[::1]))(f8[::1], f8[::1], f8[::1], '
        'f8[::1], readonly(f8[::1]), f8[::1], f8[::1], f8[::1], f8[::1], readonly(f8[::1]), '
        'f8, f8, f8, f8)')
def _swing_pass(swing_z, z_bound, swing_reach, hip_over_ankle, hump, stance_bound, hip_yaw,
                swing_forward, swing_pitch, fade, ankle_low, ankle_high, l1, l2):
    """
    Run one pass of :meth:`WalkGenerator.step`'s swing for ankle heights ``swing_z``.

    One pass of :meth:`WalkGenerator.step`'s swing: for swing ankle heights ``swing_z`` (k,), the
    pelvis height (the lowest of ``z_bound`` and what the swing leg reaches, raised by a smooth
    ``hump`` over the swing, scaled to cover any shortfall below ``hip_over_ankle``, up to the
    stance leg's ``stance_bound``: a frame-by-frame maximum jerked the pelvis up, and the arms
    swinging with the hips past their speed limit), the swing leg's joints (k, 4) (hip yaw
    ``hip_yaw``, then :func:`_sagittal_joints` for the sole pitch ``swing_pitch``) and reach;
    whether the ankle keeps within [``ankle_low``, ``ankle_high``] (a correction, faded by
    ``fade``, under 5 mm-rad everywhere), and the sole pitch that corrects it.
    """
    count = swing_z.shape[0]
    z = np.empty(count)
    most = -np.inf
    for i in range(count):
        z[i] = min(z_bound[i], swing_z[i] + swing_reach[i])
        most = max(most, swing_z[i] + hip_over_ankle[i] - z[i])
    if most > 0.0:
        scale = -np.inf
        for i in range(count):
            short = swing_z[i] + hip_over_ankle[i] - z[i]
            scale = max(scale, short / max(hump[i], 1e-3))
        for i in range(count):
            z[i] = min(z[i] + scale * hump[i], max(z[i], stance_bound[i]))
    joints = np.empty((count, 4))
    down = np.empty(count)
    for i in range(count):
        joints[i, 0] = hip_yaw[i]
        down[i] = -(swing_z[i] - z[i])
    reach = _sagittal_joints(swing_forward, down, swing_pitch, 1, l1, l2, joints)
    converged = True
    next_pitch = np.empty(count)
    for i in range(count):
        correction = _ankle_correction(joints[i, 3], ankle_low, ankle_high, fade[i])
        converged = converged and abs(correction) < 0.005
        next_pitch[i] = swing_pitch[i] + correction
    return z, joints, reach, converged, next_pitch


def _segment_gaps(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray,
                  b1: np.ndarray) -> np.ndarray:
    """Shortest distances (n,) between segments a0-a1 and b0-b1, all (3, n) (x, y, z rows), m."""
    u, v, r = a1 - a0, b1 - b0, a0 - b0
    # Dot products of (3, n) rows written out (a reduction over an axis of 3 is slow).
    uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2]
    vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    uv = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    ur = u[0] * r[0] + u[1] * r[1] + u[2] * r[2]
    vr = v[0] * r[0] + v[1] * r[1] + v[2] * r[2]
    # Closest points of the lines, then each parameter clamped and the other re-solved
    # (segments of non-zero length; parallel ones take s = 0).
    denominator = uu * vv - uv * uv
    s = np.where(denominator > 1e-12, (uv * vr - ur * vv) / np.maximum(denominator, 1e-12), 0.0)
    s = np.minimum(np.maximum(s, 0.0), 1.0)
    t = np.minimum(np.maximum((uv * s + vr) / vv, 0.0), 1.0)
    s = np.minimum(np.maximum((uv * t - ur) / uu, 0.0), 1.0)
    gap = r + u * s - v * t
    return np.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])


def _leg_segments(leg: LegGeometry, hip: np.ndarray, plane_yaw, joints: np.ndarray):
    """
    Return the (knee, ankle) points of a leg, each (3, k).

    (knee, ankle) points, each (3, k) (x, y, z rows), of a leg whose (k, 4) joints hang from
    ``hip`` (3, k) in the vertical plane of heading ``plane_yaw`` (scalar or (k,)).
    """
    cos_p, sin_p = np.cos(plane_yaw), np.sin(plane_yaw)
    thigh = joints[:, 1]
    shank = thigh - joints[:, 2]
    forward_knee = leg.thigh * np.sin(thigh)
    knee = np.empty_like(hip)
    knee[0] = hip[0] + forward_knee * cos_p
    knee[1] = hip[1] + forward_knee * sin_p
    knee[2] = hip[2] - leg.thigh * np.cos(thigh)
    forward_ankle = leg.shank * np.sin(shank)
    ankle = np.empty_like(hip)
    ankle[0] = knee[0] + forward_ankle * cos_p
    ankle[1] = knee[1] + forward_ankle * sin_p
    ankle[2] = knee[2] - leg.shank * np.cos(shank)
    return knee, ankle


def _ease(tau: np.ndarray, from_rest: bool, to_rest: bool) -> np.ndarray:
    """Progress of the pelvis over a step: constant speed, easing in or out at rest."""
    if from_rest and to_rest:
        return smoothstep(tau)
    if from_rest:
        return tau * tau * (2.0 - tau)
    if to_rest:
        return tau * (1.0 + tau - tau * tau)
    return tau


@dataclass(frozen=True)
class _StepTiming:
    """
    The time shapes of a step of k frames: everything in a step that depends only on k.

    Steps of the same number of frames share them (the step's own geometry scales them), so
    :class:`WalkGenerator` builds them once per k. All arrays are (k,) and read-only.

    Attributes
    ----------
    tau
        Normalised time of each frame, (1..k) / k.
    ease
        Pelvis progress per (from_rest, to_rest), see :func:`_ease`.
    ease_in, ease_out
        What easing fully in or out adds to constant-speed progress: ``tau + a * ease_in +
        b * ease_out`` starts at ``1 - a`` and ends at ``1 - b`` times the mean speed (a = b = 1
        are the rest eases of ``ease``).
    turn
        Pelvis yaw progress (it turns once the swing foot is off the ground).
    bezier
        Parameter of the swing curve per frame.
    lift
        Horizontal progress of the swing foot per lift-off delay (0.0 and 0.12).
    plane_turn
        Heading progress of the swing foot.
    pitch_release, pitch_take
        Weights of the lift-off pitch and of the landing pitch of the swinging sole.
    fade
        Weight of the swing ankle's range correction (none at touchdown).
    samples, bezier_terms
        Frames the swing clearance is tested at, and the swing curve's parameter, clearance
        and slack there (see :func:`_bezier_terms`).
    pinned
        How fully the swing foot's plane turns through the foot instead of moving with the hip:
        1 near lift-off and touchdown, 0 in mid-swing.
    hump
        A smooth bump over the swing, 0 at lift-off and touchdown, 1 in its middle.

    """

    tau: np.ndarray
    ease: dict
    ease_in: np.ndarray
    ease_out: np.ndarray
    turn: np.ndarray
    bezier: np.ndarray
    lift: dict
    plane_turn: np.ndarray
    pitch_release: np.ndarray
    pitch_take: np.ndarray
    fade: np.ndarray
    samples: np.ndarray
    bezier_terms: tuple
    pinned: np.ndarray
    hump: np.ndarray


def _columns(indices: np.ndarray):
    """Return a slice over ``indices`` when they are consecutive, else the indices themselves."""
    indices = np.asarray(indices)
    if indices.size and np.array_equal(indices, np.arange(indices[0], indices[0] + indices.size)):
        return slice(int(indices[0]), int(indices[0]) + indices.size)
    return indices


def _read_only(value):
    """Mark every array in a (nested) tuple or dict read-only; returns the value."""
    # A stack rather than recursion: a step's time shapes hold some forty arrays and a
    # call per item was most of the cost.
    pending = [value]
    while pending:
        item = pending.pop()
        if isinstance(item, np.ndarray):
            item.setflags(write=False)
            if isinstance(item.base, np.ndarray):
                # A row of a block built at once: the block too, or it is writable through
                # its base.
                item.base.setflags(write=False)
        elif isinstance(item, dict):
            pending.extend(item.values())
        elif isinstance(item, tuple):
            pending.extend(item)
    return value


class WalkGenerator:
    """
    Generates the lower-body motion of single steps (§4.1, Figure 3).

    Parameters
    ----------
    skeleton
        The actor model.
    config
        Gait settings.
    footstep_config
        Footstep limits (the same step-height limits bound the swing).

    """

    def __init__(self, skeleton: Skeleton, config: GaitConfig = GaitConfig(),
                 footstep_config: FootstepConfig = FootstepConfig()):
        validate_gait_config(config)
        self.skeleton = skeleton
        self.leg = skeleton.leg
        self.config = config
        self.footstep_config = footstep_config
        self._leg_index = {side: skeleton.branch('left_leg' if side == LEFT else 'right_leg')
                           for side in (LEFT, RIGHT)}
        self._leg_lower = {s: skeleton.lower[i] for s, i in self._leg_index.items()}
        self._leg_upper = {s: skeleton.upper[i] for s, i in self._leg_index.items()}
        self._root = skeleton.branch('root')
        # Where the pelvis and each leg go in a frame: a slice when the columns are in a run
        # (writing through a slice is cheaper than through an index array).
        self._root_columns = _columns(self._root)
        self._leg_columns = {s: _columns(i) for s, i in self._leg_index.items()}
        # The joint limits a planned leg is held to, with 1e-9 rad of rounding allowed.
        self._leg_bounds = {s: (self._leg_lower[s] - 1e-9, self._leg_upper[s] + 1e-9)
                            for s in (LEFT, RIGHT)}
        # The hip yaw range a swinging foot's heading is held to, 0.01 rad inside the limits.
        self._swing_yaw_range = {s: (float(self._leg_lower[s][0]) + 0.01,
                                     float(self._leg_upper[s][0]) - 0.01) for s in (LEFT, RIGHT)}
        # Where the swing clearance looks under the sole: 9 points heel..toe, and across it the
        # outer lines the footholds are read on (SOLE_LINES; the sole's own edges read obstacles
        # up to a map cell beside them, and a landing whose foothold was fine could not clear
        # a bump 5 mm beside its toe), m.
        self._sole_along = np.linspace(-self.leg.heel, self.leg.toe, 9)
        self._sole_across = np.array([SOLE_LINES[0], SOLE_LINES[-1]]) * self.leg.foot_width
        # Where a landing sole is seated on the ground (_seated_sole): 5 points heel..toe on its
        # middle line and its two edges, m.
        self._seat_along = np.linspace(-self.leg.heel, self.leg.toe, 5)
        self._seat_across = np.array([-0.5, 0.0, 0.5]) * self.leg.foot_width
        self._swing_limits = SwingLimits(float(config.swing_lift), float(config.max_swing_lift),
                                         float(self.leg.ankle_height))

    def _timing(self, k: int) -> _StepTiming:
        """Return the time shapes of a k-frame step (:func:`_step_timing`)."""
        return _step_timing(k, float(self.config.swing_clearance))

    def _turn_ease(self, heading_difference: float) -> float:
        """How far the pelvis eases to rest where the feet differ by ``heading_difference``."""
        full = self.config.turn_ease_heading
        if full <= 0.0:
            return 0.0
        return min(abs(_wrap(heading_difference)) / full, 1.0)

    def preferred_step_length(self, speed: float, nominal_step_time: float) -> float:
        """
        Return the step length a walk at ``speed`` m/s aims for, m.

        The step length a walk at ``speed`` m/s aims for, m: ``speed`` x ``nominal_step_time`` s,
        at most ``fast_step_length`` (a faster walk quickens its cadence instead,
        :meth:`step_duration`).
        """
        return float(min(speed * nominal_step_time, self.config.fast_step_length))

    def step_duration(self, length: float, speed: float, rise: float) -> float:
        """Duration of a step of ``length`` m at ``speed`` m/s changing height by ``rise`` m."""
        cfg = self.config
        base = length / max(speed, cfg.min_turn_speed, 1e-3)
        duration = float(min(max(base, cfg.min_step_time), cfg.max_step_time))
        duration += cfg.time_per_rise * abs(rise)
        return np.ceil(duration * cfg.frame_rate - 1e-9) / cfg.frame_rate

    def step(self, stance: Stance, landing_xy: np.ndarray, landing_yaw: float,
             landing_sole: float, landing_pitch: float, pelvis_target: np.ndarray,
             duration: float, swing_profile, to_rest: bool = False) -> StepMotion:
        """
        Generate one step: the swing foot moves to the landing foothold.

        Parameters
        ----------
        stance
            State at the start of the step (double support).
        landing_xy, landing_yaw, landing_sole, landing_pitch
            Planned foothold of the swing foot: ankle xy (m), yaw (rad), sole height (m), sole
            pitch (rad). The xy is adjusted along the landing heading so the foot lies in the
            swing hip's plane.
        pelvis_target
            (3,) desired pelvis x, y (m) and yaw (rad) at touchdown.
        duration
            Step time, s (a multiple of the frame period).
        swing_profile
            Callable (xy (N, 2), z_ref float) -> (N,) obstacle heights the swinging sole must
            clear (NaN over empty space).
        to_rest
            Ease the pelvis to a stop at the end.

        Raises
        ------
        GaitError
            When the step is out of reach, breaks a joint limit, or the swing cannot clear.

        """
        cfg, leg = self.config, self.leg
        rate = cfg.frame_rate
        k = int(round(duration * rate))
        if k < 2:
            raise GaitError(f'step duration {duration} s is too short')
        timing = self._timing(k)
        tau = timing.tau
        stance_side = stance.stance_side
        swing_side = 1 - stance_side
        foot_s, foot_w = stance.feet[stance_side], stance.feet[swing_side]
        w_s = leg.hip_half_width if stance_side == LEFT else -leg.hip_half_width
        w_w = -w_s
        x0, y0, z0, yaw0 = stance.pelvis
        yaw1 = yaw0 + _wrap(pelvis_target[2] - yaw0)
        if abs(yaw1 - yaw0) > 2 * cfg.max_heading_change + 1e-9:
            raise GaitError(f'heading change {yaw1 - yaw0:.2f} rad in one step is too large')

        # The stance hip slides along the stance foot's sagittal line.
        d_s = np.array([np.cos(foot_s.yaw), np.sin(foot_s.yaw)])
        hip0 = np.array([x0, y0]) + _lateral(yaw0, w_s)
        lam0 = float(np.dot(hip0 - foot_s.xy, d_s))
        hip1 = pelvis_target[:2] + _lateral(yaw1, w_s)
        lam1 = float(np.dot(hip1 - foot_s.xy, d_s))
        # In a turn the feet point different ways and a 2-DOF hip cannot keep both legs'
        # planes on their feet while the pelvis travels: the swing hip drifts across its
        # foot's plane as fast as the pelvis moves times the sine of the angle between the
        # feet. So the pelvis slows towards the moments a foot leaves or meets the ground, in
        # proportion to that angle (to rest at turn_ease_heading); the next step starts
        # from the same two feet, so its start speed matches this step's end.
        ease_start = 1.0 if stance.at_rest else self._turn_ease(foot_w.yaw - foot_s.yaw)
        ease_end = 1.0 if to_rest else self._turn_ease(landing_yaw - foot_s.yaw)
        if ease_start in (0.0, 1.0) and ease_end in (0.0, 1.0):
            progress = timing.ease[(ease_start == 1.0, ease_end == 1.0)]
        else:
            progress = tau + ease_start * timing.ease_in + ease_end * timing.ease_out
        # The pelvis turns once the swing foot is off the ground: turning it moves the swing
        # hip's plane sideways, which would drag a foot still on the ground.
        yaw, lam, stance_hip_xy, pelvis_xy, swing_hip_xy = _pelvis_track(
            timing.turn, progress, float(yaw0), float(yaw1), lam0, lam1,
            float(foot_s.xy[0]), float(foot_s.xy[1]), float(d_s[0]), float(d_s[1]), w_s, w_w)

        # Touchdown: the landing ankle lies in the swing hip's plane at the end of the step.
        d_l = np.array([np.cos(landing_yaw), np.sin(landing_yaw)])
        forward_end = float(np.dot(np.asarray(landing_xy) - swing_hip_xy[-1], d_l))
        land_xy = swing_hip_xy[-1] + forward_end * d_l
        landing_sole = self._seated_sole(land_xy, landing_yaw, float(landing_sole),
                                         float(landing_pitch), swing_profile)
        landing = foot_pose_on(land_xy, landing_yaw, landing_sole, landing_pitch, leg)
        # A diagnostic (not in the frames): math on two floats, not np.linalg.norm.
        error_x, error_y = (land_xy - np.asarray(landing_xy)).tolist()
        lateral_error = math.sqrt(error_x * error_x + error_y * error_y)

        # Swing foot: straight horizontal line with Bezier timing, lifted to clear the ground.
        # The curve parameter is eased in time so the foot leaves and meets the ground at rest.
        bezier = timing.bezier
        # The foot rises before it moves forward and is over its foothold before it descends.
        # A foot lifting from a heel-off is already rolling forward on its toe: no pause.
        delay = 0.0 if foot_w.pitch < -0.05 else 0.12
        p = timing.lift[delay]
        # The foot turns to its new heading only once it is off the ground (§4: hip yaw).
        # Near lift-off and touchdown the sole is within millimetres of the ground: there the
        # leg's plane turns through the foot (hip yaw) rather than carrying it sideways with the
        # hip, which in a turn moves across the foot's own plane (2-DOF hip, no hip roll). Where
        # both feet, the landing and the pelvis share one heading the hip moves along that
        # plane and nothing changes: straight walking skips it (see _swing_plane).
        turning = max(abs(_wrap(other - foot_w.yaw))
                      for other in (landing.yaw, foot_s.yaw, yaw0, yaw1)) > 1e-9
        low, high = self._swing_yaw_range[swing_side]
        plane_yaw, direction, forward, swing_xy, swing_pitch = _swing_plane(
            p, timing.plane_turn, timing.pinned, timing.pitch_release, timing.pitch_take,
            swing_hip_xy, yaw, float(foot_w.xy[0]), float(foot_w.xy[1]), float(foot_w.yaw),
            float(_wrap(landing.yaw - foot_w.yaw)), float(landing.xy[0]), float(landing.xy[1]),
            turning, 1.0 if swing_side == RIGHT else -1.0, float(foot_s.yaw),
            float(cfg.swing_toe_in), low, high, float(foot_w.pitch), float(landing.pitch))
        # Pelvis height: the key frames by category (§4.1, Figure 4), bounded by what both legs
        # can reach.
        key_frames = step_key_frames(foot_s, landing, float(z0), leg, cfg.pelvis_height_drop,
                                     tau)
        r = cfg.reach_fraction * (leg.thigh + leg.shank)
        # The swinging knee bends at most to its limit (less a margin), so an ankle lifted
        # close under the hip holds the hip up, as far as the stance leg reaches: up steep
        # stairs the rear foot passes over the front foot's tread in mid-swing while the pelvis
        # rises late (Figure 4), and the knee would pass its limit.
        knee_limit = self._leg_upper[swing_side][2] - 0.02
        closest = math.sqrt(leg.thigh ** 2 + leg.shank ** 2
                            + 2.0 * leg.thigh * leg.shank * math.cos(knee_limit))
        # Only the heights change between passes: the pelvis height bounds, the swing leg's
        # hip yaw and its horizontal reach in and across its plane (leg_inverse_kinematics'
        # first part) are solved once (see _swing_bounds).
        (out_of_reach, stance_bound, z_bound, swing_reach, swing_forward, swing_hip_yaw,
         hip_over_ankle, swing_lateral) = _swing_bounds(
            lam, forward, swing_xy, swing_hip_xy, direction, plane_yaw, yaw,
            key_frames.weight, key_frames.start_height, key_frames.touchdown_height, r,
            float(foot_s.z), closest)
        if out_of_reach:
            raise GaitError(f"the next foothold is beyond the swing leg's reach "
                            f'({r:.2f} m from hip to ankle at most)')
        fade = timing.fade
        ankle_low = self._leg_lower[swing_side][3] + 0.02
        ankle_high = self._leg_upper[swing_side][3] - 0.02
        # The swing sole's real pitch depends on the leg posture (the ankle has limits), and the
        # posture on the swing height: two passes make the clearance test use the real pitch.
        footprint = self._swing_footprint(timing, foot_w, landing, swing_xy, direction,
                                          swing_profile)
        # The swing leg's IK of the last pass, when its inputs are final (the pass converged).
        swing_solution = None
        for _ in range(5):
            # §4.1: the ankle's Bezier curve, raised until the sole clears the ground profile.
            curve = bezier_swing(foot_w, landing, footprint, swing_pitch, self._swing_limits)
            swing_z = curve.heights(bezier)
            z, joints, reach, converged, next_pitch = _swing_pass(
                swing_z, z_bound, swing_reach, hip_over_ankle, timing.hump, stance_bound,
                swing_hip_yaw, swing_forward, swing_pitch, fade, float(ankle_low),
                float(ankle_high), float(leg.thigh), float(leg.shank))
            if converged:
                swing_solution = (joints, reach)
                break
            swing_pitch = next_pitch

        self._check_feet_apart(foot_s, swing_xy, direction, swing_z)
        foot_end = [None, None]
        foot_end[stance_side] = foot_s
        frames = np.zeros((k, len(self.skeleton.joint_names)))
        pelvis = np.empty((k, 4))
        pelvis[:, :2] = pelvis_xy
        pelvis[:, 2] = z
        pelvis[:, 3] = yaw
        frames[:, self._root_columns] = pelvis
        # The stance leg (leg_inverse_kinematics written out): its ankle, plane and sole pitch
        # stay put over the step, so they enter as numbers, not as columns of k equal values.
        cos_s, sin_s = d_s.tolist()
        limit = self._leg_upper[stance_side][3] - 0.03
        joints, reach, stance_lateral, over_limit = _stance_leg(
            stance_hip_xy, yaw, z, float(foot_s.xy[0]), float(foot_s.xy[1]), float(foot_s.yaw),
            float(foot_s.z), float(foot_s.pitch), cos_s, sin_s, float(leg.thigh),
            float(leg.shank), float(limit))
        if over_limit:
            # Heel-off: the stance foot rolls about its toe instead of over-flexing the ankle.
            joints, foot_s_end = self._heel_off(leg, _points(stance_hip_xy, z), foot_s, yaw,
                                                joints, limit,
                                                self._supported_toe(foot_s, swing_profile))
            foot_end[stance_side] = foot_s_end
        self._check_leg(stance_side, joints, reach)
        frames[:, self._leg_columns[stance_side]] = joints
        stance_joints = joints
        lateral_error = max(lateral_error, abs(stance_lateral))

        if swing_solution is not None:
            # The same hip, ankle, plane and pitch as the converged pass: same answer.
            joints, reach = swing_solution
        else:
            joints, lateral, reach = leg_inverse_kinematics(
                leg, _points(swing_hip_xy, z), _points(swing_xy, swing_z), plane_yaw, yaw,
                swing_pitch)
            swing_lateral = float(lateral[-1])
        # A foot in the air may point its toes (push-off) or lift them: its pitch is free, so
        # the ankle stays inside its range; contact frames are unchanged. It rolls on from a
        # heel-off at lift-off; the correction fades out towards touchdown, where the sole
        # must meet its foothold flat.
        _fade_ankle(joints, float(self._leg_lower[swing_side][3] + 0.02),
                    float(self._leg_upper[swing_side][3] - 0.02), fade)
        self._check_leg(swing_side, joints, reach)
        if turning:
            # Legs in parallel planes a hip width apart cannot meet: only turns are tested.
            self._check_legs_apart(1.0 if stance_side == LEFT else -1.0,
                                   np.vstack([stance_hip_xy.T, z]), foot_s.yaw, stance_joints,
                                   np.vstack([swing_hip_xy.T, z]), plane_yaw, joints)
        frames[:, self._leg_columns[swing_side]] = joints
        self._check_end_knees(frames[-1])
        lateral_error = max(lateral_error, abs(swing_lateral))
        feet = foot_end
        feet[swing_side] = landing
        end = Stance(np.array([pelvis_xy[-1, 0], pelvis_xy[-1, 1], z[-1], yaw1]),
                     (feet[0], feet[1]), swing_side, to_rest)
        return StepMotion(times=tau * duration, frames=frames, stance=end,
                          category=key_frames.category, swing_lift=curve.lift,
                          lateral_error=lateral_error)

    def _check_end_knees(self, last_frame: np.ndarray) -> None:
        """Raise GaitError if a step ending at ``last_frame`` (22,) leaves a knee too bent."""
        for side in (LEFT, RIGHT):
            knee = float(last_frame[self._leg_columns[side]][2])
            if knee > self._leg_upper[side][2] - END_KNEE_MARGIN:
                name = 'left' if side == LEFT else 'right'
                raise GaitError(f'{name}_knee would end the step at {knee:.2f} rad, too bent '
                                'for the next step')

    def _seated_sole(self, xy: np.ndarray, yaw: float, sole: float, pitch: float,
                     ground) -> float:
        """
        Return the landing sole's height, moved onto smooth ground where the foot lands, m.

        The landing sole's height: ``sole`` (m) moved onto the ground where the foot lands, by at
        most ``SEAT_SHIFT`` up or down, where that ground is smooth (it varies under the sole by at
        most ``SEAT_SHIFT`` from the sole's plane).

        The foothold was judged at the planned point and heading; the foot lands in its hip's
        plane, centimetres away, and turned up to ``max_toe_in`` from the path. On a slope
        the ground there stands millimetres higher under part of the sole (under its uphill
        edge when the foot points across the slope), or lower under all of it (downhill of the
        foothold): on a 6-degree hill the 3D check refused the first kind of landing (the sole
        1-3 mm in the ground) at every reversal of a weave, a long step's landing 2 cm in the
        ground left the swing nothing to clear, and a landing 10-14 cm downhill floated
        8-34 mm and was refused as unsupported. The sole rests on the highest ground under
        it, its pitch kept. Other ground (an edge under the sole) is left to the 3D and landing
        checks, as planned.
        """
        leg = self.leg
        along = self._seat_along
        across = self._seat_across
        cos_pitch, sin_pitch = math.cos(pitch), math.sin(pitch)
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        forward = along * cos_pitch
        x = xy[0] + forward[None, :] * cos_yaw - across[:, None] * sin_yaw
        y = xy[1] + forward[None, :] * sin_yaw + across[:, None] * cos_yaw
        plane = sole + along * sin_pitch
        under = ground(np.column_stack([x.ravel(), y.ravel()]), sole + leg.ankle_height)
        excess = under.reshape(x.shape) - plane[None, :]
        if np.isnan(excess).any():
            # Part of the sole over no ground: the landing check judges its support.
            return sole
        # Ground that varies under the sole by more than a slope's tilt is an edge or a bump:
        # not seated here.
        if float(np.ptp(excess)) > SEAT_SHIFT:
            return sole
        excess = float(excess.max())
        if -SEAT_SHIFT <= excess <= SEAT_SHIFT:
            return sole + excess
        return sole

    def _check_feet_apart(self, stance_foot: FootPose, swing_xy: np.ndarray,
                          direction: np.ndarray, swing_z: np.ndarray) -> None:
        """
        Raise GaitError if the swinging foot would pass into the stance foot.

        The feet are the soles' boxes seen from above, wherever the swinging one is not above
        the other's top (its ankle): a separating-axis test per such frame. In a tight arc or
        where a turn reverses, a footstep can otherwise land on the other foot or sweep
        through it.
        """
        leg = self.leg
        shift = 0.5 * (leg.toe - leg.heel)  # ankle -> middle of the sole
        half_length = 0.5 * (leg.heel + leg.toe)
        half_width = 0.5 * leg.foot_width
        if _feet_meet(swing_xy, direction, swing_z, float(stance_foot.xy[0]),
                      float(stance_foot.xy[1]), stance_foot.z + leg.ankle_height,
                      math.cos(stance_foot.yaw), math.sin(stance_foot.yaw), shift, half_length,
                      half_width, 4.0 * (half_length ** 2 + half_width ** 2)):
            raise GaitError('the swing foot would pass into the stance foot')

    def _check_legs_apart(self, stance_outward: float, stance_hip: np.ndarray, stance_plane,
                          stance_joints: np.ndarray, swing_hip: np.ndarray, swing_plane,
                          swing_joints: np.ndarray) -> None:
        """
        Raise GaitError if a thigh or shank would pass into the other leg's.

        ``stance_outward`` is +1 when the stance leg is the left one, else -1; the hips are
        (3, k) (x, y, z rows), the joints (k, 4), a plane a heading (rad) or (k,).

        With the feet pointing towards each other (a turn reversed mid-step) both thighs turn
        in, and with the hips flexed the knees meet. The segments are the cylinders' axes
        (hip-knee, knee-ankle); two of them are apart when their distance is at least the sum
        of the radii.
        """
        leg = self.leg
        # Seen from the front, in the pelvis's frame (the hip yaw is the leg's plane there):
        # legs whose points stay a cylinder's width apart across need no more (most turns).
        inner = []
        for joints, outward in ((stance_joints, stance_outward), (swing_joints, -stance_outward)):
            across = outward * np.sin(joints[:, 0])
            knee = leg.thigh * np.sin(joints[:, 1]) * across
            ankle = knee + leg.shank * np.sin(joints[:, 1] - joints[:, 2]) * across
            inner.append(min(float(knee.min()), float(ankle.min()), 0.0))
        if 2 * leg.hip_half_width + inner[0] + inner[1] >= (
                2 * max(leg.thigh_radius, leg.shank_radius) + LEGS_LANDING_MARGIN):
            return
        stance_knee, stance_ankle = _leg_segments(leg, stance_hip, stance_plane, stance_joints)
        swing_knee, swing_ankle = _leg_segments(leg, swing_hip, swing_plane, swing_joints)
        k = stance_hip.shape[1]
        # thigh-thigh, thigh-shank, shank-thigh, shank-shank in one call.
        a0 = np.concatenate([stance_hip, stance_hip, stance_knee, stance_knee], axis=1)
        a1 = np.concatenate([stance_knee, stance_knee, stance_ankle, stance_ankle], axis=1)
        b0 = np.concatenate([swing_hip, swing_knee, swing_hip, swing_knee], axis=1)
        b1 = np.concatenate([swing_knee, swing_ankle, swing_knee, swing_ankle], axis=1)
        need = np.repeat([2 * leg.thigh_radius, leg.thigh_radius + leg.shank_radius,
                          leg.thigh_radius + leg.shank_radius, 2 * leg.shank_radius], k)
        # The next step starts where this one ends: it ends with room to move (a stance with
        # the thighs just touching left every next step refused at its first frames).
        need[k - 1::k] += LEGS_LANDING_MARGIN
        short = _segment_gaps(a0, a1, b0, b1) < need
        if short.any():
            which = ('thighs', 'thigh and shank', 'shank and thigh', 'shanks')[
                int(short.nonzero()[0][0]) // k]
            raise GaitError(f'the legs would pass through each other ({which})')

    def _check_leg(self, side: int, joints: np.ndarray, reach: np.ndarray) -> None:
        """Raise GaitError if a leg's (k, 4) joints leave their limits or it is out of reach."""
        low, high = self._leg_bounds[side]
        row, column = _leg_violation(joints, reach, low, high)
        if row == -2:
            side_name = 'left' if side == LEFT else 'right'
            raise GaitError(f"the {side_name} foot would be beyond its leg's reach")
        if row >= 0:
            name = self.skeleton.joint_names[self._leg_index[side][column]]
            raise GaitError(f'{name} would reach {joints[row, column]:.2f} rad, outside its '
                            'limits')

    def _supported_toe(self, foot: FootPose, ground) -> float:
        """
        Return how far ahead of the ankle a stance sole's heel lifts about, m.

        How far ahead of the ankle a stance sole's heel lifts about, m: its toe tip where its toes
        rest on the ground, else the first sampled point past the end of its support.

        Rolling about a line, the sole behind it rises and the sole ahead of it sinks; so no
        support may lie ahead of the line. Where the toes overhang an edge the line is therefore
        past the edge (by under 1 cm of sampling and the ground map's cell; the sole then rises
        off the edge by that times the sine of its pitch), and the edge is looked for across the
        sole's width: an edge the foot meets at an angle ends the support under one side of
        the sole centimetres later than under its middle. Rolling about the last supported point
        of the middle line instead sank the sole into a block's or a step's edge (5-15 mm), and
        the step was refused.

        ``ground`` is the step's swing profile (xy (N, 2), z_ref) -> (N,) heights.
        """
        leg = self.leg
        p0 = foot.pitch
        distance = leg.toe * _TOE_SAMPLES
        along = distance * np.cos(p0) + leg.ankle_height * np.sin(p0)
        cos_yaw, sin_yaw = math.cos(foot.yaw), math.sin(foot.yaw)
        across = _TOE_ACROSS * leg.foot_width
        # (3, n) points: the sole's middle line and edges, each from the ankle to the toe tip.
        x = foot.xy[0] + along * cos_yaw - across[:, None] * sin_yaw
        y = foot.xy[1] + along * sin_yaw + across[:, None] * cos_yaw
        sole_z = foot.z + distance * np.sin(p0) - leg.ankle_height * np.cos(p0)
        under = ground(np.column_stack([x.ravel(), y.ravel()]), float(sole_z.max()) + 0.02)
        # Ground well below is no support, nor is a surface over the toes (the profile reports
        # what is overhead where there is no ground).
        resting = (np.abs(under.reshape(x.shape) - sole_z) <= _TOE_SUPPORT_TOLERANCE).any(axis=0)
        if resting[-1]:
            return leg.toe
        supported = np.flatnonzero(resting)
        return float(distance[supported[-1] + 1 if len(supported) else 0])

    @staticmethod
    def _heel_off(leg: LegGeometry, hip: np.ndarray, foot: FootPose, pelvis_yaw: np.ndarray,
                  joints: np.ndarray, limit: float, toe: float):
        """
        Roll a stance foot about the front of its support where the ankle would pass ``limit``.

        Roll a stance foot about the front of its support, ``toe`` m ahead of the ankle (its toe
        tip, or an edge its toes overhang), where the ankle would pass ``limit``.

        Returns the corrected (k, 4) leg joints and the foot pose at the last frame.
        """
        p0 = foot.pitch
        direction_x, direction_y = np.cos(foot.yaw), np.sin(foot.yaw)
        toe_xy = foot.xy + (toe * np.cos(p0) + leg.ankle_height * np.sin(p0)) * np.array(
            [direction_x, direction_y])
        toe_z = foot.z + toe * np.sin(p0) - leg.ankle_height * np.cos(p0)
        over = joints[:, 3] > limit
        joints, ankle, pitch = _rolled_stance(
            hip, pelvis_yaw, joints, np.flatnonzero(over), float(limit), float(p0),
            float(foot.yaw), float(direction_x), float(direction_y), float(toe_xy[0]),
            float(toe_xy[1]), float(toe_z), float(toe), float(leg.ankle_height),
            float(leg.thigh), float(leg.shank))
        if over[-1]:
            end = FootPose(ankle[:2].copy(), float(ankle[2]), foot.yaw, float(pitch), foot.sole)
        else:
            end = foot
        return joints, end

    def _swing_footprint(self, timing: _StepTiming, lift_foot: FootPose, landing: FootPose,
                         swing_xy, direction, swing_profile) -> SwingFootprint:
        """
        Return the ground under the swinging sole at sampled frames (independent of its pitch).

        ``swing_xy`` (k, 2) is the ankle's path over the ground, m, and ``direction`` (k, 2) the
        cosine and sine of the swing foot's heading per frame; ``swing_profile`` as in
        :meth:`step`.
        """
        along, across = self._sole_along, self._sole_across
        samples = timing.samples
        points = _sole_points(swing_xy, direction, samples, along, across)
        z_ref = max(lift_foot.z, landing.z) + self.config.max_swing_lift
        # The pitch moves the points across the sole together (they share an offset along
        # it), and subtracting one number keeps the order: their maximum is taken here, once,
        # not in every pass of the swing heights.
        tops = _across_sole(np.array(swing_profile(points, z_ref), dtype=np.float64),
                            along.size, across.size)
        curve_parameter, clearance, slack = timing.bezier_terms
        return SwingFootprint(samples, along, tops, curve_parameter, clearance, slack)


def hold_frames(configuration: np.ndarray, start_time: float, duration: float,
                frame_rate: float) -> Tuple[np.ndarray, np.ndarray]:
    """Return a still block: (times (k,), frames (k, 22)) holding ``configuration``."""
    k = max(1, int(round(duration * frame_rate)))
    times = start_time + np.arange(1, k + 1) / frame_rate
    return times, np.repeat(configuration[None, :], k, axis=0)


def with_at_rest(stance: Stance, at_rest: bool) -> Stance:
    """Return the same stance with the at-rest flag changed."""
    return replace(stance, at_rest=at_rest)
