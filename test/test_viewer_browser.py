"""The viewer node in headless chromium against a stand-in planner (test/browser/fake_planner.py).

What a user sees: "waiting for joint_states" with no planner, the actor's status once one runs,
cmd_vel from the drag pad (up = forward, left = turn left, release = zero), and the page telling
that the planner died while the viewer keeps serving. The real planner is driven in
test_demo_browser.py.
"""
import os
import socket
import sys
import time

import pytest

from ros_harness import NodeProcess, ros_env, wait_for

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'browser'))
from chromium_page import ChromiumPage, missing_tools, not_blank  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.browser, pytest.mark.slow]

DOMAIN_ID = 91


def _viewer(env, port, log):
    return NodeProcess([sys.executable, '-m', 'digital_actor_planner.nodes.viewer',
                        '--port', str(port)], env, log_path=log)


def _wait_for_address(process, timeout=60.0):
    """The address the viewer printed (it names a busy port and the one it chose)."""
    found = {}

    def printed():
        for line in process.output().splitlines():
            if 'open http://' in line:
                found['url'] = line.split('open ', 1)[1].split()[0]
        return 'url' in found or not process.alive()

    wait_for(printed, timeout, interval=0.1)
    return found.get('url')


@pytest.fixture
def page(artifacts_dir):
    missing = missing_tools()
    if missing:
        pytest.skip('browser test needs: ' + ', '.join(missing))
    browser = ChromiumPage(log_path=os.path.join(artifacts_dir, 'viewer_browser_driver.log'))
    yield browser
    browser.stop()


class CommandListener:
    """Subscribes to cmd_vel (TwistStamped) in this test process."""

    def __init__(self, domain_id):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from geometry_msgs.msg import TwistStamped
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('viewer_test_listener', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.commands = []
        self.node.create_subscription(TwistStamped, 'cmd_vel', self._on_cmd, 50)

    def _on_cmd(self, msg):
        self.commands.append((time.monotonic(), msg.twist.linear.x, msg.twist.angular.z))

    def spin(self):
        self.executor.spin_once(timeout_sec=0.05)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


def test_viewer_page_waits_steers_and_survives_planner_death(
        page, artifacts_dir, tmp_path, monkeypatch):
    env = ros_env(DOMAIN_ID)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # Hold the first port so the viewer has to move on and say so.
    blocker = socket.socket()
    blocker.bind(('127.0.0.1', 0))
    blocker.listen(1)
    busy_port = blocker.getsockname()[1]
    viewer = _viewer(env, busy_port, os.path.join(artifacts_dir, 'viewer_node.log'))
    planner = None
    listener = None
    try:
        url = _wait_for_address(viewer)
        assert url, viewer.output()
        assert f'port {busy_port} is busy' in viewer.output()
        assert not url.endswith(f':{busy_port}')

        page.open(url)
        assert 'waiting for joint_states' in page.wait_for_text('waiting for joint_states', 30)

        planner = NodeProcess([sys.executable, os.path.join(HERE, 'browser', 'fake_planner.py')],
                              env, log_path=str(tmp_path / 'fake_planner.log'))
        text = page.wait_for_text('idle', 60)
        assert 'idle' in text and 'stream' in text, text
        shot = os.path.join(artifacts_dir, 'viewer_fake_planner.png')
        page.screenshot(shot)
        assert not_blank(shot)

        listener = CommandListener(DOMAIN_ID)
        assert wait_for(lambda: listener.node.count_publishers('/cmd_vel') > 0, 30,
                        spin=listener.spin)
        center = page.pad_center()
        page.press(*center)
        up = (center[0], center[1] - 100)
        page.move_to(center, up)
        assert wait_for(lambda: any(c[1] > 0.2 for c in listener.commands), 60,
                        spin=listener.spin), listener.commands
        forward = [c for c in listener.commands if c[1] > 0.2]
        assert all(abs(c[2]) < 0.2 for c in forward), 'a straight-up drag must not turn'
        assert 'walking' in page.wait_for_text('walking', 60)
        left = (center[0] - 100, center[1] - 100)
        page.move_to(up, left)
        assert wait_for(lambda: any(c[2] > 0.3 for c in listener.commands), 60,
                        spin=listener.spin), 'dragging left must turn left (+angular.z)'
        page.release()
        released_at = time.monotonic()
        assert wait_for(lambda: any(c[0] >= released_at and c[1] == 0.0 and c[2] == 0.0
                                    for c in listener.commands), 30, spin=listener.spin)
        # Released: no further non-zero commands (allow the ones already in flight).
        settle = time.monotonic() + 3.0
        wait_for(lambda: time.monotonic() > settle, 4.0, spin=listener.spin)
        late = [c for c in listener.commands if c[0] > released_at + 2.0 and (c[1] or c[2])]
        assert not late, late

        planner.stop()
        text = page.wait_for_text('planner stopped', 30)
        assert 'planner stopped' in text, text
        assert viewer.alive(), 'the viewer must keep running when the planner dies'
    finally:
        if listener is not None:
            listener.close()
        if planner is not None:
            planner.stop()
        viewer.stop()
        blocker.close()
