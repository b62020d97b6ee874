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
The planning processes: the core's actors run in child processes, reached over a pipe.

The core's NumPy and FCL calls hold the GIL for milliseconds at a time, which would delay a
publishing thread in the same process. A :class:`PlanningWorker` is one child process
(:func:`_planning_process`) that owns the core actors of one or more actors of the node; a
:class:`PlanningProcess` is one actor's handle on its worker; a :class:`PlanningPool` hands out
the workers of a process. A worker that dies or stops answering is replaced.
"""
from __future__ import annotations

import collections
import copy
from dataclasses import dataclass
import itertools
import math
import multiprocessing
import os
import signal
import threading
import time
from typing import Any, Optional, Tuple
import weakref

from digital_actor_planner.core.settings import ConfigError
from digital_actor_planner.runtime.scheduling import PlanningScheduler
import numpy as np

# The ground profile marker shows surfaces up to this far above the predicted path (m).
PROFILE_STEP_UP = 0.5
# A planning process gets this long (s) to place an actor: from an empty kernel cache it
# compiles the core's kernels first (minutes on a loaded machine).
ADD_TIMEOUT = 900.0
# Planned blocks (per actor) that can be planned again; as many states kept to go back to.
REPLAN_BLOCKS = 8


class ConfigurationError(ConfigError):
    """
    A parameter value the node cannot run with; ``parameter`` names it.

    Parameters
    ----------
    parameter
        Name of the parameter (or option) at fault.
    message
        What is wrong with its value.
    value
        The bad value, when known.

    """

    def __init__(self, parameter: str, message: str, value: Any = None):
        super().__init__(parameter, value, f'parameter {parameter!r}: {message}')

    @property
    def parameter(self) -> str:
        """Return the parameter at fault."""
        return self.name

    @classmethod
    def of(cls, error: ConfigError) -> 'ConfigurationError':
        """Return the node's error for a setting the core refused, naming it as a parameter."""
        return cls(error.name, str(error), error.value)


@dataclass
class PlanningStats:
    """Planner state and timing shown on /diagnostics."""

    state: str = 'idle'
    reason: str = ''
    steps: int = 0
    blocks: int = 0
    last_planning_time: float = float('nan')

    def __post_init__(self):
        self.planning_times = collections.deque(maxlen=1000)

    def record(self, status: str, reason: str, planning_time: float) -> None:
        """
        Record one planned block.

        Parameters
        ----------
        status, reason
            The block's status (``walking``, ``idle``, ``stuck``, ...) and why.
        planning_time
            s spent planning it; NaN when nothing was planned (a failure or a state change).

        """
        self.state, self.reason = status, reason
        self.last_planning_time = planning_time
        self.planning_times.append(planning_time)
        if math.isfinite(planning_time):
            self.blocks += 1
        if status == 'walking':
            self.steps += 1

    def percentiles(self) -> Tuple[float, float]:
        """Return p50 and p99 planning time (s) of the recent blocks (NaN when none)."""
        times = np.fromiter(self.planning_times, float)
        times = times[np.isfinite(times)]  # a failure or a state change plans nothing
        if not len(times):
            return float('nan'), float('nan')
        p50, p99 = np.percentile(times, [50.0, 99.0])
        return float(p50), float(p99)


def build_actor(skeleton, actor_config, scene_path: str,
                start_pose: Optional[Tuple[float, float, float]], scene=None):
    """
    Load a scene and place a new actor at its start (or at ``start_pose``).

    Parameters
    ----------
    skeleton, actor_config
        The core ``Skeleton`` and ``ActorConfig``.
    scene_path
        Scene file (YAML or a bare mesh).
    start_pose
        ``(x, y, yaw)`` m and rad, or None for the scene's start.
    scene
        The scene at ``scene_path`` already loaded (by another actor); it is not loaded
        again.

    Returns
    -------
    (Actor, Scene)

    Raises
    ------
    ConfigurationError
        Naming ``scene`` (unreadable, bad mesh, no standing room at the scene's start) or
        ``start_pose`` (no ground or an obstacle there).

    """
    # Imported here: only the planning processes run (and compile) the core's kernels.
    from digital_actor_planner.core.actor import Actor
    from digital_actor_planner.core.scene import check_start, load_scene
    try:
        if scene is None:
            scene = load_scene(scene_path)
        if start_pose is None:
            try:
                check_start(scene.environment, scene.start, skeleton)
            except ValueError as error:
                raise ValueError(f'{scene_path}: {error}') from error
    except (OSError, ValueError) as error:
        raise ConfigurationError('scene', str(error)) from error
    try:
        if start_pose is not None:
            check_start(scene.environment, start_pose, skeleton)
        actor = Actor(skeleton, scene.environment, actor_config,
                      start=tuple(scene.start if start_pose is None else start_pose))
    except ValueError as error:
        raise ConfigurationError('scene' if start_pose is None else 'start_pose',
                                 str(error)) from error
    return actor, scene


def _mesh_arrays(scene) -> list:
    return [(np.asarray(m.vertices, dtype=float), np.asarray(m.faces, dtype=np.int64))
            for m in getattr(scene.environment, 'meshes', ())]


def _ground_profile(actor, block) -> np.ndarray:
    """Walkable ground (p, 3) under the block's predicted path, for the RViz markers."""
    path = np.asarray(block.path, dtype=float).reshape(-1, 3)
    if len(path) == 0:
        return path
    # §4.2: the ground profile the footstep planner sees, up to a step up above the path.
    height, _ = actor.environment.ground_height(path[:, :2], path[:, 2] + PROFILE_STEP_UP)
    return np.column_stack([path[:, :2], height])[np.isfinite(height)]


class SceneCache:
    """
    Scenes a planning worker's actors use, shared among them (keyed by file and version).

    Weak: a scene no actor holds any more (replaced at run time) is forgotten.
    """

    def __init__(self):
        self._scenes = weakref.WeakValueDictionary()

    def build(self, skeleton, actor_config, scene_path: str, start_pose):
        """
        Place a new actor on ``scene_path``, loading the scene unless an actor holds it.

        Parameters
        ----------
        skeleton, actor_config, scene_path, start_pose
            As for :func:`build_actor`.

        Returns
        -------
        (Actor, Scene)
            As :func:`build_actor` does.

        """
        try:
            info = os.stat(scene_path)
            key = (os.path.abspath(scene_path), info.st_mtime_ns, info.st_size)
        except OSError:
            key = None
        cached = self._scenes.get(key) if key is not None else None
        actor, scene = build_actor(skeleton, actor_config, scene_path, start_pose, scene=cached)
        if key is not None:
            self._scenes[key] = scene
        return actor, scene


def _actor_config(fields: dict):
    """
    Return the core ``ActorConfig`` of the node's parameters, validated (in the planning process).

    Raises
    ------
    ConfigurationError
        Naming the parameter the core refuses, with its value.

    """
    from digital_actor_planner.core.actor import ActorConfig
    from digital_actor_planner.core.settings import ConfigError
    try:
        return ActorConfig.from_settings(**fields)
    except ConfigError as error:
        raise ConfigurationError.of(error) from error


def _planning_process(connection) -> None:
    """
    Child process: own the core Actors of one or more nodes and answer their requests.

    A request is ``(number, kind, id, ...)`` with the actor's id: ``('add', id,
    actor_fields, urdf_path, scene_path, start_pose, place_at)`` (``place_at``: where to
    stand now instead of the start pose, or None), ``('plan', id, linear_x,
    angular_z)``, ``('scene', id, scene_path)``, ``('remove', id)``; ``(number, 'stop')``
    ends the process. Each reply starts with its request's number, so that a reply the node
    stopped waiting for is recognised as stale and dropped.
    """
    # Ctrl-C goes to the whole process group; the node decides when this process ends.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from digital_actor_planner.core.skeleton import Skeleton
    skeletons, scenes, actors = {}, SceneCache(), {}
    # Per actor: (block number, the actor as it was before planning that block).
    histories = collections.defaultdict(lambda: collections.deque(maxlen=REPLAN_BLOCKS))
    numbers = collections.Counter()
    while True:
        try:
            number, kind, *request = connection.recv()
        except (EOFError, OSError):
            return

        def reply(*message):
            connection.send((number, *message))

        if kind == 'add':
            key, fields, urdf_path, scene_path, start_pose, place_at = request
            try:
                if urdf_path not in skeletons:
                    skeletons[urdf_path] = Skeleton(urdf_path)
                actor_config = _actor_config(fields)
                actor, scene = scenes.build(skeletons[urdf_path], actor_config, scene_path,
                                            start_pose if place_at is None else place_at)
            except ConfigurationError as error:
                reply('error', error.parameter, str(error))
                continue
            except Exception as error:  # noqa: B902 -- a URDF or kernel fault, told to the node
                reply('error', 'scene', f'{type(error).__name__}: {error}')
                continue
            actors[key] = (actor, actor_config, start_pose, scene)
            histories.pop(key, None)
            reply('ready', actor.configuration, _mesh_arrays(scene))
        elif kind == 'plan':
            if request[0] not in actors:
                reply('failed', f'no actor {request[0]} in this process')
                continue
            actor = actors[request[0]][0]
            numbers[request[0]] += 1
            # The state before this block, to plan it again if the command changes before
            # it is played (the core's state is replaced, not changed in place, by a step).
            histories[request[0]].append((numbers[request[0]], copy.copy(actor)))
            try:
                warning = actor.set_command(request[1], request[2])
                block = actor.plan_next()
                reply('block', warning, block, _ground_profile(actor, block),
                      numbers[request[0]])
            except Exception as error:  # noqa: B902 -- reported on diagnostics, stream goes on
                reply('failed', f'{type(error).__name__}: {error}')
        elif kind == 'scene':
            if request[0] not in actors:
                reply('scene', f'no actor {request[0]} in this process', None, None)
                continue
            old, actor_config, start_pose, _ = actors[request[0]]
            try:
                actor, scene = scenes.build(old.skeleton, actor_config, request[1], start_pose)
            except ConfigurationError as error:
                reply('scene', str(error), None, None)
                continue
            actors[request[0]] = (actor, actor_config, start_pose, scene)
            histories.pop(request[0], None)
            reply('scene', '', actor.configuration, _mesh_arrays(scene))
        elif kind == 'rewind':
            kept = [(n, a) for n, a in histories[request[0]] if n == request[1]]
            if kept and request[0] in actors:
                actors[request[0]] = (kept[0][1], *actors[request[0]][1:])
                while histories[request[0]] and histories[request[0]][-1][0] >= request[1]:
                    histories[request[0]].pop()
            reply('rewound', bool(kept))
        elif kind == 'remove':
            actors.pop(request[0], None)
            reply('removed')
        else:
            return


class PlanningFailed(RuntimeError):
    """The planning process could not plan (or has gone)."""


class PlanningLost(PlanningFailed):
    """
    The planning process died or stopped answering and has been replaced by a new one.

    The new process knows none of the actors yet.
    """


class PlanningWorker:
    """
    A child process that plans for one or more actors, one request at a time.

    The core's NumPy and FCL calls hold the GIL for milliseconds, so they run outside the
    node's process. Actors sharing a worker share its scene cache and take turns. A process
    that dies, or gives no answer within a request's timeout, is killed and replaced by a
    fresh one (``generation`` counts them); its actors are placed in the new one again.
    """

    #: What the child process runs: it reads ``(number, kind, ...)`` requests from its end of
    #: the pipe and answers each with ``(number, ...)``.
    child_main = staticmethod(_planning_process)

    def __init__(self):
        self._lock = threading.Lock()
        self._numbers = itertools.count()
        self._closed = False
        self.generation = 0
        self.stale_replies = 0
        self._start()
        self.scheduler = PlanningScheduler()

    def _start(self) -> None:
        context = multiprocessing.get_context('spawn')
        self._connection, child = context.Pipe()
        self._process = context.Process(target=self.child_main, name='actor_planning',
                                        args=(child,), daemon=True)
        self._process.start()
        child.close()

    @property
    def pid(self) -> Optional[int]:
        """Process id of the current planning process."""
        return self._process.pid

    def alive(self) -> bool:
        """Whether the current planning process is running."""
        return self._process.is_alive()

    def request(self, message: tuple, timeout: float):
        """
        Send one request and wait for its reply (timeout counted from sending).

        Each reply carries its request's number: one left in the pipe by an earlier request
        is dropped (counted in ``stale_replies``). A request that times out kills and replaces
        the child, so a reply that late never arrives.

        Parameters
        ----------
        message
            ``(kind, actor id, ...)`` as :func:`_planning_process` reads it.
        timeout
            s to wait for the reply.

        Returns
        -------
        tuple
            The reply without its request number.

        Raises
        ------
        PlanningLost
            The process died or gave no answer in time; a new one has been started.
        PlanningFailed
            The worker is closed.

        """
        with self._lock:
            if self._closed:
                raise PlanningFailed('planning process closed')
            number = next(self._numbers)
            deadline = time.monotonic() + timeout
            try:
                self._connection.send((number, *message))
                while True:
                    left = deadline - time.monotonic()
                    if left <= 0.0 or not self._connection.poll(left):
                        problem = f'planning process gave no answer in {timeout:g} s'
                        break
                    reply = self._connection.recv()
                    if reply[0] == number:
                        return reply[1:]
                    self.stale_replies += 1
            except (EOFError, OSError, ValueError) as error:
                problem = f'planning process exited ({error!r})'
            if self._closed:
                raise PlanningFailed(problem)
            self._replace()
            raise PlanningLost(problem)

    def _replace(self) -> None:
        """Kill the planning process (stopped or not) and start a new one (lock held)."""
        self._process.kill()
        self._process.join(timeout=5.0)
        self._connection.close()
        self.generation += 1
        self._start()

    def close(self) -> None:
        """Ask the child to finish; kill it if it does not (or is busy)."""
        if self._closed:
            return
        self._closed = True
        # A request in flight (a scene loading) holds the lock: the process is killed
        # instead, which ends that request at once.
        if self._lock.acquire(timeout=0.5):
            try:
                self._connection.send((-1, 'stop'))
            except (OSError, ValueError):
                pass
            finally:
                self._lock.release()
            self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join(timeout=5.0)


class PlanningPool:
    """
    Up to ``size`` planning workers, started at once and handed out round-robin.

    Parameters
    ----------
    size
        Number of worker processes (the actors of a process share them).

    """

    def __init__(self, size: int):
        if size < 1:
            raise ConfigurationError('planning-processes', f'must be at least 1, got {size}')
        # Started together so that their imports overlap.
        self._workers = [PlanningWorker() for _ in range(size)]
        self._next = 0

    def worker(self) -> PlanningWorker:
        """Return the worker for the next actor."""
        worker = self._workers[self._next % len(self._workers)]
        self._next += 1
        return worker

    def close(self) -> None:
        """End every worker."""
        for worker in self._workers:
            worker.close()


class PlanningProcess:
    """
    One actor's core Actor in a planning worker, driven by request/reply over its pipe.

    Nothing is asked of the worker until :meth:`place`: the node streams meanwhile.

    Parameters
    ----------
    actor_fields
        Keyword arguments of the core ``ActorConfig``.
    urdf_path, scene_path, start_pose
        As for :func:`build_actor`.
    worker
        A shared :class:`PlanningWorker`; None starts one for this actor alone.

    """

    _ids = itertools.count()

    def __init__(self, actor_fields: dict, urdf_path: str, scene_path: str, start_pose,
                 worker: Optional[PlanningWorker] = None):
        self._owned = worker is None
        self._worker = PlanningWorker() if worker is None else worker
        self._id = next(PlanningProcess._ids)
        self._fields, self._urdf_path = dict(actor_fields), urdf_path
        self.scene_path, self._start_pose = scene_path, start_pose
        # The worker generation holding this actor (None: not placed).
        self._generation = None

    @property
    def scheduler(self) -> 'PlanningScheduler':
        """Return the planning thread of this actor's worker."""
        return self._worker.scheduler

    @property
    def worker(self) -> PlanningWorker:
        """Return the worker this actor plans in."""
        return self._worker

    @property
    def placed(self) -> bool:
        """Whether the current planning process holds this actor."""
        return self._generation == self._worker.generation and self._worker.alive()

    def place(self, start_pose=None, timeout: float = ADD_TIMEOUT):
        """
        Place the actor in the planning process on its scene.

        Parameters
        ----------
        start_pose
            ``(x, y, yaw)`` m and rad to stand at instead of the configured start (where a
            replaced process's actor stood); None: the configured start.
        timeout
            s to wait for the planning process (which may first compile the core's kernels).

        Returns
        -------
        (numpy.ndarray, list)
            The actor's configuration (22,) rad or m, and the scene's meshes (vertices (v, 3)
            m, faces (f, 3)).

        Raises
        ------
        ConfigurationError
            The scene or start pose cannot be used (naming the parameter).
        PlanningLost
            The process died or gave no answer meanwhile (a new one is running).

        """
        generation = self._worker.generation
        reply = self._worker.request(('add', self._id, self._fields, self._urdf_path,
                                      self.scene_path, self._start_pose,
                                      None if start_pose is None else tuple(start_pose)),
                                     timeout)
        if reply[0] == 'error':
            raise ConfigurationError(reply[1], reply[2].split(': ', 1)[-1])
        self._generation = generation
        return reply[1], reply[2]

    def plan(self, linear_x: float, angular_z: float, timeout: float = 60.0):
        """
        Set the command and plan the next block.

        Parameters
        ----------
        linear_x, angular_z
            The command, m/s and rad/s.
        timeout
            s to wait for the planning process.

        Returns
        -------
        (str or None, StepBlock, numpy.ndarray, int)
            The clamping warning, the block, the ground profile (p, 3) under its path (m) and
            the block's number (for :meth:`replan_from`).

        Raises
        ------
        PlanningLost
            The actor must be placed again (its process was replaced).
        PlanningFailed
            The core failed on this block.

        """
        if self._generation != self._worker.generation:
            raise PlanningLost('planning process was replaced')
        reply = self._worker.request(('plan', self._id, linear_x, angular_z), timeout)
        if reply[0] == 'failed':
            raise PlanningFailed(reply[1])
        return reply[1], reply[2], reply[3], reply[4]

    def replan_from(self, number: int, timeout: float = 60.0) -> bool:
        """
        Take the actor back to its state before block ``number``.

        That block and the ones after it are to be planned again.

        Parameters
        ----------
        number
            The block's number, as :meth:`plan` returned it.
        timeout
            s to wait for the planning process.

        Returns
        -------
        bool
            False when that state is no longer kept.

        """
        if self._generation != self._worker.generation:
            raise PlanningLost('planning process was replaced')
        return bool(self._worker.request(('rewind', self._id, int(number)), timeout)[1])

    def load_scene(self, scene_path: str, timeout: float = 300.0):
        """
        Replace the actor by one on a new scene.

        Parameters
        ----------
        scene_path
            The new scene file.
        timeout
            s to wait for the planning process.

        Returns
        -------
        (numpy.ndarray, list)
            The new actor's configuration (22,) rad or m, and the scene's meshes.

        Raises
        ------
        ConfigurationError
            The scene cannot be used; the old actor stays.

        """
        if self._generation != self._worker.generation:
            # The process was replaced: the actor is placed on the new scene at its start.
            old = self.scene_path
            self.scene_path = scene_path
            try:
                return self.place(timeout=max(timeout, ADD_TIMEOUT))
            except (ConfigurationError, PlanningFailed) as error:
                self.scene_path = old
                if isinstance(error, ConfigurationError):
                    raise
                raise ConfigurationError('scene', str(error)) from error
        try:
            _, error, configuration, meshes = self._worker.request(
                ('scene', self._id, scene_path), timeout)
        except PlanningFailed as failure:
            raise ConfigurationError('scene', str(failure)) from failure
        if error:
            raise ConfigurationError('scene', error.split(': ', 1)[-1])
        self.scene_path = scene_path
        return configuration, meshes

    def close(self) -> None:
        """Forget this actor in its worker; end the worker if it was this actor's own."""
        if self._owned:
            self._worker.close()
            return
        if self._generation is None or self._generation != self._worker.generation:
            return
        try:
            self._worker.request(('remove', self._id), 5.0)
        except PlanningFailed:
            pass


def usable_cores() -> int:
    """
    Return the number of cores this process may run on (its affinity, e.g. under taskset).

    Returns
    -------
    int
        At least 1.

    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return os.cpu_count() or 1
