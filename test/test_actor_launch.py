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
launch_testing for a ROS 2 install: the actor_planner stream, a command, a bad configuration.

Run with ``launch_test test/test_actor_launch.py`` or ``colcon test`` on Jazzy/Kilted; skipped
where launch_testing is not installed (the venv's CI covers the same ground with
test_node_*.py).
"""
import math
import time
import unittest

import pytest

launch_testing = pytest.importorskip('launch_testing')

import launch  # noqa: E402, I100 (pytest first, for the skip)
import launch_ros.actions  # noqa: E402
import launch_testing.actions  # noqa: E402
import launch_testing.asserts  # noqa: E402
import rclpy  # noqa: E402

PACKAGE = 'digital_actor_planner'


@pytest.mark.launch_test
def generate_test_description():
    planner = launch_ros.actions.Node(package=PACKAGE, executable='actor_planner',
                                      name='actor_planner', output='screen')
    bad = launch_ros.actions.Node(package=PACKAGE, executable='actor_planner',
                                  name='actor_planner', namespace='bad', output='screen',
                                  parameters=[{'publish_rate': 0.5}])
    return (launch.LaunchDescription([planner, bad, launch_testing.actions.ReadyToTest()]),
            {'planner': planner, 'bad': bad})


class TestActorPlanner(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rclpy.init()
        cls.node = rclpy.create_node('actor_launch_probe')

    @classmethod
    def tearDownClass(cls):
        cls.node.destroy_node()
        rclpy.shutdown()

    def _collect(self, seconds, command=None):
        from geometry_msgs.msg import TwistStamped
        from sensor_msgs.msg import JointState
        received = []
        subscription = self.node.create_subscription(JointState, 'joint_states',
                                                     received.append, 100)
        publisher = self.node.create_publisher(TwistStamped, 'cmd_vel', 10)
        try:
            deadline = time.monotonic() + 60.0
            while not received and time.monotonic() < deadline:
                rclpy.spin_once(self.node, timeout_sec=0.1)
            self.assertTrue(received, 'no joint_states')
            first = len(received)
            end = time.monotonic() + seconds
            next_command = 0.0
            while time.monotonic() < end:
                if command is not None and time.monotonic() >= next_command:
                    msg = TwistStamped()
                    msg.header.stamp = self.node.get_clock().now().to_msg()
                    msg.twist.linear.x, msg.twist.angular.z = command
                    publisher.publish(msg)
                    next_command = time.monotonic() + 0.05
                rclpy.spin_once(self.node, timeout_sec=0.01)
            return received[:first], received[first:]
        finally:
            self.node.destroy_subscription(subscription)
            self.node.destroy_publisher(publisher)

    def test_joint_states_has_22_joints_at_100_hz(self):
        _, messages = self._collect(10.5)
        self.assertEqual(len(messages[-1].name), 22)
        stamps = [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in messages]
        window = [s for s in stamps if stamps[0] <= s < stamps[0] + 10.0]
        rate = len(window) / 10.0
        self.assertTrue(95.0 <= rate <= 105.0, f'{rate:.1f} Hz')

    def test_twist_stamped_forward_command_moves_root_x_forward(self):
        before, after = self._collect(4.0, command=(0.5, 0.0))
        index = list(after[-1].name).index('root_x')
        start = before[-1].position[index]
        self.assertGreater(after[-1].position[index] - start, 0.5)
        self.assertTrue(all(math.isfinite(v) for v in after[-1].position))

    def test_bad_parameters_exit(self, proc_info, proc_output, bad):
        proc_info.assertWaitForShutdown(process=bad, timeout=60)
        proc_output.assertWaitFor('publish_rate', process=bad, timeout=10, stream='stderr')


@launch_testing.post_shutdown_test()
class TestExitCodes(unittest.TestCase):

    def test_bad_parameters_exit_non_zero(self, proc_info, bad):
        launch_testing.asserts.assertExitCodes(proc_info, allowable_exit_codes=[2], process=bad)

    def test_planner_exits_cleanly(self, proc_info, planner):
        launch_testing.asserts.assertExitCodes(proc_info, process=planner)
