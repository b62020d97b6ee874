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
Upper-body compliant motion: objective motion patterns and prioritized planning (paper §5).

§5.1 defines the motion patterns O_x(t), x in {waist, left arm, right arm}, that the upper body
follows whenever it can: the waist kept erect, the arms swinging alternately in step with the
legs. §5 plans the branches in priority order, waist first, then the arms, each in its own
configuration-time space with the earlier branches fixed.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import time
from typing import Dict, Optional, Tuple
import weakref

import numpy as np

from .body_model import BodyKinematics, BodyShapes, EnvironmentIndex, TimedBody
from .ct_roadmap import CTRoadmap, direct_return, objective_grid, ROADMAP_SEARCHES, warm_up
from .ct_space import branch_layout, branch_model, CTSpace
from .jit import kernel
from .settings import check_settings, require, setting
from .skeleton import Skeleton

#: Shoulder roll that keeps a hanging arm clear of the torso and the thigh, rad.
ARM_CLEARANCE_ROLL = 0.06
#: Elbow flexion of a relaxed walking arm, rad.
RELAXED_ELBOW = 0.25
#: Extra elbow flexion per radian of forward arm swing, rad/rad.
ELBOW_SWING_GAIN = 0.2
#: Half the hip-pitch difference of a normal stride, rad: the arm swing saturates around it.
NOMINAL_HIP_SWING = 0.35


def motion_patterns(skeleton: Skeleton, frames: np.ndarray,
                    swing_amplitude: float = 0.35) -> np.ndarray:
    """
    Fill the upper-body columns with the walking motion patterns O_x(t) (§5.1).

    The waist is erect (yaw = pitch = 0). Each arm swings opposite to the leg on its own side:
    the left shoulder pitch follows the right hip pitch and the right shoulder pitch the left,
    through half the hip-pitch difference so the swing is centred on the hanging arm. The
    shoulder roll stays at a small abduction that keeps the arm clear of the body, the shoulder
    yaw at 0, and the elbow slightly flexed, flexing a little more as the arm swings forward.

    Parameters
    ----------
    skeleton
        The actor model (joint order and limits).
    frames
        (k, 22) float64 configurations, rad or m; the leg columns drive the arm swing.
    swing_amplitude
        Largest shoulder-pitch swing, rad, in [0, 1].

    Returns
    -------
    numpy.ndarray
        (k, 22) float64: a copy of ``frames`` with the waist and arm columns replaced, clipped
        to the joint limits.

    """
    frames = np.asarray(frames, dtype=float)
    if frames.ndim != 2 or frames.shape[1] != len(skeleton.joint_names):
        raise ValueError(f'frames must have shape (k, {len(skeleton.joint_names)}), '
                         f'got {frames.shape}')
    if not np.isfinite(frames).all():
        raise ValueError('frames contain NaN or infinite values')
    if not (np.isfinite(swing_amplitude) and 0.0 <= swing_amplitude <= 1.0):
        raise ValueError(f'swing_amplitude must be in [0, 1] rad, got {swing_amplitude}')
    out = frames.copy()
    waist, arms, right_hip, left_hip, lower, upper = _pattern_layout(skeleton)
    # Half the difference is zero-mean over a stride, so no per-block centring is needed and
    # successive blocks join continuously.
    stride = 0.5 * (frames[:, right_hip] - frames[:, left_hip])
    swing = swing_amplitude * np.tanh(stride / NOMINAL_HIP_SWING)
    _write_patterns(out, swing, waist, arms, lower, upper)
    return out


_PATTERN_LAYOUTS = weakref.WeakKeyDictionary()


def _pattern_layout(skeleton: Skeleton) -> tuple:
    """
    Return the columns and limits :func:`motion_patterns` writes, built once per skeleton.

    The columns and limits :func:`motion_patterns` writes, built once per skeleton: the waist's
    columns, the left then the right arm's (shoulder pitch, roll, yaw, elbow), the right and the
    left hip pitch, and every joint's lower and upper limit.
    """
    layout = _PATTERN_LAYOUTS.get(skeleton)
    if layout is None:
        index = skeleton.index
        arms = [index[f'{side}_{joint}'] for side in ('left', 'right')
                for joint in ('shoulder_pitch', 'shoulder_roll', 'shoulder_yaw', 'elbow')]
        layout = (np.asarray(skeleton.branch('waist'), dtype=np.int64),
                  np.array(arms, dtype=np.int64), index['right_hip_pitch'],
                  index['left_hip_pitch'], np.array(skeleton.lower, dtype=np.float64),
                  np.array(skeleton.upper, dtype=np.float64))
        _PATTERN_LAYOUTS[skeleton] = layout
    return layout


@kernel('void(f8[:, ::1], f8[::1], i8[::1], i8[::1], f8[::1], f8[::1])')
def _write_patterns(out, swing, waist, arms, lower, upper):
    """
    Write :func:`motion_patterns`' columns of ``out`` (k, 22).

    :func:`motion_patterns`' columns of ``out`` (k, 22): the ``waist`` columns erect; each arm's
    ``arms`` columns (the left arm's shoulder pitch, roll, yaw and elbow, then the right's)
    swinging with ``swing`` (k,) rad, the left arm forward where it is positive, the elbow flexing
    more as its arm swings forward; every value clipped to its joint's [``lower``, ``upper``] as
    np.minimum(np.maximum(value, lower), upper) would.
    """
    for f in range(out.shape[0]):
        for j in waist:
            out[f, j] = min(max(0.0, lower[j]), upper[j])
        for side in range(2):
            pitch = (1.0 if side == 0 else -1.0) * swing[f]
            first = 4 * side
            values = (pitch, ARM_CLEARANCE_ROLL, 0.0, RELAXED_ELBOW + ELBOW_SWING_GAIN * pitch)
            for i in range(4):
                j = arms[first + i]
                out[f, j] = min(max(values[i], lower[j]), upper[j])


# -- prioritized planning (§5) ------------------------------------------------------------
#: Planning order of the branches (§5: the waist first, then the arms).
BRANCH_ORDER = ('waist', 'left_arm', 'right_arm')
_LEG_LINKS = ('pelvis', 'left_hip', 'right_hip', 'left_thigh', 'right_thigh', 'left_shank',
              'right_shank', 'left_foot', 'right_foot')
_TRUNK_LINKS = ('waist', 'torso', 'head', 'left_shoulder', 'right_shoulder')
_ARM_LINKS = {side: (f'{side}_shoulder_roll_link', f'{side}_upper_arm', f'{side}_forearm')
              for side in ('left', 'right')}


@dataclass(frozen=True)
class UpperBodyConfig:
    """
    Settings of the upper-body compliant motion planner (§5.2).

    Why each rule and default is as it is: docs/UPPER_BODY.md.

    Attributes
    ----------
    roadmap_radius
        Distance r of a node grown when the search is stuck, rad (weighted norm).
    node_budget
        States a branch search may expand per plan.
    check_budget
        Configurations a branch search may check per plan: a work budget, so the same step
        gives the same plan however loaded the machine is.
    time_budget
        CPU time a branch search may take per plan, s, or None (no limit, the default: the
        work budgets above bound it). This process's CPU time, never wall time: on a loaded
        machine a plan takes longer, it does not come out differently.
    waist_back_lean
        How far back of upright the waist's search may pitch it, rad (the joint allows more):
        leaning back under an overhead obstacle while walking on only puts off meeting it.
    max_backtracks
        Backtracking steps a branch search may take per plan. 20: a failing search costs
        half of what 40 did (beside 200 random tables the slowest step fell from 1.1-1.2 to
        0.6-0.76 s, as many passed, the courses planned the same;
        bench/bench_arm_obstacles.py).
    preview_backtracks
        Backtracking steps a branch search may take from a block inside the preview (frames
        past the step's own, see :meth:`UpperBodyPlanner.plan`) before it gives up (>= 0).
    max_roadmap_nodes
        Largest CT-roadmap per branch (initial patterns plus grown nodes).
    hold_frames
        Frames a posture is held for when the search keeps it (>= 1).
    speed_fraction
        Fraction of the joint speed limits used to time motions between nodes, (0, 1].
    growth_attempts
        Random directions tried when growing a node.
    waist_weights, arm_weights
        Joint weights of the closeness to the objective: (yaw, pitch) and
        (shoulder pitch, shoulder roll, shoulder yaw, elbow), > 0.
    time_weight
        Weight of time in the CT-space distance, rad/s (>= 0).
    lasting_branches
        Branches whose search prefers postures that last through the blocked stretch ahead
        (:class:`CTRoadmap`, ``prefer_lasting``). The arms by default: beside a table the
        closest legal arm posture is often one that fails half-way along it. Not the waist:
        with it the low beam course leaned the waist back instead of bending, and one step took
        0.58 s to plan (measured).
    roadmap_search
        How the roadmaps expand a search state (:class:`CTRoadmap`, ``search``):
        ``'compiled'``, the runtime path, or ``'readable'``, the code of record; the same
        plans.

    """

    roadmap_radius: float = setting(0.3, 0.0, None, 'Distance r of a grown node.', 'rad',
                                    low_open=True)
    node_budget: int = setting(300, 1, None, 'States a branch search may expand per plan.')
    check_budget: int = setting(
        15000, 1, None, 'Configurations a branch search may check per plan.')
    time_budget: Optional[float] = setting(
        None, 0.0, None, 'CPU time a branch search may take per plan (None: no limit).', 's',
        low_open=True, optional=True, kind=float)
    max_backtracks: int = setting(
        20, 0, None, 'Backtracking steps a branch search may take per plan.')
    preview_backtracks: int = setting(
        1, 0, None, 'Backtracking steps from a block inside the preview before giving up.')
    max_roadmap_nodes: int = setting(
        64, 1, None, 'Largest CT-roadmap per branch (initial patterns plus grown nodes).')
    hold_frames: int = setting(5, 1, None, 'Frames a kept posture is held for.')
    speed_fraction: float = setting(
        0.8, 0.0, 1.0, 'Fraction of the joint speed limits motions between nodes use.',
        low_open=True)
    growth_attempts: int = setting(4, 1, None, 'Random directions tried when growing a node.')
    waist_weights: Tuple[float, float] = setting(
        (1.0, 1.0), doc='Joint weights (yaw, pitch) of the closeness to the objective, > 0.')
    arm_weights: Tuple[float, float, float, float] = setting(
        (1.0, 1.0, 1.0, 0.5), doc='Joint weights (shoulder pitch, roll, yaw, elbow) of the '
        'closeness to the objective, > 0.')
    time_weight: float = setting(1.0, 0.0, None, 'Weight of time in the CT-space distance.',
                                 'rad/s')
    lasting_branches: Tuple[str, ...] = setting(
        ('left_arm', 'right_arm'), doc='Branches whose search prefers postures that last '
        'through the blocked stretch ahead.')
    roadmap_search: str = setting('compiled', doc='How the roadmaps expand a search state.',
                                  choices=ROADMAP_SEARCHES)
    waist_back_lean: float = setting(
        0.0, 0.0, 1.0, 'How far back of upright the waist may pitch.', 'rad')

    def __post_init__(self):
        """Check every field against its declaration, the weights and the branches."""
        check_settings(self)
        for name, size in (('waist_weights', 2), ('arm_weights', 4)):
            weights = getattr(self, name)
            require(len(weights) == size, name, weights,
                    f'{name} must have {size} values, got {weights!r}')
            require(all(isinstance(w, (int, float)) and math.isfinite(w) and w > 0
                        for w in weights), name, weights,
                    f'{name} must all be finite numbers > 0, got {weights!r}')
        require(all(name in BRANCH_ORDER for name in self.lasting_branches), 'lasting_branches',
                self.lasting_branches, f'lasting_branches must name branches of {BRANCH_ORDER}, '
                f'got {self.lasting_branches!r}')
        initial = len(_waist_patterns()) + 1
        require(self.max_roadmap_nodes >= initial, 'max_roadmap_nodes', self.max_roadmap_nodes,
                f'max_roadmap_nodes must hold the {initial} initial patterns, got '
                f'{self.max_roadmap_nodes}')


def validate_upper_body_config(config: UpperBodyConfig) -> UpperBodyConfig:
    """Check an :class:`UpperBodyConfig`; raise :class:`ConfigError` naming the first bad field."""
    config.__post_init__()
    return config


@dataclass(frozen=True)
class UpperBodyPlan:
    """
    The upper-body motion of one step.

    Attributes
    ----------
    frames
        (k, 22) float64: the input frames with the upper-body columns planned, rad or m.
    ok
        Whether every branch reaches the final frame collision-free.
    reason
        Empty when ok; otherwise which branch is blocked and when.
    deviation
        Largest absolute deviation of the upper-body columns from the objective, rad.
    planning_time
        Wall time of the plan, s.
    per_branch
        Branch name -> dict(time s, ok, fast bool, nodes, backtracks, grown, deviation rad;
        a branch that searched also: checks, preview_backtracks, seeded frame; ``returned``
        True where it went straight back to its pattern, checked in one batch with the others
        instead of searching: see :meth:`UpperBodyPlanner.plan`).
    blocked_frame
        When not ok, the index of the frame the blocked branch could not get past (0 when its
        start is in collision); -1 when ok.

    """

    frames: np.ndarray
    ok: bool
    reason: str
    deviation: float
    planning_time: float
    per_branch: Dict[str, dict]
    blocked_frame: int = -1


def _waist_patterns() -> np.ndarray:
    """Return common waist postures as deviations (yaw, pitch) from erect, rad: bends and turns."""
    bends = [(0.0, p) for p in (0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 1.05, 1.2)]
    turns = [(y, 0.0) for y in (0.25, -0.25, 0.5, -0.5, 0.75, -0.75)]
    both = [(y, p) for y in (0.4, -0.4) for p in (0.4, 0.8)]
    return np.array(bends + turns + both + [(0.0, -0.2)])


def _arm_patterns() -> np.ndarray:
    """
    Return common arm postures as deviations (pitch, roll, yaw, elbow) from the swing, rad.

    Flexed, raised and abducted arms, and (last) the arm held in against the side, nearly
    straight: the one posture that does not stick out sideways, for squeezing between two
    obstacles with the waist turned (Figure 9b) rather than finding it by random growth.
    """
    return np.array([(0.0, 0.0, 0.0, e) for e in (0.3, 0.6, 0.9, 1.2, 1.6)]
                    + [(0.3, 0.0, 0.0, 0.8), (0.6, 0.0, 0.0, 1.4), (-0.3, 0.0, 0.0, 0.6),
                       (0.0, 0.25, 0.0, 0.0), (0.0, 0.5, 0.0, 0.4), (0.0, 0.0, -0.5, 0.9),
                       (0.0, 0.2, 0.0, 1.0), (0.0, -ARM_CLEARANCE_ROLL, 0.0, -0.15)])


class UpperBodyPlanner:
    """
    Prioritized CT-roadmap planning of the waist, then the left arm, then the right arm.

    Parameters
    ----------
    skeleton
        The actor model.
    body_collision
        ``BodyCollision`` of the actor in the environment: its environment (FCL objects,
        meshes) and padding are the ones checked here.
    config
        Planner settings (validated here).
    rng
        Random generator for roadmap growth; seeded default when omitted.

    """

    def __init__(self, skeleton: Skeleton, body_collision, config: UpperBodyConfig = None,
                 rng: Optional[np.random.Generator] = None):
        self.skeleton = skeleton
        self.body_collision = body_collision
        self.config = validate_upper_body_config(config or UpperBodyConfig())
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.kinematics = BodyKinematics(skeleton)
        self.shapes = BodyShapes(skeleton, getattr(body_collision, 'padding', 0.0))
        environment = body_collision.environment
        self.environment = EnvironmentIndex(environment.meshes,
                                            getattr(environment, 'objects', None))
        config = self.config
        self.roadmaps = {
            'waist': CTRoadmap(_waist_patterns(), np.array(config.waist_weights),
                               config.roadmap_radius, config.max_roadmap_nodes, self.rng,
                               prefer_lasting='waist' in config.lasting_branches,
                               search=config.roadmap_search)}
        for side in ('left', 'right'):
            self.roadmaps[f'{side}_arm'] = CTRoadmap(
                _arm_patterns(), np.array(config.arm_weights), config.roadmap_radius,
                config.max_roadmap_nodes, self.rng,
                prefer_lasting=f'{side}_arm' in config.lasting_branches,
                search=config.roadmap_search)
        self.indices = {name: skeleton.branch(name) for name in BRANCH_ORDER}
        self.upper_indices = np.concatenate([self.indices[name] for name in BRANCH_ORDER])
        # The same columns as slices where they are contiguous (views, not copies, on the
        # per-step hot path): the branches' and the whole upper body's.
        self._columns = {name: _columns(self.indices[name]) for name in BRANCH_ORDER}
        self._upper_columns = _columns(self.upper_indices)
        upper = self.upper_indices
        self._upper_index = np.asarray(upper, dtype=np.int64)
        # The joint limits with their tolerances and the speed caps: the upper body's, with
        # its branches as column groups (_within_limits), and each branch's own.
        lower, upper_limit = skeleton.lower - 1e-9, skeleton.upper + 1e-9
        speed = skeleton.velocity_limit * (1 + 1e-6)
        self._upper_lower, self._upper_upper = lower[upper], upper_limit[upper]
        self._branch_limits = {
            name: (lower[self.indices[name]], upper_limit[self.indices[name]],
                   speed[self.indices[name]], np.array([0, len(self.indices[name])]))
            for name in BRANCH_ORDER}
        # The waist searches forward of upright, however far back its joint goes: leaning
        # back under an overhead obstacle only puts off meeting it, for to bend forward from
        # there the head passes upright, its highest. After a stop under the low beam the
        # search leaned back to the limit, walked on, and every step from there was blocked.
        waist_lower = np.full(len(self.indices['waist']), -np.inf)
        waist_lower[list(self.indices['waist']).index(skeleton.index['waist_pitch'])] = (
            -config.waist_back_lean)
        self._growth_lower = {'waist': waist_lower}
        self._checked = {'waist': _TRUNK_LINKS, 'left_arm': _ARM_LINKS['left'],
                         'right_arm': _ARM_LINKS['right']}
        self._obstacles = {'waist': _LEG_LINKS,
                           'left_arm': _LEG_LINKS + _TRUNK_LINKS,
                           'right_arm': _LEG_LINKS + _TRUNK_LINKS + _ARM_LINKS['left']}
        # Every branch's own check of its start and motion pattern (start_and_objective), as
        # groups of one check over the whole upper body (pattern_checks).
        layouts = [branch_layout(self.kinematics, self.shapes, name, self._checked[name],
                                 self._obstacles[name]) for name in BRANCH_ORDER]
        self._layouts = dict(zip(BRANCH_ORDER, layouts))
        self._models = {name: branch_model(self.kinematics, self.shapes, name,
                                           self._checked[name], self._obstacles[name])
                        for name in BRANCH_ORDER}
        self._pattern_checked = np.concatenate([layout[1] for layout in layouts])
        self._pattern_pairs = np.vstack([layout[3] for layout in layouts])
        self._pattern_group = np.full(len(self.shapes.kind), -1, dtype=int)
        for group, layout in enumerate(layouts):
            self._pattern_group[layout[1]] = group
        first = np.cumsum([0] + [len(self.indices[name]) for name in BRANCH_ORDER])
        self._pattern_limits = (self._upper_lower, self._upper_upper, speed[upper],
                                first.astype(np.int64))
        self._warm_up()

    def _warm_up(self) -> None:
        """
        Call a search's kernels once on a small CT-space of an arm.

        A search's kernels called on a small CT-space of an arm (the actor at the origin over
        three frames, in this environment), so that numba's first look at their arguments in
        this process does not fall on the first step that searches (:func:`ct_roadmap.warm_up`).
        Every planner does it: after the first of a process it costs under a millisecond, less
        than keeping track of whether one has.
        """
        frames = np.zeros((3, len(self.skeleton.joint_names)))
        body = TimedBody(self.kinematics, self.shapes, self.environment, frames)
        columns = self._columns['left_arm']
        space = CTSpace('left_arm', body, np.arange(3) * 0.01, frames[:, columns].copy(),
                        self._checked['left_arm'], self._obstacles['left_arm'],
                        self.config.time_weight)
        warm_up(space, _arm_patterns(), np.array(self.config.arm_weights))

    def _check_input(self, times: np.ndarray, frames: np.ndarray) -> None:
        skeleton = self.skeleton
        if times.ndim != 1 or len(times) < 2:
            raise ValueError(f'times must have shape (k,) with k >= 2, got {times.shape}')
        if frames.shape != (len(times), len(skeleton.joint_names)):
            raise ValueError(f'frames must have shape ({len(times)}, '
                             f'{len(skeleton.joint_names)}), got {frames.shape}')
        if _input_sound(times, frames, self._upper_index, self._upper_lower,
                        self._upper_upper):
            return  # the usual case, in one pass; else find what is wrong and say it
        if not (np.isfinite(times).all() and np.isfinite(frames).all()):
            raise ValueError('times or frames contain NaN or infinite values')
        if not (times[1:] > times[:-1]).all():
            bad = int(np.flatnonzero(np.diff(times) <= 0)[0])
            raise ValueError(f'times must increase strictly, got {times[bad]} then '
                             f'{times[bad + 1]} at index {bad}')
        upper = self.upper_indices
        values = frames[:, self._upper_columns]
        outside = (values < self._upper_lower) | (values > self._upper_upper)
        if outside.any():
            row, column = np.argwhere(outside)[0]
            name = skeleton.joint_names[upper[column]]
            raise ValueError(f'objective {name} = {values[row, column]:.4f} rad at frame {row} '
                             f'is outside the joint limits [{skeleton.lower[upper[column]]}, '
                             f'{skeleton.upper[upper[column]]}]')

    def plan(self, times: np.ndarray, frames: np.ndarray,
             preview_from: Optional[int] = None,
             seeds: Optional[Dict[str, np.ndarray]] = None) -> UpperBodyPlan:
        """
        Plan the upper body over one step (§5), optionally with a preview after it.

        Parameters
        ----------
        times
            (k,) frame times, s, strictly increasing.
        frames
            (k, 22) configurations, rad or m: root and legs fixed; upper-body columns hold the
            objective O(t) except frame 0, which holds the start (the previous plan's end).
        preview_from
            When the frames from this index on are a preview of the pelvis carrying on past
            the step (a receding-horizon aid, not part of §5's goal), a branch search blocked
            there backtracks at most ``config.preview_backtracks`` times, then gives up with
            ``blocked_frame >= preview_from``; None: every frame is the step's own.
        seeds
            Branch name -> (s, d) deviations of the branch from its objective at frames 0..s-1
            (s <= k), rad: a motion likely to be legal, such as the rest of the previous plan
            from where this step starts (receding horizon; row 0 is not used). A branch with a
            seed that must search first goes along it (see :meth:`CTRoadmap.solve`).

        Returns
        -------
        UpperBodyPlan
            Frames whose upper-body columns follow the objective wherever it is legal.

        Notes
        -----
        Where branches start too far off their patterns to join them at once, their searches'
        first tries (straight back to the pattern) are checked first, together, in one batch
        with the whole body (:meth:`_plan_returning`); otherwise the whole input motion is
        checked in one batch and stands where it is legal. Where neither is, the branches
        are planned one by one.

        """
        began = time.perf_counter()
        times = np.asarray(times, dtype=float)
        frames = np.asarray(frames, dtype=float)
        self._check_input(times, frames)
        if preview_from is not None and not 0 < preview_from < len(times):
            raise ValueError(f'preview_from must be in (0, {len(times) - 1}], got '
                             f'{preview_from}')
        seeds = dict(seeds or {})
        for name, seed in seeds.items():
            if name not in self.indices:
                raise ValueError(f'seed for unknown branch {name!r}; branches: {BRANCH_ORDER}')
            seed = seeds[name] = np.asarray(seed, dtype=float)
            d = len(self.indices[name])
            if seed.ndim != 2 or seed.shape[1] != d or not 1 <= len(seed) <= len(times):
                raise ValueError(f'{name} seed must have shape (s, {d}) with 1 <= s <= '
                                 f'{len(times)}, got {seed.shape}')
            if not np.all(np.isfinite(seed)):
                raise ValueError(f'{name} seed contains NaN or infinite values')
        config = self.config
        start_inside, within = _within_limits(frames[:, self._upper_columns], times,
                                              self._pattern_limits)
        if start_inside.all() and not within.all():
            plan = self._plan_returning(times, frames, within, seeds, began)
            if plan is not None:
                return plan
        body = TimedBody(self.kinematics, self.shapes, self.environment, frames)
        out = frames.copy()
        per_branch: Dict[str, dict] = {}
        legality = self.pattern_checks(times, body, (start_inside, within))
        if all(start and motion for start, motion in legality.values()):
            for name in BRANCH_ORDER:
                per_branch[name] = {'ok': True, 'fast': True, 'nodes': 0, 'backtracks': 0,
                                    'grown': 0, 'deviation': 0.0, 'checks': 0, 'time': 0.0}
            return UpperBodyPlan(frames=out, ok=True, reason='', deviation=0.0,
                                 planning_time=time.perf_counter() - began,
                                 per_branch=per_branch)
        ok, reason, blocked_frame = True, '', -1
        moved = False  # whether a branch planned so far left the motion the body held
        for name in BRANCH_ORDER:
            tic = time.perf_counter()
            indices = self.indices[name]
            columns = self._columns[name]
            start = frames[0, columns].copy()
            objective = self._objective(frames, columns)
            record = {'ok': True, 'fast': False, 'nodes': 0, 'backtracks': 0, 'grown': 0}
            path = None
            checks = 0
            start_legal, objective_legal = (self.start_and_objective(times, body, name)
                                            if moved else legality[name])
            if not start_legal:
                ok, record['ok'], blocked_frame = False, False, 0
                links = self._links_in_collision(frames[0], name)
                reason = (f'{name} start in collision at t={times[0]:.2f} s'
                          + (f' ({", ".join(links)})' if links else ''))
            elif objective_legal:
                # Fast path: the objective, joined from the start, is legal at every frame.
                path = objective.copy()
                record['fast'] = True
            else:
                # Only a branch that must leave its motion pattern needs its CT-space.
                space = CTSpace(name, body, times, objective, self._checked[name],
                                self._obstacles[name], config.time_weight)
                result = self.roadmaps[name].solve(
                    space, start, hold_frames=config.hold_frames,
                    speed_fraction=config.speed_fraction,
                    growth_attempts=config.growth_attempts,
                    node_budget=config.node_budget, max_backtracks=config.max_backtracks,
                    check_budget=config.check_budget, preview_from=preview_from,
                    preview_backtracks=config.preview_backtracks,
                    seed=seeds.get(name), growth_lower=self._growth_lower.get(name),
                    deadline=None if config.time_budget is None
                    else time.process_time() + config.time_budget)
                record.update(nodes=result.nodes, backtracks=result.backtracks,
                              grown=result.grown, ok=result.ok,
                              preview_backtracks=result.preview_backtracks,
                              seeded=result.seeded)
                path = result.path
                steps, checks = space.steps, space.checks
                if not result.ok:
                    ok, blocked_frame = False, result.blocked_frame
                    reason = (f'{name} blocked at t={times[blocked_frame]:.2f} s'
                              + self._blocking(out, objective, columns, blocked_frame, name)
                              + (' (in the preview)' if result.gave_up_in_preview else ''))
            if path is not None and record['ok']:
                path[0] = start
                out[:, columns] = path
                if not record['fast'] and name != BRANCH_ORDER[-1]:
                    # The branches planned after this one see it where it now is.
                    body.set_branch(indices, path, steps)
                    moved = True
            record['deviation'] = (0.0 if record['fast'] or path is None else
                                   float(np.abs(out[1:, columns] - frames[1:, columns]).max()))
            record['checks'] = checks
            record['time'] = time.perf_counter() - tic
            per_branch[name] = record
            if not ok:
                break
        # Only the branches' own columns changed: the largest of their deviations.
        deviation = max([record['deviation'] for record in per_branch.values()], default=0.0)
        return UpperBodyPlan(frames=out, ok=ok, reason=reason, deviation=deviation,
                             planning_time=time.perf_counter() - began, per_branch=per_branch,
                             blocked_frame=blocked_frame)

    def _objective(self, frames: np.ndarray, columns) -> np.ndarray:
        """
        Return a branch's objective over the step, (k, d) rad.

        A branch's objective over the step, (k, d) rad: its columns of ``frames``, where frame 0
        holds the start, not the pattern: there the pattern continued back one frame.
        """
        objective = frames[:, columns].copy()
        objective[0] = np.minimum(np.maximum(
            2 * objective[1] - objective[2] if len(frames) > 2 else objective[1],
            self.skeleton.lower[columns]), self.skeleton.upper[columns])
        return objective

    def _plan_returning(self, times: np.ndarray, frames: np.ndarray, within: np.ndarray,
                        seeds: dict, began: float) -> Optional[UpperBodyPlan]:
        """
        Plan a step where each branch keeps its motion pattern or goes straight back to it.

        The plan of a step whose branches, each, keep their motion pattern or go straight back to
        it, when all of that is legal; None otherwise.

        A branch that starts too far off its pattern to join it at once (the joined motion
        breaks a speed limit) must search, and its search first tries to go straight back to
        the pattern and along it (:func:`direct_return`), which succeeds when that motion is
        legal and the pattern itself is legal at the search's grid frames before it is back
        (``CTRoadmap.solve``: where the pattern is blocked, the search first goes another
        way). Here those motions are written into the body, the grid frames' patterns
        appended as extra rows, and everything checked in one batch (:meth:`pattern_checks`):
        the same plan as the searches one by one would make, without a CT-space per branch
        (the step after an obstacle, when the obstacle is behind).

        ``within``: per branch whether its input motion (joined at once) keeps to the limits;
        ``seeds``: as :meth:`plan` takes them; a branch whose seed is still off the pattern
        where the way back would be on it is not tried (the last plan saw this step coming and
        kept it off: something is in the way). Where the batch finds anything illegal, the
        branches are planned one by one, and its cost, about that of a pattern check, is lost
        (on the obstacle courses rarely; far more often without the seed rule).
        """
        k = len(times)
        config = self.config
        grid = objective_grid(k - 1, config.hold_frames)
        out = frames.copy()
        extra = []
        returning = {}
        for name, legal in zip(BRANCH_ORDER, within.tolist()):
            if legal:
                continue
            model = self._models[name]
            columns = self._columns[name]
            objective = self._objective(frames, columns)
            route = direct_return(objective, times, frames[0, columns],
                                  config.speed_fraction * model.speed_limit)
            if route is None:
                return None
            arrival, path = route
            seed = seeds.get(name)
            if seed is not None and np.any(seed[min(arrival, len(seed) - 1):]):
                # The last plan, which saw this step coming, was still off the pattern here
                # (or did not go back as directly): something is in the way.
                return None
            # The search's check of the way back takes it within the limits (tolerances
            # included), and its path is clipped to them.
            if not np.all((path[1:] >= model.lower_tolerant)
                          & (path[1:] <= model.upper_tolerant)):
                return None
            path = np.minimum(np.maximum(path, model.lower), model.upper)
            path[0] = frames[0, columns]
            out[:, columns] = path
            # The pattern where the search checks it before the arrival (the earlier branches
            # where they are now planned): at the grid frame just before it, whose block would
            # reach past it, or, where a seed would be followed into a blocked stretch, at
            # every grid frame before it.
            before = grid[grid < arrival]
            if name not in seeds and len(before):
                before = before[-1:] if grid[len(before)] > arrival else before[:0]
            rows = out[before]
            rows[:, columns] = objective[before]
            extra.append(rows)
            returning[name] = len(before)
        body = TimedBody(self.kinematics, self.shapes, self.environment,
                         np.concatenate([out] + extra))
        legality = self.pattern_checks(times, body)
        if not all(start and motion for start, motion in legality.values()):
            return None
        row = k
        for name, count in returning.items():
            layout = self._layouts[name]
            if count and body.first_collision(layout[1], layout[3],
                                              np.arange(row, row + count)) >= 0:
                return None
            row += count
        per_branch: Dict[str, dict] = {}
        for name in BRANCH_ORDER:
            if name in returning:
                columns = self._columns[name]
                per_branch[name] = {
                    'ok': True, 'fast': False, 'returned': True, 'nodes': 0, 'backtracks': 0,
                    'grown': 0, 'preview_backtracks': 0, 'seeded': 0,
                    'deviation': float(np.abs(out[1:, columns] - frames[1:, columns]).max()),
                    'checks': k - 1 + returning[name], 'time': 0.0}
            else:
                per_branch[name] = {'ok': True, 'fast': True, 'nodes': 0, 'backtracks': 0,
                                    'grown': 0, 'deviation': 0.0, 'checks': 0, 'time': 0.0}
        return UpperBodyPlan(frames=out, ok=True, reason='',
                             deviation=max(r['deviation'] for r in per_branch.values()),
                             planning_time=time.perf_counter() - began, per_branch=per_branch)

    def start_and_objective(self, times: np.ndarray, body: TimedBody,
                            name: str) -> Tuple[bool, bool]:
        """
        Whether a branch's start is legal, and whether its motion in ``body`` is.

        Before the branch is planned its columns of ``body`` hold its start at frame 0, then
        its objective: the motion its fast path would take. Checked on the poses ``body``
        already holds (no kinematics), in one batch for both answers, with the shapes and
        pairs of the branch's :class:`CTSpace` and the same tests.

        Parameters
        ----------
        times
            (k,) frame times, s.
        body
            The actor over the step, with the branches before ``name`` fixed.
        name
            The branch.

        Returns
        -------
        tuple of bool
            (start legal at frame 0, the whole motion legal: start included).

        """
        layout = self._layouts[name]
        checked, pairs = layout[1], layout[3]
        start_inside, within = _within_limits(
            body.frames[:, self._columns[name]], times, self._branch_limits[name])
        if not within[0]:
            # The motion is not legal whatever it touches: only the start is left to check.
            return bool(start_inside[0]) and body.first_collision(checked, pairs, [0]) < 0, False
        # Where the branches fixed since the last check of this one left it clear, it still is:
        # only the frames they changed, and those from its first contact on, are checked.
        frames = body.frames_to_recheck(name)
        bad = body.first_collision(checked, pairs, frames)
        # Every frame was checked up to the first contact (the branch's CT-space skips them).
        body.set_clear(name, bad)
        return bad != 0, bad < 0

    def pattern_checks(self, times: np.ndarray, body: TimedBody,
                       limits: Optional[tuple] = None) -> Dict[str, Tuple[bool, bool]]:
        """
        :meth:`start_and_objective` of every branch, in one batch over the upper body.

        The input upper-body motion is the start at frame 0, then the objective: the motion
        every branch's fast path would take. Each branch's answer is the one
        :meth:`start_and_objective` gives on ``body`` as it is, with one batch for all three
        (the poses and boxes of every shape at every frame are already in ``body``), each
        branch's shapes left out once they have collided. The
        answers hold for a branch as long as the branches before it keep the motion ``body``
        holds. Rows of ``body`` from ``len(times)`` on, if any, are not part of the motion.
        ``limits``: per branch whether the motion's start and whole motion keep to the joint
        limits ((B,) bool each, speeds included), when already known.

        Returns
        -------
        dict
            Branch name -> (start legal at frame 0, the whole motion legal: start included).

        """
        k = len(times)
        start_inside, within = limits or _within_limits(body.frames[:k, self._upper_columns],
                                                        times, self._pattern_limits)
        first = body.first_collisions(self._pattern_checked, self._pattern_pairs,
                                      self._pattern_group, len(BRANCH_ORDER),
                                      None if len(body.frames) == k else np.arange(k))
        out = {}
        for name, bad in zip(BRANCH_ORDER, first):
            # Every frame was checked up to the first contact (the CT-spaces skip them).
            body.set_clear(name, bad)
        for name, bad, start, legal in zip(BRANCH_ORDER, first, start_inside.tolist(),
                                           within.tolist()):
            if not legal:
                # The motion is not legal whatever it touches: only the start is left.
                out[name] = (start and bad != 0, False)
            else:
                out[name] = (bad != 0, bad < 0)
        return out

    def _blocking(self, frames: np.ndarray, objective: np.ndarray, columns, frame: int,
                  branch: str) -> str:
        """
        Return what blocks a branch, for its reason, or '' when nothing would touch there.

        What blocks a branch, for its reason: ': the head would be 85 mm into an obstacle' (the
        deepest of its links in its motion pattern at the blocked ``frame``, the branches planned
        before it where they were planned), or '' when none would touch there (the joints could not
        move it clear in time).
        """
        q = frames[frame].copy()
        q[columns] = objective[frame]
        try:
            depths = self.body_collision.penetration(q, self._checked[branch])
        except (AttributeError, ValueError):
            return ''
        link, depth = max(depths.items(), key=lambda item: item[1], default=('', 0.0))
        if depth <= 0.0:
            return ''
        return f': the {link.replace("_", " ")} would be {1e3 * depth:.0f} mm into an obstacle'

    def _links_in_collision(self, q: np.ndarray, branch: str) -> list:
        """Names of the branch's links touching the environment at ``q`` (for the reason)."""
        try:
            return list(self.body_collision.links_in_collision(q, self._checked[branch]))
        except (AttributeError, ValueError):
            return []


def _columns(indices: np.ndarray):
    """Return ``indices`` as a slice when they are consecutive, else as they are."""
    indices = np.asarray(indices)
    if len(indices) and np.array_equal(indices, np.arange(indices[0], indices[0] + len(indices))):
        return slice(int(indices[0]), int(indices[0]) + len(indices))
    return indices


@kernel('Tuple((b1[::1], b1[::1]))(f8[:, :], f8[:], UniTuple(f8[::1], 3), i8[::1])')
def _within_limits_kernel(path, times, bounds, groups):
    """Check a motion ``path`` (k, c) per group of columns against the joint limits and speeds."""
    lower, upper, cap = bounds
    count = groups.shape[0] - 1
    start = np.ones(count, dtype=np.bool_)
    legal = np.ones(count, dtype=np.bool_)
    k = path.shape[0]
    for g in range(count):
        for j in range(groups[g], groups[g + 1]):
            for i in range(k):
                if not (path[i, j] >= lower[j] and path[i, j] <= upper[j]):
                    legal[g] = False
                    if i == 0:
                        start[g] = False
                if i > 0 and abs(path[i, j] - path[i - 1, j]) / (times[i] - times[i - 1]) > cap[j]:
                    legal[g] = False
    return start, legal


def _within_limits(path: np.ndarray, times: np.ndarray, limits: tuple) -> tuple:
    """
    Check a motion ``path`` (k, c) per group of columns against the joint limits and speeds.

    Per group of columns of a motion ``path`` (k, c) over ``times`` (k,): whether its first frame
    is within the joint limits, and whether every frame is and no joint moves faster than its cap
    between frames. ``limits``: (lower (c,), upper (c,), speed cap (c,), the groups' first columns
    and the end (G + 1,)), the limits' tolerances included.
    """
    lower, upper, cap, groups = limits
    return _within_limits_kernel(path, times, (lower, upper, cap), groups)


@kernel('b1(f8[:], f8[:, :], i8[::1], f8[::1], f8[::1])')
def _input_sound(times, frames, columns, lower, upper):
    """
    Return whether ``times`` and ``frames`` are finite, increasing and within the limits.

    Whether ``times`` (k,) and ``frames`` (k, J) are finite, the times strictly increase and the
    ``columns`` of every frame lie in [lower, upper] (the checks of
    :meth:`UpperBodyPlanner._check_input`).
    """
    for i in range(times.shape[0]):
        if not math.isfinite(times[i]) or (i > 0 and not times[i] > times[i - 1]):
            return False
        for j in range(frames.shape[1]):
            if not math.isfinite(frames[i, j]):
                return False
        for c in range(columns.shape[0]):
            value = frames[i, columns[c]]
            if value < lower[c] or value > upper[c]:
                return False
    return True
