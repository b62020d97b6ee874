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
the planner's markers and path and ``/diagnostics``, and publishes ``cmd_vel`` from the drag pad.
The logic lives in :mod:`viewer_page` (drag mapping, status text with what to do when stuck,
marker conversion, the course list, the follow camera, port choice), free of ROS; the node only
wires it to topics and to the page.
"""
from __future__ import annotations

import io
import math
import os
import signal
import sys
import threading
import time
from typing import Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from digital_actor_planner.nodes.viewer_page import (
    along_view_plane, ASKING, build_parser, config_from_args, course_catalog, disc_mesh,
    drag_to_command, follow_target, marker_color, normalize_namespace, pad_pose,
    parse_planner_diagnostics, pick_port, PLANNER_NODE, PlannerDiagnostics, polyline_segments,
    quaternion_xyzw_to_wxyz, ROOT_JOINTS, smooth_step, status_text, StreamMonitor,
    triangle_list_mesh, ViewerConfig)
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Path
import numpy as np
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState
from std_msgs.msg import String
import viser
from viser import transforms
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


def _update_urdf_pose(urdf, positions: Dict[str, float], sent: Dict[int, tuple]) -> None:
    """
    Move a ViserUrdf's joint frames to ``positions`` (rad or m by joint name).

    yourdfpy's ``update_cfg`` rebuilds its whole scene graph (about 5 ms a frame); the joint
    frames only need each joint's own parent->child transform, computed here directly. Frames
    whose transform did not change since the last call (``sent``, updated here) are not re-sent,
    so a browser on a slow machine gets only what moved.
    """
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


def main(argv: Optional[List[str]] = None) -> int:
    """Run the viewer node until Ctrl-C; returns the exit code."""
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
        node = ActorViewer(config, namespace)
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
