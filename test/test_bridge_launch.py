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
launch_testing check of launch/bridge.launch.py on a ROS 2 install (skipped without one).

Run with ``launch_test test/test_bridge_launch.py`` or ``colcon test``: the bridge starts in
dry-run mode (no serial port needed), logs the goal ticks for the commanded joints, publishes
diagnostics, and exits cleanly on shutdown.
"""
import os
import unittest

import pytest

launch_testing = pytest.importorskip('launch_testing')

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402, I100 (pytest first, for the skip)
from launch import LaunchDescription  # noqa: E402
from launch.actions import IncludeLaunchDescription  # noqa: E402
from launch.launch_description_sources import PythonLaunchDescriptionSource  # noqa: E402
import launch_testing.actions  # noqa: E402
import launch_testing.asserts  # noqa: E402
import rclpy  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

LAUNCH_FILE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                           'launch', 'bridge.launch.py')


@pytest.mark.launch_test
def generate_test_description():
    bridge = IncludeLaunchDescription(
        PythonLaunchDescriptionSource(LAUNCH_FILE),
        launch_arguments={'dry_run': 'true', 'port': '/dev/null-dynamixel'}.items())
    return LaunchDescription([bridge, launch_testing.actions.ReadyToTest()])


class TestBridgeLaunch(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rclpy.init()
        cls.node = rclpy.create_node('bridge_launch_test')

    @classmethod
    def tearDownClass(cls):
        cls.node.destroy_node()
        rclpy.shutdown()

    def test_dry_run_logs_ticks_and_reports_health(self, proc_output):
        publisher = self.node.create_publisher(JointState, 'joint_states', 10)
        diagnostics = []
        self.node.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 10)
        message = JointState(name=['left_knee'], position=[0.5])
        for _ in range(100):
            publisher.publish(message)
            rclpy.spin_once(self.node, timeout_sec=0.05)
            if diagnostics:
                break
        self.assertTrue(diagnostics, 'no /diagnostics from dynamixel_bridge')
        names = [status.name for status in diagnostics[-1].status]
        self.assertIn('dynamixel_bridge: bus', names)
        proc_output.assertWaitFor('dry run ticks', timeout=10)


@launch_testing.post_shutdown_test()
class TestBridgeShutdown(unittest.TestCase):

    def test_exit_code(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
