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
End to end: the real demo (actor_planner + viewer) driven with the mouse in headless chromium.

The page renders (screenshot in test-artifacts/, not blank); dragging the pad up walks the actor
forward (root_x in /joint_states grows), dragging sideways turns it (root_yaw changes), releasing
stops it, the restart button puts it back at the course start, and on the wall course walking
into the wall shows 'stuck' in the status line with what to do. Ctrl-C (SIGINT) to the demo stops
it and both of its children.

Set DAP_UPDATE_SCREENSHOT=1 to also write the screenshot to docs/images/demo.png for the README.
"""
import os
import shutil
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(HERE, 'browser'))
from chromium_page import ChromiumPage, missing_tools, not_blank  # noqa: E402
import pytest  # noqa: E402
from ros_harness import NodeProcess, ros_env, wait_for  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.browser, pytest.mark.slow]

DOMAIN_ID = 92
PORT = 18380


class JointStateRecorder:
    """Records (time, root_x, root_yaw) from /joint_states in this test process."""

    def __init__(self, domain_id):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('demo_test_recorder', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.samples = []
        self.node.create_subscription(JointState, '/joint_states', self._on_joints, 100)

    def _on_joints(self, msg):
        index = {name: i for i, name in enumerate(msg.name)}
        self.samples.append((time.monotonic(), msg.position[index['root_x']],
                             msg.position[index['root_yaw']]))

    def spin(self):
        self.executor.spin_once(timeout_sec=0.05)

    def latest(self):
        return self.samples[-1] if self.samples else None

    def still_for(self, seconds, tolerance=0.01):
        """Return true when root_x and root_yaw stayed within ``tolerance`` for ``seconds``."""
        if not self.samples or self.samples[-1][0] - self.samples[0][0] < seconds:
            return False
        recent = [s for s in self.samples if s[0] >= self.samples[-1][0] - seconds]
        xs = [s[1] for s in recent]
        yaws = [s[2] for s in recent]
        return max(xs) - min(xs) < tolerance and max(yaws) - min(yaws) < tolerance

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


def _children(pid):
    """Return the PIDs of the direct children of ``pid`` (Linux /proc)."""
    found = []
    for task in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{task}/children') as f:
            found += [int(p) for p in f.read().split()]
    return found


def _gone(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    with open(f'/proc/{pid}/stat') as f:
        return f.read().split(')')[-1].split()[0] == 'Z'


def test_demo_in_browser_walk_turn_stop_and_stuck(artifacts_dir, monkeypatch):
    missing = missing_tools()
    if missing:
        pytest.skip('browser test needs: ' + ', '.join(missing))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    demo = NodeProcess([sys.executable, '-m', 'digital_actor_planner.demo', '--port', str(PORT)],
                       ros_env(DOMAIN_ID), log_path=os.path.join(artifacts_dir, 'demo.log'))
    page = None
    recorder = None
    try:
        assert wait_for(lambda: 'the actor is at http://' in demo.output() or not demo.alive(),
                        120, interval=0.2), demo.output()
        url = demo.output().split('the actor is at ', 1)[1].split()[0]
        recorder = JointStateRecorder(DOMAIN_ID)
        page = ChromiumPage(log_path=os.path.join(artifacts_dir, 'demo_browser_driver.log'))
        page.open(url)
        # The planner builds its course first; the page says so until joint_states flow.
        text = page.wait_for_text('idle', 300)
        assert 'idle' in text and 'received' in text, text
        assert wait_for(lambda: recorder.latest() is not None, 60, spin=recorder.spin)

        shot = os.path.join(artifacts_dir, 'demo_page.png')
        page.screenshot(shot)
        assert not_blank(shot), 'the page shows no rendered scene'

        # Drag up: the actor walks forward.
        center = page.pad_center()
        start_x = recorder.latest()[1]
        start_yaw = recorder.latest()[2]
        page.press(*center)
        up = (center[0], center[1] - 100)
        page.move_to(center, up)
        assert wait_for(lambda: recorder.latest()[1] > start_x + 0.3, 120,
                        spin=recorder.spin), f'root_x stayed near {start_x}'
        # The pelvis swings a little with each step; a turn is well beyond that.
        assert abs(recorder.latest()[2] - start_yaw) < 0.3, 'a straight-up drag turned the actor'
        assert 'walking' in page.wait_for_text('walking', 60)
        walking_shot = os.path.join(artifacts_dir, 'demo.png')
        page.screenshot(walking_shot)
        if os.environ.get('DAP_UPDATE_SCREENSHOT') == '1':
            os.makedirs(os.path.join(REPO, 'docs', 'images'), exist_ok=True)
            shutil.copy(walking_shot, os.path.join(REPO, 'docs', 'images', 'demo.png'))

        # Drag to the side (still forward): the actor turns left.
        side = (center[0] - 100, center[1] - 100)
        yaw_before = recorder.latest()[2]
        page.move_to(up, side)
        assert wait_for(lambda: recorder.latest()[2] > yaw_before + 0.6, 120,
                        spin=recorder.spin), 'dragging left did not turn the actor left'

        # Release: the actor comes to a stop (within a step or two).
        page.release()
        recorder.samples.clear()
        assert wait_for(lambda: recorder.still_for(1.5), 60, spin=recorder.spin), \
            'the actor kept moving after the pad was released'

        # Restart: the planner starts the course over, the actor back at its start.
        page.click('restart course')
        assert wait_for(lambda: recorder.latest()[1] < start_x + 0.05, 120,
                        spin=recorder.spin), f'restart left the actor at {recorder.latest()}'
        assert abs(recorder.latest()[2] - start_yaw) < 0.05, 'restart kept the turn'

        # The wall course: walking into the wall leaves the actor stuck, and the page says so.
        page.select('course', 'wall (impassable)')
        assert 'course: wall' in page.wait_for_text('course: wall', 300)
        assert 'idle' in page.wait_for_text('idle', 120)
        center = page.pad_center()
        page.press(*center)
        page.move_to(center, (center[0], center[1] - 100))
        text = page.wait_for_text('turn on the spot', 240)
        page.release()
        assert 'stuck' in text, text
        assert wait_for(lambda: recorder.latest()[1] < 3.0, 5, spin=recorder.spin), \
            'the actor went through the wall at x = 3 m'
    finally:
        if page is not None:
            page.stop()
        if recorder is not None:
            recorder.close()
        children = _children(demo.pid) if demo.alive() else []
        code = demo.stop(timeout=30)
    assert code == 0, demo.output()
    assert 'stopped' in demo.output()
    assert children and all(_gone(pid) for pid in children), 'the demo left processes behind'
