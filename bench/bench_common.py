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
