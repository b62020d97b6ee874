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
The viewer node in headless chromium against a stand-in planner (test/browser/fake_planner.py).

What a user sees: "waiting for joint_states" with no planner, the actor's status once one runs,
cmd_vel from the drag pad (up = forward, left = turn left, release = zero), and the page telling
that the planner died while the viewer keeps serving; the camera following the actor during a
drag, the restart button putting the actor back at the start, each course's description when it
is chosen, the stuck reason with what to do, and no notice left over the page's top left. The real
planner is driven in test_demo_browser.py.
"""
import os
import socket
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'browser'))
from chromium_page import ChromiumPage, missing_tools, not_blank  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from ros_harness import NodeProcess, ros_env, wait_for  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.browser, pytest.mark.slow]

DOMAIN_ID = 91


def _viewer(env, port, log):
    return NodeProcess([sys.executable, '-m', 'digital_actor_planner.nodes.viewer',
                        '--port', str(port)], env, log_path=log)


def _wait_for_address(process, timeout=60.0):
    """Return the address the viewer printed (it names a busy port and the one it chose)."""
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
    """Subscribes to cmd_vel (TwistStamped) and joint_states in this test process."""

    def __init__(self, domain_id):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from geometry_msgs.msg import TwistStamped
        from sensor_msgs.msg import JointState
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('viewer_test_listener', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.commands = []
        self.actor = None   # (root_x, root_y) m, the latest joint_states
        self.node.create_subscription(TwistStamped, 'cmd_vel', self._on_cmd, 50)
        self.node.create_subscription(JointState, 'joint_states', self._on_joints, 10)

    def _on_joints(self, msg):
        index = {name: i for i, name in enumerate(msg.name)}
        self.actor = (msg.position[index['root_x']], msg.position[index['root_y']])

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
        assert 'idle' in text and 'received' in text and 'published' in text, text
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
        # Released: no further non-zero commands. Counted from the first zero (when the viewer
        # took the release, however late a loaded machine delivered it), allowing 1 s for a
        # publish already under way then.
        stopped_at = min(c[0] for c in listener.commands
                         if c[0] >= released_at and c[1] == 0.0 and c[2] == 0.0)
        settle = time.monotonic() + 3.0
        wait_for(lambda: time.monotonic() > settle, 4.0, spin=listener.spin)
        late = [c for c in listener.commands if c[0] > stopped_at + 1.0 and (c[1] or c[2])]
        assert not late, (stopped_at, late)

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


def _latest_camera(page, last):
    """Return the camera the page reported last (see ChromiumPage.camera_reports), or ``last``."""
    reports = page.camera_reports()
    return reports[-1] if reports else last


def _on_screen(camera, point):
    """Where ``point`` (3,) m is drawn in ``camera``: (u, v), 0..1 from the top left."""
    from viser import transforms
    rotation = transforms.SO3(np.asarray(camera['wxyz'])).as_matrix()
    x, y, z = rotation.T @ (np.asarray(point) - np.asarray(camera['position']))
    half_height = np.tan(camera['fov'] / 2.0)
    aspect = camera['image_width'] / camera['image_height']
    return 0.5 + 0.5 * x / z / (half_height * aspect), 0.5 + 0.5 * y / z / half_height


def test_viewer_follows_restarts_and_describes_courses(page, artifacts_dir, tmp_path,
                                                       monkeypatch):
    env = ros_env(DOMAIN_ID + 1)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    planner = NodeProcess([sys.executable, os.path.join(HERE, 'browser', 'fake_planner.py')],
                          env, log_path=str(tmp_path / 'fake_planner.log'))
    viewer = _viewer(env, port, os.path.join(artifacts_dir, 'viewer_follow_node.log'))
    listener = None
    try:
        url = _wait_for_address(viewer)
        assert url, viewer.output()
        listener = CommandListener(DOMAIN_ID + 1)
        page.open(url)
        # The planner's course and speed limit from the first load (not the list's first name
        # or the viewer's own defaults): the fake planner runs flat at 0.90 m/s.
        text = page.wait_for_text('10 m straight on a flat floor', 90)
        assert '10 m straight on a flat floor' in text, text
        assert 'full drag: 0.90 m/s' in page.wait_for_text('full drag: 0.90 m/s', 60)
        assert '0.45 m/s back' in page.wait_for_text('0.45 m/s back', 60)
        assert 'idle' in page.wait_for_text('idle', 60)
        assert wait_for(lambda: listener.actor is not None, 30, spin=listener.spin)

        # The software-WebGL notice of a headless page closes by itself.
        text = page.wait_for_text_gone('Software WebGL', 60)
        assert 'Software WebGL' not in text, text

        # Drag up and hold: the camera moves with the actor while the hand is down, keeping it
        # where it was on the screen, left of the control panel.
        camera = _latest_camera(page, None)
        center = page.pad_center()
        page.press(*center)
        page.move_to(center, (center[0], center[1] - 100))
        start = listener.actor
        assert wait_for(lambda: listener.actor[0] > start[0] + 1.0, 90, spin=listener.spin), \
            listener.actor
        camera = _latest_camera(page, camera)
        assert camera is not None, 'the page reported no camera'
        actor_before = listener.actor + (0.9,)
        seen_before = _on_screen(camera, actor_before)
        assert 0.0 < seen_before[0] < 0.6, f'the actor is drawn at {seen_before}, under the panel'
        assert wait_for(lambda: listener.actor[0] > actor_before[0] + 3.0, 90,
                        spin=listener.spin), listener.actor
        later = {}

        def kept_in_place():
            later['camera'] = _latest_camera(page, later.get('camera', camera))
            seen = _on_screen(later['camera'], listener.actor + (0.9,))
            later['seen'] = seen
            return abs(seen[0] - seen_before[0]) < 0.06 and abs(seen[1] - seen_before[1]) < 0.08
        assert wait_for(kept_in_place, 30, interval=0.3, spin=listener.spin), \
            f'the actor went from {seen_before} to {later.get("seen")} on the screen'
        camera_moved = np.linalg.norm(np.subtract(later['camera']['position'],
                                                  camera['position']))
        assert camera_moved > 1.0, f'the camera moved only {camera_moved:.2f} m'
        text = page.text()
        assert 'walking' in text, 'the drag still steers after the camera moved'
        page.move_to((center[0], center[1] - 100), (center[0] - 100, center[1] - 100))
        assert wait_for(lambda: any(c[2] > 0.3 for c in listener.commands), 60,
                        spin=listener.spin), 'a sideways drag after the camera moved must turn'
        page.release()
        assert wait_for(lambda: any(c[1] == 0.0 for c in listener.commands[-5:]), 30,
                        spin=listener.spin)
        far = listener.actor[0]
        assert far > 3.0, far

        # Restart: the actor is back at the course start, the page still on flat.
        page.click('restart course')
        assert wait_for(lambda: listener.actor[0] < 0.1, 60, spin=listener.spin), \
            f'the actor stayed at x = {listener.actor[0]:.2f} m after restart'
        assert 'course: flat' in page.wait_for_text('course: flat', 30)

        # Choosing a course shows its description; an impassable one says so.
        page.select('course', 'stairs_up')
        text = page.wait_for_text('Five steps up', 60)
        assert 'Five steps up' in text and 'course: stairs_up' in page.wait_for_text(
            'course: stairs_up', 30)
        page.select('course', 'wall (impassable)')
        text = page.wait_for_text('Built to stop the actor', 60)
        assert 'Built to stop the actor' in text, text

        # Walk into the fake wall: the status says why in plain words, and what to do.
        center = page.pad_center()
        page.press(*center)
        page.move_to(center, (center[0], center[1] - 100))
        text = page.wait_for_text('turn on the spot', 90)
        page.release()
        assert 'stuck: no room for the next steps ahead' in text, text
        assert 'step back (drag down)' in text, text
        page.screenshot(os.path.join(artifacts_dir, 'viewer_stuck.png'))
    finally:
        if listener is not None:
            listener.close()
        viewer.stop()
        planner.stop()
