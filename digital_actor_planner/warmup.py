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
Compile the planner's kernels once, ahead of the first walk: ``digital-actor warm-up``.

numba compiles every kernel when its module is first imported and keeps the machine code on disk
(core/jit.py). The first import on a fresh install therefore takes about a minute (several on a
loaded machine); afterwards it loads in seconds. Set-up (``./quickstart.sh setup``), the demo and
the test runner call this first, so that time is spent once, with progress a person can read,
instead of inside a node that looks stuck. A stamp next to the kernel cache records the sources
and the numba it was made for; while it matches, a warm-up returns at once.
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import importlib
import importlib.metadata
import os
import platform
import sys
import time
from typing import Callable, List, Optional

#: Core modules with compiled kernels, in import order (each imports only modules before it),
#: so every line of progress times one module's own kernels.
KERNEL_MODULES = ('skeleton', 'environment', 'convex', 'collision', 'path', 'footstep_search',
                  'footsteps', 'gait', 'body_model', 'ct_space', 'ct_roadmap', 'upper_body',
                  'actor')
#: The course one step is planned on: flat ground compiles what only runs while walking.
WARM_UP_COURSE = 'flat.yaml'
STAMP_NAME = 'digital-actor-warm-up.stamp'
EXIT_FAILED = 1


def _core_directory() -> str:
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), 'core')


def _numba_version() -> Optional[str]:
    try:
        return importlib.metadata.version('numba')
    except importlib.metadata.PackageNotFoundError:
        return None


def cache_key() -> str:
    """
    Return what the kernel cache depends on: the core's sources, numba, Python and the processor.

    Returns
    -------
    str
        16 hex digits; a different key means the cached kernels may be stale.

    """
    digest = hashlib.sha256()
    core = _core_directory()
    for name in sorted(os.listdir(core)):
        if name.endswith('.py'):
            with open(os.path.join(core, name), 'rb') as f:
                digest.update(name.encode() + b'\0' + f.read())
    digest.update(f'{_numba_version()}|{sys.version}|{platform.machine()}'.encode())
    digest.update(_processor_name().encode())
    return digest.hexdigest()[:16]


def _processor_name() -> str:
    # numba compiles for the host processor: a cache copied to another one is recompiled.
    try:
        with open('/proc/cpuinfo') as f:
            for line in f:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def stamp_path() -> str:
    """
    Where the stamp lives: beside numba's cache in the package, else in the user's cache.

    numba keeps its cache in ``core/__pycache__`` when that is writable and in the user's cache
    folder otherwise; the stamp follows it, so deleting the one deletes the other.
    """
    in_tree = os.path.join(_core_directory(), '__pycache__')
    try:
        os.makedirs(in_tree, exist_ok=True)
    except OSError:
        pass
    if os.access(in_tree, os.W_OK):
        return os.path.join(in_tree, STAMP_NAME)
    base = os.environ.get('XDG_CACHE_HOME') or os.path.join(os.path.expanduser('~'), '.cache')
    tag = hashlib.sha256(_core_directory().encode()).hexdigest()[:12]
    return os.path.join(base, 'digital_actor_planner', f'{tag}-{STAMP_NAME}')


def is_warm() -> bool:
    """Return true when this installation's kernels were compiled for its current sources."""
    try:
        with open(stamp_path()) as f:
            return f.read().strip() == cache_key()
    except OSError:
        return False


def _write_stamp() -> None:
    path = stamp_path()
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        temporary = f'{path}.{os.getpid()}'
        with open(temporary, 'w') as f:
            f.write(cache_key() + '\n')
        os.replace(temporary, path)
    except OSError:
        pass   # no stamp: the next warm-up loads the cache again (seconds), nothing breaks


def _plan_one_step() -> None:
    """Plan a few steps on the flat course, as the node's first walk does."""
    from digital_actor_planner.core.actor import Actor, ActorConfig
    from digital_actor_planner.core.scene import load_scene
    from digital_actor_planner.core.skeleton import Skeleton
    from digital_actor_planner.nodes.viewer_page import shipped_scenes

    course = shipped_scenes().get(os.path.splitext(WARM_UP_COURSE)[0])
    if course is None:
        return   # an install without its courses: the imports above compiled the kernels
    skeleton = Skeleton()
    scene = load_scene(course, skeleton)
    actor = Actor(skeleton, scene.environment, ActorConfig(), start=scene.start)
    actor.set_command(0.6, 0.0)
    for _ in range(3):
        actor.plan_next()
    actor.set_command(0.0, 0.0)
    actor.plan_next()


def warm_up(report: Callable[[str], None] = print, force: bool = False) -> float:
    """
    Compile (or load) every kernel and plan one step; return the seconds it took.

    Parameters
    ----------
    report : callable
        Called with one line of progress per stage (which stage, how long it took).
    force : bool
        Warm up even when the stamp says the cache is current.

    Returns
    -------
    float
        Wall time in s (0.0 when the cache was current and nothing was done).

    """
    if not force and is_warm():
        report("warm-up: the planner's kernels are already compiled for this installation")
        return 0.0
    with _exclusive(report):
        # Another warm-up may have finished while this one waited: nothing left to do.
        if not force and is_warm():
            report("warm-up: the planner's kernels are already compiled for this installation")
            return 0.0
        return _compile_all(report)


@contextlib.contextmanager
def _exclusive(report: Callable[[str], None]):
    """
    Hold the warm-up lock, so that two warm-ups do not compile at once.

    Hold the warm-up lock: two warm-ups at once (set-up and a demo) would both compile, each at
    half the speed; the second waits and then finds the cache current.
    """
    path = stamp_path() + '.lock'
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        handle = open(path, 'a')
    except OSError:
        yield   # nowhere to lock: compile anyway
        return
    with handle:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX
            yield
            return
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            report('warm-up: another warm-up is compiling the kernels; waiting for it')
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _compile_all(report: Callable[[str], None]) -> float:
    started = time.perf_counter()
    if _numba_version() is None:
        report('warm-up: numba is not installed, so the kernels run as plain Python (slowly); '
               'nothing to compile')
    else:
        report("warm-up: compiling the planner's kernels once for this installation (about a "
               'minute on an idle machine, a few on a busy one; loading them from the cache '
               'takes seconds)')
    stages: List[tuple] = [('libraries (numpy, trimesh, fcl)', _import_libraries)]
    for name in KERNEL_MODULES:
        stages.append((f'{name} kernels',
                       lambda name=name: importlib.import_module(
                           f'digital_actor_planner.core.{name}')))
    stages.append(('one step planned on the flat course', _plan_one_step))
    for index, (what, run) in enumerate(stages, start=1):
        stage_start = time.perf_counter()
        run()
        report(f'warm-up: [{index:2d}/{len(stages)}] {what}: '
               f'{time.perf_counter() - stage_start:5.1f} s')
    total = time.perf_counter() - started
    _write_stamp()
    report(f'warm-up: done in {total:.0f} s; the kernels are cached for later starts')
    return total


def _import_libraries() -> None:
    import numpy  # noqa: F401
    import trimesh  # noqa: F401
    try:
        import fcl  # noqa: F401
    except ImportError:
        pass
    if _numba_version() is not None:
        import numba  # noqa: F401


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of ``digital-actor warm-up``."""
    parser = argparse.ArgumentParser(
        prog='digital-actor warm-up',
        description="Compile the planner's kernels once, so that the first start of the "
                    'planner node streams at once.')
    parser.add_argument('--force', action='store_true',
                        help='compile (or load) even when the cache is recorded as current')
    parser.add_argument('--check', action='store_true',
                        help='only say whether the cache is current (exit 0) or not (exit 1)')
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    """Run ``digital-actor warm-up``; returns the exit code."""
    args = build_parser().parse_args(argv)
    if args.check:
        warm = is_warm()
        print('warm-up: the kernel cache is ' + ('current' if warm else 'not current'))
        return 0 if warm else EXIT_FAILED

    def report(line: str) -> None:
        print(line, flush=True)

    try:
        warm_up(report, force=args.force)
    except KeyboardInterrupt:
        print('warm-up: interrupted; the next start compiles what is missing', file=sys.stderr)
        return 130
    except Exception as error:  # noqa: B902 - a failed warm-up must say why, not trace back
        print(f'warm-up: failed: {type(error).__name__}: {error}', file=sys.stderr)
        return EXIT_FAILED
    return 0


if __name__ == '__main__':
    sys.exit(main())
