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
A stand-in actor_planner for viewer tests: JointState at 100 Hz that follows cmd_vel.

It is not the planner: it integrates root_x/root_y/root_yaw from the last command, publishes a wall
(TRIANGLE_LIST) when the scene's file name contains 'wall', stops there and reports 'stuck' on
/diagnostics. Setting its ``scene`` parameter (to the same file too) puts the actor back at the
start, as the planner does. Its speed limits differ from the viewer's defaults, so a page that
shows them shows the planner's. Used to test the viewer alone; the end-to-end test runs the real
planner.
"""
import math
import os
import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', '..'))
from digital_actor_planner.core.skeleton import Skeleton  # noqa: E402
from geometry_msgs.msg import Point, TwistStamped  # noqa: E402
from rcl_interfaces.msg import SetParametersResult  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import ExternalShutdownException  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

WALL_X = 1.0


class FakePlanner(Node):

    def __init__(self):
        super().__init__('actor_planner')
        self.declare_parameter('scene', 'flat.yaml')
        self.declare_parameter('max_linear_speed', 0.9)
        self.declare_parameter('max_angular_speed', 1.1)
        self.declare_parameter('max_backward_speed', 0.45)
        self.names = list(Skeleton().joint_names)
        self.start_pose()
        self.add_on_set_parameters_callback(self.on_parameters)
        self.command = (0.0, 0.0)
        self.state = 'idle'
        self.reason = ''
        self.create_subscription(TwistStamped, 'cmd_vel', self.on_cmd, 10)
        self.joints = self.create_publisher(JointState, 'joint_states', 10)
        self.diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.markers = self.create_publisher(MarkerArray, '~/environment', latched)
        self.create_timer(0.01, self.step)
        self.create_timer(0.5, self.report)

    def start_pose(self):
        self.q = [0.0] * len(self.names)
        self.q[self.names.index('root_z')] = 0.9

    def on_parameters(self, parameters):
        if any(p.name == 'scene' for p in parameters):
            self.start_pose()
        return SetParametersResult(successful=True)

    def wall(self):
        return 'wall' in os.path.basename(self.get_parameter('scene').value)

    def on_cmd(self, msg):
        self.command = (msg.twist.linear.x, msg.twist.angular.z)

    def step(self):
        lin, ang = self.command
        ix, iy, iyaw = (self.names.index(n) for n in ('root_x', 'root_y', 'root_yaw'))
        yaw = self.q[iyaw]
        x = self.q[ix] + lin * 0.01 * math.cos(yaw)
        self.state, self.reason = ('walking' if lin or ang else 'idle'), ''
        if self.wall() and x > WALL_X - 0.3:
            x = min(x, self.q[ix])
            if lin > 0:
                self.state, self.reason = 'stuck', 'no collision-free footstep window'
        self.q[ix] = x
        self.q[iy] += lin * 0.01 * math.sin(yaw)
        self.q[iyaw] += ang * 0.01
        msg = JointState(name=self.names, position=self.q)
        msg.header.stamp = self.get_clock().now().to_msg()
        self.joints.publish(msg)

    def report(self):
        name = self.get_fully_qualified_name()
        status = DiagnosticStatus(name=f'{name}: actor planner', hardware_id=name,
                                  message=self.state)
        status.values = [KeyValue(key='state', value=self.state),
                         KeyValue(key='reason', value=self.reason),
                         KeyValue(key='planning_time_last_ms', value='1.5'),
                         KeyValue(key='publish_rate_hz', value='100.00')]
        self.diagnostics.publish(DiagnosticArray(status=[status]))
        array = MarkerArray()
        if self.wall():
            marker = Marker(ns='environment', id=0, type=Marker.TRIANGLE_LIST)
            marker.header.frame_id = 'world'
            marker.scale.x = marker.scale.y = marker.scale.z = 1.0
            marker.pose.orientation.w = 1.0
            marker.color.r, marker.color.g, marker.color.b, marker.color.a = 0.7, 0.6, 0.5, 1.0
            a, b, c, d = ((WALL_X, -1.0, 0.0), (WALL_X, 1.0, 0.0), (WALL_X, 1.0, 2.0),
                          (WALL_X, -1.0, 2.0))
            marker.points = [Point(x=p[0], y=p[1], z=p[2]) for p in (a, b, c, a, c, d)]
            array.markers.append(marker)
        else:
            array.markers.append(Marker(action=Marker.DELETEALL))
        self.markers.publish(array)


def main():
    rclpy.init()
    node = FakePlanner()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
