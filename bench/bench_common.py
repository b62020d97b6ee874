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

"""Shared by the benchmark scripts: the line that says how a table was made."""
import os
import sys


def print_command(script: str, argv=None) -> None:
    """
    Print the command line and the load average of a benchmark run.

    Print the command line of ``script`` (a path) with ``argv`` (default: the process's own
    arguments) and the load average, so a table pasted into the README carries both.
    """
    load = os.getloadavg()[0] if hasattr(os, 'getloadavg') else float('nan')
    arguments = ' '.join(sys.argv[1:] if argv is None else argv)
    print(f'\n(command: python bench/{os.path.basename(script)} {arguments}; '
          f'load average {load:.1f})')


def spread(values) -> str:
    """'p50 / p90 / max' of ``values``, rounded to whole units (a table cell)."""
    import numpy as np
    values = np.asarray(values, dtype=float)
    return (f'{np.percentile(values, 50):.0f} / {np.percentile(values, 90):.0f} / '
            f'{values.max():.0f}')


def machine() -> str:
    """
    Describe the machine: processor model, CPU count and CPU 0's caches.

    The processor's model, the CPU count and CPU 0's caches (Linux's sysfs), for the top of a
    table: some ratios, the footstep search's against the exhaustive one for instance, differ from
    machine to machine (docs/BENCHMARKS.md).
    """
    import platform
    model = platform.processor() or platform.machine()
    try:
        with open('/proc/cpuinfo') as cpuinfo:
            model = next((line.split(':', 1)[1].strip() for line in cpuinfo
                          if line.startswith('model name')), model)
    except OSError:
        pass
    caches = []
    root = '/sys/devices/system/cpu/cpu0/cache'
    try:
        for index in sorted(name for name in os.listdir(root) if name.startswith('index')):
            kind, level, size = (_first_line(os.path.join(root, index, name))
                                 for name in ('type', 'level', 'size'))
            suffix = {'Data': 'd', 'Instruction': 'i'}.get(kind, '')
            caches.append(f'L{level}{suffix} {size}')
    except OSError:
        pass
    described = f'{model}, {os.cpu_count()} CPUs'
    if caches:
        described += f'; caches of CPU 0: {", ".join(caches)}'
    return described


def paired_walks(courses, rounds: int, walk, what: str):
    """
    Walk each course with the compiled and the readable version in turn, their order alternated.

    ``walk(course, kind, times)`` walks one course with one version (``'compiled'`` or
    ``'readable'``), appends the timed calls' CPU seconds to ``times`` and returns the blocks.
    A first walk of each version is not counted (kernels compiled, course data read).

    Returns
    -------
    (times, steps) : dicts by version of the timed calls' and the walking steps' seconds, or
        None (after printing which course) where the two versions walked different frames.

    """
    import numpy as np
    kinds = ('compiled', 'readable')
    times = {kind: [] for kind in kinds}
    steps = {kind: [] for kind in kinds}
    for name in courses:
        for kind in kinds:
            walk(name, kind, [])
        for round_ in range(rounds):
            frames = {}
            for kind in (kinds if round_ % 2 == 0 else kinds[::-1]):
                blocks = walk(name, kind, times[kind])
                steps[kind].extend(b.planning_time for b in blocks if b.status == 'walking')
                frames[kind] = np.vstack([b.frames for b in blocks])
            if not np.array_equal(frames['compiled'], frames['readable']):
                print(f'{name}: the two {what} walked different frames')
                return None
    return times, steps


def _first_line(path: str) -> str:
    with open(path) as f:
        return f.readline().strip()
