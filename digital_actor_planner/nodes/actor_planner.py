"""ROS 2 node ``actor_planner``: cmd_vel and a mesh scene in, a 22-DOF JointState stream out.

A thin adapter over :class:`digital_actor_planner.core.actor.Actor` (STYLE: nodes only adapt).
Planning never stalls the stream:

* the core runs in a child process (:class:`PlanningProcess`): its NumPy and FCL calls hold
  the GIL for milliseconds at a time, which would delay a publishing thread in the same process;
* a planning thread asks it for the next block whenever less than the planning lead of
  committed frames is buffered ahead of playback (so about one step is buffered); actors that
  share a planning process share its planning thread (:class:`PlanningScheduler`), and an actor
  standing at rest (or stuck) with an unchanged command is not planned for at all;
* a publishing thread ticks on a monotonic schedule at ``publish_rate`` and publishes the frame
  for "now", interpolated from the buffer; if planning is late it holds the last frame; ticks
  it slept over (the machine took its core away) are published late, not dropped;
* the executor's threads handle cmd_vel and parameter changes (a scene reload occupies one of
  them); a housekeeping thread publishes markers and diagnostics.

The stream starts at once, from a stand-in pose, while the planning process compiles the
core's kernels ("warming up"); a planning process that dies or stops answering is replaced and
the actor goes on from where it stands; blocks not yet begun are planned again when the
command changes (docs/planner_node_runtime.md).
"""
from __future__ import annotations

import argparse
import array
import collections
import copy
import gc
import hashlib
from dataclasses import dataclass
import math
import multiprocessing
import os
import signal
import sys
import itertools
import threading
import time
import traceback
import weakref
from typing import Optional, Tuple

# Ctrl-C while these load (a second or more on a busy machine) ends the node quietly, as
# it does once it runs.
try:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from geometry_msgs.msg import Point, PoseStamped, Quaternion, Twist, TwistStamped
    from nav_msgs.msg import Path
    import numpy as np
    from rcl_interfaces.msg import SetParametersResult
    import rclpy
    from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
    from rclpy.exceptions import InvalidNamespaceException, ParameterException, \
        ParameterUninitializedException
    from rclpy.callback_groups import ReentrantCallbackGroup
    from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, \
        SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.serialization import serialize_message
    from rclpy.utilities import remove_ros_args
    from rclpy.validate_namespace import validate_namespace
    from sensor_msgs.msg import JointState
    from std_msgs.msg import ColorRGBA, String
    from visualization_msgs.msg import Marker, MarkerArray
    from digital_actor_planner.nodes.planner_params import ConfigurationError, \
        parameter_declarations, PlannerNodeConfig, read_node_config, RUNTIME_PARAMETERS, \
        scene_file_error, validate_node_config
    from digital_actor_planner.runtime.retiming import hurry
    from digital_actor_planner.runtime.standing import stand_in_configuration
except KeyboardInterrupt:  # pragma: no cover - depends on when the signal lands
    # Not sys.exit: after an import cut short by the signal, the interpreter's exit would end
    # the process by SIGINT whatever status it was given.
    os._exit(0)

# Committed frames older than this (s of actor time) are dropped from the buffer.
BUFFER_HISTORY = 1.0
# Mesh triangles drawn in RViz at most (one TRIANGLE_LIST per mesh).
MAX_MARKER_TRIANGLES = 200_000
PAST_FOOTSTEPS = 40
# The planning lead grows to LEAD_SAFETY times the slowest of the last RECENT_BLOCKS response
# times (from a block falling due to its commit), up to MAX_LEAD s.
LEAD_SAFETY = 1.5
RECENT_BLOCKS = 10
MAX_LEAD = 2.0
# The ground profile marker shows surfaces up to this far above the predicted path (m).
PROFILE_STEP_UP = 0.5
# A planning thread with nothing due looks again after this long at most (s), e.g. for a
# command that timed out.
IDLE_RESCAN = 0.25
# The executor thread returns to Python at least this often (s), for the SIGTERM handler.
SIGNAL_CHECK = 0.5
# Executor threads of the node process (parameters, cmd_vel, scene reloads).
EXECUTOR_THREADS = 4
# After a planning failure an actor is asked again after this long (s).
RETRY_AFTER = 0.1
# A planning process gets this long (s) to place an actor: from an empty kernel cache it
# compiles the core's kernels first (minutes on a loaded machine).
ADD_TIMEOUT = 900.0
# The stream blends from the pose it holds to a newly placed actor's first frame over this
# long (s): the stand-in pose of the start, or the stance held when a planning process failed.
BLEND_TIME = 0.5
# Blocks planned but not yet begun are planned again when the command changes this much
# (m/s, rad/s) or to a stop, instead of being played out: a released drag stills the actor
# at the end of the step in progress (docs/stopping.md).
REPLAN_LINEAR = 0.15
REPLAN_ANGULAR = 0.3
# A block starting sooner than this (s) after the frame on show is played as planned.
REPLAN_GUARD = 0.05
# The same for a stop: any block not yet begun is dropped. Should the stream reach the cut
# before the stop is planned, it holds the stance the step in progress landed in, which is
# where the actor stops anyway; a step played out instead would delay the stop by a step.
STOP_GUARD = 0.0
# Told to stop, the actor lands the step in progress sooner: the rest of it is played at up to
# this many times its planned speed, never a joint above its velocity limit (docs/stopping.md).
HURRY_MAX_RATE = 1.5
# Frames due within this long (s) after the frame on show keep their time when the step is
# hurried: the stream may be showing them while the buffer changes.
HURRY_GUARD = 0.02
# Planned blocks (per actor) that can be planned again; as many states kept to go back to.
REPLAN_BLOCKS = 8
# A planning process that fails this many times in a row while placing its actors is given
# up on: the node exits non-zero (a supervisor may start it again).
MAX_REPLACEMENTS = 3


class FrameBuffer:
    """Committed timed frames, sampled at any playback time; safe to share between threads.

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
        """Commit frames after the current end; frames before ``now - BUFFER_HISTORY`` go.

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
        """Drop every frame after ``start_time`` and continue from ``configuration`` there.

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
        """Drop every frame at or after ``before`` s (the first frame always stays)."""
        with self._lock:
            times, frames, velocities = self._data
            keep = max(1, int(np.searchsorted(times, before, side='left')))
            self._data = (times[:keep], frames[:keep], velocities[:keep])

    def hurry(self, start: float, velocity_limit: np.ndarray, max_rate: float) -> float:
        """Play the frames after ``start`` faster along the same poses (``runtime.retiming``).

        Returns the time (s) by which the buffer now ends sooner: 0 when nothing changed.
        """
        with self._lock:
            times, frames, velocities = self._data
            hurried = hurry(times, velocities, start, velocity_limit, max_rate)
            if hurried.saved > 0.0:
                self._data = (hurried.times, frames, hurried.velocities)
        return hurried.saved

    def sample(self, t: float) -> Tuple[np.ndarray, np.ndarray]:
        """Return the configuration (22,) and velocity (22,) at time ``t`` s, interpolated.

        Beyond the last frame the last configuration is held with zero velocity.
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
        """Store a command received at ``now``."""
        with self._lock:
            if (linear_x, angular_z) != self._command:
                self.changed = now
            self._command = (linear_x, angular_z)
            self._received = now

    def current(self, now: float, timeout: float) -> Tuple[float, float]:
        """Return the command to follow at ``now``: zero when none arrived within ``timeout``."""
        with self._lock:
            if self._received is None or now - self._received > timeout:
                return 0.0, 0.0
            return self._command


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
        """Record one planned block."""
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


def _color(r: float, g: float, b: float, a: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=float(r), g=float(g), b=float(b), a=float(a))


def _yaw_quaternion(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def _points(xyz: np.ndarray):
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in xyz]


def environment_markers(meshes, frame_id: str) -> bytes:
    """The serialized MarkerArray that draws the environment in RViz.

    Parameters
    ----------
    meshes
        (vertices (v, 3) float64 m, faces (f, 3) int) per mesh, world frame.
    frame_id
        Frame of the markers.

    Returns
    -------
    bytes
        A DELETEALL marker, then one TRIANGLE_LIST per mesh (MAX_MARKER_TRIANGLES in all at
        most), stamped zero (static: RViz uses the latest transform), serialized. The points
        are written straight into the serialized message: a point object each took ~0.5 s
        and 120k fresh objects for the garbage collector for a 40k-triangle terrain (the
        stream thread missed frames behind it); now a few ms.

    """
    drawn, budget = [], MAX_MARKER_TRIANGLES
    for index, (vertices, faces) in enumerate(meshes):
        faces = np.asarray(faces)[:budget]
        budget -= len(faces)
        if len(faces):
            drawn.append((index, np.asarray(vertices, dtype=float)[faces].reshape(-1, 3)))
    raw = _spliced(drawn, frame_id)
    if raw is None:
        raw = serialize_message(_environment_array(
            drawn, frame_id, lambda number: _points(drawn[number][1])))
    return raw


def _placeholder_point(marker: int, point: int) -> Point:
    # Values no real scene has, to find each marker's points in the serialized template.
    return Point(x=-7.25e301 - marker * 1e290, y=3.5e-301 * (point + 1), z=-1.125e299)


def _environment_array(drawn, frame_id: str, points_of) -> MarkerArray:
    array = MarkerArray(markers=[Marker(action=Marker.DELETEALL)])
    array.markers[0].header.frame_id = frame_id
    for number, (index, _) in enumerate(drawn):
        marker = Marker(ns='environment', id=index, type=Marker.TRIANGLE_LIST,
                        action=Marker.ADD)
        marker.header.frame_id = frame_id
        marker.pose.orientation.w = 1.0
        marker.scale.x = marker.scale.y = marker.scale.z = 1.0
        marker.color = _color(0.62, 0.64, 0.66)
        marker.points = points_of(number)
        array.markers.append(marker)
    return array


def _spliced(drawn, frame_id: str) -> Optional[bytes]:
    """Serialize the environment by writing each TRIANGLE_LIST's points into a serialized
    template; None when the template's layout is not the expected one.

    The RMW serializes a template with one placeholder point per marker, and again with two.
    A point sequence is a count, then 24 bytes (three float64) per point: the count is the
    word before the placeholder that reads 1 in the first template and 2 in the second, and a
    sequence of any length fits in its place without moving the alignment of what follows.
    """
    one, two = (serialize_message(_environment_array(
        drawn, frame_id, lambda m, k=k: [_placeholder_point(m, i) for i in range(k)]))
        for k in (1, 2))
    if one[:2] != b'\x00\x01':  # CDR little endian, as on every ROS 2 platform
        return None
    pieces, read = [], 0
    for number, (_, points) in enumerate(drawn):
        placeholder = _placeholder_point(number, 0)
        data = one.find(np.array([placeholder.x, placeholder.y, placeholder.z],
                                 dtype='<f8').tobytes(), read)
        # In the two-point template each earlier marker's extra point moves it by 24 bytes.
        shift = 24 * number
        count = next((c for c in (data - 4, data - 8) if data >= 0 and c >= read and
                      one[c:c + 4] == (1).to_bytes(4, 'little') and
                      two[c + shift:c + shift + 4] == (2).to_bytes(4, 'little')), None)
        if count is None:
            return None
        pieces += [one[read:count], len(points).to_bytes(4, 'little'), one[count + 4:data],
                   np.ascontiguousarray(points, dtype='<f8').tobytes()]
        read = data + 24
    pieces.append(one[read:])
    return b''.join(pieces)


def _meshes_digest(meshes) -> bytes:
    digest = hashlib.blake2b(digest_size=16)
    for vertices, faces in meshes:
        for values in (np.ascontiguousarray(vertices, dtype=float),
                       np.ascontiguousarray(faces, dtype=np.int64)):
            digest.update(str(values.shape).encode())
            digest.update(values.tobytes())
    return digest.digest()


def build_actor(skeleton, actor_config, scene_path: str,
                start_pose: Optional[Tuple[float, float, float]], scene=None):
    """Load a scene and place a new actor at its start (or at ``start_pose``).

    ``scene``: the scene at ``scene_path`` already loaded (by another actor); it is not
    loaded again.

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


class _SceneCache:
    """Scenes a planning worker's actors use, shared among them (keyed by file and version).

    Weak: a scene no actor holds any more (replaced at run time) is forgotten.
    """

    def __init__(self):
        self._scenes = weakref.WeakValueDictionary()

    def build(self, skeleton, actor_config, scene_path: str, start_pose):
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
    """The core ``ActorConfig`` of the node's parameters, validated (in the planning process).

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
    """Child process: own the core Actors of one or more nodes and answer their requests.

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
    skeletons, scenes, actors = {}, _SceneCache(), {}
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
    """The planning process died or stopped answering and has been replaced by a new one,
    which knows none of the actors yet."""


class PlanningWorker:
    """A child process that plans for one or more actors, one request at a time.

    The core's NumPy and FCL calls hold the GIL for milliseconds, so they run outside the
    node's process. Actors sharing a worker share its scene cache and take turns. A process
    that dies, or gives no answer within a request's timeout, is killed and replaced by a
    fresh one (``generation`` counts them); its actors are placed in the new one again.
    """

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
        self._process = context.Process(target=_planning_process, name='actor_planning',
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
        """Send one request and wait for its reply (timeout counted from sending).

        Replies to earlier requests (given up on) are dropped.

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
    """Up to ``size`` planning workers, started at once and handed out round-robin.

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
        """The worker for the next actor."""
        worker = self._workers[self._next % len(self._workers)]
        self._next += 1
        return worker

    def close(self) -> None:
        """End every worker."""
        for worker in self._workers:
            worker.close()


class PlanningProcess:
    """One actor's core Actor in a planning worker, driven by request/reply over its pipe.

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
        """The planning thread of this actor's worker."""
        return self._worker.scheduler

    @property
    def worker(self) -> PlanningWorker:
        """The worker this actor plans in."""
        return self._worker

    @property
    def placed(self) -> bool:
        """Whether the current planning process holds this actor."""
        return self._generation == self._worker.generation and self._worker.alive()

    def place(self, start_pose=None, timeout: float = ADD_TIMEOUT):
        """Place the actor in the planning process on its scene; return (configuration (22,)
        rad or m, meshes).

        ``start_pose``: ``(x, y, yaw)`` to stand at instead of the configured start (where a
        replaced process's actor stood).

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
        """Set the command and plan the next block.

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
        """Take the actor back to its state before block ``number`` (that block and the ones
        after it are to be planned again); False when that state is no longer kept."""
        if self._generation != self._worker.generation:
            raise PlanningLost('planning process was replaced')
        return bool(self._worker.request(('rewind', self._id, int(number)), timeout)[1])

    def load_scene(self, scene_path: str, timeout: float = 300.0):
        """Replace the actor by one on a new scene; return (configuration (22,), meshes).

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


class NodesThread:
    """A thread that serves the actor nodes attached to it: it starts with the first node and
    ends when the last one is detached. Subclasses write ``_loop`` (run with ``attach``'s
    extra arguments of the first node) and may wake it up for the end in ``_wake_up``."""

    name = 'actor_thread'

    def __init__(self):
        self._nodes = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None

    def attach(self, node: 'ActorPlannerNode', *args) -> None:
        """Serve ``node`` (the thread starts with the first node)."""
        with self._lock:
            self._nodes = self._nodes + [node]
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, args=args, name=self.name,
                                                daemon=True)
                self._thread.start()

    def detach(self, node: 'ActorPlannerNode') -> None:
        """Stop serving ``node``; the thread ends with the last node."""
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
    """One thread that plans for every actor sharing a planning worker, most urgent first.

    An actor is due when its buffered motion ahead of playback is down to its planning lead;
    of the due actors, the one with the least motion left goes first. The worker plans one
    request at a time anyway, so one thread per worker is all the planning threads a process
    needs (with one thread per actor, 20 idle actors kept a core half busy).
    """

    name = 'actor_planning'

    def __init__(self):
        super().__init__()
        self.wake = threading.Event()

    def attach(self, node: 'ActorPlannerNode', priority: int) -> None:
        """Plan for ``node`` (the thread starts with the first node, at ``priority`` if > 0)."""
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


class Housekeeper(NodesThread):
    """One thread that publishes the markers (5 Hz) and diagnostics (1 Hz) of every actor of a
    process; plain thread, not executor timers (see ``ActorPlannerNode._make_interfaces``)."""

    name = 'actor_housekeeping'
    #: Serialized environments kept for actors on the same scene.
    ENVIRONMENTS_KEPT = 4

    def __init__(self):
        super().__init__()
        self._environments = collections.OrderedDict()

    def environment(self, meshes, frame_id: str) -> bytes:
        """The serialized environment markers of ``meshes`` (built once per content)."""
        key = (frame_id, _meshes_digest(meshes))
        if key in self._environments:
            self._environments.move_to_end(key)
        else:
            self._environments[key] = environment_markers(meshes, frame_id)
            while len(self._environments) > self.ENVIRONMENTS_KEPT:
                self._environments.popitem(last=False)
        return self._environments[key]

    def _loop(self) -> None:
        next_diagnostics = time.monotonic() + 1.0
        while not self._stop.wait(0.2):
            diagnostics = time.monotonic() >= next_diagnostics
            if diagnostics:
                next_diagnostics += 1.0
            for node in self._nodes:
                node.housekeeping(diagnostics, self)


def wall_clock_offset_ns() -> int:
    """``time.time_ns() - time.monotonic_ns()``, read as a pair: the tightest of three reads
    (a thread losing its core between two reads would otherwise skew it)."""
    best = None
    for _ in range(3):
        before = time.monotonic_ns()
        wall = time.time_ns()
        spread = time.monotonic_ns() - before
        if best is None or spread < best[0]:
            best = (spread, wall - before - spread // 2)
    return best[1]


def real_time(priority: int) -> bool:
    """Put the calling thread under SCHED_FIFO at ``priority``; False when not permitted.

    Children forked later start with normal scheduling (SCHED_RESET_ON_FORK).
    """
    try:
        policy = os.SCHED_FIFO | getattr(os, 'SCHED_RESET_ON_FORK', 0)
        os.sched_setscheduler(threading.get_native_id(), policy, os.sched_param(priority))
    except (AttributeError, OSError):
        return False
    return True


class StreamTicker(NodesThread):
    """One thread that publishes the joint_states of every actor attached to it, and a backup
    thread on another core that publishes a tick the first one has not reached in time.

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


class SharedThreads:
    """The threads the actors of one process share: a stream ticker per (publish period,
    priority), and one housekeeper. Planning threads belong to the planning workers."""

    def __init__(self):
        self._tickers = {}
        self._lock = threading.Lock()
        self.housekeeper = Housekeeper()

    def ticker(self, period: float, priority: int, warn=None) -> StreamTicker:
        """The ticker for ``period`` s at ``priority`` (created on first use)."""
        with self._lock:
            key = (float(period), int(priority))
            if key not in self._tickers:
                self._tickers[key] = StreamTicker(period, priority, warn)
            return self._tickers[key]


class CommandRouter:
    """The cmd_vel subscriptions of the actors hosted by one process, on one small hidden node
    spun by its own executor thread.

    Each subscription is made on the topic its actor resolves ``cmd_vel`` to (the actor's
    namespace and remappings). rclpy's SingleThreadedExecutor walks every entity of every node
    on each wake-up; 20 actors with their parameter services made that about 2.5 ms, so 20
    teleops at 10 Hz kept half a core busy. A command now wakes a node with only the
    subscriptions; the actors' executor wakes only for parameter and other services.
    """

    def __init__(self):
        # No global arguments: the topics are resolved by the actors already.
        self.node = Node(f'_actor_planner_commands_{os.getpid()}', use_global_arguments=False,
                         start_parameter_services=False)
        self._executor = SingleThreadedExecutor()
        self._executor.add_node(self.node)
        self._thread = None

    def start(self, priority: int) -> None:
        """Start delivering commands (from a thread at ``priority`` when > 0)."""
        self._thread = threading.Thread(target=self._spin, args=(priority,),
                                        name='actor_commands', daemon=True)
        self._thread.start()

    def _spin(self, priority: int) -> None:
        if priority > 0:
            real_time(priority)
        try:
            self._executor.spin()
        except ExternalShutdownException:
            pass

    def stop(self) -> None:
        """Stop the thread and destroy the node."""
        self._executor.shutdown(timeout_sec=5.0)
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self.node.destroy_node()


class ActorPlannerNode(Node):
    """Stream the digital actor's whole-body motion as JointState, directed by cmd_vel."""

    def __init__(self, node_name: str = 'actor_planner', threads: Optional[SharedThreads] = None,
                 planners: Optional[PlanningPool] = None,
                 commands: Optional[CommandRouter] = None, **kwargs):
        super().__init__(node_name, **kwargs)
        self._commands = commands
        self.config = self._declare_and_read()
        from digital_actor_planner.core.skeleton import Skeleton
        self.skeleton = Skeleton()
        # The actor is placed by the planning thread (its process may first compile the
        # core's kernels): the stream starts at once, from a stand-in pose.
        self.planner = PlanningProcess(self.config.actor_config_fields(),
                                       self.skeleton.urdf_path, self.config.scene,
                                       self.config.start_pose,
                                       worker=planners.worker() if planners else None)
        self.meshes = []
        self.scene_path = self.config.scene
        self.scene_error = ''
        self.cmd_timeout = self.config.cmd_timeout
        self.planning_lead = self.config.planning_lead
        self.period = 1.0 / self.config.publish_rate

        self.buffer = FrameBuffer(stand_in_configuration(self.skeleton, self.config.scene,
                                                         self.config.start_pose))
        self.actor_offset = 0.0  # buffer time of the current actor's clock zero
        self.command = CommandState()
        self.stats = PlanningStats(state='warming up',
                                   reason='the planning process is starting')
        # Exit status asked for by a fault the node cannot recover from (None: running).
        self.exit_code = None
        # Failed attempts in a row to place the actor in a (replaced) planning process.
        self._placement_failures = 0
        self._placed_once = False
        # A Twist publisher on cmd_vel while TwistStamped is expected, or the reverse.
        self.cmd_vel_mismatch = ''
        self._reload_lock = threading.Lock()
        self.playback_time = 0.0
        self.underruns = 0
        self.missed_frames = 0
        self.tick_times = collections.deque(maxlen=max(4, int(2 * self.config.publish_rate)))
        self.committed_footsteps = collections.deque(maxlen=PAST_FOOTSTEPS)
        self._latest_block = None
        self._markers_block = None
        self._pending_start = None
        self._pending_lock = threading.Lock()
        # Loading a scene and planning a block exclude each other: the new scene's start is
        # handed over before anything is planned on it, so no block planned on the new scene
        # reaches the old scene's buffer, and none is dropped as if planned on the old one.
        self._scene_lock = threading.Lock()
        self._stop = threading.Event()
        # The planning lead in force (s); the stream wakes the planner when less is buffered.
        self._lead = self.planning_lead
        # The block last planned repeats while the command stays this one (a hold at rest, or
        # stuck): no more blocks are planned and the stream holds the last frame.
        self._holding_for = None
        # The last block committed holds the actor still (at rest or stuck): the stream running
        # past it is not a buffer underrun, also while the first step after it is planned.
        self._at_rest = False
        # A scene is loading (or the new actor has not had its first block): the walk on the
        # old scene may run out meanwhile; holding then is not running dry either.
        self._reloading = True  # until the planner has placed the actor
        self._restarted = False
        self._retry_at = 0.0
        self._clock_zero = None
        # Seconds from each recent block falling due to its commit: its wait for the shared
        # planning thread plus its planning (the planning lead must cover both).
        self._responses = collections.deque(maxlen=RECENT_BLOCKS)
        self._due_since = None
        # (number, buffer start time s, command) of the blocks committed lately.
        self._blocks = collections.deque(maxlen=REPLAN_BLOCKS)
        self._hurried_block = None  # the step last hurried to a stop
        self.replanned_blocks = 0

        threads = threads or SharedThreads()
        self._scheduler = self.planner.scheduler
        self._housekeeper = threads.housekeeper
        self._make_interfaces()
        self.add_on_set_parameters_callback(self._on_set_parameters)
        # The planning thread below the stream's priority: it holds the GIL only briefly, and
        # below that priority it cannot be preempted by other programs while holding it.
        self._scheduler.attach(self, self.config.stream_priority - 1
                               if self.config.stream_priority > 1 else 0)
        self._housekeeper.attach(self)
        self._ticker = threads.ticker(self.period, self.config.stream_priority,
                                      self.get_logger().info)
        self._ticker.attach(self)
        self.get_logger().info(
            f'streaming {len(self.skeleton.joint_names)} joints at {self.config.publish_rate:g} '
            f'Hz, scene {self.scene_path}')

    @property
    def default_callback_group(self):
        """Reentrant: the parameter services answer while a scene set loads in another
        executor thread (rclpy's default group would make them wait for it)."""
        group = self.__dict__.get('_reentrant_group')
        if group is None:
            group = self.__dict__['_reentrant_group'] = ReentrantCallbackGroup()
        return group

    # -- configuration ----------------------------------------------------------------------
    def _declare_and_read(self) -> PlannerNodeConfig:
        for name, default, descriptor in parameter_declarations():
            if name not in RUNTIME_PARAMETERS:
                descriptor.read_only = True
            try:
                self.declare_parameter(name, default, descriptor)
            except ParameterException as error:
                raise ConfigurationError(name, str(error)) from error
        config = read_node_config(self._parameter_value)
        validate_node_config(config)
        return config

    def _parameter_value(self, name: str):
        try:
            return self.get_parameter(name).value
        except ParameterUninitializedException:
            return None

    def _make_interfaces(self) -> None:
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self.joint_state_msg = JointState()
        self.joint_state_msg.header.frame_id = self.config.frame_id
        self.joint_state_msg.name = list(self.skeleton.joint_names)
        # Half a second of history, so a reliable subscriber that is briefly busy loses nothing.
        # No QoS event handlers (rclpy adds two per publisher and subscription by default, for
        # its "incompatible QoS" warnings): the SingleThreadedExecutor matches every node's
        # handlers against every other's on each wake-up, so with 20 actors in one process the
        # cmd_vel traffic alone kept most of a core busy. The warnings could not fire anyway:
        # the latched publishers offer the strongest QoS, joint_states and diagnostics clash only
        # with a transient-local subscriber, and a best-effort cmd_vel subscription accepts every
        # publisher (a lost command is replaced by the next one, or by cmd_timeout).
        quiet = {'event_callbacks': PublisherEventCallbacks(use_default_callbacks=False)}
        self.joint_state_pub = self.create_publisher(JointState, 'joint_states', 50, **quiet)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10,
                                                     **quiet)
        self.markers_pub = self.create_publisher(MarkerArray, '~/markers', latched, **quiet)
        self.environment_pub = self.create_publisher(MarkerArray, '~/environment', latched,
                                                     **quiet)
        self.path_pub = self.create_publisher(Path, '~/path', latched, **quiet)
        if self.config.publish_robot_description:
            self.description_pub = self.create_publisher(String, 'robot_description', latched,
                                                         **quiet)
            with open(self.skeleton.urdf_path) as urdf:
                self.description_pub.publish(String(data=urdf.read()))
        commands = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        quiet_sub = SubscriptionEventCallbacks(use_default_callbacks=False)
        # Hosted with other actors, the process's CommandRouter holds the subscription.
        owner, topic = self, 'cmd_vel'
        if self._commands is not None:
            owner, topic = self._commands.node, self.resolve_topic_name('cmd_vel')
        if self.config.cmd_vel_stamped:
            owner.create_subscription(TwistStamped, topic,
                                      lambda msg: self._on_cmd_vel(msg.twist), commands,
                                      event_callbacks=quiet_sub)
        else:
            owner.create_subscription(Twist, topic, self._on_cmd_vel, commands,
                                      event_callbacks=quiet_sub)
        # Diagnostics (1 Hz) and markers (5 Hz) come from the process's Housekeeper thread,
        # not executor timers: with a dozen actors in one process, rclpy's executor spent most
        # of a core waking up for their timers, at the stream's priority, starving the planning
        # processes.
        self._environment_due = None  # published by the Housekeeper once placed

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for parameter in parameters:
            if parameter.name == 'cmd_timeout':
                if not (math.isfinite(parameter.value) and parameter.value > 0.0):
                    return SetParametersResult(successful=False,
                                               reason=f'cmd_timeout {parameter.value!r}')
                self.cmd_timeout = float(parameter.value)
            elif parameter.name == 'scene':
                result = self._reload_scene(str(parameter.value))
                if not result.successful:
                    return result
        return SetParametersResult(successful=True)

    def _reload_scene(self, path: str) -> SetParametersResult:
        """Load ``path`` in the planning process and hand its start to the planning thread.

        Runs in one of the executor's threads (the others go on serving parameters and
        commands) while the stream holds the stance. The parameter takes the new value only
        once the scene is loaded; a scene that fails keeps the old one, with the reason.
        """
        problem = scene_file_error(path)
        if not problem and not self._placed_once:
            problem = 'the planner is still warming up (compiling its kernels); set it again ' \
                'once diagnostics no longer say "warming up"'
        if problem:
            return self._scene_refused(path, problem)
        with self._reload_lock:  # one reload at a time
            self._reloading = True
            with self._scene_lock:
                try:
                    configuration, meshes = self.planner.load_scene(path)
                except (ConfigurationError, PlanningFailed) as error:
                    self._reloading = False
                    return self._scene_refused(path, str(error))
                with self._pending_lock:
                    self._pending_start = (configuration, False)
                    self._environment_due = meshes
            self.meshes, self.scene_path, self.scene_error = meshes, path, ''
        self._scheduler.wake.set()
        self.get_logger().info(f'scene reloaded: {self.scene_path}')
        return SetParametersResult(successful=True)

    def _scene_refused(self, path: str, problem: str) -> SetParametersResult:
        problem = problem.replace("parameter 'scene': ", '')
        self.scene_error = f'{path}: {problem}' if path not in problem else problem
        self.get_logger().error(f'scene not reloaded, keeping {self.scene_path}: {problem}')
        return SetParametersResult(successful=False, reason=f'scene not loaded: {problem}')

    # -- planning (called by the worker's PlanningScheduler thread) -------------------------
    def planning_slack(self) -> Optional[float]:
        """Seconds until this actor's next block is due (<= 0: due now); None: nothing to plan.

        Nothing is planned while the last block would only repeat: a hold at rest or a stuck
        hold, with the command unchanged since. A new scene's first block is due at once, as
        is placing the actor in a planning process that does not hold it (at the start, or
        after the process was replaced).
        """
        if self._stop.is_set() or self.exit_code is not None:
            return None
        now = time.monotonic()
        if now < self._retry_at:
            return self._retry_at - now
        if self._pending_start is not None or not self.planner.placed:
            return -self._lead
        if self._holding_for is not None:
            if self.command.current(now, self.cmd_timeout) == self._holding_for:
                return None
            self._holding_for = None
        if self._replan_target(now) is not None or self._hurry_due(now):
            return -self._lead
        lead = self._lead = self._effective_lead()
        return self.buffer.end_time - self.playback_time - lead

    def plan_once(self) -> None:
        """Plan this actor's next block and commit it to the buffer (a new scene's first
        block after the buffer restarts at the new start; the actor placed first when its
        planning process does not hold it)."""
        try:
            with self._scene_lock:
                if not self.planner.placed and not self._place():
                    return
                with self._pending_lock:
                    pending, self._pending_start = self._pending_start, None
                if pending is not None:
                    self._blocks.clear()
                    self._hurried_block = None
                    configuration, blend = pending
                    # A new actor: its clock starts at 0 from its start pose, right after
                    # the frame on show (a new scene) or after a blend from the pose held.
                    held = max(self.playback_time, self.buffer.end_time) + self.period
                    self.actor_offset = held + BLEND_TIME if blend else \
                        self.playback_time + self.period
                    self.buffer.restart(configuration, self.actor_offset,
                                        held if blend else None)
                    self.committed_footsteps.clear()
                    self._holding_for = None
                    self._restarted = True
                try:
                    if pending is None:
                        self._replan_tail()
                        if self._hurry_due(time.monotonic()):
                            self._hurry_to_stop()
                    self._plan_block()
                except Exception as error:  # noqa: B902 -- the thread serves every actor
                    # A fault in one block must not end the thread that plans for all the
                    # process's actors: this one holds its last frame and tries again.
                    self.stats.record('stuck', f'internal error: {error!r}', float('nan'))
                    self.get_logger().error(f'planning failed: {error!r}\n'
                                            f'{traceback.format_exc()}',
                                            throttle_duration_sec=2.0)
                    self._retry_at = time.monotonic() + RETRY_AFTER
        except Exception as error:  # noqa: B902 -- never a silently frozen actor
            self.fail(1, f'planning thread failed: {error!r}\n{traceback.format_exc()}')

    def _replan_target(self, now: float):
        """The first committed block not yet begun that was planned for a command unlike the
        current one (a stop, or a change of REPLAN_LINEAR / REPLAN_ANGULAR); None if none."""
        linear, angular = self.command.current(now, self.cmd_timeout)
        stop = abs(linear) < 1e-3 and abs(angular) < 1e-3
        guard = STOP_GUARD if stop else REPLAN_GUARD
        for block in self._blocks:
            number, start, (old_linear, old_angular), _ = block
            if start <= self.playback_time + guard:
                continue
            if (stop and (abs(old_linear) >= 1e-3 or abs(old_angular) >= 1e-3)) or \
                    abs(linear - old_linear) >= REPLAN_LINEAR or \
                    abs(angular - old_angular) >= REPLAN_ANGULAR:
                return block
            return None
        return None

    def _replan_tail(self) -> None:
        """Drop the blocks not yet begun that the command has overtaken, and take the actor in
        its planning process back to the state before them (the next block replaces them)."""
        target = self._replan_target(time.monotonic())
        if target is None:
            return
        number, start, _, _ = target
        # The stream holds the last frame kept (a double-support stance at a step's end) if
        # it gets there before the new block is planned.
        self.buffer.truncate(start)
        if not self.planner.replan_from(number):
            # That state is no longer kept: the actor goes on from the end of what it
            # planned, after a hold (its clock and the buffer's stay in step).
            self.get_logger().warning(f'block {number} could not be planned again')
            return
        self.replanned_blocks += sum(1 for block in self._blocks if block[0] >= number)
        while self._blocks and self._blocks[-1][0] >= number:
            self._blocks.pop()
        self._at_rest = False

    def _hurry_due(self, now: float) -> bool:
        """True when told to stop during a walking step that can still land sooner: the step
        has begun, is the last block committed (what is planned next starts where it ends)
        and was not hurried yet."""
        linear, angular = self.command.current(now, self.cmd_timeout)
        if abs(linear) >= 1e-3 or abs(angular) >= 1e-3 or not self._blocks:
            return False
        number, start, _, status = self._blocks[-1]
        return status == 'walking' and number != self._hurried_block and \
            start <= self.playback_time

    def _hurry_to_stop(self) -> None:
        """Play the rest of the step in progress faster (``runtime.retiming``); the actor's
        clock moves on by the time saved, so that the block planned next follows on."""
        self._hurried_block = self._blocks[-1][0]
        self.actor_offset -= self.buffer.hurry(self.playback_time + HURRY_GUARD,
                                               self.skeleton.velocity_limit, HURRY_MAX_RATE)

    def _place(self) -> bool:
        """Place the actor in its planning process; True when placed.

        The first time on the configured scene and start; after the process was replaced,
        where the actor stood (the root of the last committed frame), blended over to.
        A bad scene or start ends the node with status 2 (a configuration error), a process
        that keeps failing with status 1.
        """
        first = not self._placed_once
        pose = None
        if not first:
            q = self.buffer.sample(self.buffer.end_time)[0]
            index = self.skeleton.index
            pose = (float(q[index['root_x']]), float(q[index['root_y']]),
                    float(q[index['root_yaw']]))
            self.stats.record('recovering', 'the planning process was replaced; placing the '
                              'actor where it stands', float('nan'))
            self.get_logger().warning(f'planning process replaced; placing the actor again at '
                                      f'({pose[0]:.3f}, {pose[1]:.3f}, yaw {pose[2]:.3f})')
        self._reloading = True
        try:
            configuration, meshes = self.planner.place(pose)
        except ConfigurationError as error:
            if first:
                self.fail(2, f'invalid configuration: {error}')
            else:
                self.fail(1, f'the actor cannot stand where it stood after the planning '
                          f'process was replaced: {error}')
            return False
        except PlanningFailed as error:
            if self._stop.is_set():
                return False
            self._placement_failures += 1
            if self._placement_failures >= MAX_REPLACEMENTS:
                self.fail(1, f'planning process failed {self._placement_failures} times in a '
                          f'row: {error}')
            else:
                self.get_logger().error(f'planning process failed while placing the actor, '
                                        f'trying a new one: {error}')
            return False
        self._placement_failures = 0
        self._placed_once = True
        with self._pending_lock:
            self._pending_start = (configuration, True)
            self._environment_due = meshes
        self.meshes = meshes
        if first:
            self.stats.record('idle', '', float('nan'))
            self.get_logger().info('planner ready')
        return True

    def fail(self, code: int, message: str) -> None:
        """End the node with exit status ``code``: an ERROR on /diagnostics and the log, then
        the context is shut down (``main`` returns ``exit_code``)."""
        if self.exit_code is not None or self._stop.is_set():
            return
        self.exit_code = code
        self.stats.state, self.stats.reason = 'error', message.splitlines()[0]
        self.get_logger().fatal(message)
        try:
            self._publish_diagnostics()
        except Exception:  # noqa: B902 -- shutting down anyway
            pass
        self.context.try_shutdown()

    def _plan_block(self) -> None:
        started = time.monotonic()
        command = self.command.current(started, self.cmd_timeout)
        try:
            warning, block, profile, number = self.planner.plan(
                *command, timeout=self.config.planning_timeout)
        except PlanningFailed as error:
            if self._stop.is_set():
                return  # shutting down: the planning process was told to finish
            if isinstance(error, PlanningLost):
                self.get_logger().error(f'planning failed: {error}')
                return  # placed again in the new process at the next turn
            self.stats.record('stuck', f'planner error: {error}', float('nan'))
            self.get_logger().error(f'planning failed: {error}', throttle_duration_sec=2.0)
            self._retry_at = time.monotonic() + RETRY_AFTER
            return
        if warning:
            self.get_logger().warning(warning, throttle_duration_sec=2.0)
        times = np.asarray(block.times) + self.actor_offset
        self.buffer.append(times, block.frames, block.velocities, self.playback_time)
        if len(times):
            self._blocks.append((number, float(times[0]), command, block.status))
        if self._restarted:  # the new actor's first block
            self._reloading = self._restarted = False
        self.stats.record(block.status, block.reason, block.planning_time)
        due, self._due_since = self._due_since, None
        self._responses.append(time.monotonic() - min(started, due or started))
        if block.status == 'walking' and len(block.footsteps):
            self.committed_footsteps.append(np.asarray(block.footsteps[0], dtype=float))
        self._at_rest = (block.status, block.reason) == ('idle', '') or block.status == 'stuck'
        if self._at_rest:
            self._holding_for = command
        self._latest_block = (block, profile)

    def _effective_lead(self) -> float:
        """Buffered time (s) below which the next block is planned.

        At least ``planning_lead``, and more when recent blocks took long to plan or waited
        long for their turn in a shared planning process (a loaded
        machine), so that playback does not run dry while the next block is planned.
        """
        slowest = max(self._responses, default=0.0)
        return min(MAX_LEAD, max(self.planning_lead, LEAD_SAFETY * slowest))

    def publish_frame(self, now: float, late_ticks: int, instant: Optional[float],
                      stamp_ns: int) -> None:
        """Publish the frame for monotonic time ``instant`` (None: ``now``) at ``now``
        (called by the stream ticker).

        ``late_ticks`` ticks were skipped before this one because the tick came too late to
        catch them up. A frame published a period or more after its tick (``instant``) shows
        the motion at ``instant``. ``stamp_ns`` is the wall-clock time of the instant shown;
        with ``use_sim_time`` the stamp is the ROS clock's time instead.
        """
        if self._stop.is_set():
            return
        self.missed_frames += late_ticks
        shown = now if instant is None else instant
        if self._clock_zero is None:
            self._clock_zero = shown
        play = max(0.0, shown - self._clock_zero)
        end = self.buffer.end_time
        if play > end:
            # Holding the last frame on purpose (at rest, or stuck), or while a new scene
            # loads, is not running dry.
            if play - end > self.period and not (self._at_rest or self._reloading):
                self.underruns += 1
            self._clock_zero = shown - end
            play = end
        self.playback_time = play
        if end - play <= self._lead and self._holding_for is None:
            if self._due_since is None:
                self._due_since = now
            self._scheduler.wake.set()
        q, v = self.buffer.sample(play)
        msg = self.joint_state_msg
        clock = self.get_clock()
        if clock.ros_time_is_active:  # use_sim_time: the stamp comes from /clock
            msg.header.stamp = clock.now().to_msg()
        else:  # ROS time is system time; this is about 10 us cheaper per frame
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
        # array('d') is taken by the message setters without a per-element type check.
        msg.position = array.array('d', q.tobytes())
        msg.velocity = array.array('d', v.tobytes())
        try:
            self.joint_state_pub.publish(msg)
        except Exception:  # noqa: B902 -- the context is shutting down
            if self._stop.is_set() or not rclpy.ok(context=self.context):
                return
            raise
        self.tick_times.append(now)

    def housekeeping(self, diagnostics: bool, housekeeper: 'Housekeeper') -> None:
        """Publish a new environment and new markers, and diagnostics when ``diagnostics``
        (the Housekeeper's call)."""
        if self._stop.is_set():
            return
        try:
            with self._pending_lock:  # a reload may hand over newer meshes meanwhile
                meshes, self._environment_due = self._environment_due, None
            if meshes is not None:
                # Built in this thread, not in the executor's, which serves commands and the
                # reply to the scene change.
                self.environment_pub.publish(housekeeper.environment(meshes,
                                                                     self.config.frame_id))
            self._publish_markers()
            if diagnostics:
                self._check_cmd_vel_type()
                self._publish_diagnostics()
        except Exception as error:  # noqa: B902 -- the context is shutting down
            if self._stop.is_set() or not rclpy.ok(context=self.context):
                return
            self.get_logger().error(f'diagnostics/markers not published: {error!r}',
                                    throttle_duration_sec=2.0)

    def request_stop(self) -> None:
        """Tell the threads to finish (without waiting for them)."""
        self._stop.set()
        self._scheduler.wake.set()

    def stop(self) -> None:
        """Stop streaming and planning, and end the planning process."""
        self.request_stop()
        self._ticker.detach(self)
        self._housekeeper.detach(self)
        self._scheduler.detach(self)
        self.planner.close()

    # -- executor callbacks -----------------------------------------------------------------
    def _on_cmd_vel(self, twist: Twist) -> None:
        linear_x, angular_z = twist.linear.x, twist.angular.z
        if not (math.isfinite(linear_x) and math.isfinite(angular_z)):
            self.get_logger().warning(
                f'ignoring non-finite cmd_vel (linear.x={linear_x}, angular.z={angular_z})',
                throttle_duration_sec=2.0)
            return
        now = time.monotonic()
        was_moving = any(abs(c) >= 1e-3 for c in self.command.current(now, self.cmd_timeout))
        self.command.update(float(linear_x), float(angular_z), now)
        stop = abs(linear_x) < 1e-3 and abs(angular_z) < 1e-3
        if (self._holding_for is not None and (linear_x, angular_z) != self._holding_for) or \
                (stop and was_moving):
            self._scheduler.wake.set()  # a stop is planned at once (docs/stopping.md)

    def stream_timing(self) -> Tuple[float, float]:
        """Return the jitter p99 and the longest interval (ms) of the recent ticks (NaN when
        unknown): the deviation of each interval between published frames from the period."""
        ticks = np.array(self.tick_times)
        if len(ticks) < 3:
            return float('nan'), float('nan')
        intervals = np.diff(ticks)
        jitter = np.abs(intervals - 1.0 / self.config.publish_rate)
        return 1e3 * float(np.percentile(jitter, 99)), 1e3 * float(intervals.max())

    def publish_rate_measured(self) -> float:
        """Return the joint_states rate (Hz) over the last second of ticks (NaN when unknown)."""
        ticks = list(self.tick_times)
        if len(ticks) < 2:
            return float('nan')
        recent = [t for t in ticks if t >= ticks[-1] - 1.0]
        if len(recent) < 2 or recent[-1] <= recent[0]:
            return float('nan')
        return (len(recent) - 1) / (recent[-1] - recent[0])

    def _check_cmd_vel_type(self) -> None:
        """Warn (log and diagnostics) about cmd_vel publishers of the other Twist type: the
        subscription never hears them, and nothing else would say so."""
        topic = self.resolve_topic_name('cmd_vel')
        expected = 'geometry_msgs/msg/TwistStamped' if self.config.cmd_vel_stamped else \
            'geometry_msgs/msg/Twist'
        others = sorted({info.topic_type for info in self.get_publishers_info_by_topic(topic)
                         if info.topic_type != expected})
        mismatch = ''
        if others:
            mismatch = (f'{topic} has a {", ".join(others)} publisher, ignored: this node '
                        f'takes {expected}; set cmd_vel_stamped:='
                        f'{"false" if self.config.cmd_vel_stamped else "true"} to follow it')
            if mismatch != self.cmd_vel_mismatch:
                self.get_logger().warning(mismatch)
        self.cmd_vel_mismatch = mismatch

    def _publish_diagnostics(self) -> None:
        stats = self.stats
        p50, p99 = stats.percentiles()
        rate = self.publish_rate_measured()
        jitter_p99, longest = self.stream_timing()
        rate_ok = math.isfinite(rate) and abs(rate - self.config.publish_rate) <= \
            0.05 * self.config.publish_rate
        level = DiagnosticStatus.OK
        message = stats.state + (f': {stats.reason}' if stats.reason else '')
        if stats.state in ('stuck', 'recovering') or self.scene_error or not rate_ok or \
                self.cmd_vel_mismatch:
            level = DiagnosticStatus.WARN
        if self.exit_code is not None:
            level = DiagnosticStatus.ERROR
        if self.scene_error:
            message += f'; scene error: {self.scene_error}'
        if self.cmd_vel_mismatch:
            message += f'; {self.cmd_vel_mismatch}'
        if not rate_ok:
            message += f'; joint_states at {rate:.1f} Hz'
        values = {
            'state': stats.state,
            'reason': stats.reason,
            'steps': str(stats.steps),
            'blocks_planned': str(stats.blocks),
            'planning_time_last_ms': f'{1e3 * stats.last_planning_time:.3f}',
            'planning_time_p50_ms': f'{1e3 * p50:.3f}',
            'planning_time_p99_ms': f'{1e3 * p99:.3f}',
            'publish_rate_hz': f'{rate:.2f}',
            'publish_rate_target_hz': f'{self.config.publish_rate:g}',
            'stream_jitter_p99_ms': f'{jitter_p99:.3f}',
            'stream_longest_interval_ms': f'{longest:.2f}',
            'missed_frames': str(self.missed_frames),
            'stream_backup_ticks': str(self._ticker.backup_publishes),
            'stream_caught_up_ticks': str(self._ticker.caught_up),
            'stream_late_ticks': str(self._ticker.late_ticks),
            'stream_lateness_max_ms': f'{1e3 * self._ticker.max_lateness:.2f}',
            'buffer_underruns': str(self.underruns),
            'buffered_ahead_s': f'{self.buffer.end_time - self.playback_time:.3f}',
            'planning_lead_s': f'{self._effective_lead():.3f}',
            'scene': self.scene_path,
            'scene_error': self.scene_error,
            'cmd_vel_type_mismatch': self.cmd_vel_mismatch,
            'planning_process_pid': str(self.planner.worker.pid),
            'planning_processes_replaced': str(self.planner.worker.generation),
            'stale_replies_dropped': str(self.planner.worker.stale_replies),
            'blocks_planned_again': str(self.replanned_blocks),
        }
        status = DiagnosticStatus(
            level=level, name=f'{self.get_fully_qualified_name()}: actor planner',
            message=message, hardware_id=self.get_fully_qualified_name(),
            values=[KeyValue(key=k, value=v) for k, v in values.items()])
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self.diagnostics_pub.publish(array)

    def _header(self, marker: Marker) -> Marker:
        marker.header.frame_id = self.config.frame_id
        marker.header.stamp = self.get_clock().now().to_msg()
        return marker

    def _publish_markers(self) -> None:
        latest = self._latest_block
        if latest is None or latest is self._markers_block:
            return
        self._markers_block = latest
        block, profile = latest
        markers = [self._header(Marker(action=Marker.DELETEALL))]
        window = np.asarray(block.footsteps, dtype=float).reshape(-1, 4)
        past = list(self.committed_footsteps)
        for ns, steps, color in (('footsteps_past', past, _color(0.5, 0.5, 0.5, 0.6)),
                                 ('footsteps_window', window, _color(0.1, 0.8, 0.2, 0.9))):
            for index, (x, y, z, yaw) in enumerate(steps):
                marker = self._header(Marker(ns=ns, id=index, type=Marker.CUBE,
                                             action=Marker.ADD))
                marker.pose.position = Point(x=float(x), y=float(y), z=float(z) + 0.005)
                marker.pose.orientation = _yaw_quaternion(float(yaw))
                marker.scale.x, marker.scale.y, marker.scale.z = 0.25, 0.1, 0.01
                marker.color = color
                markers.append(marker)
        if len(profile) >= 2:
            line = self._header(Marker(ns='ground_profile', id=0, type=Marker.LINE_STRIP,
                                       action=Marker.ADD))
            line.pose.orientation.w = 1.0
            line.scale.x = 0.02
            line.color = _color(0.9, 0.5, 0.1)
            line.points = _points(profile + [0.0, 0.0, 0.01])
            markers.append(line)
        self.markers_pub.publish(MarkerArray(markers=markers))
        path = np.asarray(block.path, dtype=float).reshape(-1, 3)
        message = Path()
        message.header.frame_id = self.config.frame_id
        message.header.stamp = self.get_clock().now().to_msg()
        for x, y, z in path:
            pose = PoseStamped()
            pose.header = message.header
            pose.pose.position = Point(x=float(x), y=float(y), z=float(z))
            pose.pose.orientation.w = 1.0
            message.poses.append(pose)
        self.path_pub.publish(message)


def _usable_cores() -> int:
    """Cores this process may run on (its affinity, e.g. under taskset), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _command_line(argv) -> Tuple[list, int]:
    """The ``--actors NS [NS ...]`` and ``--planning-processes K`` options among the non-ROS
    arguments: (namespaces, [''] when absent; number of planning processes).

    Raises
    ------
    ConfigurationError
        An unknown argument or an invalid / repeated namespace.
    """
    parser = argparse.ArgumentParser(
        prog='actor_planner', description='Stream digital actors as JointState.',
        epilog='Several actors in one process share one DDS participant and one stream thread.')
    parser.add_argument('--actors', nargs='+', metavar='NS', default=[''],
                        help='host one actor per namespace in this process')
    parser.add_argument('--planning-processes', type=int, metavar='K', default=None,
                        help='planning processes shared by the actors (default: one per actor '
                        'up to the number of usable cores)')
    parsed, unknown = parser.parse_known_args(argv)
    if unknown:
        raise ConfigurationError('arguments', f'unknown arguments {unknown}')
    names = [ns.strip() for ns in parsed.actors]
    for ns in names:
        try:
            validate_namespace(ns if ns.startswith('/') else '/' + ns)
        except InvalidNamespaceException as error:
            raise ConfigurationError('actors', f'invalid namespace {ns!r}: '
                                     f'{str(error).splitlines()[0]}') from None
    if len(set(names)) != len(names):
        raise ConfigurationError('actors', f'repeated namespace in {names}')
    processes = parsed.planning_processes
    if processes is None:
        processes = min(len(names), _usable_cores())
    return names, processes


def _terminated(signum, frame):
    raise KeyboardInterrupt(f'signal {signum}')


def spin_until_shutdown(executor, ok=rclpy.ok) -> None:
    """Spin ``executor`` until the context is shut down (``ok()`` false).

    Bounded waits, so that the SIGTERM handler (Python code, run by the main thread) gets its
    turn even when no message arrives. Ctrl-C shuts the context down from rclpy's signal
    handler, which can land between ``ok()`` and ``spin_once`` building its wait set (RCLError,
    a RuntimeError: "the given context is not valid"): that is the shutdown asked for, not a
    failure (the node exited with status 1 and a traceback, one CI run in many).
    """
    while ok():
        try:
            executor.spin_once(timeout_sec=SIGNAL_CHECK)
        except RuntimeError:
            if ok():
                raise


def _close_partial(nodes, commands, planners) -> None:
    """Shut down what :func:`main` built before it stopped starting."""
    for node in nodes:
        node.stop()
        node.destroy_node()
    if commands is not None:
        commands.stop()
    if planners is not None:
        planners.close()
    rclpy.try_shutdown()


def _without_kernels() -> None:
    """Load the core in this process as plain Python, not compiled.

    The node process runs no kernel (its planning processes do); compiling them here too
    took tens of seconds from an empty cache before the first frame.
    """
    if 'numba' not in sys.modules and 'digital_actor_planner.core.jit' not in sys.modules:
        sys.modules['numba'] = None


def main(args=None) -> int:
    """Run the node(s) until interrupted; exit status 2 on a bad configuration, 1 on a fault
    the planner could not recover from."""
    try:
        return _run(args)
    except KeyboardInterrupt:  # Ctrl-C while starting, before rclpy took it over
        rclpy.try_shutdown()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)  # see the imports: a plain exit could end by SIGINT


def _run(args) -> int:
    _without_kernels()
    # The executor and planning threads hold the GIL at times; a short switch interval bounds
    # how long the publishing thread waits for it after waking (the default 5 ms would be the
    # jitter).
    sys.setswitchinterval(0.0005)
    # SIGTERM (docker stop, systemd, ros2 launch after SIGINT) ends the node as Ctrl-C does.
    # rclpy's own SIGTERM handling left a node hosting 20 walking actors running for minutes.
    signal.signal(signal.SIGTERM, _terminated)
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.SIGINT)
    logger = rclpy.logging.get_logger('actor_planner')
    nodes, planners, commands = [], None, None
    try:
        namespaces, processes = _command_line(remove_ros_args(
            sys.argv if args is None else args)[1:])
        threads = SharedThreads()
        planners = PlanningPool(processes)
        commands = CommandRouter() if len(namespaces) > 1 else None
        for ns in namespaces:
            nodes.append(ActorPlannerNode(threads=threads, planners=planners, commands=commands,
                                          **({'namespace': ns} if ns else {})))
    except ConfigurationError as error:
        logger.fatal(f'invalid configuration: {error}')
        _close_partial(nodes, commands, planners)
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        _close_partial(nodes, commands, planners)
        return 0
    except RuntimeError:
        # Ctrl-C while a node was being built: rclpy's handler shut the context down under it.
        if rclpy.ok():
            raise
        _close_partial(nodes, commands, planners)
        return 0
    priority = nodes[0].config.stream_priority
    if priority > 2:
        real_time(priority - 1)  # the executor thread, as the planning threads
        # The DDS threads too: publish() takes locks they hold, so they must not wait behind
        # the planning processes (which stay at normal priority).
        tasks = '/proc/self/task'
        for thread_id in (os.listdir(tasks) if os.path.isdir(tasks) else ()):
            try:
                if os.sched_getscheduler(int(thread_id)) == os.SCHED_OTHER:
                    os.sched_setscheduler(int(thread_id), os.SCHED_FIFO | getattr(
                        os, 'SCHED_RESET_ON_FORK', 0), os.sched_param(priority - 2))
            except OSError:
                pass
    if commands is not None:
        commands.start(priority - 1 if priority > 2 else 0)
    # Several threads: a scene reload (seconds for a large scene) occupies one of them while
    # the others answer parameter requests and cmd_vel (the node's callbacks are reentrant).
    executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
    for node in nodes:
        executor.add_node(node)
    # Everything built so far (scene meshes for the markers, messages, modules) is moved out of
    # the garbage collector's reach, so its full collections, which run in whatever thread
    # allocates and hold the GIL, cannot delay a tick by milliseconds.
    gc.freeze()
    try:
        spin_until_shutdown(executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        for node in nodes:
            node.request_stop()
        if commands is not None:
            commands.stop()
        for node in nodes:
            node.stop()
        executor.shutdown(timeout_sec=5.0)
        for node in nodes:
            node.destroy_node()
        planners.close()
        rclpy.try_shutdown()
    codes = [node.exit_code for node in nodes if node.exit_code is not None]
    return max(codes, default=0)


if __name__ == '__main__':
    sys.exit(main())
