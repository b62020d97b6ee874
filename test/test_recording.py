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

"""`digital-actor simulate --out run.mcap`: a rosbag2 bag (MCAP storage) that rosbags reads."""
import os

from digital_actor_planner import cli
from digital_actor_planner.cli import read_trajectory
from digital_actor_planner.core.scene import load_scene
import numpy as np
import pytest

rosbags = pytest.importorskip('rosbags')
from rosbags.rosbag2 import Reader  # noqa: E402 (after the skip)
from rosbags.typesys import get_typestore, Stores  # noqa: E402
import yaml  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')


@pytest.fixture(scope='module')
def recorded(tmp_path_factory):
    """Write the same run as CSV and as a bag."""
    folder = tmp_path_factory.mktemp('recording')
    run = ['simulate', '--scene', os.path.join(SCENES, 'stairs_up.yaml'),
           '--commands', os.path.join(SCENES, 'stairs_up.csv')]
    assert cli.main(run + ['--out', str(folder / 'run.csv')]) == 0
    assert cli.main(run + ['--out', str(folder / 'run.mcap')]) == 0
    return folder


def _messages(bag_path):
    store = get_typestore(Stores.ROS2_KILTED)
    with Reader(bag_path) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        messages = [(c.topic, timestamp, store.deserialize_cdr(raw, c.msgtype))
                    for c, timestamp, raw in reader.messages()]
    return reader, topics, messages


def test_the_bag_has_the_frames_of_the_csv_in_order_with_stamps(recorded):
    names, times, frames = read_trajectory(str(recorded / 'run.csv'))
    _, topics, messages = _messages(recorded / 'run.mcap')
    assert sorted(os.listdir(recorded / 'run.mcap')) == ['metadata.yaml', 'run.mcap']
    metadata = yaml.safe_load((recorded / 'run.mcap' / 'metadata.yaml').read_text())
    assert metadata['rosbag2_bagfile_information']['storage_identifier'] == 'mcap'
    assert topics == {'/joint_states': 'sensor_msgs/msg/JointState',
                      '/actor_planner/markers': 'visualization_msgs/msg/MarkerArray',
                      '/actor_planner/path': 'nav_msgs/msg/Path',
                      '/actor_planner/environment': 'visualization_msgs/msg/MarkerArray',
                      '/robot_description': 'std_msgs/msg/String'}
    joint_states = [(t, m) for topic, t, m in messages if topic == '/joint_states']
    assert len(joint_states) == times.size > 100
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec
                       for _, m in joint_states])
    np.testing.assert_allclose(stamps, times, atol=1e-4)  # the CSV prints 4 decimals
    assert np.all(np.diff(stamps) > 0)
    # the bag's receive times are the stamps, so `ros2 bag play` paces the run as planned
    assert [t for t, _ in joint_states] == [round(s * 1e9) for s in stamps]
    assert all(tuple(m.name) == names for _, m in joint_states)
    positions = np.array([m.position for _, m in joint_states])
    np.testing.assert_allclose(positions, frames, atol=1e-6)  # the CSV prints 6 decimals
    assert all(m.header.frame_id == 'world' for _, m in joint_states)


def test_the_bag_has_the_planned_footsteps_and_paths_along_the_run(recorded):
    _, _, messages = _messages(recorded / 'run.mcap')
    _, times, frames = read_trajectory(str(recorded / 'run.csv'))
    paths = [(t, m) for topic, t, m in messages if topic == '/actor_planner/path']
    markers = [(t, m) for topic, t, m in messages if topic == '/actor_planner/markers']
    assert len(paths) == len(markers) > 5
    assert all(times[0] - 1e-9 <= t * 1e-9 <= times[-1] for t, _ in paths)
    walking = [m for _, m in paths if m.poses]
    assert len(walking) > 5
    # the paths lead up the stairs, as the actor went
    ends = np.array([[m.poses[-1].pose.position.x, m.poses[-1].pose.position.z]
                     for m in walking])
    assert ends[:, 0].max() > frames[-1, 0] - 0.5 and ends[:, 1].max() > 0.5
    window = [mk for _, m in markers for mk in m.markers if mk.ns == 'footsteps_window']
    assert window and max(mk.pose.position.z for mk in window) > 0.5
    assert all(m.markers[0].action == 3 for _, m in markers)  # DELETEALL first
    description = [m for topic, _, m in messages if topic == '/robot_description']
    assert len(description) == 1 and '<robot' in description[0].data
    # the stairs themselves, for RViz: as many triangles as the scene's meshes have
    environment = [m for topic, _, m in messages if topic == '/actor_planner/environment']
    assert len(environment) == 1
    triangles = [mk for mk in environment[0].markers if mk.type == 11]  # TRIANGLE_LIST
    scene = load_scene(os.path.join(SCENES, 'stairs_up.yaml'))
    assert sum(len(mk.points) for mk in triangles) == 3 * sum(
        len(mesh.faces) for mesh in scene.environment.meshes)
    top = max(p.z for mk in triangles for p in mk.points)
    assert top == pytest.approx(max(mesh.bounds[1][2] for mesh in scene.environment.meshes))
