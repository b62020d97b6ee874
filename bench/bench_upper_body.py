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
Benchmark the upper-body planner (paper §5) per step, side by side with OMPL.

Courses: open ground, a low beam (underside 1.60 m: the waist must bend), a table beside the
path (top 0.78 m: the left arm must flex) and two pillars closer than the shoulders (the waist
must turn). The actor walks along +x at 0.9 m/s. A reference CT-roadmap plan over the whole walk
gives the start state of every step window (61 frames = 0.6 s at 100 Hz, one every
``--stride`` frames), so every per-step problem is feasible and both planners get the same
problems: the same branch CT-spaces, time grid and validity checker (``CTSpace``), waist, then
left arm, then right arm, with the earlier branches fixed, after the same check of the whole
motion pattern. The CT-roadmap keeps its roadmap from window to window (§5.2); it is run
``--repeat`` times per window for the per-course table, and its first run of each window is the
one compared with the peers, which see each problem once.

The OMPL peers (RRTConnect and PRM) plan each branch that is not free along its motion pattern
over (branch joints x time) with a motion validator that allows only forward time and joint
speeds within the limits and checks collisions at every frame between the ends. Their goal is
the motion pattern at the last frame when it is legal there, else the reference plan's
configuration (a legal one); the CT-roadmap accepts any legal configuration at the last frame.

Usage::

    .venv/bin/python bench/bench_upper_body.py [--repeat 3] [--stride 10] [--ompl-time 0.5]
"""
import argparse
import os
import sys
import time

from digital_actor_planner.core.body_model import TimedBody
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.ct_space import CTSpace
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.core.upper_body import (
    BRANCH_ORDER, motion_patterns, UpperBodyConfig, UpperBodyPlanner)
import numpy as np
import trimesh

RATE = 100.0
WINDOW = 61


def _box(lower, upper):
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    mesh = trimesh.creation.box(extents=upper - lower)
    mesh.apply_translation((lower + upper) / 2)
    return mesh


def courses():
    """Name -> obstacle meshes (the ground is added to each)."""
    return {
        'open': [],
        'beam 1.60 m': [_box([0.6, -1.0, 1.60], [0.8, 1.0, 1.80])],
        'table': [_box([0.3, 0.21, 0.0], [1.1, 1.0, 0.78])],
        'pillars': [_box([0.6, 0.235, 0.0], [0.75, 0.6, 2.2]),
                    _box([0.6, -0.6, 0.0], [0.75, -0.235, 2.2])],
    }


def walk(skeleton, k=320, x0=-1.0, speed=0.9):
    times = np.arange(k) / RATE
    q = np.tile(skeleton.neutral(), (k, 1))
    q[:, skeleton.index['root_x']] = x0 + speed * times
    q[:, skeleton.index['root_z']] = 0.92
    phase = 2 * np.pi * times / 1.2
    q[:, skeleton.index['left_hip_pitch']] = 0.3 * np.sin(phase)
    q[:, skeleton.index['right_hip_pitch']] = -0.3 * np.sin(phase)
    return times, motion_patterns(skeleton, q)


class OmplBranchPlanner:
    """Prioritized waist -> left arm -> right arm planning with an OMPL planner per branch."""

    def __init__(self, planner_name, time_limit):
        from ompl import base, geometric, util
        util.setLogLevel(util.LogLevel.LOG_NONE)
        self.base, self.geometric = base, geometric
        self.planner_name = planner_name
        self.time_limit = time_limit

    def _solve_branch(self, space, start, goal):
        base, geometric = self.base, self.geometric
        d = space.dimension
        times = space.times
        t0, t1 = float(times[0]), float(times[-1])
        state_space = base.RealVectorStateSpace(d + 1)
        bounds = base.RealVectorBounds(d + 1)
        for i in range(d):
            bounds.setLow(i, float(space.lower[i]))
            bounds.setHigh(i, float(space.upper[i]))
        bounds.setLow(d, t0)
        bounds.setHigh(d, t1)
        state_space.setBounds(bounds)
        info = base.SpaceInformation(state_space)

        def frame_of(t):
            return int(np.clip(np.rint((t - t0) * RATE), 0, len(times) - 1))

        def valid(state):
            q = np.array([state[i] for i in range(d)])
            return space.is_valid(q, frame_of(state[d]))

        class ForwardInTime(base.MotionValidator):
            """Only forward time, bounded speed, collision-free at every frame between."""

            def checkMotion(self, a, b, *rest):
                ta, tb = a[d], b[d]
                if not tb > ta:
                    return False
                qa = np.array([a[i] for i in range(d)])
                qb = np.array([b[i] for i in range(d)])
                if np.any(np.abs(qb - qa) > space.speed_limit * (tb - ta)):
                    return False
                fa, fb = frame_of(ta), frame_of(tb)
                frames = np.arange(fa + 1, fb + 1)
                if not len(frames):
                    return space.is_valid(qb, fb)
                s = np.clip((times[frames] - ta) / (tb - ta), 0.0, 1.0)
                rows = qa + s[:, None] * (qb - qa)
                return space.first_invalid(rows, frames) < 0

        info.setStateValidityChecker(valid)
        validator = ForwardInTime(info)
        info.setMotionValidator(validator)
        info.setup()
        problem = base.ProblemDefinition(info)
        start_state, goal_state = info.allocState(), info.allocState()
        for i in range(d):
            start_state[i] = float(start[i])
            goal_state[i] = float(goal[i])
        start_state[d], goal_state[d] = t0, t1
        problem.setStartAndGoalStates(start_state, goal_state)
        planner = (geometric.RRTConnect(info) if self.planner_name == 'RRTConnect'
                   else geometric.PRM(info))
        planner.setProblemDefinition(problem)
        planner.setup()
        planner.solve(self.time_limit)
        if not problem.hasExactSolution():
            return None
        path = problem.getSolutionPath()
        states = [(np.array([path.getState(i)[j] for j in range(d)]), path.getState(i)[d])
                  for i in range(path.getStateCount())]
        stamps = np.array([t for _, t in states])
        if np.any(np.diff(stamps) <= 0):
            return None  # an undirected roadmap edge taken backwards in time
        values = np.array([q for q, _ in states])
        out = np.stack([np.interp(times, stamps, values[:, j]) for j in range(d)], axis=1)
        out[0] = start
        return out

    def plan(self, planner, times, frames, reference):
        """Plan one step; return (ok, deviation rad, seconds)."""
        began = time.perf_counter()
        body = TimedBody(planner.kinematics, planner.shapes, planner.environment, frames)
        out = frames.copy()
        # The same check of the whole pattern as the CT-roadmap's plan starts with.
        legality = planner.pattern_checks(times, body)
        if all(start and motion for start, motion in legality.values()):
            return True, 0.0, time.perf_counter() - began
        moved = False
        for name in BRANCH_ORDER:
            indices = planner.indices[name]
            start = frames[0, indices].copy()
            objective = frames[:, indices].copy()
            objective[0] = np.clip(2 * objective[1] - objective[2],
                                   planner.skeleton.lower[indices],
                                   planner.skeleton.upper[indices])
            # The same checks of the start and of the motion pattern as the CT-roadmap's plan.
            start_legal, objective_legal = (planner.start_and_objective(times, body, name)
                                            if moved else legality[name])
            if not start_legal:
                return False, 0.0, time.perf_counter() - began
            if objective_legal:
                # The body already holds this motion (the CT-roadmap's fast path).
                continue
            # Only a branch that must leave its motion pattern needs its CT-space.
            space = CTSpace(name, body, times, objective, planner._checked[name],
                            planner._obstacles[name])
            goal = (objective[-1] if space.is_valid(objective[-1], len(times) - 1)
                    else reference[-1, indices])
            path = self._solve_branch(space, start, goal)
            if path is None:
                return False, 0.0, time.perf_counter() - began
            out[:, indices] = path
            if name != BRANCH_ORDER[-1]:
                body.set_branch(indices, path, space.steps)
                moved = True
        upper = planner.upper_indices
        deviation = float(np.max(np.abs(out[1:, upper] - frames[1:, upper])))
        return True, deviation, time.perf_counter() - began


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().split('\n')[0])
    parser.add_argument('--repeat', type=int, default=3, help='CT-roadmap runs per window')
    parser.add_argument('--stride', type=int, default=10, help='frames between windows')
    parser.add_argument('--ompl-time', type=float, default=0.5,
                        help='OMPL time limit per branch problem, s')
    parser.add_argument('--no-ompl', action='store_true', help='benchmark the CT-roadmap only')
    args = parser.parse_args(argv)

    skeleton = Skeleton()
    times, frames = walk(skeleton)
    ground = _box([-2.5, -1.5, -0.1], [3.5, 1.5, 0.0])
    peers = {}
    if not args.no_ompl:
        try:
            peers = {name: OmplBranchPlanner(name, args.ompl_time)
                     for name in ('RRTConnect', 'PRM')}
        except ImportError as error:
            print(f'ompl does not import: {error!r}; benchmarking the CT-roadmap only')
    rows = {}
    per_course = []
    searched = set()  # problems where the motion pattern was not legal for some branch
    for course, obstacles in courses().items():
        environment = Environment([ground, *obstacles], resolution=0.05)
        collision = BodyCollision(skeleton, environment)
        reference_planner = UpperBodyPlanner(skeleton, collision,
                                             UpperBodyConfig(check_budget=1_000_000),
                                             rng=np.random.default_rng(0))
        reference = reference_planner.plan(times, frames)
        if not reference.ok:
            print(f'{course}: no reference plan ({reference.reason}); skipped')
            continue
        planner = UpperBodyPlanner(skeleton, collision, UpperBodyConfig(),
                                   rng=np.random.default_rng(1))
        course_times = []
        for begin in range(0, len(times) - WINDOW + 1, args.stride):
            window = slice(begin, begin + WINDOW)
            step_times, step_frames = times[window], frames[window].copy()
            step_frames[0] = reference.frames[begin]
            for repeat in range(args.repeat):
                cpu = time.process_time()
                plan = planner.plan(step_times, step_frames)
                cpu = time.process_time() - cpu
                if repeat == 0:
                    # The peers see each problem once; a repeat would find the roadmap grown on
                    # this very problem, so only first runs enter the peer comparison.
                    rows.setdefault('CT-roadmap', []).append(
                        (plan.ok, plan.deviation, plan.planning_time, course, begin, cpu))
                    if not all(r.get('fast', False) for r in plan.per_branch.values()):
                        searched.add((course, begin))
                course_times.append((plan.planning_time, cpu))
            for name, peer in peers.items():
                cpu = time.process_time()
                ok, deviation, seconds = peer.plan(planner, step_times, step_frames,
                                                   reference.frames[window])
                cpu = time.process_time() - cpu
                rows.setdefault(name, []).append((ok, deviation, seconds, course, begin, cpu))
        ms = np.array(course_times) * 1e3
        per_course.append((course, len(ms), np.percentile(ms[:, 0], 50),
                           np.percentile(ms[:, 0], 99), np.percentile(ms[:, 1], 50),
                           np.percentile(ms[:, 1], 99), reference.deviation))

    print('\n### Upper-body planning per step (61 frames = 0.6 s), CT-roadmap\n')
    print('Wall time, and CPU time of the process (less sensitive to a shared machine).\n')
    print('| course | plans | p50 ms | p99 ms | p50 CPU ms | p99 CPU ms | '
          'max deviation of the walk, rad |')
    print('|---|---:|---:|---:|---:|---:|---:|')
    for course, n, p50, p99, cpu50, cpu99, deviation in per_course:
        print(f'| {course} | {n} | {p50:.2f} | {p99:.2f} | {cpu50:.2f} | {cpu99:.2f} | '
              f'{deviation:.3f} |')

    print('\n### Peer comparison on the same per-step problems (obstacle courses)\n')
    print('Deviation: largest |planned - motion pattern| over the step, rad. "common" is the mean '
          'over the problems every planner solved.\n')
    print('| planner | problems | success | p50 ms | p99 ms | p50 CPU ms | p99 CPU ms | '
          'mean deviation | max deviation | mean deviation, common |')
    print('|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
    solved = {}
    for name, results in rows.items():
        solved[name] = {(r[3], r[4]): r[1] for r in results if r[0] and r[3] != 'open'}
    common = set.intersection(*(set(v) for v in solved.values())) if solved else set()
    for name, results in rows.items():
        results = [r for r in results if r[3] != 'open']
        ok = np.array([r[0] for r in results])
        ms = np.array([r[2] for r in results]) * 1e3
        cpu = np.array([r[5] for r in results]) * 1e3
        deviation = np.array([r[1] for r in results if r[0]])
        mean_dev = deviation.mean() if len(deviation) else float('nan')
        max_dev = deviation.max() if len(deviation) else float('nan')
        common_dev = (np.mean([solved[name][key] for key in common]) if common
                      else float('nan'))
        print(f'| {name} | {len(results)} | {ok.mean() * 100:.1f} % | '
              f'{np.percentile(ms, 50):.2f} | {np.percentile(ms, 99):.2f} | '
              f'{np.percentile(cpu, 50):.2f} | {np.percentile(cpu, 99):.2f} | '
              f'{mean_dev:.3f} | {max_dev:.3f} | {common_dev:.3f} ({len(common)}) |')
    # The same times on the problems every planner solved (a failure costs a peer its whole
    # time limit), and on those of them where some branch could not keep its pattern (about
    # half the problems are answered by the one-batch check of the pattern, the same code in
    # every planner).
    print('\nTime on the problems every planner solved (wall ms), and on those of them where '
          'some branch had to search:\n')
    print('| planner | solved by all | p50 | mean | total | searched | p50 | mean | total |')
    print('|---|---:|---:|---:|---:|---:|---:|---:|---:|')
    for name, results in rows.items():
        by_key = {(r[3], r[4]): 1e3 * r[2] for r in results}
        both = np.array([by_key[key] for key in sorted(common)])
        hard = np.array([by_key[key] for key in sorted(common & searched)])
        cells = []
        for values in (both, hard):
            stats = ['', '', '']
            if len(values):
                stats = [f'{np.percentile(values, 50):.2f}', f'{values.mean():.2f}',
                         f'{values.sum():.0f}']
            cells += [str(len(values))] + stats
        print(f'| {name} | ' + ' | '.join(cells) + ' |')
    print(f'\n(command: {" ".join([sys.executable.split("/")[-1]] + sys.argv)}; '
          f'OMPL time limit {args.ompl_time} s per branch problem; load average '
          f'{", ".join(f"{x:.1f}" for x in os.getloadavg())} on {os.cpu_count()} cores)')


if __name__ == '__main__':
    main()
