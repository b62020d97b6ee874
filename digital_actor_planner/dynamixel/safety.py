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

"""The safety envelope between the joint stream and the servos: clamp, rate limit, watchdog."""
from __future__ import annotations

import math
from typing import Iterable, List, Sequence

import numpy as np


class SafetyEnvelope:
    """
    Turn whatever arrives on the input topic into goals that are safe to send.

    Targets are clamped to each joint's safe range; the commanded position moves toward the
    target no faster than the joint's maximum speed; NaN/inf values and unknown names are
    ignored; when no valid input has arrived for ``watchdog_timeout`` seconds the commanded
    position is held. A servo that is found outside its safe range (switched on where it was
    left, or back on the bus) starts from where it is and eases into the range at its speed
    limit: commanding the nearest end at once would be a jump of the whole distance.

    Parameters
    ----------
    joint_names
        (n,) names of the driven joints.
    lower, upper
        (n,) safe range, rad.
    max_speed
        (n,) rad/s.
    watchdog_timeout
        Seconds without valid input after which the servos hold.
    max_step_time
        Longest time step (s) the rate limiter will integrate, so that a stalled cycle does
        not turn into one large jump.

    """

    def __init__(self, joint_names: Sequence[str], lower, upper, max_speed,
                 watchdog_timeout: float, max_step_time: float = 0.05):
        self.joint_names = tuple(joint_names)
        self.index = {name: i for i, name in enumerate(self.joint_names)}
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.max_speed = np.asarray(max_speed, dtype=float)
        n = len(self.joint_names)
        for name, array in (('lower', self.lower), ('upper', self.upper),
                            ('max_speed', self.max_speed)):
            if array.shape != (n,):
                raise ValueError(f'{name}: shape {array.shape}, expected ({n},)')
        if not np.all(self.lower < self.upper):
            raise ValueError(f'lower {self.lower} not below upper {self.upper}')
        if not np.all(self.max_speed > 0):
            raise ValueError(f'max_speed {self.max_speed} must be positive')
        if not (math.isfinite(watchdog_timeout) and watchdog_timeout > 0):
            raise ValueError(f'watchdog_timeout {watchdog_timeout} must be positive')
        self.watchdog_timeout = float(watchdog_timeout)
        self.max_step_time = float(max_step_time)
        self.commanded = np.clip(np.zeros(n), self.lower, self.upper)
        self.target = self.commanded.copy()
        self.last_input_time = -math.inf
        self.last_step_time = None
        self.holding = True
        #: Counts of ignored input values, by reason, for diagnostics.
        self.ignored = {'not finite': 0, 'unknown name': 0, 'clamped': 0}

    def reset(self, positions, now: float) -> None:
        """
        Start from measured positions (n,) rad: hold there, or ease in from outside the range.

        Non-finite entries keep the joint's current commanded position.
        """
        self.resume(range(len(self.joint_names)), positions)
        self.last_step_time = now
        self.holding = True

    def resume(self, indices: Iterable[int], positions) -> None:
        """
        Restart the joints ``indices`` from measured ``positions`` (rad, one per index).

        The commanded position becomes the measured one, so the first goal moves nothing; the
        target becomes its nearest point in the safe range, reached at the speed limit.
        """
        for i, position in zip(indices, np.asarray(positions, dtype=float)):
            if math.isfinite(position):
                self.commanded[i] = position
            self.target[i] = min(max(self.commanded[i], self.lower[i]), self.upper[i])

    def command(self, names: Iterable[str], positions: Iterable[float], now: float) -> List[str]:
        """Take one input message; return the names whose values were ignored."""
        ignored = []
        accepted = False
        for name, value in zip(names, positions):
            i = self.index.get(name)
            if i is None:
                self.ignored['unknown name'] += 1
                ignored.append(name)
                continue
            value = float(value)
            if not math.isfinite(value):
                self.ignored['not finite'] += 1
                ignored.append(name)
                continue
            clamped = min(max(value, self.lower[i]), self.upper[i])
            if clamped != value:
                self.ignored['clamped'] += 1
            self.target[i] = clamped
            accepted = True
        if accepted:
            self.last_input_time = now
            self.holding = False
        return ignored

    def step(self, now: float) -> np.ndarray:
        """Advance the commanded positions to time ``now`` (s); return them, (n,) rad."""
        if now - self.last_input_time > self.watchdog_timeout:
            # Watchdog: stop where we are instead of chasing a stale target (a joint still
            # outside its range stops at the nearest end).
            self.target = np.clip(self.commanded, self.lower, self.upper)
            self.holding = True
        dt = 0.0 if self.last_step_time is None else now - self.last_step_time
        dt = min(max(dt, 0.0), self.max_step_time)
        self.last_step_time = now
        limit = self.max_speed * dt
        # The target is always inside the range, so a joint inside stays inside and one
        # outside only moves toward it; never clamp the commanded position (that would jump).
        self.commanded = self.commanded + np.clip(self.target - self.commanded, -limit, limit)
        return self.commanded.copy()
