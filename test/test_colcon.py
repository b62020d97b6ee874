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

"""colcon builds the package and the installed node streams joint_states (CI-proof)."""
import os
import shutil
import subprocess
import sys

import pytest
from ros_harness import fresh_domain_id, NodeProcess, ros_env
from test_node_helpers import JOINT_NAMES, node_command, Probe, REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

# ACTOR_NODE_TEST_DOMAIN pins the domain (e.g. to a range of your own); by default each
# module takes a fresh one, so runs started side by side do not hear each other.
DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 3 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()
PACKAGE = 'digital_actor_planner'


@pytest.fixture(scope='module')
def install(tmp_path_factory):
    colcon = os.path.join(sys.prefix, 'bin', 'colcon')
    if not os.path.exists(colcon):
        colcon = shutil.which('colcon')
    assert colcon, 'colcon is pinned in requirements.txt'
    base = tmp_path_factory.mktemp('colcon')
    env = dict(os.environ, COLCON_HOME=str(base / 'colcon_home'))
    env['PATH'] = os.path.dirname(sys.executable) + os.pathsep + env.get('PATH', '')
    result = subprocess.run(
        [colcon, 'build', '--base-paths', REPO, '--packages-select', PACKAGE,
         '--build-base', str(base / 'build'), '--install-base', str(base / 'install'),
         '--event-handlers', 'console_direct+'],
        cwd=str(base), env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-4000:]
    return base / 'install'


def test_colcon_installs_executables_launch_urdf_and_config(install):
    share = install / PACKAGE / 'share' / PACKAGE
    for relative in ('package.xml', 'launch/actor.launch.py', 'urdf/digital_actor.urdf',
                     'config/planner.yaml', 'config/actor.rviz', 'config/scenes/flat.yaml'):
        assert (share / relative).is_file(), relative
    assert (install / PACKAGE / 'share' / 'ament_index' / 'resource_index' / 'packages' /
            PACKAGE).is_file()
    assert os.access(install / PACKAGE / 'lib' / PACKAGE / 'actor_planner', os.X_OK)


def test_node_from_the_colcon_install_streams_the_22_joints(install, tmp_path):
    prefix = install / PACKAGE
    executable = prefix / 'lib' / PACKAGE / 'actor_planner'
    site = sorted((prefix / 'lib').glob('python3*/site-packages'))
    assert site, list((prefix / 'lib').iterdir())
    # As `source install/setup.bash` would: the install's Python packages and ament prefix
    # first. The default scene must then be found through the install's share directory.
    env = ros_env(DOMAIN_ID)
    env['PYTHONPATH'] = os.pathsep.join([str(site[0])] + [
        p for p in env.get('PYTHONPATH', '').split(os.pathsep) if p])
    env['AMENT_PREFIX_PATH'] = os.pathsep.join([str(prefix), env['AMENT_PREFIX_PATH']])
    process = NodeProcess(node_command(executable=str(executable)), env,
                          log_path=str(tmp_path / 'node.log'))
    probe = Probe(DOMAIN_ID)
    try:
        # The stream starts at once; the planner of a fresh install compiles its kernels
        # first (numba caches them in the install): about 50 s on a quiet machine, several
        # minutes with both cores busy.
        assert probe.wait_for_stream(process, 60.0, ready=False), process.output()
        _, msg = probe.joint_states[-1]
        assert tuple(msg.name) == JOINT_NAMES
        assert probe.wait_for_stream(process, 900.0), process.output()
        _, msg = probe.joint_states[-1]
        assert tuple(msg.name) == JOINT_NAMES
        probe.drive(0.5, 0.0, 3.0)
        assert probe.latest()[0] > 0.3
        # The default scene came from the install's share directory, not the source tree.
        assert f'scene {prefix}' in process.output(), process.output()
    finally:
        probe.close()
        assert process.stop() == 0, process.output()
