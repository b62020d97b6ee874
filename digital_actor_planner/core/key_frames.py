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
§4.1's procedural key frames of a step and its Bezier swing, written out as the code of record.

The footstep planner hands the walk generator the next foothold. By the level of that foothold
the step is one of three categories, moving on level ground, uphill or downhill, and the key
frames of the pelvis differ by category (Figure 4): :func:`step_key_frames`. Between the key
frames the motion is interpolated; the free leg's ankle follows a Bezier curve in Cartesian
space, and where the curve would make the sole meet the ground profile the curve adjustment
raises its two control points until it is collision-free: :func:`bezier_swing`. Where no curve
is feasible the step fails, and the footstep planner is told (:class:`GaitError`).

``WalkGenerator.step`` (core/gait.py) runs these functions as they are; the leg inverse
kinematics, the pelvis track and the checks around them are its compiled kernels.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Protocol, Tuple

import numpy as np

from .skeleton import LegGeometry

#: A foothold this far above (below) the stance sole makes the step uphill (downhill), m.
CATEGORY_RISE = 0.03
#: A swing foot lifting with its sole pitched further toes-down than this, rad, lifts from a
#: heel-off: its toe is still on the ground.
HEEL_OFF_PITCH = -0.05
#: Rounds of the curve adjustment before the flat-topped curve is tried.
ADJUSTMENT_ROUNDS = 12
#: The curve clears where it misses the ground by at most this much, m.
CLEARED = 1e-4
#: The flat-topped curve's control heights are searched on a grid of this step, m.
FLAT_TOP_GRID = 0.005


class GaitError(Exception):
    """A step cannot be realised (out of reach, joint limit, swing cannot clear the ground)."""


class RestingFoot(Protocol):
    """A foot on the ground as the key frames see it (``gait.FootPose`` is one)."""

    z: float       # ankle height, m
    sole: float    # sole height under the ankle, m
    pitch: float   # sole pitch, rad, toes up positive


def smoothstep(t: np.ndarray) -> np.ndarray:
    """Cubic ease 3t^2 - 2t^3 on [0, 1] (also the horizontal part of the swing Bezier)."""
    # minimum/maximum rather than clip: the same values for a fraction of the call overhead.
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


@dataclass(frozen=True)
class PelvisRamp:
    """When in a step the pelvis moves from one key-frame height to the next (step fractions)."""

    start: float
    length: float


#: Figure 4: on level ground the pelvis changes height evenly over the step; uphill it rises
#: late, once the front leg is bent and the foot is up; downhill it starts lowering a little
#: earlier than uphill and is down before the foot lands.
PELVIS_RAMPS: Dict[str, PelvisRamp] = {
    'level': PelvisRamp(0.0, 1.0),
    'uphill': PelvisRamp(0.35, 0.65),
    'downhill': PelvisRamp(0.3, 0.65),
}


@dataclass(frozen=True)
class StepKeyFrames:
    """
    The key frames of one step's pelvis height and the motion between them.

    Attributes
    ----------
    category
        'level', 'uphill' or 'downhill'.
    start_height
        Pelvis height at lift-off, m.
    touchdown_height
        Pelvis height the key frames reach at touchdown, m (nominal over the two footholds).
    weight
        (k,) how far each frame has moved from ``start_height`` to ``touchdown_height``, 0..1.

    """

    category: str
    start_height: float
    touchdown_height: float
    weight: np.ndarray

    def pelvis_heights(self) -> np.ndarray:
        """Return the pelvis height (k,) of each frame between the key frames, m."""
        return self.start_height + (self.touchdown_height - self.start_height) * self.weight


def step_category(stance_foot: RestingFoot, landing: RestingFoot) -> str:
    """Classify a step by the level of its foothold: 'level', 'uphill' or 'downhill' (§4.1)."""
    rise = landing.sole - stance_foot.sole
    if rise > CATEGORY_RISE:
        return 'uphill'
    if rise < -CATEGORY_RISE:
        return 'downhill'
    return 'level'


def step_key_frames(stance_foot: RestingFoot, landing: RestingFoot, start_height: float,
                    leg: LegGeometry, height_drop: float, tau: np.ndarray) -> StepKeyFrames:
    """
    Return the pelvis key frames of a step from ``stance_foot`` to the ``landing`` (Figure 4).

    Parameters
    ----------
    stance_foot, landing
        The foot that stays down and the foothold the other one lands on.
    start_height
        Pelvis height at the start of the step, m.
    leg
        The leg's dimensions (thigh and shank), m.
    height_drop
        How far below the straight legs the pelvis walks, m (``GaitConfig.pelvis_height_drop``).
    tau
        (k,) normalised time of each frame, (1..k) / k.

    """
    category = step_category(stance_foot, landing)
    # At touchdown the pelvis stands over the middle of the two ankles, the legs bent a little.
    touchdown_height = 0.5 * (stance_foot.z + landing.z) + leg.thigh + leg.shank - height_drop
    ramp = PELVIS_RAMPS[category]
    weight = smoothstep((tau - ramp.start) / ramp.length)
    return StepKeyFrames(category, float(start_height), float(touchdown_height), weight)


@dataclass(frozen=True)
class SwingFootprint:
    """
    The ground under the swinging sole at the sampled frames of a step, read once per step.

    The sole's path over the ground does not depend on its pitch or height: it is read once,
    and every round of the swing (whose sole pitch changes) judges it again.

    Attributes
    ----------
    samples
        (s,) indices of the frames the swing is tested at.
    along
        (P,) points along the sole, heel to toe, as offsets from the ankle, m.
    tops
        (s, P) the highest ground across the sole at each point along it, m; -inf over empty
        space.
    curve_parameter
        (s,) the Bezier curve's parameter at the samples, 0..1.
    clearance
        (s,) how far above the ground the sole keeps at each sample, m (less near the ends).
    slack
        (s,) how much of that the curve may miss near lift-off and touchdown, m: there the sole
        is at its foothold by definition, and the conservative ground map may read high.

    """

    samples: np.ndarray
    along: np.ndarray
    tops: np.ndarray
    curve_parameter: np.ndarray
    clearance: np.ndarray
    slack: np.ndarray


@dataclass(frozen=True)
class SwingLimits:
    """The swing's nominal and largest lift and the ankle's height over its sole, m."""

    lift: float
    max_lift: float
    ankle_height: float


@dataclass(frozen=True)
class SwingCurve:
    """
    The swing ankle's heights: a Bezier curve from lift-off to touchdown.

    The control heights are ``lift_off``, ``lift_off + raise_lift_off``, ``touchdown +
    raise_touchdown``, ``touchdown`` (m): a cubic, or with ``flat_topped`` a degree-5 curve whose
    two inner control heights are each used twice (it rises steeply and stays up).
    """

    lift_off: float
    touchdown: float
    raise_lift_off: float
    raise_touchdown: float
    flat_topped: bool = False

    @property
    def lift(self) -> float:
        """Return the larger control height above its foothold, m."""
        return float(max(self.raise_lift_off, self.raise_touchdown))

    def heights(self, u: np.ndarray) -> np.ndarray:
        """Return the ankle height (n,) at curve parameters ``u`` (n,), m."""
        w0, w1, w2, w3 = (_flat_topped_weights(u) if self.flat_topped else
                          _cubic_weights(u))
        return (w0 * self.lift_off + w1 * (self.lift_off + self.raise_lift_off)
                + w2 * (self.touchdown + self.raise_touchdown) + w3 * self.touchdown)


def _cubic_weights(u: np.ndarray) -> Tuple[np.ndarray, ...]:
    """Bernstein polynomials of degree 3 at ``u``."""
    return (1 - u) ** 3, 3 * u * (1 - u) ** 2, 3 * u * u * (1 - u), u ** 3


def _flat_topped_weights(u: np.ndarray) -> Tuple[np.ndarray, ...]:
    """Bernstein polynomials of degree 5 at ``u``: the end points and the two inner pairs."""
    v = 1.0 - u
    return (v ** 5, 5 * u * v ** 4 + 10 * u * u * v ** 3, 10 * u ** 3 * v * v + 5 * u ** 4 * v,
            u ** 5)


def ankle_need(footprint: SwingFootprint, sole_pitch: np.ndarray,
               ankle_height: float) -> np.ndarray:
    """
    Return the height (s,) the swinging ankle must keep at each sampled frame, m.

    The ground under the sole, relative to a sole pitched like the foot (``sole_pitch`` (k,)
    per frame, rad), plus the ankle's height over its sole and the clearance kept there.
    """
    pitch = sole_pitch[footprint.samples]
    ground = np.max(footprint.tops - footprint.along * np.sin(pitch)[:, None], axis=1)
    return ground + ankle_height * np.cos(pitch) + footprint.clearance


def bezier_swing(lift_off: RestingFoot, touchdown: RestingFoot, footprint: SwingFootprint,
                 sole_pitch: np.ndarray, limits: SwingLimits) -> SwingCurve:
    """
    Return the swing ankle's Bezier curve, raised until the sole clears the ground (§4.1).

    The control points start a nominal lift above the two footholds (more above the lower one,
    so the foot rises over the higher). Where the sole would meet the ground profile, the curve
    adjustment raises both control points at the sample that misses most, the nearer one by the
    shortfall and the other by half of it, until the curve clears every sample or the lift limit
    is reached. Then a flat-topped curve is tried (:func:`flat_topped_swing`).

    Parameters
    ----------
    lift_off, touchdown
        The swing foot where it lifts off and the foothold it lands on.
    footprint
        The ground under the swinging sole (``WalkGenerator._swing_footprint``).
    sole_pitch
        (k,) the swinging sole's pitch per frame, rad.
    limits
        The nominal and largest lift and the ankle's height over its sole.

    Raises
    ------
    GaitError
        When no curve clears the ground within the lift limit.

    """
    z0, z1 = lift_off.z, touchdown.z
    u = footprint.curve_parameter
    need = ankle_need(footprint, sole_pitch, limits.ankle_height)
    # Off a heel-off the toe is on the ground: lift more briskly so it does not scuff.
    h1 = limits.lift * (2.0 if lift_off.pitch < HEEL_OFF_PITCH else 1.0) + max(0.0, z1 - z0)
    h2 = limits.lift + 0.5 * max(0.0, z0 - z1)
    cap = limits.max_lift + abs(z1 - z0)
    least = (h1, h2)
    w0, w1, w2, w3 = _cubic_weights(u)
    for _ in range(ADJUSTMENT_ROUNDS):
        curve = w0 * z0 + w1 * (z0 + h1) + w2 * (z1 + h2) + w3 * z1
        short = need - curve - footprint.slack
        worst = int(np.argmax(short))
        if short[worst] <= CLEARED:
            return SwingCurve(z0, z1, h1, h2)
        # Raise the curve where it misses most: the inner weights there say how much of a
        # control point's rise reaches the curve (a step past the shortfall, so it converges).
        raise_by = min(short[worst] / max(w1[worst] + w2[worst], 0.05), 0.15) + 0.005
        if u[worst] < 0.5:
            h1 += raise_by
            h2 += 0.5 * raise_by
        else:
            h2 += raise_by
            h1 += 0.5 * raise_by
        if max(h1, h2) > cap:
            break
    return flat_topped_swing(z0, z1, u, need - footprint.slack, least, cap)


def flat_topped_swing(z0: float, z1: float, u: np.ndarray, need: np.ndarray,
                      least: Tuple[float, float], cap: float) -> SwingCurve:
    """
    Return the lowest flat-topped swing curve that clears ``need`` (s,) at parameters ``u``.

    Over a block whose face is close ahead of the lifting toe (or behind the landing heel) the
    foot must rise steeply and stay up: a Bezier of degree 5 whose inner control points are
    paired, (h1, h1, h2, h2), rises about half as fast again as the cubic and is flat on top.
    Its pair is the lowest (on a 5 mm grid, each at least ``least`` and at most ``cap``, m)
    whose curve is above ``need`` at every sample.

    Raises
    ------
    GaitError
        When no such pair exists.

    """
    w0, w1, w2, w3 = _flat_topped_weights(u)
    required = need - CLEARED - (w0 + w1) * z0 - (w2 + w3) * z1
    h1 = np.arange(least[0], cap + 1e-9, FLAT_TOP_GRID)[:, None]
    # Where the second pair's weight is ~0 (at lift-off) the first pair alone must do.
    alone = w2 < 1e-9
    h2 = np.where(alone, -np.inf, (required - w1 * h1) / np.where(alone, 1.0, w2))
    h2 = np.maximum(h2.max(axis=1), least[1])
    feasible = (h2 <= cap) & (w1[alone] * h1 >= required[alone]).all(axis=1)
    if not feasible.any():
        # In words a user reads: how far above the higher foothold the foot would have to
        # lift, against the most it lifts; or that it would have to rise at once.
        rise = max(float(np.max(need)) - max(z0, z1), 0.0)
        raise GaitError(f'swing foot cannot clear the terrain: it would have to lift '
                        f'{rise:.2f} m'
                        + (f', at most {cap:.2f} m' if rise > cap else
                           ' right after lift-off or just before touchdown'))
    best = int(np.where(feasible, np.maximum(h1[:, 0], h2), np.inf).argmin())
    return SwingCurve(z0, z1, float(h1[best, 0]), float(h2[best]), flat_topped=True)
