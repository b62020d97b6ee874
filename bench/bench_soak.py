"""
Soak the actor_planner node: mouse-like steering for minutes, the scene switched now and then.

    .venv/bin/python bench/bench_soak.py [--duration 600] [--switch-every 60]
        [--scenes flat,stairs_up,...] [--seed 0]

Prints numbers; asserts nothing. The node runs as its own process (the venv's console script),
with localhost discovery in its own ROS_DOMAIN_ID. A probe steers it as a hand on the mouse
would (the command wanders, held for 0.3-2 s at a time, now and then released) and sets the
``scene`` parameter to the next course every ``--switch-every`` s, while it counts every
joint_states frame: frames received, frames lost, frames with a NaN or infinite position, the
rate in each 10 s window, and the resident memory of the node and its planning processes after
the warm-up and at the end.

A frame's stamp is the instant it shows, at or after its tick and before the next tick, so two
frames in a row are between 0 and 2 periods apart: a gap of less than 2 periods is one late
frame, not a lost one. A gap of g periods certainly lost floor(g) - 1 frames (``lost``); over the
whole run the frames the stamps' span calls for, less those received, is the total however the
lateness fell. The node's own count of ticks it skipped (diagnostics' ``missed_frames``) tells
the node's losses from the subscriber's.
"""
import argparse
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'test'))

from ros_harness import fresh_domain_id, NodeProcess, ros_env  # noqa: E402
from test_node_helpers import node_command, Probe, REPO, scene  # noqa: E402

PERIOD = 0.01
WINDOW = 10.0


def resident_kib(pid: int) -> int:
    """Resident memory (KiB) of process ``pid`` and all its descendants."""
    total, pending = 0, [pid]
    while pending:
        current = pending.pop()
        try:
            with open(f'/proc/{current}/status') as status:
                total += next(int(line.split()[1]) for line in status
                              if line.startswith('VmRSS:'))
            for task in os.listdir(f'/proc/{current}/task'):
                with open(f'/proc/{current}/task/{task}/children') as children:
                    pending.extend(int(child) for child in children.read().split())
        except (OSError, StopIteration):
            continue
    return total


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--duration', type=float, default=600.0, help='s of steering')
    parser.add_argument('--switch-every', type=float, default=60.0, help='s between scenes')
    parser.add_argument('--scenes', default='flat,stairs_up,slope,rough,table',
                        help='courses of config/scenes, switched to in turn')
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args(argv)
    from sensor_msgs.msg import JointState

    scenes = [scene(name) for name in args.scenes.split(',')]
    domain = fresh_domain_id()
    command = node_command('--params-file', os.path.join(REPO, 'config', 'planner.yaml'),
                           '-p', f'scene:={scenes[0]}')
    process = NodeProcess(command, ros_env(domain), log_path=os.devnull)
    probe = Probe(domain, rviz=False)
    stamps, bad, missed = [], [0], '?'

    def on_frame(message):
        stamps.append(message.header.stamp.sec + 1e-9 * message.header.stamp.nanosec)
        if not all(math.isfinite(v) for v in message.position):
            bad[0] += 1
    probe.node.create_subscription(JointState, 'joint_states', on_frame, 1000)
    rng = np.random.default_rng(args.seed)
    try:
        if not probe.wait_for_stream(process, 600.0):
            print('no joint_states from the node', file=sys.stderr)
            return 1
        probe.spin(5.0)  # past the first plans
        memory_start = resident_kib(process.pid)
        stamps.clear()
        began = time.monotonic()
        next_switch, switches, refused = began + args.switch_every, 0, 0
        switched_at = []  # wall-clock time of each scene switch, as the stamps are
        linear, angular = 0.0, 0.0
        while time.monotonic() - began < args.duration:
            if rng.random() < 0.15:
                linear, angular = 0.0, 0.0  # the drag released
            else:
                linear = float(np.clip(linear + rng.normal(0.0, 0.25), -0.3, 1.0))
                angular = float(np.clip(angular + rng.normal(0.0, 0.3), -1.0, 1.0))
            probe.drive(linear, angular, float(rng.uniform(0.3, 2.0)))
            if time.monotonic() >= next_switch:
                switches += 1
                switched_at.append(time.time())
                result = probe.set_scene(scenes[switches % len(scenes)], timeout=120.0)
                refused += not result.successful
                next_switch += args.switch_every
        probe.command = (0.0, 0.0)
        probe.spin(1.5)  # a diagnostics report after the last frame counted
        memory_end = resident_kib(process.pid)
        missed = probe.diagnostic_values().get('missed_frames', '?')
    finally:
        probe.close()
        code = process.stop()
    times = np.array(stamps)
    gaps = np.diff(times)
    lost = int(np.sum(np.maximum(np.floor(gaps / PERIOD + 1e-6) - 1, 0)))
    expected = int(round((times[-1] - times[0]) / PERIOD)) + 1
    edges = np.arange(times[0], times[-1] - WINDOW + 1e-9, WINDOW)
    rates = [np.sum((times >= e) & (times < e + WINDOW)) / WINDOW for e in edges]
    print(f'frames {times.size} over {times[-1] - times[0]:.1f} s of stamps, lost {lost}, '
          f'not finite {bad[0]}; the span calls for {expected} ({expected - times.size} '
          f'short); the node skipped {missed} ticks; late frames (1.5-2 periods after the '
          f'one before) {int(np.sum((gaps > 1.5 * PERIOD) & (gaps < 2.0 * PERIOD)))}')
    if rates:
        print(f'rate per {WINDOW:.0f} s window: min {min(rates):.1f} Hz, '
              f'max {max(rates):.1f} Hz ({len(rates)} windows)')
    print(f'scene switches {switches} ({refused} refused)')
    late = np.nonzero(gaps >= 2.0 * PERIOD)[0]
    if late.size:
        since = [times[i] - max([t for t in switched_at if t <= times[i]], default=-np.inf)
                 for i in late]
        print('gaps (s after the last scene switch: frames lost): ' + ', '.join(
            f'{d:.2f}: {int(np.floor(gaps[i] / PERIOD + 1e-6)) - 1}'
            for d, i in zip(since, late)))
    print(f'resident memory (node and planning processes): {memory_start / 1024:.1f} MiB '
          f'after warm-up, {memory_end / 1024:.1f} MiB at the end '
          f'({100.0 * (memory_end - memory_start) / memory_start:+.1f} %)')
    print(f'node exit status after SIGINT: {code}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
