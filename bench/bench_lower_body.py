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
Planning cost per step, and the footstep search against the exhaustive optimum.

Run: .venv/bin/python bench/bench_lower_body.py [--courses flat stairs_up ...]
     .venv/bin/python bench/bench_lower_body.py --whole-body   (obstacle courses, upper body on)

For every walking step on the lower-body courses (upper-body planning off) it records the wall
and CPU time of the whole step (profile + footstep window + leg motion + 3D check), and for every
footstep window it also solves the same window exhaustively to compare effort and time (targets:
effort ratio <= 1.05, time <= 1/20). CPU time is reported because the machine may be shared.

     .venv/bin/python bench/bench_lower_body.py --against ../other-checkout [--rounds 8]
         [--whole-body]

walks every course (with --whole-body: the obstacle courses, upper body on) with this package
and with the one in another checkout in one process,
course by course in alternating order, checks that both produce the same frames, and reports
both CPU times per step: on a shared machine whose speed drifts, separate runs differ by more
than most changes do.
"""
import argparse
import dataclasses
import importlib
import importlib.util
import os
import re
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'test'))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_common import machine  # noqa: E402
from course_runs import scene, skeleton  # noqa: E402
from digital_actor_planner.cli import read_commands  # noqa: E402
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands  # noqa: E402
from digital_actor_planner.core.footsteps import FootstepPlanner  # noqa: E402
import numpy as np  # noqa: E402

COURSES = ('flat', 'slope', 'stairs_up', 'stairs_down', 'gap', 'figure8_trap', 'blocks',
           'rough', 'turn')
OBSTACLE_COURSES = ('low_beam', 'table', 'pillars', 'uneven_beam')
#: Slowest steps (the other package's) whose paired time --against also reports.
SLOWEST = 10
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')


class ComparingPlanner(FootstepPlanner):
    """Footstep planner that also solves each window exhaustively and records both."""

    def __init__(self, inner):
        super().__init__(inner.config, inner.leg)
        self.records = []
        self.calls = 0
        # Per window (a call not banning a first footstep): its configuration and the
        # exhaustive search's first time, None where either search found none.
        self.windows = []

    def plan(self, profile, stance_side, stance_s, stance_height, swing_s, swing_height, s_init,
             previous_length, start=None, banned_first=(), max_length=np.inf):
        # The walk's first window follows the scene's loading and the actor's making, not a
        # walking step: its first call is reported apart.
        first = self.calls == 0
        self.calls += 1
        t0 = time.process_time()
        window = super().plan(profile, stance_side, stance_s, stance_height, swing_s,
                              swing_height, s_init, previous_length, start=start,
                              banned_first=banned_first, max_length=max_length)
        t1 = time.process_time()
        if not banned_first:
            arguments = (profile, stance_side, stance_s, stance_height, swing_s, swing_height,
                         s_init, previous_length)
            exhaustive = []
            for _ in range(2):
                t2 = time.process_time()
                best = self.plan_exhaustive(*arguments)
                exhaustive.append(time.process_time() - t2)
            # Warm: the window planned again twice (its tables too), the best of the three.
            ours = t1 - t0
            for _ in range(2):
                t2 = time.process_time()
                super().plan(*arguments, start=start, max_length=max_length)
                ours = min(ours, time.process_time() - t2)
            found = window is not None and best is not None
            self.windows.append((window.indices if window is not None else None,
                                 exhaustive[0] if found else None))
            if found:
                self.records.append(((window.effort + 1e-3) / (best.effort + 1e-3),
                                     (t1 - t0) / max(exhaustive[0], 1e-9),
                                     ours / max(min(exhaustive), 1e-9),
                                     window.evaluated / best.evaluated, first,
                                     t1 - t0, exhaustive[0]))
        return window


class TimingPlanner(FootstepPlanner):
    """
    Footstep planner that records the CPU time of each window's search.

    Footstep planner that records the CPU time of each window's search (a call not banning a first
    footstep) and its configuration, and runs nothing else.
    """

    def __init__(self, inner):
        super().__init__(inner.config, inner.leg)
        self.windows = []

    def plan(self, *arguments, banned_first=(), **keywords):
        started = time.process_time()
        window = super().plan(*arguments, banned_first=banned_first, **keywords)
        elapsed = time.process_time() - started
        if not banned_first:
            self.windows.append((window.indices if window is not None else None, elapsed))
        return window


def _alone_ratios(sc, commands, compared, walks):
    """
    Time the default search alone over more walks of a course.

    The default search timed alone in ``walks`` more walks of a course, nothing but the actor
    running between its calls: each window's median time over the walks divided by the exhaustive
    search's first time in the compared walk (``compared.windows``), and whether the window is the
    walk's first.
    """
    times = []
    for _ in range(walks):
        actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                      start=sc.start)
        timing = TimingPlanner(actor._planner)
        actor._planner = timing
        run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                     [c.angular_z for c in commands])
        # The walks are deterministic: the same windows as the compared walk's.
        if [w[0] for w in timing.windows] != [w[0] for w in compared.windows]:
            raise RuntimeError('a walk timing the search alone planned other windows than the '
                               'compared walk: the walks are no longer deterministic')
        times.append([w[1] for w in timing.windows])
    medians = np.median(np.array(times), axis=0)
    return [(median / exhaustive, k == 0)
            for k, (median, (_, exhaustive)) in enumerate(zip(medians, compared.windows))
            if exhaustive is not None]


def _load_other(root):
    """Import the actor module of the package in another checkout as ``other_dap``."""
    package = os.path.join(os.path.abspath(root), 'digital_actor_planner')
    # A module that imports its siblings by absolute name would get this package's instead.
    absolute = re.compile(r'^\s*(from|import)\s+digital_actor_planner\b', re.MULTILINE)
    for name in sorted(os.listdir(os.path.join(package, 'core'))):
        if not name.endswith('.py'):
            continue
        with open(os.path.join(package, 'core', name)) as source:
            if absolute.search(source.read()):
                raise SystemExit(f'{root}: core/{name} imports digital_actor_planner by '
                                 'absolute name; make its imports relative to compare it')
    for name, path in (('other_dap', package), ('other_dap.core', os.path.join(package, 'core'))):
        spec = importlib.util.spec_from_file_location(
            name, os.path.join(path, '__init__.py'), submodule_search_locations=[path])
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    # Its kernels, compiled under the name other_dap, are cached away from its own tree: in
    # its __pycache__ they would be read back by its own imports and fail there (the pickled
    # kernels refer to other_dap). Every core module is imported here, while that holds (the
    # actor imports some only when they are needed).
    try:
        import numba
    except ImportError:
        numba = None
    if numba is not None:
        cache_dir = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = os.path.join(tempfile.gettempdir(), 'dap_against_numba_cache')
    try:
        for name in sorted(os.listdir(os.path.join(package, 'core'))):
            if name.endswith('.py') and name != '__init__.py':
                importlib.import_module('other_dap.core.' + name[:-3])
    finally:
        if numba is not None:
            numba.config.CACHE_DIR = cache_dir
    return importlib.import_module('other_dap.core.actor')


def _time_steps(actor):
    """Make ``actor`` record the CPU time of each walking step it plans (s); returns the list."""
    cpu = []
    plan_next = actor.plan_next

    def timed():
        c0 = time.process_time()
        block = plan_next()
        if block.status == 'walking':
            cpu.append(time.process_time() - c0)
        return block

    actor.plan_next = timed
    return cpu


def _walk(actor_module, sc, commands, upper):
    """CPU time of each walking step (s) and the bytes of all frames of one course."""
    actor = actor_module.Actor(skeleton(), sc.environment,
                               actor_module.ActorConfig(plan_upper_body=upper), start=sc.start)
    cpu = _time_steps(actor)
    blocks = actor_module.run_commands(actor, [c.time for c in commands],
                                       [c.linear_x for c in commands],
                                       [c.angular_z for c in commands])
    return cpu, np.concatenate([b.frames for b in blocks]).tobytes()


def compare(courses, other_root, rounds, upper=False, unpaired=False):
    """
    Paired CPU times per step of this package and the one at ``other_root``.

    Steps pair only where both packages walk the same frames; with ``unpaired`` packages that
    walk differently (other steps, other counts) are compared by their steps' distributions.
    """
    from digital_actor_planner.core import actor as this_actor
    labels = {'this': this_actor, 'other': _load_other(other_root)}
    # Each package walks the scene as its own loader builds it (their environments' internals
    # may differ).
    other_loader = sys.modules.get('other_dap.core.scene') or sys.modules[
        'other_dap.core.environment']
    setups = [(name, {'this': scene(name), 'other': other_loader.load_scene(
                   os.path.join(ROOT, 'config', 'scenes', name + '.yaml'))},
               read_commands(os.path.join(ROOT, 'config', 'scenes', name + '.csv')))
              for name in courses]
    per_round = {label: [] for label in labels}
    differing = set()
    print(f'load average {os.getloadavg()[0]:.1f}; {machine()}; other = {other_root}')
    print('| round | this p50 ms | this p99 ms | other p50 ms | other p99 ms |')
    print('|---|---:|---:|---:|---:|')
    for r in range(rounds):
        cpu = {label: [] for label in labels}
        for i, (name, sc, commands) in enumerate(setups):
            order = list(labels) if (r + i) % 2 == 0 else list(labels)[::-1]
            frames = {}
            for label in order:
                times, frames[label] = _walk(labels[label], sc[label], commands, upper)
                cpu[label] += times
            if frames['this'] != frames['other']:
                if not unpaired:
                    raise SystemExit(f'{name}: the two packages produce different frames '
                                     f'(--unpaired compares their distributions)')
                differing.add(name)
        for label in labels:
            per_round[label].append(np.array(cpu[label]))
        print(f'| {r} | {1e3 * np.percentile(cpu["this"], 50):.2f} | '
              f'{1e3 * np.percentile(cpu["this"], 99):.2f} | '
              f'{1e3 * np.percentile(cpu["other"], 50):.2f} | '
              f'{1e3 * np.percentile(cpu["other"], 99):.2f} |')
    # Each step's fastest round is the least disturbed one.
    best = {label: np.min(per_round[label], axis=0) for label in labels}
    for label in labels:
        print(f'{label}: median of the rounds p50 '
              f'{1e3 * np.median([np.percentile(c, 50) for c in per_round[label]]):.2f} ms, p99 '
              f'{1e3 * np.median([np.percentile(c, 99) for c in per_round[label]]):.2f} ms; '
              f'fastest round per step p50 {1e3 * np.percentile(best[label], 50):.2f} ms, '
              f'p99 {1e3 * np.percentile(best[label], 99):.2f} ms')
    if differing:
        p50, p99 = ({label: np.percentile(best[label], q) for label in labels} for q in (50, 99))
        print(f'this / other: p50 {p50["this"] / p50["other"]:.3f}, '
              f'p99 {p99["this"] / p99["other"]:.3f}, '
              f'mean per step {best["this"].mean() / best["other"].mean():.3f} (fastest rounds; '
              f'{best["this"].size} and {best["other"].size} steps); different frames on '
              f'{", ".join(sorted(differing))}')
        return
    # p99 of a few dozen steps comes from the slowest few: their own paired ratio.
    slowest = np.argsort(best['other'])[-SLOWEST:]
    print(f'this / other per step (fastest rounds): median '
          f'{np.median(best["this"] / best["other"]):.3f}, the {len(slowest)} slowest steps '
          f'{best["this"][slowest].sum() / best["other"][slowest].sum():.3f} (their sum); '
          f'frames identical on every course')


@dataclasses.dataclass(frozen=True)
class FootstepTargets:
    """
    The footstep targets judged on the default search's windows.

    The effort ratio (ours over the exhaustive optimum's) on average and at p95, the time ratio
    in the walk at p95 (the strictest of the readings) and its median, and every window's time
    summed, ours and the exhaustive search's, ms.
    """

    windows: int
    effort_mean: float
    effort_p95: float
    time_p95: float
    time_median: float
    ours_ms: float
    exhaustive_ms: float

    @property
    def effort_met(self) -> bool:
        """Return whether the effort target (<= 1.05 on average and at p95) is met."""
        return max(self.effort_mean, self.effort_p95) <= 1.05

    @property
    def time_met(self) -> bool:
        """Return whether the time target (<= 1/20 at p95) is met."""
        return self.time_p95 <= 0.05

    def sentence(self) -> str:
        """Return the verdict as the benchmark prints it last."""
        return (f'footstep targets (default search, {self.windows} windows): effort ratio mean '
                f'{self.effort_mean:.3f}, p95 {self.effort_p95:.3f} (target <= 1.05: '
                f'{"met" if self.effort_met else "NOT met"}); time ratio in the walk p95 '
                f'{self.time_p95:.4f} (target <= 1/20: {"met" if self.time_met else "NOT met"}'
                f'), median {self.time_median:.4f}, every window together '
                f'{self.ours_ms:.2f} ms against {self.exhaustive_ms:.1f} ms = '
                f'{self.ours_ms / self.exhaustive_ms:.4f}')


def main(argv=None):
    """
    Run the benchmark; return the footstep targets' verdict (None with --against or --whole-body).

    Returns
    -------
    FootstepTargets or None

    """
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--courses', nargs='*')
    parser.add_argument('--whole-body', action='store_true',
                        help='plan the upper body too (default courses: the obstacle courses)')
    parser.add_argument('--against', metavar='CHECKOUT',
                        help='compare with the package in another checkout, paired in one '
                             'process')
    parser.add_argument('--rounds', type=int, default=8, help='rounds of --against')
    parser.add_argument('--unpaired', action='store_true',
                        help="with --against: compare the steps' distributions where the two "
                             'packages walk different frames')
    parser.add_argument('--walks', type=int, default=5,
                        help='walks of each course timing the default footstep search alone '
                             '(0: none)')
    args = parser.parse_args(argv)
    courses = args.courses or (OBSTACLE_COURSES if args.whole_body else COURSES)
    if args.against:
        compare(courses, args.against, args.rounds, args.whole_body, args.unpaired)
        return None
    upper = args.whole_body
    wall_all, cpu_all, slowest = [], [], []
    ratios, speed, warm, judged, firsts, spent = ({False: [], True: []} for _ in range(6))
    alone = []
    print(f'load average {os.getloadavg()[0]:.1f}; {machine()}')
    print('| course | steps | wall p50 ms | wall p99 ms | CPU p50 ms | CPU p99 ms | x real time |')
    print('|---|---:|---:|---:|---:|---:|---:|')
    for name in courses:
        sc = scene(name)
        commands = read_commands(os.path.join(ROOT, 'config', 'scenes', name + '.csv'))
        actor = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=upper),
                      start=sc.start)
        cpu = _time_steps(actor)
        started = time.perf_counter()
        blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                              [c.angular_z for c in commands])
        elapsed = time.perf_counter() - started
        wall = [b.planning_time for b in blocks if b.status == 'walking']
        wall_all += wall
        cpu_all += cpu
        slowest += [(seconds, name, step) for step, seconds in enumerate(cpu)]
        print(f'| {name} | {len(wall)} | {1e3 * np.percentile(wall, 50):.2f} | '
              f'{1e3 * np.percentile(wall, 99):.2f} | {1e3 * np.percentile(cpu, 50):.2f} | '
              f'{1e3 * np.percentile(cpu, 99):.2f} | {blocks[-1].times[-1] / elapsed:.0f} |')
        if upper:
            continue
        for greedy in (False, True):
            inner = actor._planner
            comparing = ComparingPlanner(FootstepPlanner(
                dataclasses.replace(inner.config, greedy_restart=greedy), inner.leg))
            actor2 = Actor(skeleton(), sc.environment, ActorConfig(plan_upper_body=False),
                           start=sc.start)
            actor2._planner = comparing
            run_commands(actor2, [c.time for c in commands], [c.linear_x for c in commands],
                         [c.angular_z for c in commands])
            ratios[greedy] += [r[0] for r in comparing.records]
            speed[greedy] += [r[1] for r in comparing.records]
            warm[greedy] += [r[2] for r in comparing.records]
            judged[greedy] += [r[3] for r in comparing.records]
            firsts[greedy] += [r[4] for r in comparing.records]
            spent[greedy] += [r[5:] for r in comparing.records]
            if greedy and args.walks > 0:
                alone += _alone_ratios(sc, commands, comparing, args.walks)
    print(f'| all | {len(wall_all)} | {1e3 * np.percentile(wall_all, 50):.2f} | '
          f'{1e3 * np.percentile(wall_all, 99):.2f} | {1e3 * np.percentile(cpu_all, 50):.2f} | '
          f'{1e3 * np.percentile(cpu_all, 99):.2f} | |')
    # With n steps, p99 lies between the two slowest (n <= 100) or near them.
    print('slowest steps (CPU ms, course and walking step from 0): ' + ', '.join(
        f'{1e3 * seconds:.1f} {name} {step}'
        for seconds, name, step in sorted(slowest)[-5:][::-1]))
    if upper:
        return None
    print()
    print('footstep windows compared with the exhaustive optimum '
          '(each course walked again with each search):')
    print('both compiled (footstep_search), the exhaustive one judging every configuration with '
          "the search's own effort kernel from scratch (no prefix memo), each with its foothold "
          'table; time ratio in the walk: '
          'the first call of each search, ours right after planning the step before (cold '
          'caches), then the exhaustive one, over every window and over the windows after a '
          "step (not the first of each walk, which follows the scene's loading); warm: each "
          'search run again, the best of 3 (ours) and of 2 (exhaustive); judged: '
          'configurations judged, ours / all')
    print('| search | windows | effort ratio mean | median | p95 | max '
          '| time ratio in the walk median | p95 | after a step p95 | warm median | p95 '
          '| judged median | p95 |')
    print('|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
    for greedy, label in ((False, 'paper: BFS + hill-climbing'),
                          (True, '+ climb from a greedy start (default)')):
        r, t, w, j = ratios[greedy], speed[greedy], warm[greedy], judged[greedy]
        stepped = [ratio for ratio, first in zip(t, firsts[greedy]) if not first]
        print(f'| {label} | {len(r)} | {np.mean(r):.3f} | {np.median(r):.3f} | '
              f'{np.percentile(r, 95):.3f} | {np.max(r):.3f} | {np.median(t):.4f} | '
              f'{np.percentile(t, 95):.4f} | {np.percentile(stepped, 95):.4f} | '
              f'{np.median(w):.4f} | {np.percentile(w, 95):.4f} | '
              f'{np.median(j):.4f} | {np.percentile(j, 95):.4f} |')
    print("the default search's first window of each walk, time ratio in the walk: "
          + ', '.join(f'{ratio:.3f}' for ratio, first in sorted(zip(speed[True], firsts[True]))
                      if first))
    if alone:
        every = [ratio for ratio, _ in alone]
        stepped = [ratio for ratio, first in alone if not first]
        print(f'the default search timed alone in {args.walks} more walks of each course '
              f"(nothing but the actor between its calls), each window's median time over "
              f"the walks against the exhaustive search's: median {np.median(every):.4f}, "
              f'p95 {np.percentile(every, 95):.4f}, after a step p95 '
              f'{np.percentile(stepped, 95):.4f}')
    # The footstep targets, judged on the default search: the effort ratio on average
    # and at p95, the time ratio at p95 of the first calls in the walk (the strictest of the
    # readings above; the median and the sum of all windows' times are printed beside it).
    targets = FootstepTargets(
        windows=len(speed[True]), effort_mean=float(np.mean(ratios[True])),
        effort_p95=float(np.percentile(ratios[True], 95)),
        time_p95=float(np.percentile(speed[True], 95)),
        time_median=float(np.median(speed[True])),
        ours_ms=1e3 * sum(o for o, _ in spent[True]),
        exhaustive_ms=1e3 * sum(e for _, e in spent[True]))
    print(targets.sentence())
    return targets


if __name__ == '__main__':
    main()
