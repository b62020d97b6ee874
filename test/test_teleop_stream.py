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
actor_planner as actor.launch.py starts it, steered as mouse_teleop steers a held drag.

While the drag is held still, mouse_teleop (at the launch's ``teleop_frequency``, 10 Hz) repeats
one unchanged TwistStamped; the actor must walk on for the whole hold, not stop after the
planner's cmd_timeout. The node runs in a namespace with the frame_id the launch gives it there.
CI-proof: rclpy only, localhost discovery, own ROS_DOMAIN_ID.
"""
import os
import time

from digital_actor_planner.launch_support import TELEOP_FREQUENCY, world_frame
import pytest
from ros_harness import fresh_domain_id, NodeProcess, ros_env
from test_node_helpers import node_command, Probe, REPO, ROOT_X, scene

pytestmark = [pytest.mark.ros, pytest.mark.slow]

DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 7 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()
NAMESPACE = '/actor1'
HOLD_S = 6.0
SPEED = 0.5


@pytest.fixture(scope='module')
def actor(tmp_path_factory):
    log = tmp_path_factory.mktemp('teleop_stream') / 'node.log'
    command = node_command('--params-file', os.path.join(REPO, 'config', 'planner.yaml'),
                           '-p', f'scene:={scene("flat")}',
                           '-p', f'frame_id:={world_frame(NAMESPACE)}',
                           '-r', f'__ns:={NAMESPACE}')
    process = NodeProcess(command, ros_env(DOMAIN_ID), log_path=str(log))
    probe = Probe(DOMAIN_ID, namespace=NAMESPACE, rviz=False)
    try:
        # The first start may compile the planner's kernels: a bound for a loaded machine.
        assert probe.wait_for_stream(process, 300.0), \
            f'no joint_states from the node:\n{process.output()}'
        yield process, probe
    finally:
        probe.close()
        code = process.stop()
        assert code == 0, f'node exit status {code} after SIGINT:\n{process.output()}'


def _hold_drag(probe, linear_x, angular_z, seconds):
    """Repeat one unchanged command at mouse_teleop's rate for ``seconds``; return the start."""
    from geometry_msgs.msg import TwistStamped
    message = TwistStamped()
    message.header.frame_id = 'mouse_teleop'
    message.twist.linear.x, message.twist.angular.z = float(linear_x), float(angular_z)

    def send():
        message.header.stamp = probe.node.get_clock().now().to_msg()
        probe.cmd_pub.publish(message)

    probe.command = None  # the probe's own 20 Hz stream stays silent
    timer = probe.node.create_timer(1.0 / TELEOP_FREQUENCY, send)
    try:
        started = time.monotonic()
        send()
        probe.spin(seconds)
        return started
    finally:
        probe.node.destroy_timer(timer)


def test_the_launch_frame_id_is_on_the_stream(actor):
    _, probe = actor
    assert probe.joint_states[-1][1].header.frame_id == 'actor1/world'


def test_a_held_drag_at_the_teleop_rate_walks_the_whole_hold(actor):
    _, probe = actor
    start_x = probe.latest()[ROOT_X]
    began = _hold_drag(probe, SPEED, 0.0, HOLD_S)
    times, frames = probe.positions_since(began)
    assert len(times) > 10, 'no joint_states during the hold'
    walked = frames[-1, ROOT_X] - start_x
    # Without the repeated command the actor stops about a step after cmd_timeout (0.5 s):
    # the last two seconds of the hold would then move it by nothing.
    late = frames[times >= times[-1] - 2.0, ROOT_X]
    assert walked > 0.3 * SPEED * HOLD_S, f'walked {walked:.2f} m in {HOLD_S} s'
    assert late[-1] - late[0] > 0.3 * SPEED * 2.0, \
        f'walked {late[-1] - late[0]:.2f} m in the last 2 s of the hold'
