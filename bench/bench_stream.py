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
Benchmark the actor_planner stream: jitter, missed frames, command latency, actors per core.

    .venv/bin/python bench/bench_stream.py [--duration 60] [--courses stairs_up,...]
        [--course stairs_up] [--actors 1,5,10,20] [--actors-duration 20] [--skip-latency]

Prints numbers; asserts nothing. Every node runs as its own process (the venv's console
script), with localhost discovery in ROS_DOMAIN_ID 40-59 by default.

* Stream health: one actor walks the obstacle courses in turn (each with its command file; the
  scene parameter is reloaded between them) while a probe records every joint_states message.
  Jitter is the deviation of the header-stamp interval from the period (a stamp is the instant
  the frame shows: when the node's stream thread woke for it); missed frames are the periods
  the stream carried no frame for (a late frame is jitter). Reported with and without the
  second after each reload. A frame published a period or more late (the node stalled) is
  stamped at its own tick instead, so stalls show in the node's count of ticks published more
  than 2 ms late (publication lateness p99 <= 2 ms when that is under 1 % of the ticks) and in
  the delivery delay, the probe's receipt minus the stamp (which also holds the transport and
  the probe's own scheduling).
* Command latency: from publishing a forward command to the first frame whose root moved, and from
  publishing a zero command to the first frame of a still actor; beside a bare rclpy
  publish -> echo -> receive round trip measured in the same run. Each stop is accounted for
  (the walking steps planned after the command, the blocks planned again).
* Actors per core: N actors pinned to CPU 0 (the probe on the other CPU) all walking; the
  stream rate and missed frames of the worst one. By default all N are hosted by one
  actor_planner process (``--actors NS ...``: one DDS participant, one stream thread, a planning
  process per actor); ``--one-process-per-actor`` starts N separate nodes instead.
"""
import argparse
import collections
import math
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'test'))

from ros_harness import NodeProcess, ros_env  # noqa: E402
from test_node_helpers import node_command, Probe, ROOT_X, ROOT_Y, ROOT_YAW, scene  # noqa: E402

PERIOD = 0.01
# Latency trials walk on from where the last one stopped; after this many the course is
# loaded again (the actor back at its start) before the walks reach its end.
TRIALS_PER_VISIT = 3
ECHO = """
import sys, rclpy
from std_msgs.msg import Header
rclpy.init()
node = rclpy.create_node('bench_echo')
pub = node.create_publisher(Header, 'bench_pong', 10)
node.create_subscription(Header, 'bench_ping', pub.publish, 10)
try:
    rclpy.spin(node)
except Exception:
    pass
"""


def stamps_of(messages) -> np.ndarray:
    """Header stamps (s) of JointState messages."""
    return np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in messages])


def stream_health(*segments: np.ndarray) -> dict:
    """
    Jitter (ms) and missed frames of a stream from its header stamps (s).

    Each segment is a run of stamps without a deliberate pause between them. Jitter is the
    deviation of each stamp interval from the period. A frame is missed when the stream carried
    fewer frames than its span holds periods: a late frame is jitter, not a missed frame (the
    node counts the same way, as ticks it skipped).
    """
    segments = [np.sort(s) for s in segments if len(s) >= 2]
    if not segments or sum(len(s) for s in segments) < 3:
        return {'frames': sum(len(s) for s in segments), 'rate_hz': 0.0,
                'jitter_p50_ms': math.nan, 'jitter_p99_ms': math.nan,
                'jitter_max_ms': math.nan, 'missed': 0, 'longest_gap_ms': math.nan}
    gaps = np.concatenate([np.diff(s) for s in segments])
    jitter = np.abs(gaps - PERIOD) * 1e3
    missed = sum(max(0, int(round((s[-1] - s[0]) / PERIOD)) + 1 - len(s)) for s in segments)
    frames = sum(len(s) for s in segments)
    span = sum(s[-1] - s[0] for s in segments)
    return {'frames': frames,
            'rate_hz': (frames - len(segments)) / span if span > 0 else 0.0,
            'jitter_p50_ms': float(np.percentile(jitter, 50)),
            'jitter_p99_ms': float(np.percentile(jitter, 99)),
            'jitter_max_ms': float(jitter.max()), 'missed': missed,
            'longest_gap_ms': float(gaps.max() * 1e3)}


def health_line(name: str, h: dict) -> str:
    return (f'{name}: {h["frames"]} frames, {h["rate_hz"]:.2f} Hz, jitter p50 '
            f'{h["jitter_p50_ms"]:.3f} ms p99 {h["jitter_p99_ms"]:.3f} ms max '
            f'{h["jitter_max_ms"]:.2f} ms, missed {h["missed"]}, longest gap '
            f'{h["longest_gap_ms"]:.1f} ms')


#: The courses the stream-health run walks in turn (the obstacle courses).
OBSTACLE_COURSES = ('stairs_up', 'stairs_down', 'blocks', 'rough', 'gap', 'low_beam', 'table',
                    'pillars', 'uneven_beam')


def course_commands(course: str) -> list:
    """(time, linear_x, angular_z) rows of a shipped course's command file."""
    rows = []
    with open(scene(course)[:-len('.yaml')] + '.csv') as stream:
        for line in stream.read().splitlines()[1:]:
            if line.strip():
                rows.append(tuple(float(v) for v in line.split(',')))
    return rows


def walk_course(probe: Probe, course: str, until: float, settle: float = 1.0) -> None:
    """Play ``course``'s command file (each row until the next; the last for ``settle`` s)."""
    rows = course_commands(course)
    began = time.monotonic()
    for i, (at, linear_x, angular_z) in enumerate(rows):
        end = began + (rows[i + 1][0] if i + 1 < len(rows) else at + settle)
        probe.command = (linear_x, angular_z)
        probe.spin(max(0.0, min(end, until) - time.monotonic()))
        if time.monotonic() >= until:
            return


def bench_stream(domain: int, courses, duration: float, folder: str) -> None:
    process = NodeProcess(node_command('-p', f'scene:={scene(courses[0])}'), ros_env(domain),
                          log_path=os.path.join(folder, 'stream.log'))
    probe = Probe(domain, rviz=False)  # only the stream: a probe busy elsewhere delays it
    probe.joint_states = collections.deque()  # every frame of the run, however long
    try:
        if not probe.wait_for_stream(process, 120.0):
            print('node did not start:\n' + process.output())
            return
        began = time.monotonic()
        wall_offset = time.time() - time.monotonic()
        probe.spin_until(lambda: probe.diagnostic_values(), 5.0)
        first = probe.diagnostic_values()
        visits, reloads, failed = 0, [], []
        while time.monotonic() < began + duration:
            course = courses[visits % len(courses)]
            if visits > 0:
                reloads.append(time.monotonic())
                result = probe.set_scene(scene(course))
                if not result.successful:
                    failed.append(f'{course}: {result.reason}')
            walk_course(probe, course, began + duration)
            visits += 1
        probe.command = (0.0, 0.0)
        probe.spin(1.5)
        last = probe.diagnostic_values()
        received = [(t, m) for t, m in list(probe.joint_states) if t >= began]
        messages = [m for _, m in received]
        frames = np.array([m.position for m in messages])
        moving = np.any(np.abs(np.diff(frames[:, [ROOT_X, ROOT_Y, ROOT_YAW]], axis=0)) > 1e-6,
                        axis=1)
        span = received[-1][0] - received[0][0]
        print(f'stream walking {visits} course visits ({", ".join(courses)}) for '
              f'{span:.0f} s: root moving in {100 * moving.mean():.0f} % of frames, '
              f'{len(reloads)} scene reloads' + (f', FAILED: {failed}' if failed else ''))
        stamps = stamps_of(messages)
        print('  ' + health_line('all frames', stream_health(stamps)))
        # The same without the second after each scene reload (reloading builds and sends the
        # new environment's markers): the stream while the actor walks.
        times = np.array([t for t, _ in received])
        cuts = [0]
        for at in reloads:
            cuts += [int(np.searchsorted(times, at)), int(np.searchsorted(times, at + 1.0))]
        cuts.append(len(times))
        quiet = [stamps[a:b] for a, b in zip(cuts[::2], cuts[1::2])]
        print('  ' + health_line('without reloads', stream_health(*quiet)))
        # The probe's receipt on the wall clock (the stamps' clock), minus the stamp.
        delay = 1e3 * (times + wall_offset - stamps)
        print(f'  delivery delay (receipt - stamp): p50 {np.percentile(delay, 50):.2f} ms, p99 '
              f'{np.percentile(delay, 99):.2f} ms, max {delay.max():.1f} ms; frames more than '
              f'10 ms late {int(np.sum(delay > 10.0))}')
        np.savez(os.path.join(folder, 'stream.npz'), received=times, stamps=stamps,
                 reloads=np.array(reloads), wall_offset=wall_offset)

        def delta(key):
            try:
                return int(last[key]) - int(first[key])
            except (KeyError, ValueError):
                return 'n/a'
        print(f'  node diagnostics: state {last.get("state")}, steps {delta("steps")}, '
              f'planning p50 {last.get("planning_time_p50_ms")} ms p99 '
              f'{last.get("planning_time_p99_ms")} ms, missed {delta("missed_frames")}, '
              f'underruns {delta("buffer_underruns")}, ticks by the backup thread '
              f'{delta("stream_backup_ticks")}, lead {last.get("planning_lead_s")} s')
        ticks = len(stamps)
        late = delta('stream_late_ticks')
        share = f' ({100 * late / ticks:.2f} % of {ticks})' if isinstance(late, int) else ''
        print(f'  node publication: ticks more than 2 ms late {late}{share}, caught up after a '
              f'stall {delta("stream_caught_up_ticks")}, latest '
              f'{last.get("stream_lateness_max_ms")} ms')
    finally:
        probe.close()
        process.stop()


def _moved(q, reference, tolerance=1e-3) -> bool:
    return bool(np.any(np.abs(q[[ROOT_X, ROOT_Y, ROOT_YAW]] -
                              reference[[ROOT_X, ROOT_Y, ROOT_YAW]]) > tolerance))


def fresh_diagnostics(probe: Probe, timeout: float = 3.0) -> dict:
    """
    Return the node's diagnostic values from a message received after this call.

    The node publishes them about once a second; after ``timeout`` s the latest ones.
    """
    last = probe.diagnostics[-1] if probe.diagnostics else None
    probe.spin_until(lambda: probe.diagnostics and probe.diagnostics[-1] is not last, timeout)
    return probe.diagnostic_values()


def stop_trial(before: dict, after: dict, stopped: float, still: float) -> str:
    """
    Give one stop's account: how long it took and what the node planned meanwhile.

    A stop takes the command's trip to the node, the rest of the step in progress (at most
    one step time), the settling (``actor.SETTLE_TIME``) or a closing step, and a further
    step where one was due within ``REPLAN_GUARD`` of the frame on show (then no block was
    planned again).
    """
    def delta(key):
        try:
            return int(after[key]) - int(before[key])
        except (KeyError, ValueError):
            return 'n/a'
    return (f'stop trial: still after {1e3 * (still - stopped):.0f} ms; walking steps planned '
            f'after the command {delta("steps")}, blocks planned again '
            f'{delta("blocks_planned_again")}')


def bench_latency(domain: int, folder: str, trials: int, course: str = 'slope') -> None:
    from std_msgs.msg import Header
    env = ros_env(domain)
    process = NodeProcess(node_command('-p', f'scene:={scene(course)}'), env,
                          log_path=os.path.join(folder, 'latency.log'))
    echo = NodeProcess([sys.executable, '-c', ECHO], env,
                       log_path=os.path.join(folder, 'echo.log'))
    probe = Probe(domain)
    try:
        if not probe.wait_for_stream(process, 120.0):
            print('node did not start:\n' + process.output())
            return
        # Bare rclpy round trip: probe -> echo process -> probe.
        pongs = []
        ping = probe.node.create_publisher(Header, 'bench_ping', 10)
        probe.node.create_subscription(Header, 'bench_pong',
                                       lambda m: pongs.append(time.monotonic()), 10)
        probe.spin_until(lambda: ping.get_subscription_count() > 0, 30.0)
        round_trips = []
        for _ in range(200):
            count = len(pongs)
            sent = time.monotonic()
            ping.publish(Header())
            if probe.spin_until(lambda: len(pongs) > count, 2.0):
                round_trips.append(pongs[-1] - sent)
            probe.spin(0.005)
        start_latency, stop_latency, not_walking = [], [], 0
        for trial in range(trials):
            probe.command = (0.0, 0.0)
            if trial > 0 and trial % TRIALS_PER_VISIT == 0:
                # Back to the course's start before the walks run out of course.
                probe.wait_until_still(timeout=15.0)
                probe.set_scene(scene(course))
            if probe.wait_until_still(timeout=15.0) == math.inf:
                continue
            reference = probe.latest()
            sent = probe.drive(0.6, 0.0, 0.0)
            if probe.spin_until(lambda: _moved(probe.latest(), reference), 10.0):
                start_latency.append(probe.joint_states[-1][0] - sent)
            probe.spin(1.5)
            before = fresh_diagnostics(probe)
            _, recent = probe.positions_since(time.monotonic() - 0.3)
            if len(recent) < 2 or not _moved(recent[-1], recent[0]):
                not_walking += 1  # stopped by the course (its end, an obstacle): no stop
                continue
            stopped = probe.drive(0.0, 0.0, 0.0)
            still = probe.wait_until_still(timeout=15.0, still_for=0.5, tolerance=1e-4)
            if still < math.inf:
                stop_latency.append(still - stopped)
                print('  ' + stop_trial(before, fresh_diagnostics(probe), stopped, still))

        def summary(values):
            if not values:
                return 'no samples'
            v = np.array(values) * 1e3
            return (f'p50 {np.percentile(v, 50):.1f} ms, p99 {np.percentile(v, 99):.1f} ms, '
                    f'max {v.max():.1f} ms (n={len(v)})')
        print(f'bare rclpy round trip (publish -> echo -> receive): {summary(round_trips)}')
        print(f'command -> first frame that moves: {summary(start_latency)}')
        print(f'stop command -> still actor: {summary(stop_latency)}' +
              (f'; {not_walking} trials not walking at the stop' if not_walking else ''))
    finally:
        probe.close()
        echo.stop()
        process.stop()


def _node_diagnostics(arrays, prefix: str) -> list:
    """Key/values of the actor planner statuses whose name starts with ``prefix``, in order."""
    return [{kv.key: kv.value for kv in status.values} for array in list(arrays)
            for status in array.status
            if status.name.startswith(prefix) and 'actor planner' in status.name]


def bench_actors(domain: int, counts, duration: float, course: str, folder: str,
                 separate: bool = False) -> None:
    cpus = sorted(os.sched_getaffinity(0))
    node_cpu, probe_cpu = cpus[0], cpus[-1]
    os.sched_setaffinity(0, {probe_cpu})
    for count in counts:
        processes, probes = [], []
        try:
            pin = ['taskset', '-c', str(node_cpu)]
            if separate:
                for i in range(count):
                    command = pin + node_command('-r', f'__ns:=/actor{i}',
                                                 '-p', f'scene:={scene(course)}')
                    processes.append(NodeProcess(command, ros_env(domain), log_path=os.path.join(
                        folder, f'actors{count}_{i}.log')))
            else:
                command = node_command('-p', f'scene:={scene(course)}')
                at = command.index('--ros-args')
                command = pin + command[:at] + ['--actors'] + [
                    f'actor{i}' for i in range(count)] + command[at:]
                processes.append(NodeProcess(command, ros_env(domain), log_path=os.path.join(
                    folder, f'actors{count}.log')))
            for i in range(count):
                probes.append(Probe(domain, namespace=f'/actor{i}'))
            ready = all(p.wait_for_stream(processes[i if separate else 0], 300.0)
                        for i, p in enumerate(probes))
            if not ready:
                print(f'{count} actors: not all started')
                continue
            for p in probes:
                p.command = (0.5, 0.0)
            began = time.monotonic()
            window_diagnostics = collections.deque()
            while time.monotonic() < began + duration:
                for p in probes:
                    p.spin(0.01)
                if time.monotonic() > began + 2.0 and probes[0].diagnostics is not \
                        window_diagnostics:
                    probes[0].diagnostics = window_diagnostics
            # The node's own account (its publishing thread's ticks): a probe that reads many
            # streams in one Python thread loses messages itself.
            node_rates, node_missed = [], 0
            for i in range(count):
                samples = _node_diagnostics(window_diagnostics, f'/actor{i}/')
                node_rates += [float(v['publish_rate_hz']) for v in samples]
                if len(samples) >= 2:
                    node_missed += int(samples[-1]['missed_frames']) - \
                        int(samples[0]['missed_frames'])
            healths = []
            for p in probes:
                messages = [m for t, m in list(p.joint_states) if t >= began + 2.0]
                healths.append(stream_health(stamps_of(messages)))
            worst = min(healths, key=lambda h: h['rate_hz'])
            moved = sum(p.latest()[ROOT_X] > 0.5 for p in probes)
            realtime = bool(node_rates) and all(abs(r - 100.0) <= 5.0 for r in node_rates)
            print(f'{count:2d} actors on one core: node-measured rate min '
                  f'{min(node_rates, default=float("nan")):.1f} Hz, node missed frames '
                  f'{node_missed} of {count * duration * 100:.0f}; received by the probe: worst '
                  f'{worst["rate_hz"]:.1f} Hz, jitter p99 worst '
                  f'{max(h["jitter_p99_ms"] for h in healths):.2f} ms; {moved}/{count} walked '
                  f'> 0.5 m; real time (+-5 %): {"yes" if realtime else "no"}')
        finally:
            for p in probes:
                p.close()
            for process in processes:
                process.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n')[0])
    parser.add_argument('--duration', type=float, default=60.0,
                        help='seconds of walking for the stream health run')
    parser.add_argument('--course', default='stairs_up',
                        help='course of the actors-per-core run')
    parser.add_argument('--courses', default=','.join(OBSTACLE_COURSES),
                        help='courses the stream health run walks in turn')
    parser.add_argument('--actors', default='1,5,10,20')
    parser.add_argument('--actors-duration', type=float, default=20.0)
    parser.add_argument('--one-process-per-actor', action='store_true',
                        help='actors per core: a node process per actor (default: one process)')
    parser.add_argument('--trials', type=int, default=5)
    parser.add_argument('--latency-course', default='slope',
                        help='course of the command latency trials')
    parser.add_argument('--domain', type=int, default=40)
    parser.add_argument('--skip-latency', action='store_true')
    parser.add_argument('--skip-stream', action='store_true')
    args = parser.parse_args()
    print(f'machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}')
    folder = tempfile.mkdtemp(prefix='bench_stream_')
    if not args.skip_stream:
        bench_stream(args.domain, args.courses.split(','), args.duration, folder)
    if not args.skip_latency:
        bench_latency(args.domain + 1, folder, args.trials, args.latency_course)
    counts = [int(c) for c in args.actors.split(',') if c]
    if counts:
        bench_actors(args.domain + 2, counts, args.actors_duration, args.course, folder,
                     separate=args.one_process_per_actor)
    print(f'node logs: {folder}; load average now {os.getloadavg()[0]:.2f}')


if __name__ == '__main__':
    main()
