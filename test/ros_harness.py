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
Helpers for tests that start real node processes and talk DDS (no launch_testing here).

Every process runs with ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and the test's own
ROS_DOMAIN_ID; tests wait for a match, never a fixed sleep, and stop what they start by PID.
"""
import itertools
import os
import signal
import subprocess
import sys
import time

_DOMAIN_IDS = itertools.count(start=(os.getpid() % 50) + 110)


def fresh_domain_id() -> int:
    """Return a ROS_DOMAIN_ID no other test in this run uses (110..232, Fast DDS safe range)."""
    return next(_DOMAIN_IDS) % 120 + 110


def ros_env(domain_id: int, **extra) -> dict:
    """Environment for a node process: localhost discovery, own domain, the venv's ament prefix."""
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env.setdefault('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    prefix = sys.prefix
    paths = [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    if prefix not in paths:
        paths.insert(0, prefix)
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(paths)
    env['PYTHONUNBUFFERED'] = '1'
    env.update({k: str(v) for k, v in extra.items()})
    return env


class NodeProcess:
    """A node started as its own process, stopped by PID (SIGINT, then SIGKILL)."""

    def __init__(self, args, env, log_path=None):
        self.args = list(args)
        self.log_path = log_path
        self._log = open(log_path, 'w') if log_path else subprocess.DEVNULL
        self.proc = subprocess.Popen(self.args, env=env, stdout=self._log,
                                     stderr=subprocess.STDOUT, start_new_session=True)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self, timeout: float = 60.0) -> int:
        # A clean shutdown takes seconds per planning process, and far longer on a loaded
        # machine: SIGKILL only a node that is stuck, not one that is slow.
        if self.proc.poll() is None:
            try:
                os.kill(self.proc.pid, signal.SIGINT)
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout=timeout)
            except ProcessLookupError:
                pass
        if self._log is not subprocess.DEVNULL:
            self._log.close()
        return self.proc.returncode

    def output(self) -> str:
        if not self.log_path:
            return ''
        with open(self.log_path) as f:
            return f.read()


def wait_for(predicate, timeout: float, interval: float = 0.02, spin=None) -> bool:
    """Poll ``predicate`` (spinning ``spin()`` between polls) until true or ``timeout`` s pass."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if spin is not None:
            spin()
        if predicate():
            return True
        if spin is None:
            time.sleep(interval)
    return bool(predicate())


def wait_until_importing(process, timeout: float) -> bool:
    """
    Wait until ``process`` maps its first library from site-packages.

    The interpreter has then started and runs the program's imports. Before that, a SIGINT
    meets Python's own start-up (it ends the process with the signal, whatever the program),
    which no program can change.
    """
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        try:
            with open(f'/proc/{process.pid}/maps') as maps:
                if 'site-packages' in maps.read():
                    return True
        except OSError:
            pass
        time.sleep(0.002)
    return False
