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
Hurrying the step in progress when the actor is told to stop.

A step under way is never cut short: its swing foot is in the air. Told to stop, a person
lands that foot sooner; so does the actor. The rest of the step keeps its path (every pose it
passes through, in order) and is played faster: the playback rate rises smoothly from 1 to a
peak and falls back to 1 where the step ends,

    r(x) = 1 + a sin^2(pi x),   x = (t' - t0) / T'   in [0, 1],

so positions and velocities join on at both ends and the motion planned after the step (the
settling into a split stance) follows on unchanged. Over the hurried span T' the rate
averages 1 + a/2, so the rest R of the step takes T' = R / (1 + a/2). The peak ``1 + a`` is
bounded by the joints' velocity limits (no joint is driven faster than its limit) and by
``max_rate``.

Retiming changes no pose, so what the planner checked still holds: no link meets the
environment, the stance foot stays where it is, the swing foot lands where it was planned.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

#: Samples of the time map per hurried span, for inverting it.
_MAP_SAMPLES = 2001


@dataclass(frozen=True)
class Hurried:
    """
    A block's frames with their rest played faster.

    Attributes
    ----------
    times
        (k,) s, the new frame times; those up to the start of the hurry are unchanged.
    velocities
        (k, n) rad/s or m/s, scaled by the playback rate at each frame.
    saved
        s by which the block now ends sooner.
    peak_rate
        The highest playback rate used (1: not hurried).

    """

    times: np.ndarray
    velocities: np.ndarray
    saved: float
    peak_rate: float


def hurry(times: np.ndarray, velocities: np.ndarray, start: float, velocity_limit: np.ndarray,
          max_rate: float) -> Hurried:
    """
    Play the frames after ``start`` faster, ending sooner, along the same poses.

    Parameters
    ----------
    times
        (k,) s, increasing frame times of the block; its last frame ends the step.
    velocities
        (k, n) rad/s or m/s at those frames.
    start
        s; frames at or before it keep their time (the frame on show and any about to be).
    velocity_limit
        (n,) rad/s or m/s; no joint's speed is raised above it.
    max_rate
        Highest playback rate allowed (> 1).

    Returns
    -------
    Hurried
        ``saved`` is 0 and nothing changes when there is no rest to hurry or no room to do it.

    """
    times = np.asarray(times, dtype=float)
    velocities = np.asarray(velocities, dtype=float)
    unchanged = Hurried(times.copy(), velocities.copy(), 0.0, 1.0)
    rest = times > start
    remaining = float(times[-1] - start) if times.size else 0.0
    if not rest.any() or remaining <= 0.0:
        return unchanged
    limit = np.asarray(velocity_limit, dtype=float)
    usage = float(np.max(np.abs(velocities[rest]) / limit, initial=0.0))
    peak = min(max_rate, 1.0 / usage if usage > 0.0 else max_rate)
    if peak <= 1.0:
        return unchanged
    a = peak - 1.0  # the rate's rise above 1 at its peak
    span = remaining / (1.0 + 0.5 * a)

    # The time map s(t') from hurried time to the block's own time, inverted by sampling.
    new_time = np.linspace(0.0, span, _MAP_SAMPLES)
    x = new_time / span
    old_time = new_time * (1.0 + 0.5 * a) - a * span / (4.0 * math.pi) * np.sin(2.0 * math.pi * x)
    hurried_times = times.copy()
    hurried_times[rest] = start + np.interp(times[rest] - start, old_time, new_time)
    rate = 1.0 + a * np.sin(math.pi * (hurried_times[rest] - start) / span) ** 2
    hurried_velocities = velocities.copy()
    hurried_velocities[rest] *= rate[:, None]
    return Hurried(hurried_times, hurried_velocities, remaining - span, peak)
