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
Profile the planner's compiled kernels with Linux perf, each named.

    .venv/bin/python bench/perf_kernels.py [--courses stairs_up blocks] [--whole-body]
        [--seconds 20] [--out /tmp/kernels.data] [--top 40]

numba's kernels are machine code perf cannot name. This script compiles them in its own
process (into a fresh ``NUMBA_CACHE_DIR`` in a temporary folder: a kernel loaded from the disk
cache keeps no symbols; compiling takes a minute or two), walks the courses once, then attaches
``perf record -e cpu-clock`` to itself while it walks them again and again for ``--seconds``,
writes ``/tmp/perf-PID.map``, from which perf names every kernel and every helper compiled into
it (``module.function``; ``NRT_incref`` / ``NRT_decref`` are numba's reference counts),
and prints the top of ``perf report --sort sym``. ``perf report -i OUT --sort sym`` shows it
again while the map file is there. The ``cpu-clock`` event is a software one: it works in a
virtual machine without hardware counters (it names time spent in ``pow`` or in reference
counts inside a kernel). Needs ``perf`` (Debian:
``linux-perf``) and permission to attach to one's own process.
"""
import argparse
import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

# Before numba is imported: kernels compiled here, not loaded from the cache.
os.environ['NUMBA_CACHE_DIR'] = tempfile.mkdtemp(prefix='perf_kernels_')
atexit.register(shutil.rmtree, os.environ['NUMBA_CACHE_DIR'], ignore_errors=True)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))

from bench_common import print_command  # noqa: E402
from course_runs import course_names, scene, SCENES, skeleton  # noqa: E402
from digital_actor_planner.cli import read_commands  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402

#: A symbol's size when no other symbol follows it closely (bytes).
LAST_SIZE = 1 << 14


def readable(symbol: str) -> str:
    """
    Return a numba function's mangled name as its module and function.

    A numba function's mangled name (``_ZN<length><name>...``, maybe behind numba's ``cpython.`` or
    ``cfunc.`` wrapper prefix) as its module and function (``gait._swing_pass``,
    ``cfunc.gait._swing_pass``); any other name unchanged.
    """
    prefix = ''
    for wrapper in ('cpython.', 'cfunc.'):
        if symbol.startswith(wrapper + '_ZN'):
            prefix, symbol = wrapper, symbol[len(wrapper):]
    if not symbol.startswith('_ZN'):
        return symbol
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while j < len(symbol) and symbol[j].isdigit():
            j += 1
        length = int(symbol[i:j])
        parts.append(symbol[j:j + length])
        i = j + length
    return prefix + '.'.join(parts[-2:]) if parts else prefix + symbol


def kernel_symbols() -> dict:
    """
    Map the address of every compiled kernel function to its readable name.

    Address -> name (:func:`readable`) of every function compiled into the kernels of the core's
    modules loaded in this process (compiled here; a helper linked into several kernels is one
    function, named once).
    """
    import numba
    symbols = {}
    modules = [module for name, module in list(sys.modules.items())
               if name.startswith('digital_actor_planner.core.')]
    for module in modules:
        for dispatcher in vars(module).values():
            if not isinstance(dispatcher, numba.core.registry.CPUDispatcher):
                continue
            for result in dispatcher.overloads.values():
                library = result.library
                try:
                    functions = list(library.get_defined_functions())
                except Exception:  # noqa: B902 -- loaded from a cache: no module to read
                    continue
                for function in functions:
                    try:
                        address = library.get_pointer_to_function(function.name)
                    except Exception:  # noqa: B902 -- a declaration numba did not emit
                        continue
                    if address and address not in symbols:
                        symbols[address] = readable(function.name)
    return symbols


def write_perf_map(symbols: dict) -> str:
    """Write ``symbols`` as perf's map of this process's generated code; returns its path."""
    addresses = sorted(symbols)
    map_path = f'/tmp/perf-{os.getpid()}.map'
    with open(map_path, 'w') as out:
        for i, address in enumerate(addresses):
            size = LAST_SIZE
            if i + 1 < len(addresses) and addresses[i + 1] - address < LAST_SIZE:
                size = addresses[i + 1] - address
            out.write(f'{address:x} {size:x} {symbols[address]}\n')
    return map_path


def walk(walks, whole_body: bool) -> int:
    """Walk each course once; returns the walking steps."""
    steps = 0
    for course, commands in walks:
        actor = Actor(skeleton(), course.environment, ActorConfig(plan_upper_body=whole_body),
                      start=course.start)
        blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                              [c.angular_z for c in commands])
        steps += sum(block.status == 'walking' for block in blocks)
    return steps


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n\n')[0])
    parser.add_argument('--courses', nargs='*', default=['stairs_up', 'blocks'])
    parser.add_argument('--whole-body', action='store_true', help='plan the upper body too')
    parser.add_argument('--seconds', type=float, default=20.0, help='seconds of walking profiled')
    parser.add_argument('--frequency', type=int, default=10000, help='samples per second')
    parser.add_argument('--out', default='/tmp/kernels.data', help="perf's data file")
    parser.add_argument('--top', type=int, default=40, help='symbols printed')
    args = parser.parse_args(argv)
    if not args.seconds > 0:
        parser.error(f'--seconds must be positive, got {args.seconds}')
    if args.frequency < 1:
        parser.error(f'--frequency must be at least 1, got {args.frequency}')
    perf = shutil.which('perf')
    if perf is None:
        parser.error('perf not found (Debian: apt install linux-perf)')
    known = course_names()
    for name in args.courses:
        if name not in known:
            parser.error(f'no course {name!r}; the courses: {", ".join(known)}')
    walks = [(scene(name), read_commands(os.path.join(SCENES, name + '.csv')))
             for name in args.courses]
    walk(walks, args.whole_body)  # every kernel the walks call compiled before perf starts
    messages = tempfile.TemporaryFile()
    recorder = subprocess.Popen([perf, 'record', '-e', 'cpu-clock', '-F', str(args.frequency),
                                 '-p', str(os.getpid()), '-o', args.out],
                                stdout=subprocess.DEVNULL, stderr=messages)
    time.sleep(0.5)  # perf attaches
    if recorder.poll() is not None:
        messages.seek(0)
        sys.exit(f'perf record failed: {messages.read().decode().strip()}')
    started, steps = time.perf_counter(), 0
    while time.perf_counter() - started < args.seconds:
        steps += walk(walks, args.whole_body)
    elapsed = time.perf_counter() - started
    recorder.send_signal(signal.SIGINT)
    recorder.wait()
    map_path = write_perf_map(kernel_symbols())
    print(f'{steps} walking steps profiled in {elapsed:.1f} s; kernel symbols in {map_path}; '
          f'{args.out}:')
    report = subprocess.run([perf, 'report', '-i', args.out, '--sort', 'sym', '--stdio'],
                            capture_output=True, text=True)
    lines = [line for line in report.stdout.splitlines() if line.strip()
             and not line.startswith('#')]
    print('\n'.join(lines[:args.top]))
    print_command(__file__)


if __name__ == '__main__':
    main()
