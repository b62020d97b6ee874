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
actor_planner started with an empty kernel cache streams at once and walks once ready.

The planning process compiles the core's kernels first (minutes on a loaded machine); the node
publishes the standing pose meanwhile and says "warming up" on /diagnostics.
"""
import os
import time

import pytest
from ros_harness import fresh_domain_id, NodeProcess, ros_env
from test_node_helpers import JOINT_NAMES, node_command, Probe, ROOT_X, scene

pytestmark = [pytest.mark.ros, pytest.mark.slow]

DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 6 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()
# The target is 2 s from start to the first frame; discovery and a loaded machine add to it.
FIRST_FRAME_BOUND_S = 20.0
# Compiling every kernel from nothing, on a loaded 2-core machine.
READY_BOUND_S = 900.0


def test_an_empty_kernel_cache_streams_the_standing_pose_at_once_then_walks(tmp_path):
    cache = tmp_path / 'numba_cache'
    cache.mkdir()
    probe = Probe(DOMAIN_ID, rviz=False)
    started = time.monotonic()
    process = NodeProcess(node_command('-p', f'scene:={scene("flat")}'),
                          ros_env(DOMAIN_ID, NUMBA_CACHE_DIR=str(cache)),
                          log_path=str(tmp_path / 'node.log'))
    try:
        assert probe.spin_until(lambda: len(probe.joint_states) > 0 or not process.alive(),
                                FIRST_FRAME_BOUND_S), process.output()
        first = probe.joint_states[0][0] - started
        assert first < FIRST_FRAME_BOUND_S, f'first frame {first:.1f} s after start'
        # Standing on the floor: the hips about a leg's length up.
        root_z = probe.latest()[JOINT_NAMES.index('root_z')]
        assert 0.6 < root_z < 1.2, root_z
        assert probe.spin_until(lambda: probe.diagnostic_values().get('state'), 30.0)
        assert probe.diagnostic_values()['state'] == 'warming up', probe.diagnostic_values()
        assert probe.wait_for_stream(process, READY_BOUND_S), process.output()
        probe.drive(0.5, 0.0, 4.0)
        assert probe.latest()[ROOT_X] > 0.5, probe.diagnostic_values()
    finally:
        probe.close()
        code = process.stop()
    assert code == 0, process.output()
