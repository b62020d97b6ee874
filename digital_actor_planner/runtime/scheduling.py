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
The threads that serve the actor nodes of one process: planning turns and the stream's clock.

A :class:`PlanningScheduler` plans for every actor of a planning worker, most urgent first; a
:class:`StreamTicker` publishes every attached actor's frame on a monotonic schedule, with a
backup thread on another core. Both are :class:`NodesThread` s: they start with their first
actor and end with their last.
"""
from __future__ import annotations

import math
import os
import threading
import time
import traceback

# A planning thread with nothing due looks again after this long at most (s), e.g. for a
# command that timed out.
IDLE_RESCAN = 0.25


class NodesThread:
    """
    A thread that serves the actor nodes attached to it.

    It starts with the first node and ends when the last one is detached. Subclasses write
    ``_loop`` (run with ``attach``'s extra arguments of the first node) and may wake it up for
    the end in ``_wake_up``. A node is the planner node, or anything with the methods the
    subclass calls.
    """

    name = 'actor_thread'

    def __init__(self):
        self._nodes = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None

    def attach(self, node, *args) -> None:
        """
        Serve ``node`` (the thread starts with the first node).

        Parameters
        ----------
        node
            The actor node to serve.
        *args
            Passed to ``_loop`` when this node starts the thread.

        """
        with self._lock:
            self._nodes = self._nodes + [node]
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, args=args, name=self.name,
                                                daemon=True)
                self._thread.start()

    def detach(self, node) -> None:
        """
        Stop serving ``node``; the thread ends with the last node.

        Parameters
        ----------
        node
            An attached actor node.

        """
        with self._lock:
            self._nodes = [n for n in self._nodes if n is not node]
            last = not self._nodes
            thread = self._thread
        if last and thread is not None:
            self._stop.set()
            self._wake_up()
            if thread is not threading.current_thread():
                thread.join(timeout=5.0)

    def _wake_up(self) -> None:
        pass

    def _loop(self, *args) -> None:
        raise NotImplementedError


class PlanningScheduler(NodesThread):
    """
    One thread that plans for every actor sharing a planning worker, most urgent first.

    An actor is due when its buffered motion ahead of playback is down to its planning lead;
    of the due actors, the one with the least motion left goes first. The worker plans one
    request at a time anyway, so one thread per worker is all the planning threads a process
    needs (with one thread per actor, 20 idle actors kept a core half busy).
    """

    name = 'actor_planning'

    def __init__(self):
        super().__init__()
        self.wake = threading.Event()

    def attach(self, node, priority: int) -> None:
        """
        Plan for ``node`` (the thread starts with the first node).

        Parameters
        ----------
        node
            The actor node: ``planning_slack()``, ``plan_once()`` and ``fail(code, message)``.
        priority
            SCHED_FIFO priority of the planning thread when this node starts it (0: normal).

        """
        super().attach(node, priority)
        self.wake.set()

    def _wake_up(self) -> None:
        self.wake.set()

    def _loop(self, priority: int) -> None:
        if priority > 0:
            real_time(priority)
        while not self._stop.is_set():
            try:
                self._plan_most_urgent()
            except Exception as error:  # noqa: B902 -- never a silently frozen actor
                for node in self._nodes:
                    node.fail(1, f'planning thread failed: {error!r}\n'
                              f'{traceback.format_exc()}')
                return

    def _plan_most_urgent(self) -> None:
        """Plan the most urgent due actor's next block, or wait until one may be due."""
        most_urgent, least_slack, sleep = None, math.inf, IDLE_RESCAN
        for node in self._nodes:
            slack = node.planning_slack()
            if slack is None:
                continue
            if slack <= 0.0 and slack < least_slack:
                most_urgent, least_slack = node, slack
            elif slack > 0.0:
                sleep = min(sleep, slack)
        if most_urgent is None:
            # Woken early by a stream running low, a command or a new scene.
            self.wake.wait(sleep)
            self.wake.clear()
            return
        most_urgent.plan_once()


def wall_clock_offset_ns() -> int:
    """
    Return ``time.time_ns() - time.monotonic_ns()``, the two clocks read as a pair.

    The tightest of three reads: a thread losing its core between two reads would otherwise
    skew it.
    """
    best = None
    for _ in range(3):
        before = time.monotonic_ns()
        wall = time.time_ns()
        spread = time.monotonic_ns() - before
        if best is None or spread < best[0]:
            best = (spread, wall - before - spread // 2)
    return best[1]


def real_time(priority: int) -> bool:
    """
    Put the calling thread under SCHED_FIFO at ``priority``.

    Children forked later start with normal scheduling (SCHED_RESET_ON_FORK).

    Parameters
    ----------
    priority
        SCHED_FIFO priority, 1-99.

    Returns
    -------
    bool
        False when not permitted (the thread keeps its scheduling).

    """
    try:
        policy = os.SCHED_FIFO | getattr(os, 'SCHED_RESET_ON_FORK', 0)
        os.sched_setscheduler(threading.get_native_id(), policy, os.sched_param(priority))
    except (AttributeError, OSError):
        return False
    return True


def real_time_threads(priority: int) -> None:
    """
    Put the calling thread under SCHED_FIFO at ``priority``, the process's other threads below.

    The other threads still under normal scheduling (the DDS threads) get ``priority - 1``:
    publish() takes locks they hold, so they must not wait behind the planning processes
    (which stay at normal priority). A thread that may not be changed is left as it is.

    Parameters
    ----------
    priority
        SCHED_FIFO priority of the calling thread, at least 2.

    """
    real_time(priority)
    tasks = '/proc/self/task'
    for thread_id in (os.listdir(tasks) if os.path.isdir(tasks) else ()):
        try:
            if os.sched_getscheduler(int(thread_id)) == os.SCHED_OTHER:
                os.sched_setscheduler(int(thread_id), os.SCHED_FIFO | getattr(
                    os, 'SCHED_RESET_ON_FORK', 0), os.sched_param(priority - 1))
        except OSError:
            pass


class StreamTicker(NodesThread):
    """
    One thread that publishes the joint_states of every actor attached to it, and a backup.

    The backup thread, on another core, publishes a tick the first one has not reached in time.

    Ticks on a monotonic schedule at ``1 / period``. A tick published late is late (jitter), not
    lost: a thread that wakes after ticks it slept over publishes each of them at once, each
    frame sampled and stamped at its own tick's instant, then the current tick. A subscriber
    gets every frame, with the stamps and the motion of a regular stream, and a stall shows as
    frames arriving late (counted in ``late_ticks``). Up to ``CATCH_UP`` ticks are caught up;
    older ones are skipped and counted as missed by each actor (a motion that stale is of no
    use to a controller). Actors hosted in one process share a ticker: one real-time thread
    instead of one per actor.

    On a virtual machine a core is now and then taken away for 10-80 ms, and a real-time
    thread on it cannot run (measured on the 2-core development VM: a bare SCHED_FIFO Python
    thread waking every 10 ms overslept by more than 10 ms 58 times in 200 s; stalls of the two
    cores rarely coincide). With two or more usable cores the publishing thread is pinned to
    one and the backup, ``BACKUP_DELAY`` periods behind the schedule, to another: whichever wakes
    first for a tick publishes it, under a lock, so each tick is published once.

    Parameters
    ----------
    period
        Publish period, s.
    priority
        SCHED_FIFO priority of the stream threads (0: normal scheduling, no backup thread).
    warn
        Called with a message should real-time scheduling not be permitted.

    """

    name = 'joint_state_stream'
    #: How far behind each tick the backup thread wakes, in periods.
    BACKUP_DELAY = 0.15
    #: How many ticks a thread waking late publishes at most before the current one.
    CATCH_UP = 20
    #: Ticks published later than this (s) after their instant are counted as late.
    LATE = 0.002

    def __init__(self, period: float, priority: int, warn=None):
        super().__init__()
        self.period = float(period)
        self.priority = int(priority)
        self._warn = warn
        self._tick_lock = threading.Lock()
        self._published = -1
        self._start = 0.0
        self.backup_publishes = 0
        #: Ticks published by a thread that woke after their successor's instant.
        self.caught_up = 0
        #: Ticks published more than ``LATE`` s after their instant, and the most late (s).
        self.late_ticks = 0
        self.max_lateness = 0.0

    def _loop(self) -> None:
        if self.priority > 0 and not real_time(self.priority) and self._warn is not None:
            self._warn('joint_states thread keeps normal scheduling (SCHED_FIFO not '
                       'permitted); set stream_priority 0 to silence this')
        cores = sorted(os.sched_getaffinity(0))
        backup = None
        self._start = time.monotonic()
        if self.priority > 0 and len(cores) >= 2:
            os.sched_setaffinity(0, {cores[-1]})  # this thread only
            backup = threading.Thread(target=self._backup, args=(cores[-2],),
                                      name='joint_state_backup', daemon=True)
            backup.start()
        self._run(0.0)
        if backup is not None:
            backup.join(timeout=5.0)

    def _backup(self, core: int) -> None:
        real_time(self.priority)
        os.sched_setaffinity(0, {core})
        self._run(self.BACKUP_DELAY * self.period)

    def _run(self, delay: float) -> None:
        """Wake ``delay`` s after each tick and publish it unless it has been."""
        tick = 0
        while not self._stop.is_set():
            wake = self._start + tick * self.period + delay
            pause = wake - time.monotonic()
            if pause > 0.0:
                time.sleep(pause)
            now = time.monotonic()
            # The latest tick due for this thread (the ones it slept over are caught up).
            tick = max(tick, int((now - delay - self._start) / self.period))
            self._publish(tick, now, delay > 0.0)
            tick += 1

    def _publish(self, tick: int, now: float, backup: bool) -> None:
        """Publish ``tick`` at monotonic time ``now``, and the ticks before it not published."""
        with self._tick_lock:
            if tick <= self._published:
                return
            first = self._published + 1 if self._published >= 0 else tick
            skipped = max(0, tick - self.CATCH_UP - first)
            first += skipped
            self._published = tick
            if backup:
                self.backup_publishes += 1
            # Each frame is stamped with the instant it shows, on the wall clock as it is now:
            # a thread that loses its core in the middle of a burst still stamps the rest of
            # the burst on their ticks.
            wall_offset = wall_clock_offset_ns()
            for late in range(first, tick + 1):
                instant = self._start + late * self.period
                lateness = now - instant
                if lateness > self.LATE:
                    self.late_ticks += 1
                self.max_lateness = max(self.max_lateness, lateness)
                if late < tick:
                    self.caught_up += 1
                # A frame shows the time its thread woke at, unless that is past the next
                # tick's instant: then it shows its own tick's. Either way tick k shows an
                # instant in [instant k, instant k + 1), so the stamps only increase.
                shown = instant if lateness >= self.period else None
                stamp_ns = wall_offset + round(1e9 * (now if shown is None else shown))
                for node in self._nodes:
                    try:
                        node.publish_frame(now, skipped if late == first else 0, shown,
                                           stamp_ns)
                    except Exception as error:  # noqa: B902 -- one actor must not stop others
                        node.get_logger().error(f'joint_states not published: {error!r}',
                                                throttle_duration_sec=2.0)
