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
Does watching the actor in a browser slow the planner? Stream jitter with and without a page.

Starts the real actor_planner on a course with the actor walking in a circle, then measures the
joint_states stream for ``--seconds`` in three set-ups: the planner alone, the planner with the
viewer node, and the planner with the viewer and one headless chromium page attached (follow
camera on). Jitter is |interval - 1/rate| between consecutive frames, from the planner's own
header stamps (publish time) and from arrival times here (what a subscriber sees).

    .venv/bin/python bench/bench_viewer.py --seconds 30

Needs Debian chromium, node and test/browser/node_modules (npm ci) for the browser phase.
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(REPO, 'test'))
sys.path.insert(0, os.path.join(REPO, 'test', 'browser'))

from chromium_page import ChromiumPage, missing_tools  # noqa: E402
import numpy as np  # noqa: E402
from ros_harness import NodeProcess, ros_env, wait_for  # noqa: E402


class StreamProbe:
    """Subscribes to joint_states and drives the actor with a steady TwistStamped."""

    def __init__(self, domain_id):
        import rclpy
        from geometry_msgs.msg import TwistStamped
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        self.rclpy = rclpy
        self.twist_type = TwistStamped
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('bench_viewer_probe', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.stamps = []
        self.arrivals = []
        self.recording = False
        self.node.create_subscription(JointState, '/joint_states', self._on_joints, 200)
        self.cmd = self.node.create_publisher(TwistStamped, '/cmd_vel', 10)

    def _on_joints(self, msg):
        if self.recording:
            self.arrivals.append(time.monotonic())
            self.stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)

    def command(self, linear_x, angular_z):
        msg = self.twist_type()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.twist.linear.x = linear_x
        msg.twist.angular.z = angular_z
        self.cmd.publish(msg)

    def spin_for(self, seconds, linear_x=0.4, angular_z=0.25):
        """Spin ``seconds`` while commanding a circle (re-sent at 10 Hz)."""
        end = time.monotonic() + seconds
        next_cmd = 0.0
        while time.monotonic() < end:
            if time.monotonic() >= next_cmd:
                self.command(linear_x, angular_z)
                next_cmd = time.monotonic() + 0.1
            self.executor.spin_once(timeout_sec=0.01)

    def measure(self, seconds):
        self.stamps, self.arrivals = [], []
        self.recording = True
        self.spin_for(seconds)
        self.recording = False
        return self.stamps[:], self.arrivals[:]

    def close(self):
        self.command(0.0, 0.0)
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


def jitter_stats(times, rate):
    """p50/p99/max of |interval - 1/rate| in ms, and the achieved rate, for (k,) times in s."""
    times = np.asarray(times, dtype=float)
    if len(times) < 3:
        return {'frames': int(len(times))}
    intervals = np.diff(times)
    jitter = np.abs(intervals - 1.0 / rate) * 1e3
    return {'frames': int(len(times)), 'rate_hz': float((len(times) - 1) / (times[-1] - times[0])),
            'p50_ms': float(np.percentile(jitter, 50)), 'p99_ms': float(np.percentile(jitter, 99)),
            'max_ms': float(jitter.max()), 'gaps_over_20ms': int(np.sum(intervals > 0.02))}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n')[0])
    parser.add_argument('--seconds', type=float, default=30.0, help='measurement per phase')
    parser.add_argument('--scene', default=os.path.join(REPO, 'config', 'scenes', 'flat.yaml'))
    parser.add_argument('--domain-id', type=int, default=93)
    parser.add_argument('--port', type=int, default=18480)
    parser.add_argument('--json', help='also write the results to this file')
    args = parser.parse_args(argv)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env = ros_env(args.domain_id)
    logs = os.path.join(REPO, 'test-artifacts')
    os.makedirs(logs, exist_ok=True)
    planner = NodeProcess([sys.executable, '-m', 'digital_actor_planner.nodes.actor_planner',
                           '--ros-args', '-p', f'scene:={args.scene}'], env,
                          log_path=os.path.join(logs, 'bench_viewer_planner.log'))
    probe = StreamProbe(args.domain_id)
    viewer = None
    page = None
    results = {}
    try:
        if not wait_for(lambda: len(probe.arrivals) > 0 or not planner.alive(), 600,
                        spin=lambda: _spin_recording(probe)):
            raise SystemExit('actor_planner did not publish joint_states: ' + planner.output())
        probe.spin_for(5.0)   # get walking before measuring
        results['planner alone'] = probe.measure(args.seconds)

        viewer = NodeProcess([sys.executable, '-m', 'digital_actor_planner.nodes.viewer',
                              '--port', str(args.port)], env,
                             log_path=os.path.join(logs, 'bench_viewer_viewer.log'))
        wait_for(lambda: 'open http://' in viewer.output(), 60, interval=0.1)
        url = viewer.output().split('open ', 1)[1].split()[0]
        probe.spin_for(5.0)
        results['+ viewer node'] = probe.measure(args.seconds)

        missing = missing_tools()
        if missing:
            print('browser phase skipped, missing: ' + ', '.join(missing))
        else:
            page = ChromiumPage()
            page.open(url)
            page.wait_for_text('walking', 120)
            probe.spin_for(5.0)
            results['+ viewer + 1 browser'] = probe.measure(args.seconds)
    finally:
        if page is not None:
            page.stop()
        probe.close()
        if viewer is not None:
            viewer.stop()
        planner.stop()

    table = {}
    print(f'joint_states jitter |interval - 10 ms| over {args.seconds:.0f} s per phase '
          f'({os.cpu_count()} cores)')
    print(f'{"set-up":<24} {"source":<8} {"frames":>6} {"rate Hz":>8} {"p50 ms":>7} '
          f'{"p99 ms":>7} {"max ms":>7} {">20ms":>6}')
    for name, (stamps, arrivals) in results.items():
        for source, times in (('stamp', stamps), ('arrival', arrivals)):
            s = jitter_stats(times, 100.0)
            table[f'{name} / {source}'] = s
            if 'p99_ms' in s:
                print(f'{name:<24} {source:<8} {s["frames"]:>6} {s["rate_hz"]:>8.2f} '
                      f'{s["p50_ms"]:>7.3f} {s["p99_ms"]:>7.3f} {s["max_ms"]:>7.2f} '
                      f'{s["gaps_over_20ms"]:>6}')
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(table, f, indent=2)
    return 0


def _spin_recording(probe):
    probe.recording = True
    probe.executor.spin_once(timeout_sec=0.05)


if __name__ == '__main__':
    sys.exit(main())
