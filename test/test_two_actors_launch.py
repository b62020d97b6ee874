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
launch_testing for a ROS 2 install: two actors launched side by side in two namespaces.

Run with ``launch_test test/test_two_actors_launch.py`` or ``colcon test`` (needs
robot_state_publisher; skipped where launch_testing is not installed: test_launch_files.py reads
the same launch file without ROS). Each actor streams in its own namespace, in its own world
frame, and its TF frames carry its namespace, so each RViz shows its own actor.
"""
import os
import time
import unittest

import pytest

launch_testing = pytest.importorskip('launch_testing')

# Imported once the skip above has run (pytest first, out of name order: I100).
from launch import LaunchDescription  # noqa: E402, I100
from launch.actions import GroupAction, IncludeLaunchDescription  # noqa: E402
from launch.launch_description_sources import PythonLaunchDescriptionSource  # noqa: E402
import launch_testing.actions  # noqa: E402
import launch_testing.asserts  # noqa: E402
import rclpy  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

LAUNCH_FILE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                           'launch', 'actor.launch.py')
NAMESPACES = ('actor1', 'actor2')


@pytest.mark.launch_test
def generate_test_description():
    actors = []
    for namespace in NAMESPACES:
        arguments = {'namespace': namespace, 'use_rviz': 'false', 'use_teleop': 'false'}
        # Scoped: each include's arguments stay its own.
        actors.append(GroupAction([IncludeLaunchDescription(
            PythonLaunchDescriptionSource(LAUNCH_FILE), launch_arguments=arguments.items())]))
    return LaunchDescription(actors + [launch_testing.actions.ReadyToTest()])


class TestTwoActors(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rclpy.init()
        cls.node = rclpy.create_node('two_actors_probe')

    @classmethod
    def tearDownClass(cls):
        cls.node.destroy_node()
        rclpy.shutdown()

    def _spin_until(self, predicate, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not predicate():
            rclpy.spin_once(self.node, timeout_sec=0.1)
        return predicate()

    def test_each_actor_streams_in_its_own_world_frame(self):
        frames = {}
        subscriptions = [self.node.create_subscription(
            JointState, f'/{namespace}/joint_states',
            lambda msg, namespace=namespace: frames.__setitem__(namespace, msg.header.frame_id),
            10) for namespace in NAMESPACES]
        try:
            # A first start may compile the planner's kernels.
            self.assertTrue(self._spin_until(lambda: len(frames) == 2, 300.0), frames)
            self.assertEqual(frames, {n: f'{n}/world' for n in NAMESPACES})
        finally:
            for subscription in subscriptions:
                self.node.destroy_subscription(subscription)

    def test_tf_frames_carry_the_namespace(self):
        children = set()
        subscription = self.node.create_subscription(
            TFMessage, '/tf',
            lambda msg: children.update(t.child_frame_id for t in msg.transforms), 100)
        try:
            self.assertTrue(self._spin_until(
                lambda: {f'{n}/pelvis' for n in NAMESPACES} <= children, 300.0), children)
            self.assertNotIn('pelvis', children)
        finally:
            self.node.destroy_subscription(subscription)

    def test_each_namespace_has_its_robot_description(self):
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        descriptions = {}
        subscriptions = [self.node.create_subscription(
            String, f'/{namespace}/robot_description',
            lambda msg, namespace=namespace: descriptions.__setitem__(namespace, msg.data),
            latched) for namespace in NAMESPACES]
        try:
            self.assertTrue(self._spin_until(lambda: len(descriptions) == 2, 60.0))
            self.assertTrue(all('<robot' in text for text in descriptions.values()))
        finally:
            for subscription in subscriptions:
                self.node.destroy_subscription(subscription)


@launch_testing.post_shutdown_test()
class TestShutdown(unittest.TestCase):

    def test_every_process_exits_cleanly(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
