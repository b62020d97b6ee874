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
Measure how often a busy process loses the processor for a moment, and for how long.

    .venv/bin/python bench/bench_cpu_stalls.py [--duration 2] [--threshold-us 10]

A loop that does nothing but read a clock records every gap between two readings longer than
the threshold, once with the wall clock and once with the process's CPU clock (what
``bench_lower_body.py`` times its searches with). On a virtual machine the host's interrupts
show as such gaps, and those counted in the CPU clock land in whatever is being timed: a call
of 20 us that meets one takes two to four times as long. Run it pinned to the core a benchmark
uses (``taskset -c 1``). Prints numbers; asserts nothing.
"""
import argparse
import os
import time

import numpy as np


def gaps(clock, duration: float, threshold_ns: int) -> np.ndarray:
    """
    Return the gaps between back-to-back readings of a clock longer than a threshold.

    The gaps (ns) longer than ``threshold_ns`` between back-to-back readings of ``clock`` over
    ``duration`` s of the wall clock.
    """
    found = []
    end = time.perf_counter_ns() + int(duration * 1e9)
    last = clock()
    while time.perf_counter_ns() < end:
        now = clock()
        if now - last > threshold_ns:
            found.append(now - last)
        last = now
    return np.array(found, dtype=float)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n')[0])
    parser.add_argument('--duration', type=float, default=2.0, help='seconds per clock')
    parser.add_argument('--threshold-us', type=float, default=10.0,
                        help='shortest gap counted, us')
    args = parser.parse_args()
    print(f'machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; '
          f'gaps > {args.threshold_us:g} us between readings of a busy loop')
    for name, clock in (('wall (perf_counter)', time.perf_counter_ns),
                        ('CPU (process_time)', time.process_time_ns)):
        found = gaps(clock, args.duration, int(args.threshold_us * 1e3)) / 1e3
        if not found.size:
            print(f'{name}: none in {args.duration:g} s')
            continue
        print(f'{name}: {found.size / args.duration:.0f} a second, median {np.median(found):.1f} '
              f'us, p90 {np.percentile(found, 90):.1f} us, max {found.max():.1f} us, '
              f'{100 * found.sum() / (args.duration * 1e6):.1f} % of the time')


if __name__ == '__main__':
    main()
