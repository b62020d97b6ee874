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
Benchmark the planner node's start: time to the first frame and to a ready planner.

Benchmark the planner node's start: time to the first joint_states frame and to a ready planner,
with the kernel cache as it is and (``--cold``) with an empty one.

    .venv/bin/python bench/bench_start.py [--runs 3] [--cold] [--scene flat]

Prints numbers; asserts nothing. Each start is a fresh node process (the venv's console
script) with localhost discovery in its own ROS_DOMAIN_ID; the clock starts when the process
is started and stops at the probe's receipt of the first frame, and of the first diagnostics
that no longer say "warming up".
"""
import argparse
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'test'))

from bench_common import machine  # noqa: E402
from ros_harness import fresh_domain_id, NodeProcess, ros_env  # noqa: E402
from test_node_helpers import node_command, Probe, scene  # noqa: E402


def one_start(scene_path: str, cache: str = None) -> tuple:
    """(s to the first frame, s to a ready planner) of one node start; inf when not seen."""
    domain = fresh_domain_id()
    extra = {'NUMBA_CACHE_DIR': cache} if cache else {}
    probe = Probe(domain, rviz=False)
    started = time.monotonic()
    process = NodeProcess(node_command('-p', f'scene:={scene_path}'), ros_env(domain, **extra))
    try:
        probe.spin_until(lambda: probe.joint_states or not process.alive(), 120.0)
        first = probe.joint_states[0][0] - started if probe.joint_states else float('inf')
        ready = float('inf')
        if probe.spin_until(lambda: probe.planner_ready() or not process.alive(), 1200.0):
            ready = time.monotonic() - started
        return first, ready
    finally:
        probe.close()
        process.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--runs', type=int, default=3)
    parser.add_argument('--cold', action='store_true', help='also one start from an empty cache')
    parser.add_argument('--scene', default='flat')
    args = parser.parse_args()
    print(machine())
    path = scene(args.scene)
    for run in range(args.runs):
        first, ready = one_start(path)
        print(f'start {run + 1} (cache as it is): first frame {first:.2f} s, planner ready '
              f'{ready:.1f} s')
    if args.cold:
        with tempfile.TemporaryDirectory(prefix='numba_cache_') as cache:
            first, ready = one_start(path, cache)
        print(f'start from an empty kernel cache: first frame {first:.2f} s, planner ready '
              f'{ready:.1f} s')


if __name__ == '__main__':
    main()
