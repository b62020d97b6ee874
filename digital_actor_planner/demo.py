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
The one-command demo: the actor_planner node and the browser viewer as child processes.

Prints the page's address; Ctrl-C (or SIGTERM) stops both children and waits for them. Each child
also gets SIGTERM from the kernel if this process dies without cleaning up, so none is orphaned.
"""
from __future__ import annotations

import argparse
import ctypes
import os
import re
import signal
import subprocess
import sys
import threading
from typing import List, Optional

from digital_actor_planner.nodes.viewer_page import (add_page_options, normalize_namespace,
                                                     shipped_scenes)

PR_SET_PDEATHSIG = 1
URL_PATTERN = re.compile(r'open (http://\S+) in a browser')


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of ``digital-actor demo``."""
    parser = argparse.ArgumentParser(
        prog='digital-actor demo',
        description='Start the actor planner and a web page to steer it with the mouse.')
    add_page_options(parser, 'namespace for the planner and the viewer, e.g. /actor1')
    parser.add_argument('--scene', default=None,
                        help='course: a shipped name (e.g. stairs_up) or a scene YAML/mesh path '
                             "(default: the planner's default course)")
    return parser


def resolve_scene(scene: Optional[str]) -> Optional[str]:
    """Return a shipped course name or a file path as an absolute path (None keeps the default)."""
    if scene is None:
        return None
    shipped = shipped_scenes()
    if scene in shipped:
        return shipped[scene]
    if os.path.isfile(scene):
        return os.path.abspath(scene)
    raise ValueError(f'scene {scene!r} is neither a file nor a shipped course '
                     f'({", ".join(shipped) or "none found"})')


def child_environment() -> dict:
    """Return the children's environment: DDS discovery on this machine unless the user chose."""
    env = dict(os.environ)
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    env.setdefault('RMW_IMPLEMENTATION', 'rmw_fastrtps_cpp')
    paths = [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    if sys.prefix not in paths:
        paths.insert(0, sys.prefix)
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(paths)
    env['PYTHONUNBUFFERED'] = '1'
    return env


def _warm_up(env: dict) -> None:
    """
    Compile the planner's kernels first when they are not cached.

    Compile the planner's kernels first when they are not cached (progress printed), so the planner
    streams as soon as it starts; a failure is reported and the demo goes on.
    """
    from digital_actor_planner.warmup import is_warm
    if is_warm():
        return
    code = subprocess.call([sys.executable, '-m', 'digital_actor_planner.warmup'], env=env)
    if code != 0:
        print('digital-actor demo: warm-up failed; the planner compiles its kernels when it '
              'starts (a minute or more)', file=sys.stderr, flush=True)


def _die_with_parent() -> None:
    """In the child before exec: get SIGTERM when the demo process dies (Linux)."""
    try:
        libc = ctypes.CDLL('libc.so.6', use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def _start(args: List[str], env: dict, capture: bool) -> subprocess.Popen:
    return subprocess.Popen(args, env=env, start_new_session=True,
                            preexec_fn=_die_with_parent if sys.platform == 'linux' else None,
                            stdout=subprocess.PIPE if capture else None,
                            stderr=subprocess.STDOUT if capture else None, text=capture)


def _stop(process: subprocess.Popen, timeout: float = 10.0) -> None:
    """SIGINT the child's process group, then SIGKILL it if it does not exit in time."""
    if process.poll() is not None:
        return
    try:
        os.killpg(process.pid, signal.SIGINT)
        process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=timeout)
    except ProcessLookupError:
        pass


def main(argv: Optional[List[str]] = None) -> int:
    """Run the demo until Ctrl-C; returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        scene = resolve_scene(args.scene)
        namespace = normalize_namespace(args.namespace)
        if not 0 < args.port < 65536:
            raise ValueError(f'port must be in 1..65535, got {args.port!r}')
    except ValueError as error:
        print(f'digital-actor demo: {error}', file=sys.stderr)
        return 2
    env = child_environment()
    try:
        _warm_up(env)
    except KeyboardInterrupt:
        print('digital-actor demo: stopped', flush=True)
        return 130
    ros_args = ['--ros-args', '-r', f'__ns:={namespace}']
    planner_cmd = [sys.executable, '-m', 'digital_actor_planner.nodes.actor_planner'] + ros_args
    if scene is not None:
        planner_cmd += ['-p', f'scene:={scene}']
    viewer_cmd = [sys.executable, '-m', 'digital_actor_planner.nodes.viewer',
                  '--host', args.host, '--port', str(args.port), '--namespace', namespace]

    stopping = threading.Event()

    def request_stop(signum, _frame):
        stopping.set()

    previous = {sig: signal.signal(sig, request_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    planner = _start(planner_cmd, env, capture=False)
    viewer = _start(viewer_cmd, env, capture=True)

    def forward_viewer_output():
        for line in viewer.stdout:
            match = URL_PATTERN.search(line)
            if match:
                print(f'digital-actor demo: the actor is at {match.group(1)} '
                      '(drag the grey disc to walk; Ctrl-C stops)', flush=True)
            elif not line.startswith(('│', '╭', '╰')):
                sys.stdout.write(line)
                sys.stdout.flush()

    reader = threading.Thread(target=forward_viewer_output, daemon=True)
    reader.start()
    code = 0
    reported_planner = False
    try:
        while not stopping.is_set():
            if viewer.poll() is not None:
                print(f'digital-actor demo: the viewer exited with code {viewer.returncode}',
                      file=sys.stderr, flush=True)
                code = viewer.returncode or 1
                break
            if planner.poll() is not None and not reported_planner:
                reported_planner = True
                print(f'digital-actor demo: actor_planner exited with code '
                      f'{planner.returncode}; the page keeps running (Ctrl-C stops)',
                      file=sys.stderr, flush=True)
            stopping.wait(0.2)
    finally:
        for process in (viewer, planner):
            _stop(process)
        reader.join(timeout=2.0)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if stopping.is_set():
        print('digital-actor demo: stopped', flush=True)
    return code


if __name__ == '__main__':
    sys.exit(main())
