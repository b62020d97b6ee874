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
Actors per core, read from the node's own diagnostics (no joint_states subscriptions).

Run: .venv/bin/python bench/bench_crowd.py [--actors 10 20] [--duration 20] [--course stairs_up]

One ``actor_planner --actors actor0 ...`` process (with its planning processes) is pinned to the
first CPU; this monitor runs on the last one. It only sends cmd_vel (0.5 m/s, 10 Hz) to every
actor and reads ``/diagnostics``, so it cannot drop joint_states itself, unlike a probe that
subscribes to 100 Hz streams of many actors in one Python thread. Per actor it takes the node's
counts between the first and last diagnostics of the window: publish rate, missed frames,
buffer underruns, steps planned; at the end it sends SIGTERM and times the exit. It also reads
the CPU time the node process and its planning processes used (``/proc``), standing idle for a
few seconds before the commands, then walking.
"""
import argparse
import collections
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import TwistStamped  # noqa: E402
import rclpy  # noqa: E402
from ros_harness import NodeProcess, ros_env  # noqa: E402
from test_node_helpers import node_command, scene  # noqa: E402


IDLE_SECONDS = 5.0
STOP_WAIT = 30.0


def cpu_seconds(pid: int) -> tuple:
    """CPU time (s) used so far by process ``pid`` and by its child processes, from /proc."""
    tick = os.sysconf('SC_CLK_TCK')

    def used(stat_path):
        with open(stat_path) as stat:
            fields = stat.read().rsplit(')', 1)[1].split()
        return int(fields[1]), (int(fields[11]) + int(fields[12])) / tick

    own, children = used(f'/proc/{pid}/stat')[1], 0.0
    for entry in os.listdir('/proc'):
        if entry.isdigit():
            try:
                parent, seconds = used(f'/proc/{entry}/stat')
            except (OSError, IndexError, ValueError):
                continue
            if parent == pid:
                children += seconds
    return own, children


def run(count: int, duration: float, course: str, domain: int, log: str) -> str:
    cpus = sorted(os.sched_getaffinity(0))
    command = node_command('-p', f'scene:={scene(course)}')
    at = command.index('--ros-args')
    command = ['taskset', '-c', str(cpus[0])] + command[:at] + ['--actors'] + [
        f'actor{i}' for i in range(count)] + command[at:]
    started = time.monotonic()
    process = NodeProcess(command, ros_env(domain), log_path=log)
    os.environ['ROS_DOMAIN_ID'] = str(domain)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node('crowd_monitor', context=context)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    seen = collections.defaultdict(list)

    def on_diagnostics(array):
        now = time.monotonic()
        for status in array.status:
            if 'actor planner' in status.name:
                seen[status.name.split('/')[1]].append(
                    (now, {kv.key: kv.value for kv in status.values}))

    node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, 100)
    publishers = [node.create_publisher(TwistStamped, f'/actor{i}/cmd_vel', 10)
                  for i in range(count)]
    try:
        while len(seen) < count:
            if not process.alive() or time.monotonic() - started > 300.0:
                return f'{count} actors: not all reported ({len(seen)})'
            executor.spin_once(timeout_sec=0.1)
        ready = time.monotonic() - started
        idle_from, idle_cpu = time.monotonic(), cpu_seconds(process.pid)
        while time.monotonic() < idle_from + IDLE_SECONDS:
            executor.spin_once(timeout_sec=0.1)
        idle_to, idle_cpu_end = time.monotonic(), cpu_seconds(process.pid)
        command_msg = TwistStamped()
        command_msg.twist.linear.x = 0.5
        began, last, command_gap = time.monotonic(), 0.0, 0.0
        walk_cpu = cpu_seconds(process.pid)
        while time.monotonic() < began + duration:
            if time.monotonic() - last >= 0.1:
                for publisher in publishers:
                    publisher.publish(command_msg)
                if last:
                    command_gap = max(command_gap, time.monotonic() - last)
                last = time.monotonic()
            executor.spin_once(timeout_sec=0.02)
        walk_to, walk_cpu_end = time.monotonic(), cpu_seconds(process.pid)
        idle_share = [(b - a) / (idle_to - idle_from) for a, b in zip(idle_cpu, idle_cpu_end)]
        walk_share = [(b - a) / (walk_to - began) for a, b in zip(walk_cpu, walk_cpu_end)]
        rates, missed, underruns, steps, silent = [], 0, 0, 0, 0
        for samples in seen.values():
            window = [v for t, v in samples if began + 3.0 <= t <= began + duration]
            if len(window) < 2:
                silent += 1
                continue
            rates += [float(v['publish_rate_hz']) for v in window]
            missed += int(window[-1]['missed_frames']) - int(window[0]['missed_frames'])
            underruns += int(window[-1]['buffer_underruns']) - int(window[0]['buffer_underruns'])
            steps += int(window[-1]['steps']) - int(window[0]['steps'])
        rate = f'{min(rates):.2f}' if rates else 'n/a'
        # Stopped as docker stop or systemd would, while the actors still walk.
        stopping = time.monotonic()
        process.proc.send_signal(signal.SIGTERM)
        try:
            process.proc.wait(timeout=STOP_WAIT)
            stopped = f'SIGTERM while walking: exit {process.proc.returncode} after ' \
                f'{time.monotonic() - stopping:.1f} s'
        except subprocess.TimeoutExpired:
            stopped = f'SIGTERM while walking: still running after {STOP_WAIT:g} s'
        return (f'{stopped}; {count} actors: all reporting after {ready:.1f} s; node-measured '
                f'rate min '
                f'{rate} Hz, missed frames {missed}, buffer underruns {underruns}, steps '
                f'{steps} in {duration - 3.0:g} s; {silent} actors sent fewer than 2 '
                f'diagnostics in the window; CPU (share of one core) node / planning '
                f'processes: idle {idle_share[0]:.0%} / {idle_share[1]:.0%}, walking '
                f'{walk_share[0]:.0%} / {walk_share[1]:.0%}; longest gap between the '
                f"monitor's command rounds {command_gap:.2f} s")
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)
        process.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--actors', type=int, nargs='+', default=[10, 20])
    parser.add_argument('--duration', type=float, default=20.0)
    parser.add_argument('--course', default='stairs_up')
    parser.add_argument('--domain', type=int, default=47)
    args = parser.parse_args()
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})
    print(f'machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}')
    for count in args.actors:
        print(run(count, args.duration, args.course, args.domain,
                  f'/tmp/bench_crowd_{count}.log'), flush=True)


if __name__ == '__main__':
    main()
