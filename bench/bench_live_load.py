"""
Walk the obstacle courses live with the actor_planner node, idle and beside a CPU hog.

    .venv/bin/python bench/bench_live_load.py [--courses low_beam table ...] [--hogs N]
        [--domain 60] [--settle 2]

Prints a table; exits 1 when a course does not reach its end under load. Each course runs
twice, each time in a fresh node process (the venv's console script, localhost discovery, its
own ROS_DOMAIN_ID): once on the machine as it is, once while ``--hogs`` processes (default: one
per CPU) spin ``while True: pass`` at the bench's own nice level, started before the node and
stopped by PID after it. A probe in this process plays the course's command file over DDS as
a mouse teleop would (cmd_vel at 20 Hz, each row until the next, the last for ``--settle`` s),
records root_x / root_y from joint_states and waits for the actor to stand still.

A course with ``expect: reach_x`` reaches its end when the actor stops within 0.3 m of that x
or beyond it; a course meant to stop (``expect: stuck``) reaches its end when it stops before
``stop_before_x`` and within 0.3 m of where it stopped on the idle run. A plan that takes
longer under load may delay a step (the node's planning lead grows), never change where the
actor goes.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'test'))

from bench_common import print_command  # noqa: E402
from bench_stream import course_commands, walk_course  # noqa: E402
from ros_harness import NodeProcess, ros_env  # noqa: E402
from test_node_helpers import node_command, Probe, ROOT_X, ROOT_Y, scene  # noqa: E402
import yaml  # noqa: E402

#: The obstacle courses, the two meant to stop last.
COURSES = ('low_beam', 'table', 'pillars', 'uneven_beam', 'blocks', 'stairs_up', 'stairs_down',
           'gap', 'rough', 'beam_too_low', 'wall')
#: How close (m) to its goal a course must end.
REACH_TOLERANCE = 0.3
HOG = 'while True: pass'


def expectation(course: str) -> dict:
    """Return the ``expect:`` mapping of a shipped course."""
    with open(scene(course)) as stream:
        return yaml.safe_load(stream).get('expect', {})


def start_hogs(count: int) -> list:
    """``count`` busy-looping Python processes at this process's nice level."""
    return [subprocess.Popen([sys.executable, '-c', HOG], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            for _ in range(count)]


def stop_hogs(hogs: list) -> None:
    """Stop the hogs by PID."""
    for hog in hogs:
        if hog.poll() is None:
            hog.kill()
    for hog in hogs:
        hog.wait(timeout=10.0)


def walk_live(course: str, domain: int, folder: str, label: str, settle: float = 2.0,
              start_timeout: float = 300.0) -> dict:
    """
    Walk ``course`` in a fresh node process; return where the actor stood still.

    Returns
    -------
    dict
        ``x``, ``y`` (m) of the still actor's root (nan when the node never streamed),
        ``state`` and ``reason`` of the node's diagnostics, ``started_s`` (s from process
        start to a ready planner), ``walked_s`` (s from the first command to a still actor),
        ``underruns`` and ``lead_s`` (the node's diagnostics), ``error`` (a string, or '').

    """
    process = NodeProcess(node_command('-p', f'scene:={scene(course)}'), ros_env(domain),
                          log_path=os.path.join(folder, f'{course}_{label}.log'))
    probe = Probe(domain, rviz=False)
    result = {'x': math.nan, 'y': math.nan, 'state': '', 'reason': '', 'started_s': math.nan,
              'walked_s': math.nan, 'underruns': '', 'lead_s': '', 'error': ''}
    try:
        began = time.monotonic()
        if not probe.wait_for_stream(process, start_timeout):
            lines = process.output().strip().splitlines()
            result['error'] = 'node did not start: ' + (lines[-1] if lines else 'no output')
            return result
        result['started_s'] = time.monotonic() - began
        rows = course_commands(course)
        walking = time.monotonic()
        walk_course(probe, course, math.inf, settle=settle)
        probe.command = (0.0, 0.0)
        # Under load the actor may still be finishing the steps of a delayed plan.
        still = probe.wait_until_still(timeout=60.0 + rows[-1][0], still_for=1.0)
        if still == math.inf:
            result['error'] = 'never stood still'
        else:
            result['walked_s'] = still - walking
        q = probe.latest()
        result['x'], result['y'] = float(q[ROOT_X]), float(q[ROOT_Y])
        probe.spin_until(lambda: probe.diagnostic_values(), 5.0)
        values = probe.diagnostic_values()
        for key in ('state', 'reason'):
            result[key] = values.get(key, '')
        result['underruns'] = values.get('buffer_underruns', '')
        result['lead_s'] = values.get('planning_lead_s', '')
        return result
    finally:
        probe.close()
        process.stop()


def reached(course: str, run: dict, idle: dict = None) -> bool:
    """Whether ``run`` ended where ``course`` is meant to end (see the module docstring)."""
    expect = expectation(course)
    if not math.isfinite(run['x']) or run['error']:
        return False
    if 'reach_x' in expect:
        return run['x'] >= expect['reach_x'] - REACH_TOLERANCE
    before = run['x'] < expect.get('stop_before_x', math.inf)
    if idle is None:
        return before
    return before and math.hypot(run['x'] - idle['x'], run['y'] - idle['y']) <= REACH_TOLERANCE


def outcome(run: dict) -> str:
    """Return a table cell: where the actor stood still, and why it stopped when stuck."""
    if run['error'] and not math.isfinite(run['x']):
        return run['error']
    cell = f'x {run["x"]:.2f}, y {run["y"]:.2f}'
    if run['state'] == 'stuck':
        cell += f' (stuck: {run["reason"]})'
    if run['error']:
        cell += f' ({run["error"]})'
    return cell


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='+', default=list(COURSES))
    parser.add_argument('--hogs', type=int, default=os.cpu_count() or 2,
                        help='busy-looping processes beside the loaded runs (default: one per '
                        'CPU)')
    parser.add_argument('--domain', type=int, default=60,
                        help='ROS_DOMAIN_ID of the first run (each run uses the next)')
    parser.add_argument('--settle', type=float, default=2.0,
                        help='seconds the last row of a command file is sent')
    args = parser.parse_args(argv)
    unknown = [c for c in args.courses if not os.path.exists(scene(c))]
    if unknown:
        parser.error(f'unknown courses {unknown}')
    if args.hogs < 1:
        parser.error(f'--hogs must be >= 1, not {args.hogs}')
    if not 0 <= args.domain <= 230 - 2 * len(args.courses):
        parser.error(f'--domain {args.domain} leaves no room for {2 * len(args.courses)} runs')
    folder = tempfile.mkdtemp(prefix='bench_live_load_')
    print(f'machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; '
          f'node logs in {folder}')
    domain = args.domain
    rows = []
    for course in args.courses:
        idle = walk_live(course, domain, folder, 'idle', args.settle)
        hogs = start_hogs(args.hogs)
        try:
            loaded = walk_live(course, domain + 1, folder, 'loaded', args.settle)
        finally:
            stop_hogs(hogs)
        domain += 2
        rows.append((course, idle, loaded))
        print(f'{course}: idle {outcome(idle)}; loaded {outcome(loaded)}', flush=True)
    print(f'\nObstacle courses walked live, idle and beside {args.hogs} CPU hogs\n')
    print('| course | goal | idle: end | reached | loaded: end | reached | walked idle / loaded '
          's | lead loaded s |')
    print('|---|---|---|---|---|---|---:|---:|')
    reached_idle = reached_loaded = 0
    for course, idle, loaded in rows:
        expect = expectation(course)
        goal = f'x >= {expect["reach_x"] - REACH_TOLERANCE:g}' if 'reach_x' in expect else \
            f'stop before x {expect.get("stop_before_x")}, as idle'
        a, b = reached(course, idle), reached(course, loaded, idle)
        reached_idle += a
        reached_loaded += b
        print(f'| {course} | {goal} | {outcome(idle)} | {"yes" if a else "NO"} | '
              f'{outcome(loaded)} | {"yes" if b else "NO"} | {idle["walked_s"]:.1f} / '
              f'{loaded["walked_s"]:.1f} | {loaded["lead_s"]} |')
    print(f'\n{reached_idle} of {len(rows)} courses reached their end idle, {reached_loaded} of '
          f'{len(rows)} beside {args.hogs} CPU hogs')
    print_command(__file__, argv)
    return 0 if reached_loaded == len(rows) else 1


if __name__ == '__main__':
    sys.exit(main())
