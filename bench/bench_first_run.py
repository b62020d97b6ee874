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
The first run as a newcomer meets it: the warm-up, then how soon the demo streams.

With ``--cold`` the kernel cache of this checkout is deleted first (numba's files in
digital_actor_planner/core/__pycache__ and the warm-up stamp), as on a fresh clone, and the
warm-up that ``./quickstart.sh setup`` ends with is timed. Then the demo is started ``--starts``
times, one after another; for each start the table gives the seconds from launching it to the
page's address being printed, and from that address to the first joint_states frame (the actor
on the page) and to the planner reporting it is ready to walk (diagnostics state idle/walking).
Targets: the first start streams within 15 s of its address, later ones within 10 s.

    .venv/bin/python bench/bench_first_run.py --cold --starts 2
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(REPO, 'test'))
sys.path.insert(0, HERE)

from bench_common import machine, print_command  # noqa: E402
from ros_harness import NodeProcess, ros_env, wait_for  # noqa: E402

DOMAIN_ID = 77
TARGETS = (15.0, 10.0)   # s from the address to the stream: first start, later starts


class Probe:
    """Notes when the first joint_states frame and the first 'ready' diagnostics arrive."""

    def __init__(self, domain_id):
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.executors import SingleThreadedExecutor
        from sensor_msgs.msg import JointState
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('bench_first_run_probe', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.reset()
        self.node.create_subscription(JointState, '/joint_states', self._on_joints, 10)
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)

    def reset(self):
        self.first_frame = None
        self.ready = None

    def _on_joints(self, _msg):
        if self.first_frame is None:
            self.first_frame = time.monotonic()

    def _on_diagnostics(self, msg):
        for status in msg.status:
            state = {kv.key: kv.value for kv in status.values}.get('state', '')
            if self.ready is None and state in ('idle', 'walking'):
                self.ready = time.monotonic()

    def spin(self):
        self.executor.spin_once(timeout_sec=0.05)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


def clear_kernel_cache() -> int:
    """Delete this checkout's compiled kernels and the warm-up stamp; return the files removed."""
    sys.path.insert(0, REPO)
    from digital_actor_planner.warmup import stamp_path
    cache = os.path.join(REPO, 'digital_actor_planner', 'core', '__pycache__')
    files = glob.glob(os.path.join(cache, '*.nbi')) + glob.glob(os.path.join(cache, '*.nbc'))
    files += [p for p in [stamp_path()] if os.path.exists(p)]
    for path in files:
        os.remove(path)
    return len(files)


def one_start(probe, port, timeout):
    """Start the demo once; return (to address, address to stream, address to ready) in s."""
    probe.reset()
    launched = time.monotonic()
    log = tempfile.NamedTemporaryFile(prefix='bench_first_run_', suffix='.log', delete=False)
    log.close()
    demo = NodeProcess([sys.executable, '-m', 'digital_actor_planner.demo', '--port', str(port)],
                       ros_env(DOMAIN_ID), log_path=log.name)
    try:
        wait_for(lambda: 'the actor is at http://' in demo.output() or not demo.alive(),
                 timeout, interval=0.05, spin=probe.spin)
        if 'the actor is at' not in demo.output():
            raise RuntimeError('the demo printed no address:\n' + demo.output())
        address = time.monotonic()
        wait_for(lambda: probe.ready is not None or not demo.alive(), timeout, spin=probe.spin)
    finally:
        demo.stop(timeout=30)
        os.remove(log.name)
        # Frames still queued from this start must not count for the next one.
        drained = time.monotonic() + 3.0
        wait_for(lambda: time.monotonic() > drained, 5.0, spin=probe.spin)

    def since(t):
        return float('nan') if t is None else t - address
    return address - launched, since(probe.first_frame), since(probe.ready)


def main():
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--cold', action='store_true',
                        help='delete the kernel cache first and time the warm-up (fresh clone)')
    parser.add_argument('--starts', type=int, default=2, help='demo starts, one after another')
    parser.add_argument('--port', type=int, default=18480)
    parser.add_argument('--timeout', type=float, default=600.0, help='s allowed per stage')
    args = parser.parse_args()
    print(f'machine: {machine()}')
    if args.cold:
        removed = clear_kernel_cache()
        started = time.monotonic()
        code = subprocess.call([sys.executable, '-m', 'digital_actor_planner.warmup'])
        print(f'warm-up from an empty cache ({removed} files removed): '
              f'{time.monotonic() - started:.0f} s (exit {code})')
    probe = Probe(DOMAIN_ID)
    rows = []
    try:
        for k in range(args.starts):
            rows.append(one_start(probe, args.port, args.timeout))
    finally:
        probe.close()
    print('\n| start | launch to address, s | address to first frame, s | address to ready, s '
          '| target, s |')
    print('|---|---|---|---|---|')
    for k, (to_address, to_frame, to_ready) in enumerate(rows):
        target = TARGETS[0] if k == 0 else TARGETS[1]
        verdict = 'met' if to_frame <= target else 'not met'
        print(f'| {k + 1} | {to_address:.1f} | {to_frame:.1f} | {to_ready:.1f} '
              f'| {target:.0f} ({verdict}) |')
    print_command(__file__)


if __name__ == '__main__':
    main()
