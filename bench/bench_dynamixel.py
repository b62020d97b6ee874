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
Control-cycle time of the Dynamixel bridge against the emulator with 1 Mbps wire time.

One control cycle = one sync write of 18 goal positions + one sync read of 18 present
positions (the node also reads Hardware Error Status every ``health_check_period``). The
emulator runs in its own process and releases every status packet only after its bytes would
have crossed the wire (10 bits per byte) plus the servo's Return Delay Time. The bus limit is
computed from the bytes that actually crossed the bus in the same run.

The emulator stands in for hardware, which is never descheduled: it serves from a SCHED_FIFO
thread (when run as root) pinned to the second core, waits out the last 60 us of each wire
deadline by spinning, and the bridge side is pinned to the first core. Without that, a
preempted emulator thread (up to 10 ms on a 2-vCPU VM) would be charged to the bridge.

    .venv/bin/python bench/bench_dynamixel.py [--cycles 1000] [--return-delay-us 0]
"""
import argparse
from dataclasses import replace
import multiprocessing
import os
import statistics
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'test'))

from digital_actor_planner.core.skeleton import Skeleton  # noqa: E402
from digital_actor_planner.dynamixel.bus import BusError, ServoBus  # noqa: E402
from digital_actor_planner.dynamixel.config import load_config  # noqa: E402
from digital_actor_planner.dynamixel.controller import BridgeController  # noqa: E402
import dynamixel_emulator as emu  # noqa: E402

BAUD = 1_000_000


def _pin(cpu):
    """Keep one side of the bus on one core, where the machine has two or more."""
    if hasattr(os, 'sched_setaffinity') and (os.cpu_count() or 1) >= 2:
        os.sched_setaffinity(0, {cpu})


def _serve(link, ids, return_delay_us, wire_time, ready, pipe):
    _pin(1)
    emulator = emu.DynamixelEmulator(ids, link, baud_rate=BAUD, wire_time=wire_time,
                                     realtime=True)
    for servo_id in ids:
        emulator.set_register(servo_id, emu.RETURN_DELAY_TIME, return_delay_us // 2)
    emulator.start()
    ready.set()
    while True:
        request = pipe.recv()
        if request == 'stop':
            break
        with emulator.lock:
            pipe.send((emulator.bytes_in, emulator.bytes_out, emulator.wire_busy_s,
                       dict(emulator.instruction_counts)))
    emulator.stop()
    pipe.send('stopped')


def _measure(step, cycles, counters):
    before = counters()
    times = []
    cpu = time.process_time()
    for _ in range(cycles):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    cpu = (time.process_time() - cpu) / cycles
    after = counters()
    bytes_on_wire = (after[0] - before[0]) + (after[1] - before[1])
    return times, bytes_on_wire, cpu


def _report(label, times, bytes_on_wire, cpu, cycles, delays_per_cycle, return_delay_s):
    mean = statistics.fmean(times)
    limit = bytes_on_wire / cycles * 10.0 / BAUD + delays_per_cycle * return_delay_s
    ordered = sorted(times)
    print(f'{label}:')
    print(f'  bytes on the wire per cycle   {bytes_on_wire / cycles:8.1f}')
    print(f'  bus limit (packet sizes)      {limit * 1e3:8.3f} ms  = {1 / limit:7.1f} Hz')
    print(f'  measured cycle  mean          {mean * 1e3:8.3f} ms  = {1 / mean:7.1f} Hz')
    print(f'                  median / p99  {ordered[len(ordered) // 2] * 1e3:8.3f} / '
          f'{ordered[int(len(ordered) * 0.99)] * 1e3:.3f} ms')
    print(f'  bridge-side CPU per cycle     {cpu * 1e3:8.3f} ms')
    print(f'  achieved rate / limit rate    {limit / mean * 100:8.1f} %')
    return limit / mean


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--cycles', type=int, default=1000)
    parser.add_argument('--return-delay-us', type=int, default=0,
                        help='Return Delay Time of every servo (X-series default: 500 us)')
    parser.add_argument('--no-wire-time', action='store_true',
                        help='answer instantly: the software floor, not a bus model')
    args = parser.parse_args(argv)
    skeleton = Skeleton()
    config = load_config(os.path.join(HERE, '..', 'config', 'dynamixel.yaml'), skeleton)
    ids = [s.id for s in config.servos]
    folder = tempfile.mkdtemp(prefix='bench_dynamixel_')
    link = os.path.join(folder, 'ttyDXL')
    context = multiprocessing.get_context('fork')
    ready = context.Event()
    ours, theirs = context.Pipe()
    server = context.Process(
        target=_serve, daemon=True,
        args=(link, ids, args.return_delay_us, not args.no_wire_time, ready, theirs))
    server.start()
    _pin(0)
    try:
        if not ready.wait(10.0):
            raise RuntimeError('emulator did not start')

        def counters():
            ours.send('counters')
            return ours.recv()

        goals = {i: 2048 + i for i in ids}
        print(f'{len(ids)} servos, {BAUD} bps '
              f'({"NO wire time: software floor" if args.no_wire_time else "wire time modelled"})'
              f', Return Delay Time {args.return_delay_us} us, '
              f'{args.cycles} cycles, python {sys.version.split()[0]}, {os.cpu_count()} cores, '
              f'load average {os.getloadavg()[0]:.1f}')
        ratios = {}
        for fast in (False, True):
            bus = ServoBus(link, BAUD, fast_sync_read=fast)
            bus.open()
            found = bus.ping(ids)
            assert len(found) == len(ids), found
            failures = []

            def bus_cycle():
                bus.write_goals(goals)
                if len(bus.read_positions(ids)) != len(ids):
                    failures.append(1)
            times, wire, cpu = _measure(bus_cycle, args.cycles, counters)
            label = 'sync write + ' + ('fast sync read' if fast else 'sync read')
            ratios[label] = _report(label + ' (ServoBus)', times, wire, cpu, args.cycles,
                                    len(ids), args.return_delay_us * 1e-6)
            print(f'  failed reads (reply timeouts)  {len(failures):7d}')
            bus.close()

        config = replace(config, port=link)
        controller = BridgeController(config, ServoBus(link, BAUD), bus_error=BusError)
        controller.start(time.monotonic())
        names = config.joint_names
        state = {'k': 0}

        def control_cycle():
            state['k'] += 1
            controller.on_joint_state(names, [0.01 * (state['k'] % 50)] * len(names),
                                      time.monotonic())
            controller.cycle(time.monotonic())
        before = counters()[3].get(emu.SYNC_READ, 0)
        times, wire, cpu = _measure(control_cycle, args.cycles, counters)
        reads = counters()[3].get(emu.SYNC_READ, 0) - before
        _report('full BridgeController.cycle (envelope + health checks)', times, wire, cpu,
                args.cycles, len(ids) * reads / args.cycles, args.return_delay_us * 1e-6)
        controller.shutdown()
        for label, ratio in ratios.items():
            print(f'{label}: target >= 90 % of the limit-bound rate '
                  f'{"met" if ratio >= 0.9 else "NOT met"} ({ratio * 100:.1f} %)')
    finally:
        ours.send('stop')
        ours.recv()
        server.join(timeout=5)
    return 0


if __name__ == '__main__':
    sys.exit(main())
