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
Several actors hosted by one actor_planner process (``--actors NS ...``).

One process, one DDS participant and one stream thread for all of them: each actor still has
its own namespace, its own cmd_vel and its own 100 Hz joint_states; they share the planning
processes (one per core by default, ``--planning-processes K``). A bad ``--actors`` or
``--planning-processes`` value is a configuration error (exit 2, naming it).
"""
import math
import os
import signal
import subprocess
import time

import pytest
from ros_harness import fresh_domain_id, NodeProcess, ros_env
from test_node_helpers import node_command, Probe, ROOT_X, ROOT_YAW, scene

pytestmark = [pytest.mark.ros, pytest.mark.slow]

DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 5 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()
NAMESPACES = ('crowd/a', 'crowd/b', 'crowd/c')


def actors_command(*actors, ros_args=()):
    command = node_command(*ros_args)
    at = command.index('--ros-args')
    return command[:at] + ['--actors', *actors] + command[at:]


@pytest.fixture(scope='module')
def crowd(tmp_path_factory):
    folder = tmp_path_factory.mktemp('crowd')
    process = NodeProcess(actors_command(*NAMESPACES, ros_args=('-p', f'scene:={scene("flat")}')),
                          ros_env(DOMAIN_ID), log_path=str(folder / 'crowd.log'))
    probes = [Probe(DOMAIN_ID, namespace='/' + ns) for ns in NAMESPACES]
    try:
        for probe in probes:
            assert probe.wait_for_stream(process, 600.0), process.output()
        yield process, probes
    finally:
        for probe in probes:
            probe.close()
        assert process.stop() == 0, process.output()


def test_each_hosted_actor_streams_at_the_publish_rate(crowd):
    _, probes = crowd
    starts = [p.stamps_after(-1)[-1] for p in probes]

    def spans():
        return [1e-9 * (s[-1] - s[0]) if len(s) > 1 else 0.0
                for s in (p.stamps_after(t) for p, t in zip(probes, starts))]

    # Spinning the probes in turns until each stream spans 3 s of its own stamps: the rate is
    # the node's (frames per second of stream time), not how fast this process takes them in.
    deadline = time.monotonic() + 30.0
    while min(spans()) < 3.0 and time.monotonic() < deadline:
        for probe in probes:
            probe.spin(0.05)
    assert min(spans()) >= 3.0, spans()
    rates = [(len(s) - 1) / span for s, span in
             zip((p.stamps_after(t) for p, t in zip(probes, starts)), spans())]
    assert all(r > 80.0 for r in rates), rates
    for probe in probes:
        assert len(probe.joint_states[-1][1].name) == 22


def test_each_hosted_actor_follows_only_its_own_command(crowd):
    _, (a, b, c) = crowd
    starts = [p.latest().copy() for p in (a, b, c)]
    a.command = (0.5, 0.0)
    b.command = (0.0, 0.6)
    for _ in range(30):
        for probe in (a, b, c):
            probe.spin(0.05)
    a.command = b.command = None
    moved = [p.latest() - s for p, s in zip((a, b, c), starts)]
    assert moved[0][ROOT_X] * math.cos(starts[0][ROOT_YAW]) > 0.4, moved[0][ROOT_X]
    assert moved[1][ROOT_YAW] > 0.4, moved[1][ROOT_YAW]
    assert abs(moved[2][ROOT_X]) < 1e-6 and abs(moved[2][ROOT_YAW]) < 1e-6


def _children(pid):
    """Command lines of a process's child processes (from /proc)."""
    out = []
    for task in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{task}/children') as listing:
            for child in listing.read().split():
                with open(f'/proc/{child}/cmdline', 'rb') as cmdline:
                    out.append(cmdline.read().replace(b'\0', b' ').decode())
    return out


def test_hosted_actors_share_planning_processes(crowd):
    """Three actors, one planning process per core at most (the default)."""
    process, _ = crowd
    planning = [c for c in _children(process.pid) if 'spawn_main' in c]
    assert len(planning) == min(len(NAMESPACES), len(os.sched_getaffinity(0))), planning


def test_sigterm_ends_the_walking_actors_and_their_planning_processes(crowd):
    """As docker stop, systemd or ros2 launch (after SIGINT) would end the node."""
    process, probes = crowd
    planning = [int(child) for task in os.listdir(f'/proc/{process.pid}/task')
                for child in open(f'/proc/{process.pid}/task/{task}/children').read().split()
                if b'spawn_main' in open(f'/proc/{child}/cmdline', 'rb').read()]
    assert planning
    for probe in probes:
        probe.command = (0.5, 0.0)
    for _ in range(20):
        for probe in probes:
            probe.spin(0.05)
    process.proc.send_signal(signal.SIGTERM)
    try:
        code = process.proc.wait(timeout=15.0)
    except subprocess.TimeoutExpired:
        pytest.fail('the node was still running 15 s after SIGTERM')
    finally:
        for probe in probes:
            probe.command = None
    assert code == 0, process.output()
    time.sleep(1.0)  # an orphan would be adopted and reaped by init by now, if it had ended
    assert not [pid for pid in planning if os.path.exists(f'/proc/{pid}')], \
        'planning processes outlived the node'


@pytest.mark.parametrize('actors, named', [(('a', 'a'), 'repeated'), (('9lives',), '9lives'),
                                           (('a//b',), 'a//b'),
                                           (('a', '--planning-processes', '-1'),
                                            'planning-processes')])
def test_bad_actors_option_exits_2_naming_it(actors, named):
    result = subprocess.run(actors_command(*actors), env=ros_env(DOMAIN_ID),
                            capture_output=True, text=True, timeout=120)
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert named in output, output
