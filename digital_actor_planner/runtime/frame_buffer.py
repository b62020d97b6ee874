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
The committed motion an actor's stream plays, and the velocity command it follows.

:class:`FrameBuffer` holds the timed frames planned so far and samples them at any playback
time; :class:`CommandState` holds the latest command. Both are shared between the threads
of the planner node without blocking the stream.
"""
from __future__ import annotations

import threading
from typing import Optional, Tuple

from digital_actor_planner.runtime.retiming import hurry
import numpy as np

# Committed frames older than this (s of actor time) are dropped from the buffer.
BUFFER_HISTORY = 1.0


class FrameBuffer:
    """
    Committed timed frames, sampled at any playback time; safe to share between threads.

    Parameters
    ----------
    configuration
        (22,) float64 first frame, held at time ``start_time`` (s).
    start_time
        Actor-clock time of that frame.

    """

    def __init__(self, configuration: np.ndarray, start_time: float = 0.0):
        # Writers (append, restart) take the lock and publish a new (times, frames, velocities)
        # tuple with one assignment; the stream reads the tuple without locking.
        self._lock = threading.Lock()
        q = np.asarray(configuration, dtype=float).reshape(1, -1)
        self._data = (np.array([float(start_time)]), q, np.zeros_like(q))
        self._still = np.zeros(q.shape[1])

    @property
    def end_time(self) -> float:
        """Time (s) of the last committed frame."""
        return float(self._data[0][-1])

    def append(self, times: np.ndarray, frames: np.ndarray, velocities: np.ndarray,
               now: float) -> None:
        """
        Commit frames after the current end; frames before ``now - BUFFER_HISTORY`` go.

        Parameters
        ----------
        times
            (k,) s, increasing and after :attr:`end_time`.
        frames, velocities
            (k, 22) rad or m, rad/s or m/s.
        now
            Current playback time (s).

        """
        times = np.asarray(times, dtype=float)
        if times.size == 0:
            return
        with self._lock:
            old_times, old_frames, old_velocities = self._data
            if not times[0] > old_times[-1]:
                raise ValueError(f'block starts at {times[0]:.4f} s, not after the buffer end '
                                 f'{old_times[-1]:.4f} s')
            keep = max(0, int(np.searchsorted(old_times, now - BUFFER_HISTORY)) - 1)
            self._data = (np.concatenate([old_times[keep:], times]),
                          np.concatenate([old_frames[keep:], frames]),
                          np.concatenate([old_velocities[keep:], velocities]))

    def restart(self, configuration: np.ndarray, start_time: float,
                blend_from: Optional[float] = None) -> None:
        """
        Drop every frame after ``start_time`` and continue from ``configuration`` there.

        Parameters
        ----------
        configuration
            (22,) rad or m.
        start_time
            s; the frames before it are kept.
        blend_from
            s before ``start_time``: the motion is held there and moves linearly to
            ``configuration`` by ``start_time`` (None: it jumps at ``start_time``).

        Raises
        ------
        ValueError
            ``configuration`` is not one frame of the buffer's joints.

        """
        configuration = np.asarray(configuration, dtype=float)
        if configuration.shape != self._still.shape:
            raise ValueError(f'restart configuration of shape {configuration.shape}, '
                             f'expected {self._still.shape}')
        held = None if blend_from is None else self.sample(blend_from)[0]
        with self._lock:
            old_times, old_frames, old_velocities = self._data
            cut = start_time if held is None else blend_from
            keep = int(np.searchsorted(old_times, cut, side='left'))
            times, frames = [old_times[:keep]], [old_frames[:keep]]
            velocities = [old_velocities[:keep]]
            if held is not None:
                speed = (configuration - held) / max(start_time - blend_from, 1e-9)
                times.append([blend_from])
                frames.append(held[None, :])
                velocities.append(speed[None, :])
            times.append([start_time])
            frames.append(configuration[None, :])
            velocities.append(np.zeros_like(configuration)[None, :])
            self._data = (np.concatenate(times), np.vstack(frames), np.vstack(velocities))

    def truncate(self, before: float) -> None:
        """
        Drop every frame at or after ``before`` (the first frame always stays).

        Parameters
        ----------
        before
            s of actor time.

        """
        with self._lock:
            times, frames, velocities = self._data
            keep = max(1, int(np.searchsorted(times, before, side='left')))
            self._data = (times[:keep], frames[:keep], velocities[:keep])

    def hurry(self, start: float, velocity_limit: np.ndarray, max_rate: float) -> float:
        """
        Play the frames after ``start`` faster along the same poses (``runtime.retiming``).

        Parameters
        ----------
        start
            s; the frames up to it keep their times.
        velocity_limit
            (22,) rad/s or m/s, no joint is driven faster.
        max_rate
            The highest playback rate (times the planned speed).

        Returns
        -------
        float
            The time (s) by which the buffer now ends sooner: 0 when nothing changed.

        """
        with self._lock:
            times, frames, velocities = self._data
            hurried = hurry(times, velocities, start, velocity_limit, max_rate)
            if hurried.saved > 0.0:
                self._data = (hurried.times, frames, hurried.velocities)
        return hurried.saved

    def sample(self, t: float) -> Tuple[np.ndarray, np.ndarray]:
        """
        Return the configuration and velocity at time ``t``, interpolated.

        Beyond the last frame the last configuration is held with zero velocity.

        Parameters
        ----------
        t
            Playback time, s.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            Configuration (22,) rad or m and velocity (22,) rad/s or m/s.

        """
        times, frames, velocities = self._data
        i = int(times.searchsorted(t, side='right'))
        if i == len(times):
            return frames[-1].copy(), self._still.copy()
        if i == 0:
            return frames[0].copy(), velocities[0].copy()
        before, after = float(times[i - 1]), float(times[i])
        a = (t - before) / (after - before)
        q0, v0 = frames[i - 1], velocities[i - 1]
        return q0 + a * (frames[i] - q0), v0 + a * (velocities[i] - v0)


class CommandState:
    """The latest finite velocity command and when it arrived (monotonic s)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._command = (0.0, 0.0)
        self._received = None
        self.changed = 0.0

    def update(self, linear_x: float, angular_z: float, now: float) -> None:
        """
        Store a command received at ``now``.

        Parameters
        ----------
        linear_x, angular_z
            m/s and rad/s, finite.
        now
            Monotonic time of arrival, s.

        """
        with self._lock:
            if (linear_x, angular_z) != self._command:
                self.changed = now
            self._command = (linear_x, angular_z)
            self._received = now

    def current(self, now: float, timeout: float) -> Tuple[float, float]:
        """
        Return the command to follow at ``now``.

        Parameters
        ----------
        now
            Monotonic time, s.
        timeout
            s; a command older than this is no longer followed.

        Returns
        -------
        (float, float)
            ``(linear_x m/s, angular_z rad/s)``; zero when none arrived within ``timeout``.

        """
        with self._lock:
            if self._received is None or now - self._received > timeout:
                return 0.0, 0.0
            return self._command
