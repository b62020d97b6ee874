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
A simulated run as a rosbag2 bag with MCAP storage, for `ros2 bag play`, RViz and rosbags.

The bag holds what the live planner node publishes, under the node's topic names: the joint
stream (``/joint_states``, one sensor_msgs/JointState per frame), the footstep markers
(``/actor_planner/markers``) and the predicted path (``/actor_planner/path``) once per
planned block, the scene's meshes (``/actor_planner/environment``) and the URDF
(``/robot_description``) once at the start, for RViz. The ``rosbags`` library builds,
serialises (CDR) and writes everything; no ROS install is needed.

Stamps are the run's own clock (s from the start of the simulation): every header stamp and
the bag's receive time of a message are the time of the frame or block it belongs to, so that
``ros2 bag play --clock`` with ``use_sim_time`` replays the run as it was planned.
"""
from __future__ import annotations

from collections import deque
from typing import Dict, Optional, Sequence

import numpy as np

#: Topic names of the live node (nodes/actor_planner.py) under its default name, no namespace.
TOPICS = {'joint_states': '/joint_states', 'markers': '/actor_planner/markers',
          'path': '/actor_planner/path', 'environment': '/actor_planner/environment',
          'robot_description': '/robot_description'}
#: Mesh triangles drawn at most (one TRIANGLE_LIST per mesh), as the live node draws them.
MAX_MARKER_TRIANGLES = 200_000
#: Footsteps already taken that the markers keep showing (as the live node does).
PAST_FOOTSTEPS = 20
_FOOTSTEP_COLOURS = {'footsteps_past': (0.5, 0.5, 0.5, 0.6),
                     'footsteps_window': (0.1, 0.8, 0.2, 0.9)}


class RecordingError(ValueError):
    """The recording cannot be written; the message names the path."""


def write_bag(path: str, joint_names: Sequence[str], times: np.ndarray, frames: np.ndarray,
              blocks: Sequence = (), frame_id: str = 'world',
              robot_description: Optional[str] = None, meshes: Sequence = ()) -> None:
    """
    Write a run as a rosbag2 bag (a folder: ``metadata.yaml`` and one ``.mcap`` file).

    Parameters
    ----------
    path
        The bag folder to create; it must not exist (the MCAP file inside is named after it).
    joint_names
        (22,) names, in the columns' order of ``frames``.
    times
        (k,) s, increasing: the frames' times on the run's clock.
    frames
        (k, 22) joint positions, rad or m.
    blocks
        The planned blocks (:class:`~digital_actor_planner.core.actor.StepBlock`): each gives
        one markers message and one path message at its first frame's time.
    frame_id
        ``header.frame_id`` of every message, as the node's ``frame_id`` parameter.
    robot_description
        The URDF text, recorded once at the start (transient-local, as the node offers it).
    meshes
        The scene's triangle meshes (``vertices`` (v, 3) m and ``faces`` (f, 3) each, world
        frame), recorded once at the start as the environment markers; none: no such topic.

    Raises
    ------
    RecordingError
        The path exists, or the shapes of ``times`` and ``frames`` do not match.

    """
    from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
    from rosbags.typesys import get_typestore, Stores

    times = np.asarray(times, dtype=float)
    frames = np.asarray(frames, dtype=float)
    if frames.shape != (times.size, len(joint_names)):
        raise RecordingError(f'{path}: frames of shape {frames.shape} for {times.size} times '
                             f'and {len(joint_names)} joints')
    if times.size > 1 and not np.all(np.diff(times) > 0):
        raise RecordingError(f'{path}: frame times must increase')
    store = get_typestore(Stores.ROS2_KILTED)
    types = _Types(store, frame_id)
    try:
        writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    except WriterError as error:
        raise RecordingError(str(error)) from None
    with writer:
        connections = {}
        for key, msgtype in (('joint_states', 'sensor_msgs/msg/JointState'),
                             ('markers', 'visualization_msgs/msg/MarkerArray'),
                             ('path', 'nav_msgs/msg/Path'),
                             ('environment', 'visualization_msgs/msg/MarkerArray'),
                             ('robot_description', 'std_msgs/msg/String')):
            if ((key == 'robot_description' and robot_description is None)
                    or (key == 'environment' and not len(meshes))):
                continue
            latched = key != 'joint_states'
            connections[key] = writer.add_connection(
                TOPICS[key], msgtype, typestore=store,
                offered_qos_profiles=[_qos(latched, depth=1 if latched else 50)])

        def write(key: str, stamp: float, message) -> None:
            writer.write(connections[key], _nanoseconds(stamp),
                         store.serialize_cdr(message, message.__msgtype__))

        start = float(times[0]) if times.size else 0.0
        if robot_description is not None:
            write('robot_description', start, types.String(data=robot_description))
        if len(meshes):
            write('environment', start, types.environment(meshes))
        # Messages go in time order: a block's markers and path before its first frame.
        block_at = sorted(((float(b.times[0]), n) for n, b in enumerate(blocks)
                           if len(b.times)), reverse=True)
        past: deque = deque(maxlen=PAST_FOOTSTEPS)
        names = list(joint_names)
        for t, q in zip(times, frames):
            while block_at and block_at[-1][0] <= t:
                stamp, number = block_at.pop()
                block = blocks[number]
                write('markers', stamp, types.markers(stamp, list(past), block.footsteps))
                write('path', stamp, types.path(stamp, block.path))
                if block.status == 'walking' and len(block.footsteps):
                    past.append(np.asarray(block.footsteps[0], dtype=float))
            write('joint_states', t, types.JointState(
                header=types.header(t), name=names, position=np.array(q, dtype=np.float64),
                velocity=np.zeros(0), effort=np.zeros(0)))


def _nanoseconds(seconds: float) -> int:
    return int(round(seconds * 1e9))


def _qos(latched: bool, depth: int):
    from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness,
                                    QosReliability, QosTime)
    never = QosTime(sec=0, nsec=0)
    return Qos(history=QosHistory.KEEP_LAST, depth=depth,
               reliability=QosReliability.RELIABLE,
               durability=QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE,
               deadline=never, lifespan=never, liveliness=QosLiveliness.AUTOMATIC,
               liveliness_lease_duration=never, avoid_ros_namespace_conventions=False)


class _Types:
    """Message constructors of one typestore, and the few messages the bag is made of."""

    def __init__(self, store, frame_id: str):
        self.frame_id = frame_id
        found: Dict[str, type] = {}
        for name in ('builtin_interfaces/msg/Time', 'std_msgs/msg/Header',
                     'std_msgs/msg/String', 'std_msgs/msg/ColorRGBA',
                     'sensor_msgs/msg/JointState', 'geometry_msgs/msg/Point',
                     'geometry_msgs/msg/Quaternion', 'geometry_msgs/msg/Pose',
                     'geometry_msgs/msg/PoseStamped', 'geometry_msgs/msg/Vector3',
                     'nav_msgs/msg/Path', 'visualization_msgs/msg/Marker',
                     'visualization_msgs/msg/MarkerArray', 'builtin_interfaces/msg/Duration',
                     'sensor_msgs/msg/CompressedImage', 'visualization_msgs/msg/MeshFile'):
            found[name.rsplit('/', 1)[1]] = store.types[name]
        self.__dict__.update(found)

    def header(self, stamp: float):
        nanoseconds = _nanoseconds(stamp)
        return self.Header(stamp=self.Time(sec=nanoseconds // 1_000_000_000,
                                           nanosec=nanoseconds % 1_000_000_000),
                           frame_id=self.frame_id)

    def pose(self, x: float, y: float, z: float, yaw: float = 0.0):
        return self.Pose(position=self.Point(x=float(x), y=float(y), z=float(z)),
                         orientation=self.Quaternion(x=0.0, y=0.0, z=float(np.sin(yaw / 2)),
                                                     w=float(np.cos(yaw / 2))))

    def marker(self, stamp: float, ns: str, number: int, kind: int, action: int, pose,
               scale=(0.0, 0.0, 0.0), colour=(0.0, 0.0, 0.0, 0.0)):
        Marker = self.Marker  # noqa: N806 (a message type)
        return Marker(
            header=self.header(stamp), ns=ns, id=number, type=kind, action=action, pose=pose,
            scale=self.Vector3(x=scale[0], y=scale[1], z=scale[2]),
            color=self.ColorRGBA(r=colour[0], g=colour[1], b=colour[2], a=colour[3]),
            lifetime=self.Duration(sec=0, nanosec=0), frame_locked=False, points=[],
            colors=[], texture_resource='',
            texture=self.CompressedImage(header=self.header(stamp), format='',
                                         data=np.zeros(0, dtype=np.uint8)),
            uv_coordinates=[], text='', mesh_resource='',
            mesh_file=self.MeshFile(filename='', data=np.zeros(0, dtype=np.uint8)),
            mesh_use_embedded_materials=False)

    def markers(self, stamp: float, past: Sequence[np.ndarray], window: np.ndarray):
        """DELETEALL, then a flat box per footstep: those taken, then the planned window."""
        Marker = self.Marker  # noqa: N806 (a message type)
        markers = [self.marker(stamp, '', 0, Marker.ARROW, Marker.DELETEALL, self.pose(0, 0, 0))]
        window = np.asarray(window, dtype=float).reshape(-1, 4)
        for ns, steps in (('footsteps_past', past), ('footsteps_window', window)):
            for number, (x, y, z, yaw) in enumerate(steps):
                markers.append(self.marker(stamp, ns, number, Marker.CUBE, Marker.ADD,
                                           self.pose(x, y, z + 0.005, yaw), (0.25, 0.1, 0.01),
                                           _FOOTSTEP_COLOURS[ns]))
        return self.MarkerArray(markers=markers)

    def environment(self, meshes: Sequence):
        """DELETEALL, then one grey TRIANGLE_LIST per mesh, stamped zero (static)."""
        Marker = self.Marker  # noqa: N806 (a message type)
        markers = [self.marker(0.0, '', 0, Marker.ARROW, Marker.DELETEALL, self.pose(0, 0, 0))]
        budget = MAX_MARKER_TRIANGLES
        for index, mesh in enumerate(meshes):
            faces = np.asarray(mesh.faces)[:max(budget, 0)]
            budget -= len(faces)
            if not len(faces):
                continue
            marker = self.marker(0.0, 'environment', index, Marker.TRIANGLE_LIST, Marker.ADD,
                                 self.pose(0, 0, 0), (1.0, 1.0, 1.0), (0.62, 0.64, 0.66, 1.0))
            corners = np.asarray(mesh.vertices, dtype=float)[faces].reshape(-1, 3)
            marker.points = [self.Point(x=float(x), y=float(y), z=float(z))
                             for x, y, z in corners]
            markers.append(marker)
        return self.MarkerArray(markers=markers)

    def path(self, stamp: float, points: np.ndarray):
        header = self.header(stamp)
        poses = [self.PoseStamped(header=header, pose=self.pose(x, y, z))
                 for x, y, z in np.asarray(points, dtype=float).reshape(-1, 3)]
        return self.Path(header=header, poses=poses)
