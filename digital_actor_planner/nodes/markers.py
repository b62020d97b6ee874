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
RViz markers of the planner node: the environment, footsteps, ground profile and path.

The environment is serialized once per scene content and shared by the actors of a process
(:class:`Housekeeper`, the thread that publishes markers and diagnostics).
"""
from __future__ import annotations

import collections
import hashlib
import math
import time
from typing import Callable, Optional, Tuple

from digital_actor_planner.runtime.scheduling import NodesThread
from geometry_msgs.msg import Point, PoseStamped, Quaternion
from nav_msgs.msg import Path
import numpy as np
from rclpy.serialization import serialize_message
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

# Mesh triangles drawn in RViz at most (one TRIANGLE_LIST per mesh).
MAX_MARKER_TRIANGLES = 200_000


def _color(r: float, g: float, b: float, a: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=float(r), g=float(g), b=float(b), a=float(a))


def _yaw_quaternion(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def _points(xyz: np.ndarray):
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in xyz]


def environment_markers(meshes, frame_id: str) -> bytes:
    """
    Build the serialized MarkerArray that draws the environment in RViz.

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
    """
    Serialize the environment by writing each TRIANGLE_LIST's points into a template.

    None when the serialized template's layout is not the expected one.

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


def block_markers(block, profile: np.ndarray, past_footsteps, frame_id: str,
                  stamp: Callable[[], object]) -> Tuple[MarkerArray, Path]:
    """
    Build the markers and the path message of a planned block.

    Parameters
    ----------
    block
        The core's ``StepBlock``: its footstep window (w, 4) and predicted path (p, 3), m and
        rad.
    profile
        (p, 3) m, the walkable ground under the block's path.
    past_footsteps
        (x, y, z, yaw) of the footsteps committed so far, m and rad.
    frame_id
        Frame of the messages.
    stamp
        Returns the stamp (``builtin_interfaces/Time``) of each message when called.

    Returns
    -------
    (MarkerArray, Path)
        A DELETEALL marker, a CUBE per past and window footstep and a LINE_STRIP of the ground
        profile; the predicted path.

    """
    def header(marker: Marker) -> Marker:
        marker.header.frame_id = frame_id
        marker.header.stamp = stamp()
        return marker

    markers = [header(Marker(action=Marker.DELETEALL))]
    window = np.asarray(block.footsteps, dtype=float).reshape(-1, 4)
    for ns, steps, color in (('footsteps_past', past_footsteps, _color(0.5, 0.5, 0.5, 0.6)),
                             ('footsteps_window', window, _color(0.1, 0.8, 0.2, 0.9))):
        for index, (x, y, z, yaw) in enumerate(steps):
            marker = header(Marker(ns=ns, id=index, type=Marker.CUBE, action=Marker.ADD))
            marker.pose.position = Point(x=float(x), y=float(y), z=float(z) + 0.005)
            marker.pose.orientation = _yaw_quaternion(float(yaw))
            marker.scale.x, marker.scale.y, marker.scale.z = 0.25, 0.1, 0.01
            marker.color = color
            markers.append(marker)
    if len(profile) >= 2:
        line = header(Marker(ns='ground_profile', id=0, type=Marker.LINE_STRIP,
                             action=Marker.ADD))
        line.pose.orientation.w = 1.0
        line.scale.x = 0.02
        line.color = _color(0.9, 0.5, 0.1)
        line.points = _points(profile + [0.0, 0.0, 0.01])
        markers.append(line)
    path = np.asarray(block.path, dtype=float).reshape(-1, 3)
    message = Path()
    message.header.frame_id = frame_id
    message.header.stamp = stamp()
    for x, y, z in path:
        pose = PoseStamped()
        pose.header = message.header
        pose.pose.position = Point(x=float(x), y=float(y), z=float(z))
        pose.pose.orientation.w = 1.0
        message.poses.append(pose)
    return MarkerArray(markers=markers), message


class Housekeeper(NodesThread):
    """
    One thread that publishes the markers (5 Hz) and diagnostics (1 Hz) of a process's actors.

    A plain thread, not executor timers (see ``ActorPlannerNode._make_interfaces``).
    """

    name = 'actor_housekeeping'
    #: Serialized environments kept for actors on the same scene.
    ENVIRONMENTS_KEPT = 4

    def __init__(self):
        super().__init__()
        self._environments = collections.OrderedDict()

    def environment(self, meshes, frame_id: str) -> bytes:
        """
        Return the serialized environment markers of ``meshes`` (built once per content).

        Parameters
        ----------
        meshes, frame_id
            As for :func:`environment_markers`.

        Returns
        -------
        bytes
            The serialized MarkerArray, the same object for the same content and frame.

        """
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
