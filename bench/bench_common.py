"""Shared by the benchmark scripts: the line that says how a table was made."""
import os
import sys


def print_command(script: str, argv=None) -> None:
    """Print the command line of ``script`` (a path) with ``argv`` (default: the process's own
    arguments) and the load average, so a table pasted into the README carries both."""
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
    """The processor's model, its count and the first one's caches (Linux's sysfs), for the
    top of a table: footstep search ratios, for one, differ from host to host (session 38's
    in-walk p95 0.042-0.045 where session 37's host gave 0.060 with the same code)."""
    import platform
    model = platform.processor() or platform.machine()
    try:
        with open('/proc/cpuinfo') as cpuinfo:
            for line in cpuinfo:
                if line.startswith('model name'):
                    model = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    caches = []
    root = '/sys/devices/system/cpu/cpu0/cache'
    try:
        for index in sorted(os.listdir(root)):
            if not index.startswith('index'):
                continue

            def read(name, index=index):
                with open(os.path.join(root, index, name)) as f:
                    return f.read().strip()
            kind = {'Data': 'd', 'Instruction': 'i'}.get(read('type'), '')
            caches.append(f'L{read("level")}{kind} {read("size")}')
    except OSError:
        pass
    described = f'{model}, {os.cpu_count()} CPUs'
    if caches:
        described += f'; caches of CPU 0: {", ".join(caches)}'
    return described
