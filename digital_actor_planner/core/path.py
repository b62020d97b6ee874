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
Path prediction: a velocity command becomes the horizontal path of the next steps (§3.2).

"Given a user mouse input command, the horizontal location and facing direction of the actor for
the next step can be computed. If the input is not changed often, the path for the actor in the
next n steps can be further derived." A constant command (v, w) traces a circular arc.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

from .jit import kernel


@dataclass(frozen=True)
class PredictedPath:
    """
    A circular arc (or a straight line) in the ground plane.

    Attributes
    ----------
    x, y, heading
        Start of the path: m, m, rad (world frame).
    curvature
        1/m, positive turns left (counter-clockwise seen from above).
    length
        Arc length covered, m.
    backward
        The actor walks this path backward: it faces ``heading - pi`` wherever it is on it,
        and its left foot's track lies to the right of the path.

    """

    x: float
    y: float
    heading: float
    curvature: float
    length: float
    backward: bool = False

    @property
    def facing_offset(self) -> float:
        """
        Return what to add to the path's heading for the way the actor faces on it, rad.

        What to add to the path's heading for the way the actor faces on it, rad (the inverse of
        :func:`predict_path`'s half turn, so the facing stays unwrapped as given).
        """
        return -math.pi if self.backward else 0.0

    @property
    def track_sign(self) -> float:
        """+1 where the left foot's track lies to the left of the path, -1 walking backward."""
        return -1.0 if self.backward else 1.0

    def poses(self, s: np.ndarray) -> np.ndarray:
        """
        Poses on the path at arc lengths ``s``.

        Parameters
        ----------
        s
            (N,) arc lengths, m (may exceed ``length`` or be negative: the arc is extended).

        Returns
        -------
        numpy.ndarray
            (N, 3) x (m), y (m), heading (rad).

        """
        return self.offset_poses(s, 0.0)

    def offset_points(self, s: np.ndarray, lateral) -> np.ndarray:
        """
        Points on the parallel tracks ``lateral`` m to the left of the path.

        Parameters
        ----------
        s
            (N,) arc lengths, m (any shape that broadcasts with ``lateral``).
        lateral
            Scalar, or an array that broadcasts with ``s`` (e.g. (T, 1) for T tracks), m.

        Returns
        -------
        numpy.ndarray
            (N, 2) points, m; (T, N, 2) for (T, 1) offsets: the broadcast shape then x, y.

        """
        s = np.asarray(s, dtype=float)
        lateral = np.asarray(lateral, dtype=float)
        if s.ndim == 1 and lateral.ndim == 2 and lateral.shape[1] == 1:
            # T tracks of N points, the way the ground profile asks: the path evaluated once
            # per arc length.
            tracks = _arc_offsets(np.ascontiguousarray(s), lateral.ravel().copy(), False,
                                  self.x, self.y, self.heading, self.curvature)
            return tracks[:, :, :2].copy()
        return self.offset_poses(s, lateral)[..., :2].copy()

    def offset_poses(self, s: np.ndarray, lateral) -> np.ndarray:
        """
        Return points on parallel tracks with the path's heading there.

        Points on parallel tracks with the path's heading there: :meth:`offset_points` and the
        heading column of :meth:`poses` from one evaluation of the path.

        Parameters
        ----------
        s
            (N,) arc lengths, m (any shape that broadcasts with ``lateral``).
        lateral
            Scalar or (N,) offsets to the left of the path, m (or a shape that broadcasts).

        Returns
        -------
        numpy.ndarray
            (N, 3) x (m), y (m), heading (rad): the broadcast shape, then those three.

        """
        s = np.asarray(s, dtype=float)
        lateral = np.asarray(lateral, dtype=float)
        if lateral.ndim and lateral.shape != s.shape:
            s, lateral = np.broadcast_arrays(s, lateral)
        out = _arc_offsets(np.ascontiguousarray(s.ravel()), lateral.ravel().copy(), True,
                           self.x, self.y, self.heading, self.curvature)[0]
        return out.reshape(s.shape + (3,))

    def project(self, xy: np.ndarray) -> float:
        """Arc length of the path point closest to ``xy`` ((2,) m), near the start."""
        dx, dy = xy[0] - self.x, xy[1] - self.y
        along = dx * np.cos(self.heading) + dy * np.sin(self.heading)
        if abs(self.curvature) < 1e-9:
            return float(along)
        # Angle swept from the start around the turning centre.
        radius = 1.0 / self.curvature
        cx = self.x - radius * np.sin(self.heading)
        cy = self.y + radius * np.cos(self.heading)
        a0 = np.arctan2(self.y - cy, self.x - cx)
        a1 = np.arctan2(xy[1] - cy, xy[0] - cx)
        swept = (a1 - a0 + np.pi) % (2 * np.pi) - np.pi
        return float(swept * radius)


@kernel('f8[:, :, ::1](f8[::1], f8[::1], b1, f8, f8, f8, f8)')
def _arc_offsets(s, lateral, paired, x0, y0, heading0, curvature):
    """
    Return points beside a path with the path's heading, at arc lengths ``s`` (N,).

    Points beside a path: x, y (m) and the path's heading (rad) at arc lengths ``s`` (N,),
    ``lateral`` m to the left of the path (along the normal, (-sin, cos) of the heading); the arc's
    centre line in closed form, a straight line below 1e-9 /m. With ``paired`` one row (1, N, 3)
    with ``lateral`` (N,) per point, or (1,) for all; else a row per track, (T, N, 3) for
    ``lateral`` (T,).
    """
    rows = 1 if paired else lateral.shape[0]
    out = np.empty((rows, s.shape[0], 3))
    straight = abs(curvature) < 1e-9
    cos0, sin0 = math.cos(heading0), math.sin(heading0)
    for n in range(s.shape[0]):
        heading = heading0 + curvature * s[n]
        sin, cos = math.sin(heading), math.cos(heading)
        if straight:
            x = x0 + s[n] * cos0
            y = y0 + s[n] * sin0
        else:
            x = x0 + (sin - sin0) / curvature
            y = y0 - (cos - cos0) / curvature
        for t in range(rows):
            if paired:
                offset = lateral[n] if lateral.shape[0] > 1 else lateral[0]
            else:
                offset = lateral[t]
            out[t, n, 0] = x - offset * sin
            out[t, n, 1] = y + offset * cos
            out[t, n, 2] = heading
    return out


def predict_path(x: float, y: float, heading: float, linear: float, angular: float,
                 length: float, min_turn_speed: float = 0.25) -> PredictedPath:
    """
    Predict the path of a constant velocity command from a pose (§3.2).

    Parameters
    ----------
    x, y, heading
        Current pelvis pose, m and rad.
    linear, angular
        Commanded speed (m/s, negative walks backward) and turn rate (rad/s, positive =
        left, the facing turns so walking backward too).
    length
        Arc length to predict, m.
    min_turn_speed
        A pure turn command (linear near 0) is walked as an arc at this forward speed, m/s,
        so the curvature stays finite: the actor turns by walking a tight circle.

    Returns
    -------
    PredictedPath
        Backward (``linear < 0``): heading ``heading + pi``, curvature ``angular / |linear|``
        (at least ``min_turn_speed`` in the denominator), ``backward`` set.

    """
    values = (x, y, heading, linear, angular, length, min_turn_speed)
    if not all(np.isfinite(v) for v in values):
        raise ValueError(f'predict_path: non-finite input {values}')
    if length <= 0:
        raise ValueError(f'predict_path: length must be > 0, got {length}')
    backward = linear < 0
    speed = max(abs(linear), min_turn_speed)
    # Backward the pelvis travels opposite to its facing while both turn at ``angular``: the
    # travel direction's curvature keeps the sign of the turn rate.
    travel = heading + math.pi if backward else heading
    return PredictedPath(float(x), float(y), float(travel), float(angular / speed),
                         float(length), bool(backward))
