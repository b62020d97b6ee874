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
Browser viewer node: the actor, its course and a drag pad in a web page served by viser.

Like RViz, it is only a ROS 2 client: it subscribes to ``robot_description``, ``joint_states``,
the planner's markers and path and ``/diagnostics``, and publishes ``cmd_vel`` from the drag pad
(paper §3: the vertical part of a dragged vector is the forward speed, the horizontal part the turn
rate). The pure helpers at the top (drag mapping, status text with what to do when stuck, marker
conversion, the course list with descriptions, the follow camera, port choice) hold the logic; the
node only wires them to topics and to the page.
"""
from __future__ import annotations

import argparse
from collections import deque
from dataclasses import dataclass
import glob
import io
import math
import os
import signal
import socket
import sys
import threading
import time
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

PACKAGE_NAME = 'digital_actor_planner'
ROOT_JOINTS = ('root_x', 'root_y', 'root_z', 'root_yaw')
PLANNER_NODE = 'actor_planner'
#: The course list's entry until the planner has said which course it runs.
ASKING = '(asking the planner)'


# ----------------------------------------------------------------------------------------------
# Pure helpers (no ROS, no browser)
# ----------------------------------------------------------------------------------------------

def drag_to_command(start: Sequence[float], end: Sequence[float], span: float,
                    max_linear_speed: float, max_angular_speed: float,
                    max_backward_speed: Optional[float] = None) -> Tuple[float, float]:
    """
    Map a drag on the pad to a velocity command (paper §3, teleop_tools mouse_teleop signs).

    Parameters
    ----------
    start, end : (2,) float
        Screen positions of the press and of the pointer now, in pixels, x to the right and y
        down.
    span : float
        Drag length in pixels that gives full speed; longer drags are clamped.
    max_linear_speed, max_angular_speed : float
        m/s and rad/s at full deflection.
    max_backward_speed : float or None
        m/s at full downward deflection (the planner's own backward limit, so the whole lower
        half of the pad is used); None: ``max_linear_speed``.

    Returns
    -------
    (linear_x m/s, angular_z rad/s): dragging up walks forward, dragging left turns left.

    """
    if not (span > 0.0 and math.isfinite(span)):
        raise ValueError(f'drag span must be a positive number of pixels, got {span!r}')
    if max_backward_speed is None:
        max_backward_speed = max_linear_speed
    for name, value in (('max_linear_speed', max_linear_speed),
                        ('max_angular_speed', max_angular_speed),
                        ('max_backward_speed', max_backward_speed)):
        if not (value >= 0.0 and math.isfinite(value)):
            raise ValueError(f'{name} must be a finite speed >= 0, got {value!r}')
    dx = float(end[0]) - float(start[0])
    dy = float(end[1]) - float(start[1])
    if not (math.isfinite(dx) and math.isfinite(dy)):
        raise ValueError(f'drag positions must be finite, got {start!r} -> {end!r}')
    forward = min(1.0, max(-1.0, -dy / span))
    turn_left = min(1.0, max(-1.0, -dx / span))
    speed = max_linear_speed if forward >= 0.0 else max_backward_speed
    return forward * speed, turn_left * max_angular_speed


class StreamMonitor:
    """Arrival times of ``joint_states``: the stream rate and whether the planner went silent."""

    def __init__(self, window: float = 2.0):
        if not window > 0.0:
            raise ValueError(f'rate window must be > 0 s, got {window!r}')
        self.window = window
        self._arrivals: deque = deque()
        self.last_arrival: Optional[float] = None

    def add(self, now: float) -> None:
        """Record one message received at ``now`` (s, monotonic)."""
        self._arrivals.append(now)
        self.last_arrival = now
        while self._arrivals and self._arrivals[0] < now - self.window:
            self._arrivals.popleft()

    def rate(self, now: float) -> float:
        """Messages per second over the last ``window`` s (0 when silent)."""
        while self._arrivals and self._arrivals[0] < now - self.window:
            self._arrivals.popleft()
        if len(self._arrivals) < 2:
            return 0.0
        span = self._arrivals[-1] - self._arrivals[0]
        return (len(self._arrivals) - 1) / span if span > 0 else 0.0

    def silent_for(self, now: float) -> Optional[float]:
        """Seconds since the last message, or None if none ever arrived."""
        return None if self.last_arrival is None else now - self.last_arrival


@dataclass(frozen=True)
class PlannerDiagnostics:
    """What the planner reported last on /diagnostics."""

    state: str = ''
    reason: str = ''
    planning_time_ms: Optional[float] = None
    #: joint_states frames per second the planner sent (its ``publish_rate_hz``), None if unsaid.
    publish_rate_hz: Optional[float] = None


def parse_planner_diagnostics(statuses, node_name: str) -> Optional[PlannerDiagnostics]:
    """
    Pick the planner's status out of a DiagnosticArray's ``status`` list.

    A status belongs to the planner when its hardware id is ``node_name`` (fully qualified, as
    ``/ns/actor_planner``) or its name starts with it. The state
    comes from a ``state`` key (else the message's first word), the reason from ``reason``
    (else the rest of the message) and the planning time from the first key naming the last
    (or else the median) planning time, in ms or s as the key says.
    """
    for status in statuses:
        if status.hardware_id != node_name and not status.name.startswith(node_name + ':'):
            continue
        values = {kv.key.strip().lower(): kv.value.strip() for kv in status.values}
        message = status.message.strip()
        state = values.get('state', '')
        reason = values.get('reason', '')
        if not state and message:
            state = message.split()[0].rstrip(':,').lower()
            reason = reason or message[len(state):].strip(' :,')
        planning = None
        for key in sorted(values, key=lambda k: ('last' not in k, 'p50' not in k, k)):
            if 'planning' in key and 'time' in key:
                planning = _to_ms(key, values[key])
                if planning is not None:
                    break
        return PlannerDiagnostics(state=state.lower(), reason=reason, planning_time_ms=planning,
                                  publish_rate_hz=_finite(values.get('publish_rate_hz')))
    return None


def _finite(text: Optional[str]) -> Optional[float]:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _to_ms(key: str, text: str) -> Optional[float]:
    try:
        value = float(text.split()[0])
    except (ValueError, IndexError):
        return None
    in_ms = 'ms' in key or text.endswith('ms')
    return value if in_ms else value * 1000.0


#: What to do when stuck: the planner takes a turn on the spot (a sideways drag) and a step back
#: (a downward drag) wherever a forward step is not possible.
UNSTUCK_ADVICE = 'turn on the spot (drag sideways) or step back (drag down)'
WARMING_UP_ADVICE = ('The planner is compiling its kernels (once per installation; '
                     '`digital-actor warm-up` does it ahead). The actor walks when it is done.')


def stuck_in_plain_words(reason: str) -> str:
    """Return the planner's stuck ``reason`` as a person would say it (what is in the way)."""
    reason = reason.strip()
    if reason.startswith('no collision-free footstep window'):
        return 'no room for the next steps ahead (an obstacle, an edge or a drop)'
    if reason.startswith('upper body blocked'):
        return 'the upper body cannot get past the obstacle ahead'
    if reason.startswith('walk generation failed'):
        return 'the legs cannot reach the next footholds'
    if 'collides' in reason or 'collision' in reason:
        return 'the next step would hit the obstacle'
    return 'the next step is not possible here'


def status_text(now: float, stream: StreamMonitor, diagnostics: Optional[PlannerDiagnostics],
                planner_present: bool, silence_limit: float = 1.0) -> str:
    """
    Return the status shown in the page (markdown: a status line, then advice when there is some).

    Parameters
    ----------
    now : float
        s, the same monotonic clock as the stream's arrivals.
    stream : StreamMonitor
        The joint_states arrivals at this viewer.
    diagnostics : PlannerDiagnostics or None
        What the planner last reported, or None.
    planner_present : bool
        Whether a joint_states publisher is known.
    silence_limit : float
        s without a frame after which the planner counts as silent.

    """
    silent = stream.silent_for(now)
    warming = diagnostics is not None and diagnostics.state == 'warming up'
    if silent is None and warming:
        return f'warming up, no joint_states yet\n\n{WARMING_UP_ADVICE}'
    if silent is None:
        if not planner_present:
            return 'waiting for joint_states (no planner found yet: the demo starts one)'
        return 'waiting for joint_states (the planner is loading its course)'
    if silent > silence_limit:
        why = 'planner stopped' if not planner_present else 'planner not publishing'
        return f'{why}: no joint_states for {silent:.1f} s'
    parts = []
    advice = ''
    if diagnostics is not None and diagnostics.state:
        state = diagnostics.state
        if state == 'stuck':
            state = f'stuck: {stuck_in_plain_words(diagnostics.reason)}'
            advice = f'To get going again: {UNSTUCK_ADVICE}.'
        elif warming:
            advice = WARMING_UP_ADVICE
        elif diagnostics.reason and state != 'walking':
            state += f' ({diagnostics.reason})'
        parts.append(state)
        if diagnostics.planning_time_ms is not None and diagnostics.state != 'warming up':
            parts.append(f'planning {diagnostics.planning_time_ms:.1f} ms')
    else:
        parts.append('no diagnostics yet')
    rates = f'received {stream.rate(now):.0f} Hz'
    if diagnostics is not None and diagnostics.publish_rate_hz is not None:
        rates += f' of {diagnostics.publish_rate_hz:.0f} Hz published'
    parts.append(rates)
    text = ' · '.join(parts)
    return text + (f'\n\n{advice}' if advice else '')


@dataclass(frozen=True)
class Course:
    """A shipped course as the page offers it."""

    name: str
    path: str
    description: str = ''
    #: The course is built to stop the actor (its scene's ``expect`` says ``stuck``).
    impassable: bool = False

    @property
    def label(self) -> str:
        """Return the name in the course list; impassable ones say so."""
        return f'{self.name} (impassable)' if self.impassable else self.name

    def about(self) -> str:
        """Markdown for the page: the description, and what to expect when impassable."""
        text = self.description or 'No description.'
        if self.impassable:
            text += ('\n\n*Built to stop the actor: it should halt cleanly before the '
                     'obstacle and report stuck.*')
        return text


def course_catalog(directory: Optional[str] = None) -> Dict[str, Course]:
    """
    Every shipped course with its description: {name: Course}, sorted by name.

    A scene YAML that cannot be read is still offered, without a description: the planner
    reports what is wrong with it when it is chosen.
    """
    import yaml
    courses = {}
    for name, path in shipped_scenes(directory).items():
        try:
            with open(path) as f:
                data = yaml.safe_load(f)
        except (OSError, yaml.YAMLError):
            data = None
        data = data if isinstance(data, dict) else {}
        expect = data.get('expect') if isinstance(data.get('expect'), dict) else {}
        description = data.get('description')
        courses[name] = Course(name, path,
                               ' '.join(str(description).split()) if description else '',
                               bool(expect.get('stuck', False)))
    return courses


def follow_target(actor_position: Sequence[float], camera_position: Sequence[float],
                  look_at: Sequence[float], fov: float, aspect: float,
                  screen_u: float) -> np.ndarray:
    """
    Return where the camera should look so the actor appears at ``screen_u`` across the view.

    Parameters
    ----------
    actor_position : (3,) float
        m, the pelvis.
    camera_position, look_at : (3,) float
        m, the camera now (z up).
    fov : float
        Vertical field of view, rad.
    aspect : float
        Width / height.
    screen_u : float
        0 left edge .. 1 right edge; below 0.5 puts the actor left of the centre, clear of a
        control panel on the right.

    Returns
    -------
    (3,) m, the look-at point: beside the actor, along the view's horizontal right direction.

    """
    position = np.asarray(camera_position, dtype=np.float64)
    target = np.asarray(look_at, dtype=np.float64)
    forward = target - position
    distance = float(np.linalg.norm(forward))
    right = np.array([forward[1], -forward[0], 0.0])
    norm = float(np.linalg.norm(right))
    actor = np.asarray(actor_position, dtype=np.float64)
    if distance < 1e-6 or norm < 1e-6 or not math.isfinite(fov * aspect):
        return actor.copy()   # looking straight down: no horizontal right to shift along
    half_width = math.tan(fov / 2.0) * aspect * distance
    return actor + (0.5 - screen_u) * 2.0 * half_width * right / norm


def along_view_plane(move: np.ndarray, view_direction: np.ndarray) -> np.ndarray:
    """
    Return ``move`` (3,) m without its part along ``view_direction`` (3,).

    ``move`` (3,) m without its part along ``view_direction`` (3,): a camera move that keeps the
    camera's distance to every plane facing it.

    viser follows a drag's pointer on a plane facing the camera through the grab point, which is
    the drag pad just in front of the camera: a camera moved forwards through that plane would
    lose the drag (the pointer's ray no longer meets it), and the steering with it. So during a
    drag the camera slides sideways and up or down only; it catches up in depth on release.
    """
    view = np.asarray(view_direction, dtype=np.float64)
    norm = float(np.linalg.norm(view))
    move = np.asarray(move, dtype=np.float64)
    if norm < 1e-9:
        return move.copy()
    view = view / norm
    return move - float(move @ view) * view


def smooth_step(current: np.ndarray, target: np.ndarray, dt: float,
                time_constant: float) -> np.ndarray:
    """
    Move ``current`` towards ``target`` as a first-order lag.

    Move ``current`` towards ``target`` as a first-order lag with ``time_constant`` s over ``dt``
    s: a camera that glides after the actor instead of jumping a step at a time.
    """
    if not time_constant > 0.0:
        return np.asarray(target, dtype=np.float64).copy()
    fraction = 1.0 - math.exp(-max(dt, 0.0) / time_constant)
    current = np.asarray(current, dtype=np.float64)
    return current + fraction * (np.asarray(target, dtype=np.float64) - current)


def shipped_scenes(directory: Optional[str] = None) -> Dict[str, str]:
    """Every shipped course: {name: absolute path of config/scenes/<name>.yaml}, sorted by name."""
    if directory is None:
        directory = scenes_directory()
    paths = sorted(glob.glob(os.path.join(directory, '*.yaml')))
    return {os.path.splitext(os.path.basename(p))[0]: os.path.abspath(p) for p in paths}


def scenes_directory() -> str:
    """Return the package's config/scenes folder, in a source tree or an install."""
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.path.join(here, '..', '..', 'config', 'scenes'),
                  os.path.join(sys.prefix, 'share', PACKAGE_NAME, 'config', 'scenes')]
    prefix = here
    for _ in range(6):
        prefix = os.path.dirname(prefix)
        candidates.append(os.path.join(prefix, 'share', PACKAGE_NAME, 'config', 'scenes'))
    for path in candidates:
        if os.path.isdir(path):
            return os.path.normpath(path)
    return os.path.normpath(candidates[0])


def pick_port(host: str, port: int, attempts: int = 100) -> int:
    """
    Return ``port`` if it is free on ``host``, else the next free one (raises if none).

    A port left in TIME_WAIT by a viewer that just stopped counts as free (the page's server
    binds with SO_REUSEADDR too), so a restarted demo keeps its address and an open tab
    reconnects; only a port someone listens on is busy.
    """
    if not 0 < port < 65536:
        raise ValueError(f'port must be in 1..65535, got {port!r}')
    for candidate in range(port, min(port + attempts, 65536)):
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                probe.bind((host, candidate))
            except OSError:
                continue
            return candidate
    raise OSError(f'no free port on {host} in {port}..{port + attempts - 1}')


def triangle_list_mesh(points: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Return a TRIANGLE_LIST marker's points (3k, 3) as vertices (3k, 3) float32, faces (k, 3)."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] % 3:
        raise ValueError(f'TRIANGLE_LIST needs 3k points of (x, y, z), got shape {points.shape}')
    count = points.shape[0] // 3
    return points.astype(np.float32), np.arange(3 * count, dtype=np.uint32).reshape(count, 3)


def polyline_segments(points: np.ndarray) -> np.ndarray:
    """Return a polyline (p, 3) as line segments (p - 1, 2, 3) for the page."""
    points = np.asarray(points, dtype=np.float32)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f'polyline needs (p, 3) points, got shape {points.shape}')
    if len(points) < 2:
        return np.zeros((0, 2, 3), dtype=np.float32)
    return np.stack([points[:-1], points[1:]], axis=1)


def quaternion_xyzw_to_wxyz(q) -> Tuple[float, float, float, float]:
    """Convert a geometry_msgs quaternion to viser's (w, x, y, z); zero means identity."""
    w, x, y, z = float(q.w), float(q.x), float(q.y), float(q.z)
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if norm < 1e-9 or not math.isfinite(norm):
        return (1.0, 0.0, 0.0, 0.0)
    return (w / norm, x / norm, y / norm, z / norm)


def pad_pose(camera_position: np.ndarray, camera_wxyz: np.ndarray, fov: float, aspect: float,
             screen_uv: Tuple[float, float], depth: float) -> np.ndarray:
    """
    Return the world position of a point drawn at a normalized screen position, m.

    World position of a point drawn at normalized screen position ``screen_uv`` (x right, y down,
    0..1) at ``depth`` m in front of a camera (OpenCV axes: z forward, y down).
    """
    w, x, y, z = np.asarray(camera_wxyz, dtype=np.float64)
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    half_height = math.tan(fov / 2.0)
    ray = np.array([(2.0 * screen_uv[0] - 1.0) * half_height * aspect,
                    (2.0 * screen_uv[1] - 1.0) * half_height, 1.0])
    return np.asarray(camera_position, dtype=np.float64) + rotation @ (depth * ray)


def disc_mesh(radius: float, segments: int = 40) -> Tuple[np.ndarray, np.ndarray]:
    """Return a disc in the xy plane: vertices (segments + 1, 3) float32, faces (segments, 3)."""
    angles = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    rim = np.stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(segments)], 1)
    vertices = np.vstack([np.zeros((1, 3)), rim]).astype(np.float32)
    faces = np.array([[0, 1 + i, 1 + (i + 1) % segments] for i in range(segments)],
                     dtype=np.uint32)
    return vertices, faces


def marker_color(marker) -> Tuple[Tuple[int, int, int], Optional[float]]:
    """Return a marker's colour as 0-255 RGB and an opacity (None when opaque)."""
    c = marker.color
    if c.a == 0.0 and c.r == 0.0 and c.g == 0.0 and c.b == 0.0 and marker.colors:
        c = marker.colors[0]
    rgb = tuple(int(round(255 * min(1.0, max(0.0, v)))) for v in (c.r, c.g, c.b))
    alpha = float(c.a) if c.a > 0.0 else 1.0
    return rgb, (None if alpha >= 0.999 else alpha)


# ----------------------------------------------------------------------------------------------
# The node
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ViewerConfig:
    """Everything the viewer node is configured with."""

    host: str = '127.0.0.1'
    port: int = 8080
    max_linear_speed: float = 0.8
    max_angular_speed: float = 1.0
    max_backward_speed: float = 0.5
    cmd_vel_stamped: bool = True
    cmd_rate: float = 20.0
    render_rate: float = 20.0
    drag_span: float = 0.25
    urdf_wait: float = 2.0
    follow: bool = True


def validate(config: ViewerConfig) -> None:
    """Raise ValueError naming the first bad field of ``config``."""
    if not 0 < config.port < 65536:
        raise ValueError(f'port must be in 1..65535, got {config.port!r}')
    for name in ('max_linear_speed', 'max_angular_speed', 'max_backward_speed'):
        value = getattr(config, name)
        if not (value > 0.0 and math.isfinite(value)):
            raise ValueError(f'{name} must be > 0, got {value!r}')
    for name in ('cmd_rate', 'render_rate'):
        value = getattr(config, name)
        if not (0.0 < value <= 200.0):
            raise ValueError(f'{name} must be in (0, 200] Hz, got {value!r}')
    if not 0.0 < config.drag_span <= 1.0:
        raise ValueError(f'drag_span must be in (0, 1] of the view height, got '
                         f'{config.drag_span!r}')
    if not config.urdf_wait >= 0.0:
        raise ValueError(f'urdf_wait must be >= 0 s, got {config.urdf_wait!r}')


def _build_node_class():
    """Define the rclpy node class (rclpy imported only when a node is made)."""
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import Twist, TwistStamped
    from nav_msgs.msg import Path
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    import viser
    from visualization_msgs.msg import Marker, MarkerArray

    class ActorViewer(Node):
        """Serve the actor, its course and a drag pad in a web page; publish cmd_vel."""

        FOLLOW_SLACK = 0.01   # m: closer than this the follow camera stays put
        FOLLOW_TIME_CONSTANT = 0.35   # s the camera's lag behind the actor settles in
        FOLLOW_JUMP = 3.0   # m: an actor this far from the view (a new course) is cut to
        # Across the view (0 left .. 1 right) where the follow camera keeps the actor: left of
        # the centre, clear of the control panel on the right.
        FOLLOW_SCREEN_U = 0.36
        # viser's client shows this notice (never closing) on a software-rendered page; it
        # covers the status. The page replaces it with one that closes by itself.
        SOFTWARE_WEBGL_NOTICE = 'webgl-software-rendering'
        # Far enough from the left edge that a full drag to the left stays on the 3D view.
        PAD_UV = (0.3, 0.78)
        PAD_RADIUS = 0.09      # fraction of the view height
        PAD_DEPTH = 0.5        # m in front of the camera

        def __init__(self, config: ViewerConfig, namespace: str = '', announce=print):
            # The namespace is the node's, so every relative topic resolves under it.
            super().__init__('actor_viewer', namespace=namespace)
            self.config = config
            self._lock = threading.Lock()
            self._stream = StreamMonitor()
            self._diagnostics: Optional[PlannerDiagnostics] = None
            self._latest_joints: Optional[Tuple[Tuple[str, ...], np.ndarray]] = None
            self._rendered_stamp = None
            self._last_pose = None
            self._sent_frames: Dict[int, tuple] = {}
            self._last_path = b''
            self._urdf_source: Optional[str] = None
            self._urdf = None
            self._actor_position = np.zeros(3)
            self._actor_known = False
            self._command = (0.0, 0.0)
            self._dragging = False
            self._drag_start: Dict[int, Tuple[float, float]] = {}
            self._markers: Dict[Tuple[str, int], Tuple[object, object]] = {}
            self._pads: Dict[int, object] = {}
            self._planner_present = False
            self._course_note = ''
            self._max_speeds = (config.max_linear_speed, config.max_angular_speed)
            self._max_backward_speed = config.max_backward_speed
            self._speeds_known = False
            self._planner_asked = False
            self._courses = course_catalog()
            self._scenes = {name: course.path for name, course in self._courses.items()}
            self._by_label = {course.label: name for name, course in self._courses.items()}
            self._scene_path: Optional[str] = None   # the planner's scene, once asked
            self._camera_moved: Dict[int, float] = {}
            self._notice_replaced: set = set()
            self._planner_name = (self.get_namespace().rstrip('/') + '/' + PLANNER_NODE)

            self.port = pick_port(config.host, config.port)
            self.server = viser.ViserServer(host=config.host, port=self.port, verbose=False)
            self.port = self.server.get_port()
            self.url = f'http://{config.host}:{self.port}'
            if self.port != config.port:
                announce(f'actor_viewer: port {config.port} is busy, using {self.port} instead',
                         flush=True)
            announce(f'actor_viewer: open {self.url} in a browser', flush=True)
            self._build_page()

            latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                                 reliability=ReliabilityPolicy.RELIABLE)
            self.create_subscription(String, 'robot_description', self._on_description, latched)
            self.create_subscription(JointState, 'joint_states', self._on_joint_states, 10)
            # The planner latches its markers (transient local), as RViz expects.
            for topic in ('markers', 'environment'):
                self.create_subscription(
                    MarkerArray, f'{PLANNER_NODE}/{topic}',
                    lambda msg, topic=topic: self._on_markers(topic, msg), latched)
            self.create_subscription(Path, f'{PLANNER_NODE}/path', self._on_path, latched)
            self.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)
            if config.cmd_vel_stamped:
                self._cmd_type = TwistStamped
            else:
                self._cmd_type = Twist
            self._cmd_pub = self.create_publisher(self._cmd_type, 'cmd_vel', 10)
            self._set_params = self.create_client(SetParameters,
                                                  f'{PLANNER_NODE}/set_parameters')
            self._get_params = self.create_client(GetParameters,
                                                  f'{PLANNER_NODE}/get_parameters')
            self._msg = {'Parameter': Parameter, 'ParameterValue': ParameterValue,
                         'ParameterType': ParameterType, 'Marker': Marker,
                         'SetParameters': SetParameters, 'GetParameters': GetParameters}
            self._started = time.monotonic()
            self.create_timer(1.0 / config.cmd_rate, self._publish_command)
            self.create_timer(1.0 / config.render_rate, self._render)
            self.create_timer(0.25, self._refresh_status)

        # -- page -------------------------------------------------------------------------------
        def _build_page(self) -> None:
            server = self.server
            server.scene.set_up_direction('+z')
            # Shadows cost the most per frame; software-rendered browsers keep up without them.
            server.scene.configure_default_lights(enabled=True, cast_shadow=False)
            # Behind the start and to its left: the courses run along +x, which the page shows
            # going up and to the left, away from the control panel on the right.
            server.initial_camera.position = (-3.2, 3.0, 2.4)
            server.initial_camera.look_at = (0.0, 0.0, 0.9)
            server.scene.add_grid('/ground_grid', width=40.0, height=40.0, cell_size=0.5,
                                  plane='xy', position=(0.0, 0.0, -0.002))
            # Hidden until the planner's first frame: the model at its zero pose would stand
            # half sunk in the ground.
            self._actor_root = server.scene.add_frame('/actor', show_axes=False, visible=False)
            gui = server.gui
            gui.configure_theme(show_logo=False)
            self._status = gui.add_markdown('**status:** waiting for joint_states')
            # Until the planner says which course it runs, the list says it is asking (not the
            # first name in it, which would be wrong).
            labels = [ASKING] + [course.label for course in self._courses.values()]
            self._course = gui.add_dropdown('course', options=labels, initial_value=ASKING)
            self._course_shown = None
            self._course.on_update(self._on_course_picked)
            self._course_about = gui.add_markdown('')
            self._restart = gui.add_button('restart course',
                                           hint='Back to the start of the current course')
            self._restart.on_click(self._on_restart)
            self._follow = gui.add_checkbox('follow actor', initial_value=self.config.follow)
            self._speed_note = gui.add_markdown(self._speed_text())
            gui.add_markdown('Drag the grey disc at the lower left: up walks forward, down '
                             'steps back, left/right turns. Release to stop.')
            server.on_client_connect(self._on_client_connect)
            server.on_client_disconnect(self._on_client_disconnect)

        def _speed_text(self) -> str:
            if not self._speeds_known:
                return 'full drag: asking the planner for its speed limits'
            lin, ang = self._max_speeds
            return (f'full drag: {lin:.2f} m/s forward, {self._max_backward_speed:.2f} m/s '
                    f'back, {ang:.2f} rad/s turn')

        def _on_client_connect(self, client) -> None:
            vertices, faces = disc_mesh(1.0)
            pad = client.scene.add_mesh_simple('/drag_pad', vertices, faces,
                                               color=(120, 120, 130), opacity=0.55,
                                               side='double', cast_shadow=False,
                                               receive_shadow=False)
            self._pads[client.client_id] = pad

            @pad.on_drag
            def _(event) -> None:
                self._on_pad_drag(client, event)

            @client.camera.on_update
            def _(camera) -> None:
                self._place_pad(client)
                self._replace_software_notice(client)

            self._place_pad(client)
            self._replace_software_notice(client)

        def _replace_software_notice(self, client) -> None:
            """
            Make the software-WebGL notice close by itself (a no-op where there is none).

            Sent when the page connects and again with its first camera report, whichever
            comes after the page showed the notice.
            """
            if client.client_id in self._notice_replaced:
                return
            if client.camera.update_timestamp:
                self._notice_replaced.add(client.client_id)
            from viser._messages import NotificationProps, NotificationUpdateMessage
            props = NotificationProps(
                title='Software WebGL', body='This page is drawn without the GPU and may be '
                'slow; the planner is not affected.', loading=False, with_close_button=True,
                auto_close_seconds=6.0, color='orange')
            client._websock_connection.queue_message(
                NotificationUpdateMessage(self.SOFTWARE_WEBGL_NOTICE, props))

        def _on_client_disconnect(self, client) -> None:
            self._pads.pop(client.client_id, None)
            self._camera_moved.pop(client.client_id, None)
            self._notice_replaced.discard(client.client_id)
            if self._drag_start.pop(client.client_id, None) is not None:
                self._release()

        def _place_pad(self, client) -> None:
            pad = self._pads.get(client.client_id)
            camera = client.camera
            try:
                fov, aspect = camera.fov, camera.aspect
                position, wxyz = camera.position, camera.wxyz
            except AssertionError:
                return   # no camera message from this client yet
            if pad is None or not all(np.isfinite([fov, aspect])):
                return
            world = pad_pose(position, wxyz, fov, aspect, self.PAD_UV, self.PAD_DEPTH)
            radius = self.PAD_RADIUS * 2.0 * self.PAD_DEPTH * math.tan(fov / 2.0)
            with client.atomic():
                pad.position = tuple(world)
                pad.wxyz = tuple(wxyz)
                pad.scale = radius

        def _on_pad_drag(self, client, event) -> None:
            self.get_logger().debug(f'pad drag {event.phase} {event.end_screen_pos}')
            height = max(1, int(client.camera.image_height))
            width = max(1, int(client.camera.image_width))
            if event.phase == 'start':
                # The pointer where the drag was confirmed (a few pixels from the press): the
                # grab point's own projection drifts while the follow camera moves the pad.
                self._drag_start[client.client_id] = tuple(event.end_screen_pos)
            start = self._drag_start.get(client.client_id, tuple(event.end_screen_pos))
            if event.phase == 'end':
                self._drag_start.pop(client.client_id, None)
                self._release()
                return
            # Both axes in pixels so a diagonal drag means the same on any window shape.
            start_px = (start[0] * width, start[1] * height)
            end_px = (event.end_screen_pos[0] * width, event.end_screen_pos[1] * height)
            lin, ang = self._max_speeds
            command = drag_to_command(start_px, end_px, self.config.drag_span * height, lin, ang,
                                      self._max_backward_speed)
            with self._lock:
                self._command = command
                self._dragging = True

        def _release(self) -> None:
            with self._lock:
                self._command = (0.0, 0.0)
                was_dragging, self._dragging = self._dragging, False
            if was_dragging:
                self._send(0.0, 0.0)

        # -- cmd_vel ----------------------------------------------------------------------------
        def _publish_command(self) -> None:
            with self._lock:
                dragging, (lin, ang) = self._dragging, self._command
            if dragging:
                self._send(lin, ang)

        def _send(self, linear_x: float, angular_z: float) -> None:
            if not self.context.ok():
                return   # shutting down: a browser closing now must not publish
            msg = self._cmd_type()
            twist = msg.twist if self.config.cmd_vel_stamped else msg
            if self.config.cmd_vel_stamped:
                msg.header.stamp = self.get_clock().now().to_msg()
            twist.linear.x = float(linear_x)
            twist.angular.z = float(angular_z)
            self._cmd_pub.publish(msg)

        # -- course picker ----------------------------------------------------------------------
        def _on_course_picked(self, event) -> None:
            if event.client is None:
                return   # set here, to show the planner's course: nothing to load
            name = self._by_label.get(self._course.value)
            if name is None or name == self._course_shown:
                return   # the placeholder, or the course already running (see restart)
            self._load_course(name, self._scenes[name])

        def _on_restart(self, _event) -> None:
            # The planner starts a course over whenever its scene is set, to the same file too.
            path = self._scene_path
            if path is None:
                self._course_note = 'cannot restart: the planner has not said its course yet'
                return
            self._load_course(self._course_shown or os.path.basename(path), path, restart=True)

        def _load_course(self, name: str, path: str, restart: bool = False) -> None:
            if not self._set_params.service_is_ready():
                self._course_note = f'cannot load {name}: planner parameter service not found'
                return
            param = self._msg['Parameter'](name='scene', value=self._msg['ParameterValue'](
                type=self._msg['ParameterType'].PARAMETER_STRING, string_value=path))
            request = self._msg['SetParameters'].Request(parameters=[param])
            self._course_note = f'{"restarting" if restart else "loading"} {name}...'
            future = self._set_params.call_async(request)
            future.add_done_callback(lambda f: self._on_course_result(name, path, f))

        def _on_course_result(self, name: str, path: str, future) -> None:
            try:
                result = future.result().results[0]
            except Exception as error:  # noqa: B902 - report any service failure in the page
                self._course_note = f'loading {name} failed: {error}'
                return
            if result.successful:
                self._show_course(name if name in self._courses else None, path)
                self._course_note = f'course: {name}'
            else:
                self._course_note = f'course {name} rejected: {result.reason}'
                if self._course_shown in self._courses:
                    self._set_course_value(self._courses[self._course_shown].label)

        def _show_course(self, name: Optional[str], path: str) -> None:
            """
            Show ``name`` on the page as the planner's course, with its description.

            The page shows ``name`` (a shipped course, or None for another scene file) as the
            planner's course, with its description.
            """
            self._scene_path = path
            self._course_shown = name
            labels = [c.label for c in self._courses.values()]
            if name is None:
                # A scene file of the user's: listed first, under its file name.
                own = os.path.basename(path)
                self._course.options = [own] + [label for label in labels if label != own]
                self._set_course_value(own)
                self._course_about.content = f'Scene file: `{path}`'
                return
            course = self._courses[name]
            self._course_about.content = course.about()
            if tuple(self._course.options) != tuple(labels):
                self._course.options = labels
            self._set_course_value(course.label)

        def _set_course_value(self, label: str) -> None:
            self._course.value = label   # on_update sees event.client None: nothing reloads

        def _query_planner(self) -> None:
            """Read the planner's scene and speed limits once its parameter service appears."""
            if self._planner_asked or not self._get_params.service_is_ready():
                return
            self._planner_asked = True
            request = self._msg['GetParameters'].Request(
                names=['scene', 'max_linear_speed', 'max_angular_speed', 'max_backward_speed'])
            self._get_params.call_async(request).add_done_callback(self._on_planner_params)

        def _on_planner_params(self, future) -> None:
            try:
                values = future.result().values
            except Exception:  # noqa: B902 - keep the viewer's own defaults
                return
            if len(values) != 4:
                return
            scene, lin, ang, back = values
            ptype = self._msg['ParameterType']
            if lin.type == ptype.PARAMETER_DOUBLE and ang.type == ptype.PARAMETER_DOUBLE:
                if lin.double_value > 0 and ang.double_value > 0:
                    self._max_speeds = (lin.double_value, ang.double_value)
            # A planner without the parameter walks forward only: the pad's lower half stops.
            if back.type == ptype.PARAMETER_DOUBLE and back.double_value > 0:
                self._max_backward_speed = back.double_value
            else:
                self._max_backward_speed = 0.0
            self._speeds_known = True
            self._speed_note.content = self._speed_text()
            if scene.type == ptype.PARAMETER_STRING and scene.string_value:
                current = os.path.splitext(os.path.basename(scene.string_value))[0]
                self._course_note = f'course: {current}'
                self._show_course(current if current in self._scenes else None,
                                  scene.string_value)

        # -- subscriptions ----------------------------------------------------------------------
        def _on_description(self, msg) -> None:
            if msg.data and msg.data != self._urdf_source:
                self._load_urdf(msg.data)

        def _on_joint_states(self, msg) -> None:
            self._stream.add(time.monotonic())
            positions = np.asarray(msg.position, dtype=np.float64)
            if len(positions) == len(msg.name):
                self._latest_joints = (tuple(msg.name), positions)

        def _on_diagnostics(self, msg) -> None:
            parsed = parse_planner_diagnostics(msg.status, self._planner_name)
            if parsed is not None:
                self._diagnostics = parsed

        def _on_path(self, msg) -> None:
            points = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z]
                               for p in msg.poses], dtype=np.float64).reshape(-1, 3)
            if points.tobytes() == self._last_path:
                return
            self._last_path = points.tobytes()
            segments = polyline_segments(points + np.array([0.0, 0.0, 0.02]))
            if len(segments):
                self.server.scene.add_line_segments('/planner/path', segments,
                                                    colors=(30, 120, 255), line_width=3.0)

        def _on_markers(self, topic: str, msg) -> None:
            Marker = self._msg['Marker']
            # DELETEALL clears what this topic showed (one RViz display per topic); markers
            # re-sent unchanged right after it are kept instead of being rebuilt.
            stale = set()
            with self.server.atomic():
                for marker in msg.markers:
                    key = (topic, marker.ns, marker.id)
                    if marker.action == Marker.DELETEALL:
                        stale |= {k for k in self._markers if k[0] == topic}
                    elif marker.action == Marker.DELETE:
                        stale.discard(key)
                        if key in self._markers:
                            self._markers.pop(key)[1].remove()
                    else:
                        stale.discard(key)
                        self._show_marker(key, marker)
                for key in stale:
                    if key in self._markers:
                        self._markers.pop(key)[1].remove()

        def _show_marker(self, key, marker) -> None:
            Marker = self._msg['Marker']
            points = np.array([[p.x, p.y, p.z] for p in marker.points],
                              dtype=np.float64).reshape(-1, 3)
            signature = (marker.type, points.tobytes(), marker.scale.x, marker.scale.y,
                         marker.scale.z, marker.color.r, marker.color.g, marker.color.b,
                         marker.color.a)
            old = self._markers.get(key)
            name = f'/planner/{key[0]}/{marker.ns or "markers"}/{marker.id}'
            rgb, opacity = marker_color(marker)
            position = (marker.pose.position.x, marker.pose.position.y,
                        marker.pose.position.z)
            wxyz = quaternion_xyzw_to_wxyz(marker.pose.orientation)
            if old is not None and old[0] == signature:
                handle = old[1]
                handle.position, handle.wxyz = position, wxyz
                return
            scene = self.server.scene
            scale = (max(marker.scale.x, 1e-3), max(marker.scale.y, 1e-3),
                     max(marker.scale.z, 1e-3))
            handle = None
            if marker.type == Marker.TRIANGLE_LIST and len(points) >= 3:
                vertices, faces = triangle_list_mesh(points[:len(points) // 3 * 3])
                handle = scene.add_mesh_simple(name, vertices, faces, color=rgb,
                                               opacity=opacity, side='double',
                                               flat_shading=True)
            elif marker.type == Marker.LINE_STRIP and len(points) >= 2:
                handle = scene.add_line_segments(name, polyline_segments(points), colors=rgb,
                                                 line_width=2.0)
            elif marker.type == Marker.LINE_LIST and len(points) >= 2:
                pairs = points[:len(points) // 2 * 2].reshape(-1, 2, 3).astype(np.float32)
                handle = scene.add_line_segments(name, pairs, colors=rgb, line_width=2.0)
            elif marker.type in (Marker.POINTS, Marker.SPHERE_LIST) and len(points):
                handle = scene.add_point_cloud(name, points.astype(np.float32), colors=rgb,
                                               point_size=float(scale[0]),
                                               point_shape='circle')
            elif marker.type == Marker.CUBE_LIST and len(points):
                handle = scene.add_batched_meshes_simple(
                    name, *_unit_box(), batched_positions=points.astype(np.float32),
                    batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (len(points), 1)),
                    batched_scales=np.tile(scale, (len(points), 1)), color=rgb,
                    opacity=opacity)
            elif marker.type == Marker.CUBE:
                handle = scene.add_box(name, color=rgb, dimensions=scale, opacity=opacity)
            elif marker.type == Marker.SPHERE:
                handle = scene.add_icosphere(name, radius=0.5, color=rgb, scale=scale,
                                             opacity=opacity)
            elif marker.type == Marker.CYLINDER:
                handle = scene.add_cylinder(name, radius=0.5, height=1.0, color=rgb,
                                            scale=scale, opacity=opacity)
            elif marker.type == Marker.ARROW:
                handle = scene.add_box(name, color=rgb, dimensions=scale, opacity=opacity)
            if handle is None:
                if old is not None:
                    self._markers.pop(key)[1].remove()
                return
            handle.position, handle.wxyz = position, wxyz
            self._markers[key] = (signature, handle)

        # -- actor ------------------------------------------------------------------------------
        def load_fallback_urdf_if_needed(self) -> None:
            """Use the package URDF when no robot_description arrived within ``urdf_wait``."""
            if self._urdf is None and time.monotonic() - self._started >= self.config.urdf_wait:
                from digital_actor_planner.core.skeleton import default_urdf_path
                with open(default_urdf_path()) as f:
                    self._load_urdf(f.read())

        def _load_urdf(self, text: str) -> None:
            import yourdfpy
            from viser.extras import ViserUrdf
            try:
                model = yourdfpy.URDF.load(io.StringIO(text), build_scene_graph=True,
                                           load_meshes=True)
            except Exception as error:  # noqa: B902 - a bad description must not kill the viewer
                self.get_logger().error(f'robot_description could not be read: {error}')
                return
            with self._lock:
                if self._urdf is not None:
                    self._urdf[0].remove()
                self._urdf = (ViserUrdf(self.server, model, root_node_name='/actor'),
                              tuple(model.actuated_joint_names))
                self._urdf_source = text
                self._rendered_stamp = None
                self._last_pose = None
                self._sent_frames = {}

        def _render(self) -> None:
            self.load_fallback_urdf_if_needed()
            self._query_planner()
            self._show_pose()
            if self._follow.value and self._actor_known:
                self._follow_actor()

        def _show_pose(self) -> None:
            joints = self._latest_joints
            if joints is None or self._urdf is None or joints is self._rendered_stamp:
                return
            self._rendered_stamp = joints
            urdf, urdf_names = self._urdf
            names, positions = joints
            if self._last_pose is not None and self._last_pose[0] == names and \
                    np.allclose(self._last_pose[1], positions, atol=1e-6):
                return   # a standing actor: nothing to send
            self._last_pose = joints
            by_name = dict(zip(names, positions))
            configuration = np.array([by_name.get(n, 0.0) for n in urdf_names])
            with self.server.atomic():
                _update_urdf_pose(urdf, dict(zip(urdf_names, configuration)), self._sent_frames)
            self._actor_position = np.array([by_name.get(n, 0.0) for n in ROOT_JOINTS[:3]])
            if not self._actor_known:
                self._actor_root.visible = True
            self._actor_known = True

        def _follow_actor(self) -> None:
            # Also during a drag: the camera glides (a small move each render tick) rather than
            # jumping, and keeps the actor left of the centre, clear of the control panel.
            now = time.monotonic()
            actor = self._actor_position
            with self._lock:
                dragging = self._dragging
            for client in list(self.server.get_clients().values()):
                camera = client.camera
                try:
                    look_at, position = camera.look_at, camera.position
                    fov, aspect = camera.fov, camera.aspect
                except AssertionError:
                    continue   # no camera message from this page yet
                goal = follow_target(actor, position, look_at, fov, aspect,
                                     self.FOLLOW_SCREEN_U)
                error = float(np.linalg.norm(goal - look_at))
                last = self._camera_moved.get(client.client_id, now)
                self._camera_moved[client.client_id] = now
                if error < self.FOLLOW_SLACK:
                    continue
                if error > self.FOLLOW_JUMP and not dragging:
                    new_look_at = goal
                else:
                    new_look_at = smooth_step(look_at, goal, min(now - last, 0.5),
                                              self.FOLLOW_TIME_CONSTANT)
                move = new_look_at - look_at
                if dragging:
                    move = along_view_plane(move, look_at - position)
                if float(np.linalg.norm(move)) < 1e-3:
                    continue
                # Setting the position translates the camera and its look-at point together,
                # so the user's orbit angle and distance are kept.
                with client.atomic():
                    camera.position = position + move
                    self._place_pad(client)

        def _refresh_status(self) -> None:
            now = time.monotonic()
            publishers = self.count_publishers(self.resolve_topic_name('joint_states'))
            self._planner_present = publishers > 0
            text = status_text(now, self._stream, self._diagnostics, self._planner_present)
            if self._course_note:
                text += f' · {self._course_note}'
            content = f'**status:** {text}'
            if content != self._status.content:
                self._status.content = content

        def destroy_node(self):
            self.server.stop()
            return super().destroy_node()

    return ActorViewer


def _update_urdf_pose(urdf, positions: Dict[str, float], sent: Dict[int, tuple]) -> None:
    """
    Move a ViserUrdf's joint frames to ``positions`` (rad or m by joint name).

    yourdfpy's ``update_cfg`` rebuilds its whole scene graph (about 5 ms a frame); the joint
    frames only need each joint's own parent->child transform, computed here directly. Frames
    whose transform did not change since the last call (``sent``, updated here) are not re-sent,
    so a browser on a slow machine gets only what moved.
    """
    from viser import transforms
    joints = getattr(urdf, '_joint_map_values', None)
    frames = getattr(urdf, '_joint_frames', None)
    if joints is None or frames is None or len(joints) != len(frames):
        urdf.update_cfg(np.array([positions.get(n, 0.0)
                                  for n in urdf.get_actuated_joint_names()]))
        return
    for index, (joint, frame) in enumerate(zip(joints, frames)):
        origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin)
        rotation = transforms.SO3.from_matrix(origin[:3, :3])
        translation = origin[:3, 3].copy()
        value = positions.get(joint.name, 0.0)
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
        if joint.type in ('revolute', 'continuous'):
            rotation = rotation @ transforms.SO3.exp(axis * value)
        elif joint.type == 'prismatic':
            translation = translation + origin[:3, :3] @ (axis * value)
        pose = (tuple(np.round(rotation.wxyz, 5)), tuple(np.round(translation * urdf._scale, 4)))
        if sent.get(index) == pose:
            continue
        sent[index] = pose
        frame.wxyz, frame.position = pose


def _unit_box() -> Tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5)
                        for z in (-0.5, 0.5)], dtype=np.float32)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
                     dtype=np.uint32)
    return corners, faces


def add_page_options(parser: argparse.ArgumentParser, namespace_help: str) -> None:
    """Add the page options shared by the viewer and ``digital-actor demo``."""
    parser.add_argument('--host', default='127.0.0.1',
                        help='address to serve the page on (default 127.0.0.1: this machine '
                             'only; 0.0.0.0 to allow other machines)')
    parser.add_argument('--port', type=int, default=8080,
                        help='port of the page; the next free one is used if it is busy')
    parser.add_argument('--namespace', default='', help=namespace_help)


def build_parser(prog: str = 'digital-actor view') -> argparse.ArgumentParser:
    """Command-line options of the viewer (also used by ``digital-actor view``)."""
    parser = argparse.ArgumentParser(
        prog=prog, description='Show a running actor_planner in a web page and steer it.')
    add_page_options(parser, 'namespace of the actor_planner to attach to, e.g. /actor1')
    parser.add_argument('--twist', action='store_true',
                        help='publish geometry_msgs/Twist on cmd_vel (default TwistStamped)')
    parser.add_argument('--max-linear-speed', type=float, default=0.8,
                        help="m/s at a full drag (the planner's own limit is used when found)")
    parser.add_argument('--max-angular-speed', type=float, default=1.0,
                        help="rad/s at a full drag (the planner's own limit is used when found)")
    parser.add_argument('--render-rate', type=float, default=20.0,
                        help='how often the page is updated with the latest pose (Hz)')
    parser.add_argument('--no-follow', action='store_true',
                        help='start with the follow camera off')
    return parser


def config_from_args(args: argparse.Namespace) -> ViewerConfig:
    """Return the validated ViewerConfig for parsed command-line options."""
    config = ViewerConfig(host=args.host, port=args.port, cmd_vel_stamped=not args.twist,
                          max_linear_speed=args.max_linear_speed,
                          max_angular_speed=args.max_angular_speed,
                          render_rate=args.render_rate, follow=not args.no_follow)
    validate(config)
    return config


def normalize_namespace(namespace: str) -> str:
    """'' or 'a/b' or '/a/b/' as a ROS namespace ('/' or '/a/b'); raises on bad characters."""
    namespace = '/' + namespace.strip().strip('/')
    for part in namespace.strip('/').split('/'):
        if part and not (part[0].isalpha() or part[0] == '_') or \
                any(not (ch.isalnum() or ch == '_') for ch in part):
            raise ValueError(f'bad namespace {namespace!r}: use letters, digits and _')
    return namespace


def main(argv: Optional[List[str]] = None) -> int:
    """Run the viewer node until Ctrl-C; returns the exit code."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    if argv is None:
        argv = sys.argv[1:]
    parser = build_parser()
    # ROS arguments (--ros-args ...) pass through to rclpy.
    ros_args: List[str] = []
    if '--ros-args' in argv:
        cut = argv.index('--ros-args')
        argv, ros_args = argv[:cut], argv[cut:]
    args = parser.parse_args(argv)
    try:
        config = config_from_args(args)
        namespace = normalize_namespace(args.namespace)
    except ValueError as error:
        print(f'actor_viewer: {error}', file=sys.stderr)
        return 2
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    # Our own SIGINT/SIGTERM handling: a KeyboardInterrupt raised inside rclpy's message
    # conversion surfaces as an unrelated RuntimeError, so Ctrl-C only sets a flag here.
    stop = threading.Event()
    previous = {sig: signal.signal(sig, lambda *_: stop.set())
                for sig in (signal.SIGINT, signal.SIGTERM)}
    rclpy.init(args=['actor_viewer'] + ros_args,
               signal_handler_options=SignalHandlerOptions.NO)
    node = None
    executor = SingleThreadedExecutor()
    try:
        node = _build_node_class()(config, namespace)
        executor.add_node(node)
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except OSError as error:
        print(f'actor_viewer: {error}', file=sys.stderr)
        return 1
    except ExternalShutdownException:
        pass
    finally:
        executor.shutdown()
        if node is not None and getattr(node, 'server', None) is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return 0


if __name__ == '__main__':
    sys.exit(main())
