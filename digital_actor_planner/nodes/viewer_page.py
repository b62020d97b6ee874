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
The viewer's logic without ROS or a browser: what the page shows and how the viewer is set up.

Drag mapping (paper §3: the vertical part of a dragged vector is the forward speed, the
horizontal part the turn rate), status text with what to do when stuck, marker conversion, the
course list with descriptions, the follow camera, port choice, and the viewer's settings and
command line. :mod:`viewer` wires them to topics and to the page; the demo and the warm-up use
them without starting ROS.
"""
from __future__ import annotations

import argparse
from collections import deque
from dataclasses import dataclass
import glob
import math
import os
import socket
import sys
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

PACKAGE_NAME = 'digital_actor_planner'
ROOT_JOINTS = ('root_x', 'root_y', 'root_z', 'root_yaw')
PLANNER_NODE = 'actor_planner'
#: The course list's entry until the planner has said which course it runs.
ASKING = '(asking the planner)'


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
    if reason.startswith('the legs cannot take the step'):
        return 'the legs cannot reach the next footholds'
    if reason.startswith('the legs would touch'):
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
# Settings and command line
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
