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
Measure the machine's own timing floor: a bare real-time Python thread waking every period.

    .venv/bin/python bench/bench_timer_floor.py [--duration 600] [--period 0.01] [--priority 50]

Run it beside ``bench_stream.py`` to tell the stream's jitter from the machine's: the thread
does nothing but sleep to each tick of a monotonic schedule (SCHED_FIFO when permitted) and
record how late it woke. On a virtual machine its stalls show when the host takes a core away.
Prints numbers; asserts nothing.
"""
import argparse
import os
import threading
import time

import numpy as np


def lateness(duration: float, period: float, priority: int) -> np.ndarray:
    """How late (s) a thread woke for each tick over ``duration`` s."""
    late = []

    def run():
        if priority > 0:
            try:
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
            except (AttributeError, OSError):
                print('SCHED_FIFO not permitted: normal scheduling')
        start = time.monotonic()
        tick = 0
        while tick * period < duration:
            due = start + tick * period
            pause = due - time.monotonic()
            if pause > 0.0:
                time.sleep(pause)
            late.append(time.monotonic() - due)
            tick += 1

    thread = threading.Thread(target=run, name='timer_floor')
    thread.start()
    thread.join()
    return np.array(late)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n')[0])
    parser.add_argument('--duration', type=float, default=600.0, help='seconds')
    parser.add_argument('--period', type=float, default=0.01, help='seconds between ticks')
    parser.add_argument('--priority', type=int, default=50, help='SCHED_FIFO priority, 0: none')
    args = parser.parse_args()
    print(f'machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}')
    late = lateness(args.duration, args.period, args.priority) * 1e3
    print(f'{len(late)} ticks of {args.period * 1e3:g} ms: lateness p50 '
          f'{np.percentile(late, 50):.3f} ms, p99 {np.percentile(late, 99):.3f} ms, max '
          f'{late.max():.2f} ms; stalls > 5 ms: {int(np.sum(late > 5.0))}, > 10 ms: '
          f'{int(np.sum(late > 10.0))}')


if __name__ == '__main__':
    main()
