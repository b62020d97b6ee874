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
The sliding-window footstep planner (§4.2).

A footstep configuration q_f = (s_1, ..., s_n) holds the lengths of the next n steps, each in
[s_min, s_max] divided into m intervals. From q_init = (s_init, ..., s_init) a breadth-first search
finds a collision-free configuration, then hill-climbing on an effort criterion moves to the best
neighbour until every neighbour is worse. Only s_1 is executed; the next call starts from
(s_2, ..., s_n, s_init).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import functools
import itertools
import math
from typing import Optional, Tuple

import numpy as np

from .footstep_search import (DENSE_CONFIGURATIONS, DOWN, exhaustive_search, foothold_tables,
                              HEEL, judge_footholds, LIFT_RISE, LIFT_ROOM, LIFT_STEP_UP,
                              MAX_PITCH, MAX_SWING, MIN_FRACTION, MIN_HEADROOM, NUMBER_COUNT,
                              PITCH_RANGE, SPAN, TOE, TOLERANCE, TWO, UP, UP_RANGE, W_HEIGHT,
                              W_LENGTH, W_PITCH, W_SMOOTH, window_search)
from .footstep_window import FootholdTable, search_footstep_window, WindowFeet, WindowLimits
from .jit import direct, float_array
from .settings import check_settings, require, setting
from .skeleton import LegGeometry

LEFT, RIGHT = 0, 1

#: The search of a window, called as :meth:`FootstepPlanner.plan` calls it: without numba's
#: dispatch (``jit.direct``; every argument is the planner's own or a GroundProfile's checked
#: samples).
window_search = direct(window_search)

#: The lines along which the ground map is read under a sole, as fractions of its width from
#: its centre line. Both the footholds (sample_ground_profile) and the swing's clearance (gait)
#: read these same lines: a swing is then never asked to clear what its footholds stand beside.
#: The map answers for a point's whole grid cell, so an obstacle up to a cell outside a line
#: may show; the 3D check of every step (collision.BodyCollision) is exact.
SOLE_LINES = (-0.4, 0.0, 0.4)


#: The searches of a window :attr:`FootstepConfig.window_search` selects.
WINDOW_SEARCHES = ('compiled', 'readable')


@dataclass(frozen=True)
class FootstepConfig:
    """
    Footstep planner settings (paper defaults n = 3, m = 13). Lengths in m, angles in rad.

    Why each rule and default is as it is: docs/LOWER_BODY.md.

    ``greedy_restart``: after the paper's breadth-first search and hill-climbing, climb once
    more from a footstep-by-footstep greedy configuration and keep the better result (False:
    the paper's search alone).

    ``max_swing_height``: how far above the higher of its two footholds a swinging foot may
    have to clear the ground in between, m (at 0.40 the front foot strode over a 0.3 m long,
    0.28 m high block and the rear foot could not follow; at 0.25 it steps onto the block).

    ``lift_room``, ``lift_rise``, ``lift_step_up``: a foot the window places must be able to
    lift off again for the window's later footstep on that side. Within ``lift_room`` (m) ahead
    of its toe the ground may rise no more than ``lift_rise`` (m) above its sole's plane, more
    by as much as that footstep lands higher, but never more than ``lift_step_up`` (m). From
    2 cm before a 0.22 m block's face, with the next footstep onto the ground beyond, no swing
    lifted the foot (the conservative ground map puts the block under the toe at lift-off);
    bumps and 0.15 m blocks that close are lifted over, and a flight's risers (up to 0.2 m)
    stand that close to the toes while the swing onto the next tread rises at once; a 0.28 m
    step up from there bent the knee past its limit. With 3 cm of room a foot came to rest
    3.4 cm before a 0.24 m face and could not step up from there (bench_terrain random course
    269). 0 room: no such test.

    ``window_search``: which search of a window :meth:`FootstepPlanner.plan` runs:
    ``'compiled'`` (:func:`footstep_search.window_search`, the runtime path) or ``'readable'``
    (:func:`footstep_window.search_footstep_window`, the code of record, in plain Python).
    Both find the same footsteps; the compiled one is about an order of magnitude faster
    (``bench/bench_footstep_window.py``, docs/READABLE_ALGORITHMS.md).
    """

    window_steps: int = setting(3, 1, 8, 'Footstep window length n (paper §4.2).')
    step_intervals: int = setting(
        13, 1, 60, 'Step-length intervals m of the footstep planner (paper §4.2).')
    step_length_min: float = setting(0.15, 0.05, 1.0, 'Shortest step s_min.', 'm',
                                     rule='step_length_min < step_length_max')
    step_length_max: float = setting(0.80, 0.05, 1.0, 'Longest step s_max.', 'm',
                                     rule='step_length_min < step_length_max')
    max_step_up: float = setting(0.30, 0.0, None, 'Highest step up between footholds.', 'm')
    max_step_down: float = setting(0.35, 0.0, None, 'Deepest step down between footholds.',
                                   'm')
    max_swing_height: float = setting(
        0.25, 0.0, None, 'How far above the higher foothold a swing may have to clear the '
        'ground in between.', 'm')
    flatness_tolerance: float = setting(
        0.015, 0.0, None, 'How much the ground may vary under a sole.', 'm')
    min_support_fraction: float = setting(
        0.6, 0.0, 1.0, 'Fraction of a sole the ground must support.')
    max_foot_pitch: float = setting(0.30, 0.0, None, 'Steepest slope a foot stands on.', 'rad')
    min_headroom: float = setting(1.0, 0.0, None, 'Free height above a foothold.', 'm')
    weight_length: float = setting(1.0, 0.0, None, 'Effort weight of step length.')
    weight_height: float = setting(0.5, 0.0, None, 'Effort weight of height change.')
    weight_pitch: float = setting(0.2, 0.0, None, 'Effort weight of foot pitch.')
    weight_smooth: float = setting(0.3, 0.0, None, 'Effort weight of length changes.')
    greedy_restart: bool = setting(
        True, doc='Climb once more from a greedy configuration and keep the better result.')
    lift_room: float = setting(
        0.05, 0.0, None, 'Room ahead of a toe in which the ground may rise only lift_rise.',
        'm')
    lift_rise: float = setting(
        0.15, 0.0, None, 'How far the ground may rise within lift_room of a toe.', 'm')
    lift_step_up: float = setting(
        0.25, 0.0, None, 'The most the ground within lift_room may rise at all.', 'm')
    window_search: str = setting('compiled', doc='Which search of a window runs.',
                                 choices=WINDOW_SEARCHES)

    def __post_init__(self):
        """Check every field against its declaration and the lengths against each other."""
        check_settings(self)
        require(self.step_length_min < self.step_length_max, 'step_length_min',
                self.step_length_min, f'step_length_min {self.step_length_min} must be below '
                f'step_length_max {self.step_length_max}')

    @property
    def step_increment(self) -> float:
        """Length of one of the m intervals, m."""
        return (self.step_length_max - self.step_length_min) / self.step_intervals

    def lengths(self) -> np.ndarray:
        """Return the m + 1 allowed footstep lengths, (m + 1,) m."""
        return self.step_length_min + self.step_increment * np.arange(self.step_intervals + 1)


def validate_footstep_config(config: FootstepConfig) -> None:
    """Raise :class:`ConfigError` naming the first bad field of ``config``."""
    config.__post_init__()


def _samples(array) -> np.ndarray:
    """
    Return a profile's (2, K) samples as the compiled kernels take them.

    A profile's (2, K) samples as the compiled kernels take them: float64, C-contiguous and
    writable (copied only when they are not).
    """
    return np.ascontiguousarray(float_array(array))


@dataclass(frozen=True)
class GroundProfile:
    """
    The ground under each foot's track, sampled along the predicted path (§3.2).

    Attributes
    ----------
    s0, ds
        Arc length of the first sample and the sample spacing, m.
    height
        (2, K) highest ground across the foot's width per side (0 left, 1 right), m; NaN where a
        foot cannot stand (no surface within step reach, or inside a solid).
    low
        (2, K) lowest ground across the foot's width, m (for the flatness test).
    headroom
        (2, K) free height above ``height``, m.
    obstacle
        (2, K) height a swinging foot must clear, m: ``height`` where it exists, the top of the
        solid where the sample lies inside one, NaN over empty space (a gap).
    stacked
        (4, 2, K) the samples as the compiled footstep search takes them, in one array (one to
        unbox instead of four): ``height``, ``low`` and ``headroom`` (which are views of it)
        and ``obstacle`` with -inf over empty space. Made from the other four when not given;
        :func:`sample_ground_profile` gives it, having written the samples into it.

    Raises
    ------
    ValueError
        If the four sample arrays are not all (2, K) with the same K.

    """

    s0: float
    ds: float
    height: np.ndarray
    low: np.ndarray
    headroom: np.ndarray
    obstacle: np.ndarray
    stacked: Optional[np.ndarray] = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        # The compiled kernels take the samples as C-contiguous, writable float64: made so once
        # here (copied only where they are not), not at every search of a window.
        if self.stacked is not None:
            # The search is called without numba's checks of its arguments (jit.direct):
            # samples of another layout would be read as if they had this one.
            stacked = self.stacked
            if (not isinstance(stacked, np.ndarray) or stacked.dtype != np.float64
                    or stacked.ndim != 3 or stacked.shape[:2] != (4, 2)
                    or not stacked.flags.c_contiguous or not stacked.flags.writeable):
                raise ValueError('stacked ground profile samples must be a C-contiguous, '
                                 'writable float64 array of shape (4, 2, K), got '
                                 f'{getattr(stacked, "dtype", type(stacked).__name__)} '
                                 f'{getattr(stacked, "shape", "")}')
            return
        arrays = [_samples(getattr(self, name))
                  for name in ('height', 'low', 'headroom', 'obstacle')]
        shapes = [a.shape for a in arrays]
        if len(shapes[0]) != 2 or shapes[0][0] != 2 or any(x != shapes[0] for x in shapes):
            raise ValueError(f'ground profile samples must all be (2, K): height, low, '
                             f'headroom, obstacle are {shapes}')
        stacked = np.empty((4,) + shapes[0])
        stacked[:3] = arrays[:3]
        stacked[3] = np.where(np.isnan(arrays[3]), -np.inf, arrays[3])
        for k, name in enumerate(('height', 'low', 'headroom')):
            object.__setattr__(self, name, stacked[k])
        object.__setattr__(self, 'obstacle', arrays[3])
        object.__setattr__(self, 'stacked', stacked)

    @property
    def samples(self) -> int:
        """Return the number of samples K per side."""
        return self.height.shape[1]

    def arc_lengths(self) -> np.ndarray:
        """(K,) arc length of each sample, m."""
        return self.s0 + self.ds * np.arange(self.samples)

    def swing_top(self, side: int, s_toe: float, s_heel: float) -> float:
        """
        Highest ground a foot swings over between a sole's toe and a later sole's heel.

        Parameters
        ----------
        side
            0 left, 1 right.
        s_toe, s_heel
            Arc lengths of the lifting sole's toe and of the landing sole's heel, m.

        Returns
        -------
        float
            The most of ``obstacle`` from the sample at or before ``s_toe`` to the one at or
            after ``s_heel``, m; NaN where that is empty space only or no sample lies between.
            The footstep search's swing test reads the same span (on lists, for speed).

        """
        i0 = max(math.floor((s_toe - self.s0) / self.ds), 0)
        i1 = min(math.ceil((s_heel - self.s0) / self.ds), self.samples - 1)
        if i1 < i0:
            return math.nan
        # NaN (empty space, nothing to pass over) is skipped by fmax; all NaN stays NaN.
        return float(np.fmax.reduce(self.obstacle[side, i0:i1 + 1]))


@dataclass(frozen=True)
class Foothold:
    """
    Where a sole can rest at arc length ``s`` on one side.

    Where a sole can rest at arc length ``s`` on one side: height of the sole under the ankle (m),
    sole pitch (rad, toes up positive) and whether it is usable at all.
    """

    ok: bool
    height: float
    pitch: float


@dataclass(slots=True)
class FootstepWindow:
    """
    Result of one footstep-window search (treat it as read-only).

    Result of one footstep-window search (treat it as read-only: not a frozen dataclass only
    because one is built on every planned step and freezing costs four times as much).

    Attributes
    ----------
    lengths
        (n,) footstep lengths s_1..s_n, m.
    indices
        (n,) interval index of each length (0..m).
    arc_lengths
        (n,) arc length of each foothold along the path, m.
    heights, pitches
        (n,) foothold sole heights (m) and pitches (rad).
    sides
        (n,) 0 = left, 1 = right.
    effort
        Effort criterion of the configuration (dimensionless).
    evaluated
        Configurations whose feasibility was tested (BFS + hill-climbing).

    """

    lengths: np.ndarray
    indices: Tuple[int, ...]
    arc_lengths: np.ndarray
    heights: np.ndarray
    pitches: np.ndarray
    sides: np.ndarray
    effort: float
    evaluated: int


@functools.lru_cache(maxsize=None)
def _numbering(n: int, m: int) -> tuple:
    """
    Return every configuration of a window of ``n`` footsteps and ``m`` intervals by number.

    Every configuration of a window of ``n`` footsteps and ``m`` intervals by its number as the
    searches number them (base m + 1, footstep 0 first), a list of index tuples, and the numbers by
    the tuples, a dictionary: (None, None) past ``DENSE_CONFIGURATIONS``. The planner looks up a
    search's answer in the list (where the search would return an array to box and convert) and a
    start's number in the dictionary (where a loop would check and number it); planners of one
    window size share them.
    """
    if (m + 1) ** n > DENSE_CONFIGURATIONS:
        return None, None
    configurations = list(itertools.product(range(m + 1), repeat=n))
    return configurations, {config: k for k, config in enumerate(configurations)}


class FootstepPlanner:
    """
    Sliding-window footstep planner (§4.2) over a ground profile.

    Parameters
    ----------
    config
        Planner settings.
    leg
        Leg dimensions (sole length around the ankle).

    """

    def __init__(self, config: FootstepConfig, leg: LegGeometry):
        validate_footstep_config(config)
        self.config = config
        self.leg = leg
        # Foothold table layout: footstep i at cumulative interval index c = 0..(i + 1) m lies
        # (i + 1) s_min + c * increment beyond the stance foot.
        n, m = config.window_steps, config.step_intervals
        counts = [(i + 1) * m + 1 for i in range(n)]
        self._table_layout = (
            np.repeat(np.arange(n), counts),
            np.concatenate([(i + 1) * config.step_length_min
                            + config.step_increment * np.arange(counts[i]) for i in range(n)]),
            [int(b) for b in np.cumsum([0] + counts)])
        self._lengths = config.lengths()
        for table in (self._table_layout[1], self._lengths):
            table.setflags(write=False)
        # The side of each footstep of a window, by the side of the stance foot: the other
        # foot steps first. As an array (read-only: every window of that stance side holds
        # it) and as a list.
        self._sides = {}
        for stance_side in (0, 1):
            sides = np.array([(1 - stance_side) if i % 2 == 0 else stance_side
                              for i in range(n)])
            sides.setflags(write=False)
            self._sides[stance_side] = (sides, sides.tolist())
        self._rise_limits = (float(config.max_step_up), float(config.max_step_down))
        # Weights and ranges of the effort terms (footstep_search._effort), as plain floats.
        self._effort_terms = (
            float(config.weight_length), float(config.weight_height),
            float(config.weight_pitch), float(config.weight_smooth),
            float(config.step_length_max - config.step_length_min),
            float(max(config.max_step_up, 1e-6)), float(max(config.max_foot_pitch, 1e-6)))
        # The numbers the compiled search reads (footstep_search.NUMBER_COUNT), read-only: the
        # search writes the window's own (the feet, the speed, the profile's sampling) into a
        # copy.
        numbers = np.zeros(NUMBER_COUNT)
        numbers[[UP, DOWN]] = self._rise_limits
        numbers[[W_LENGTH, W_HEIGHT, W_PITCH, W_SMOOTH, SPAN, UP_RANGE, PITCH_RANGE]] = \
            self._effort_terms
        numbers[[TOE, HEEL, MAX_SWING, LIFT_ROOM, LIFT_RISE, LIFT_STEP_UP, TWO, MIN_HEADROOM,
                 MAX_PITCH, TOLERANCE, MIN_FRACTION]] = (
            leg.toe, leg.heel, config.max_swing_height, config.lift_room, config.lift_rise,
            config.lift_step_up, 2.0, config.min_headroom, config.max_foot_pitch,
            config.flatness_tolerance, config.min_support_fraction)
        # The numbers, the lengths and the table entries' offsets in one array, as the compiled
        # search takes them (footstep_search.PROFILE_TYPE); n, m, the table rows' first
        # entries, the sides of the footsteps and of the table's entries in another, by the
        # side of the stance foot. Read-only: every window shares them.
        self._search_constants = np.concatenate([numbers, self._lengths,
                                                 self._table_layout[1]])
        self._search_constants.setflags(write=False)
        self._search_layout = {}
        for stance_side in (0, 1):
            sides = self._sides[stance_side][0]
            layout = np.concatenate([[n, m], self._table_layout[2], sides,
                                     sides[self._table_layout[0]]]).astype(np.int64)
            layout.setflags(write=False)
            self._search_layout[stance_side] = layout
        # No interval index banned (read-only: every window shares it).
        self._none_banned = np.zeros(m + 1, dtype=bool)
        self._none_banned.setflags(write=False)
        self._longest = float(self._lengths.max())
        # What plan reads on every window, as plain numbers.
        self._window_size = (int(n), int(m))
        self._length_min = float(config.step_length_min)
        self._increment = float(config.step_increment)
        self._greedy_restart = bool(config.greedy_restart)
        self._configurations, self._numbers = _numbering(n, m)
        self._readable_search = config.window_search == 'readable'
        self._window_limits = WindowLimits(
            lengths=tuple(self._lengths.tolist()), window_steps=int(n),
            max_step_up=float(config.max_step_up), max_step_down=float(config.max_step_down),
            max_swing_height=float(config.max_swing_height),
            lift_rise=float(config.lift_rise), lift_step_up=float(config.lift_step_up),
            weight_length=self._effort_terms[0], weight_height=self._effort_terms[1],
            weight_pitch=self._effort_terms[2], weight_smooth=self._effort_terms[3],
            length_span=self._effort_terms[4], rise_range=self._effort_terms[5],
            pitch_range=self._effort_terms[6], greedy_restart=self._greedy_restart)

    # -- the ground under a sole -----------------------------------------------------------
    def foothold(self, profile: GroundProfile, side: int, s: float) -> Foothold:
        """
        Evaluate a sole with its ankle at arc length ``s`` on ``side``.

        One sole of :meth:`footholds`.
        """
        ok, height, pitch = self.footholds(profile, side, np.array([s], dtype=float))
        return Foothold(bool(ok[0]), float(height[0]), float(pitch[0]))

    def footholds(self, profile: GroundProfile, side: int, s: np.ndarray):
        """
        Evaluate soles with their ankles at arc lengths ``s``, all at once.

        A sole needs support under its whole length that is flat within the tolerance after
        fitting a plane (so slopes are fine), not steeper than the pitch limit, and with
        headroom. It rests on the highest point above the fitted plane and must not bridge a dip
        deeper than the tolerance anywhere under it (neither across nor along the foot). At an
        edge (a stair nosing, a block, a ditch) a flat sole may overhang lower ground, as long
        as the ankle is over the support and most of the sole is supported, however far below
        the overhung ground lies (the plane through all the samples does not count there: the
        sole rests level on the top). A sole is judged on the samples between its heel and its
        toe, none beyond them: with the ground map's own conservative cell at a riser, one
        more sample past the toe kept it 4 cm from the next riser, where a 26 cm tread left a
        2 cm window for the ankle.

        Parameters
        ----------
        profile
            Ground under both foot tracks.
        side
            0 left, 1 right; one for all or (N,), one per sole.
        s
            (N,) ankle arc lengths, m.

        Returns
        -------
        tuple
            (ok (N,) bool; sole height under the ankle (N,) m, NaN where not ok; sole pitch
            (N,) rad, toes up positive, 0 on an edge).

        """
        cfg, leg = self.config, self.leg
        # The kernel's exact argument types (it is compiled for those alone): fresh arrays.
        s = np.array(s, dtype=np.float64)
        # Filled by assignment, which broadcasts as np.broadcast_to would (the same errors) at
        # a fraction of its cost.
        sides = np.empty(s.shape, dtype=np.int64)
        sides[...] = np.asarray(side, dtype=np.int64)
        side = sides
        return judge_footholds(
            profile.height, profile.low, profile.headroom, float(profile.s0), float(profile.ds),
            side, s, float(leg.heel), float(leg.toe), float(cfg.min_headroom),
            float(cfg.max_foot_pitch), float(cfg.flatness_tolerance),
            float(cfg.min_support_fraction))

    def rise_ahead(self, profile: GroundProfile, side, s: np.ndarray, height: np.ndarray,
                   pitch: np.ndarray) -> np.ndarray:
        """
        How far the ground just ahead of soles' toes rises above their planes.

        Parameters
        ----------
        profile
            Ground under both foot tracks.
        side
            0 left, 1 right; one for all or (N,).
        s, height, pitch
            (N,) ankle arc lengths (m), sole heights under the ankles (m) and sole pitches
            (rad), as :meth:`footholds` gives them.

        Returns
        -------
        numpy.ndarray
            (N,) the most the profile's swing obstacle rises within ``lift_room`` past each
            toe above the sole's plane carried on, m; -inf where nothing is there (or no room
            is asked for), NaN where the sole has no height.

        """
        cfg, leg = self.config, self.leg
        s = np.asarray(s, dtype=float)
        out = np.full(s.shape, -np.inf)
        if cfg.lift_room <= 0 or not s.size:
            return out
        samples = profile.samples
        side = np.asarray(side, dtype=int)
        # The samples past the toe (the sole is judged on those up to it) within lift_room.
        toe = np.floor((s + leg.toe - profile.s0) / profile.ds + 1e-9).astype(int)
        reach = np.floor((s + (leg.toe + cfg.lift_room) - profile.s0) / profile.ds
                         + 1e-9).astype(int) - toe
        ahead = np.arange(1, max(int(reach.max()), 0) + 1)[:, None]
        if not ahead.size:
            return out
        index = np.minimum(np.maximum(toe + ahead, 0), samples - 1)
        past = profile.obstacle.take(side * samples + index)
        past = past - np.tan(pitch) * (profile.s0 + profile.ds * index - s) - height
        past = np.where((ahead <= reach) & ~np.isnan(past), past, -np.inf)
        out = past.max(axis=0)
        return np.where(np.isnan(height), np.nan, out)

    # -- §4.2 search -------------------------------------------------------------------
    def plan(self, profile: GroundProfile, stance_side: int, stance_s: float,
             stance_height: float, swing_s: float, swing_height: float, s_init: float,
             previous_length: float, start: Optional[Tuple[int, ...]] = None,
             banned_first: Tuple[int, ...] = (),
             max_length: float = np.inf) -> Optional[FootstepWindow]:
        """
        Plan the next n footsteps.

        Parameters
        ----------
        profile
            Ground under both foot tracks.
        stance_side, stance_s, stance_height
            The foot that stays down: side, arc length, sole height (m).
        swing_s, swing_height
            Where the swinging foot lifts from: arc length and sole height, m.
        s_init
            Neutral footstep length, m (from the commanded speed).
        previous_length
            Length of the step just taken, m (for the smoothness term).
        start
            Initial configuration as interval indices; defaults to (s_init, ..., s_init). The
            actor passes the slid previous window (s_2, ..., s_n, s_init).
        banned_first
            Interval indices that s_1 must not take (the walk generator could not realise them).
        max_length
            Longest footstep allowed here, m (on a tight turn the heading change per step
            bounds the step length).

        Returns
        -------
        FootstepWindow or None
            None when no collision-free configuration exists in the window.

        The search runs compiled, its foothold table included
        (:func:`footstep_search.window_search`), called without numba's dispatcher, unless
        ``FootstepConfig.window_search`` asks for the readable search of record
        (:func:`footstep_window.search_footstep_window`): both judge the same configurations
        and find the same footsteps and efforts to the last bit.

        """
        n, m = self._window_size
        if start is None:
            index = round((s_init - self._length_min) / self._increment)
            start = (min(max(index, 0), m),) * n
        # Numbered as the search numbers configurations (base m + 1, footstep 0 first).
        number = (self._numbers.get(start)
                  if self._numbers is not None and type(start) is tuple else None)
        if number is None:
            if len(start) != n or min(start) < 0 or max(start) > m:
                raise ValueError(f'start configuration {tuple(start)} is not {n} indices in '
                                 f'[0, {m}]')
            number = 0
            for j in start:
                number = number * (m + 1) + int(j)
        if stance_side != 0 and stance_side != 1:
            raise ValueError(f'stance side {stance_side!r} is not 0 (left) or 1 (right)')
        banned = self._none_banned
        if len(banned_first):
            banned = np.zeros(m + 1, dtype=bool)
            for b in banned_first:
                if 0 <= int(b) <= m:
                    banned[int(b)] = True
        too_long = self._none_banned
        if self._longest > max_length + 1e-9:
            too_long = self._lengths > max_length + 1e-9
        if self._readable_search:
            feet = WindowFeet(float(stance_s), float(stance_height), float(swing_s),
                              float(swing_height), float(s_init), float(previous_length))
            return self._readable_window(profile, stance_side, feet, tuple(int(j) for j in start),
                                         frozenset(np.flatnonzero(banned).tolist()),
                                         frozenset(np.flatnonzero(too_long).tolist()))
        return self._window(window_search(
            number, banned, too_long, self._greedy_restart,
            self.search_profile(profile, stance_side, stance_s, stance_height, swing_s,
                                swing_height, s_init, previous_length)), stance_side)

    @property
    def window_limits(self) -> WindowLimits:
        """Return the window's rules and effort weights as the readable search reads them."""
        return self._window_limits

    def foothold_table(self, profile: GroundProfile, stance_side: int,
                       stance_s: float) -> FootholdTable:
        """
        Return every foothold a window from the stance foot at ``stance_s`` can reach.

        Every foothold a window from the stance foot at ``stance_s`` can reach, judged by
        :meth:`footholds` and :meth:`rise_ahead`: what the readable search reads
        (:func:`footstep_window.search_footstep_window`).

        Parameters
        ----------
        profile
            Ground under both foot tracks.
        stance_side, stance_s
            The foot that stays down: 0 left, 1 right, and its arc length, m.

        Returns
        -------
        FootholdTable

        """
        step, offsets, bounds = self._table_layout
        sides, side_list = self._sides[stance_side]
        s = stance_s + offsets
        ok, height, pitch = self.footholds(profile, sides[step], s)
        rise = self.rise_ahead(profile, sides[step], s, height, pitch)

        def rows(values):
            values = values.tolist()
            return tuple(tuple(values[a:b]) for a, b in zip(bounds[:-1], bounds[1:]))

        return FootholdTable(ok=rows(ok), height=rows(height), pitch=rows(pitch),
                             rise_ahead=rows(rise), sides=tuple(side_list),
                             swing_top=profile.swing_top, toe=float(self.leg.toe),
                             heel=float(self.leg.heel))

    def _readable_window(self, profile: GroundProfile, stance_side: int, feet: WindowFeet,
                         start: Tuple[int, ...], banned_first: frozenset,
                         banned_lengths: frozenset) -> Optional[FootstepWindow]:
        """:meth:`plan` by the readable search (``FootstepConfig.window_search``)."""
        table = self.foothold_table(profile, stance_side, feet.stance_s)
        found = search_footstep_window(table, self._window_limits, feet, start, banned_first,
                                       banned_lengths)
        if found is None:
            return None
        lengths, arc_lengths, heights, pitches = [], [], [], []
        cumulative, total = 0, 0.0
        for i, j in enumerate(found.configuration):
            cumulative += j
            lengths.append(self._window_limits.lengths[j])
            total += lengths[-1]
            arc_lengths.append(feet.stance_s + total)
            heights.append(table.height[i][cumulative])
            pitches.append(table.pitch[i][cumulative])
        return FootstepWindow(np.array(lengths), found.configuration, np.array(arc_lengths),
                              np.array(heights), np.array(pitches), self._sides[stance_side][0],
                              found.effort, found.evaluated)

    def search_profile(self, profile: GroundProfile, stance_side: int, stance_s: float,
                       stance_height: float, swing_s: float, swing_height: float,
                       s_init: float, previous_length: float) -> tuple:
        """
        Return what the compiled search of a window is given, as a tuple.

        What the compiled search of a window is given (:data:`footstep_search.PROFILE_TYPE`): the
        profile's samples, the layout of the window's foothold table, the planner's numbers and the
        window's own as a tuple (the arguments are :meth:`plan`'s). The search builds the table
        itself (:func:`footstep_search.foothold_tables`).
        """
        return (profile.stacked, self._search_constants, self._search_layout[stance_side],
                (stance_s, stance_height, swing_s, swing_height, s_init, previous_length,
                 profile.s0, profile.ds))

    def search_tables(self, *arguments) -> tuple:
        """
        Return the foothold table and numbers the search reads.

        The foothold table and numbers the search reads (:data:`footstep_search.TABLES_TYPE`), for
        :meth:`search_profile`'s arguments.
        """
        return foothold_tables(self.search_profile(*arguments))

    def plan_exhaustive(self, profile: GroundProfile, stance_side: int, stance_s: float,
                        stance_height: float, swing_s: float, swing_height: float,
                        s_init: float, previous_length: float) -> Optional[FootstepWindow]:
        """
        Return the optimum over every configuration of the window (for benchmarks only).

        The optimum over every configuration of the window (for benchmarks only): each judged by
        the same compiled effort as :meth:`plan`'s search
        (:func:`footstep_search.exhaustive_search`).
        """
        cfg = self.config
        return self._window(exhaustive_search(
            cfg.window_steps, cfg.step_intervals,
            self.search_profile(profile, stance_side, stance_s, stance_height, swing_s,
                                swing_height, s_init, previous_length)), stance_side)

    def _window(self, found: tuple, stance_side: int) -> Optional[FootstepWindow]:
        """
        Return the window a search found, None when it found none.

        The window a search found (:func:`footstep_search.window_search`'s answer), None when it
        found none.
        """
        number, footholds, effort, evaluated = found
        if number < 0:
            return None
        if self._configurations is not None:
            indices = self._configurations[number]
        else:
            n, m = self._window_size
            digits = []
            for _ in range(n):
                number, j = divmod(number, m + 1)
                digits.append(j)
            indices = tuple(digits[::-1])
        # Positional: keywords cost a fifth more on every planned step.
        return FootstepWindow(footholds[0], indices, footholds[1], footholds[2],
                              footholds[3], self._sides[stance_side][0], effort, evaluated)


def sample_ground_profile(environment, path, s_start: float, s_end: float, ds: float,
                          hip_half_width: float, foot_width: float, base_height: float,
                          max_step_up: float, levels: int) -> GroundProfile:
    """
    Sample the ground under both foot tracks along a predicted path (§3.2).

    "By taking the intersection of the ground and the sagittal plane of the actor, one can
    compute the ground profile along the global path." Here each foot has its own track, offset
    from the path by the hip half-width, sampled on the three lines of ``SOLE_LINES`` across the
    sole.

    Parameters
    ----------
    environment
        An :class:`environment.Environment`.
    path
        The :class:`path.PredictedPath`.
    s_start, s_end, ds
        Arc-length range and spacing of the samples, m.
    hip_half_width, foot_width
        Lateral track offset and sole width, m: side 0 (the left foot) lies ``hip_half_width``
        to the left of the path, so a negative offset puts it on the right (a path walked
        backward, ``PredictedPath.track_sign``).
    base_height
        Sole height of the stance foot, m: ground within reach is looked for at or below
        ``base_height + max_step_up`` first, then one step-up higher per level (stairs).
    max_step_up
        Largest step-up, m.
    levels
        How many step-ups ahead to look (the window length).

    Returns
    -------
    GroundProfile

    """
    count = int(np.ceil((s_end - s_start) / ds)) + 1
    s = s_start + ds * np.arange(count)
    across = np.array(SOLE_LINES) * foot_width
    # Left track first, then right; three lines across each sole.
    tracks = np.concatenate([hip_half_width + across, -hip_half_width + across])
    points = path.offset_points(s, tracks[:, None])
    xy = points.reshape(-1, 2)
    height, clearance = environment.ground_height(xy, base_height + max_step_up + 0.02)
    for level in range(1, max(levels, 1)):
        missing = np.isnan(height)
        if not missing.any():
            break
        z_ref = base_height + (level + 1) * max_step_up + 0.02
        h, c = environment.ground_height(xy[missing], z_ref)
        height[missing], clearance[missing] = h, c
    obstacle = height.copy()
    missing = np.isnan(obstacle)
    if missing.any():
        # Inside a solid the swing must clear its top; over empty space there is nothing to hit.
        top, _ = environment.ground_height(xy[missing], base_height + 3.0)
        obstacle[missing] = top
    shape = (2, across.size, count)
    height = height.reshape(shape)
    clearance = clearance.reshape(shape)
    obstacle = obstacle.reshape(shape)
    # Written into the array the footstep search takes (GroundProfile.stacked). Maxima, minima
    # and comparisons with NaN raise no floating-point warnings: no errstate.
    stacked = np.empty((4, 2, count))
    height.max(axis=1, out=stacked[0])
    height.min(axis=1, out=stacked[1])
    np.where(np.isnan(clearance), 0.0, clearance).min(axis=1, out=stacked[2])
    # NaN (nothing to hit) read as -inf, so a plain max is the NaN-ignoring one.
    np.where(np.isnan(obstacle), -np.inf, obstacle).max(axis=1, out=stacked[3])
    tops = stacked[3].copy()
    tops[tops == -np.inf] = np.nan
    return GroundProfile(s0=float(s_start), ds=float(ds), height=stacked[0], low=stacked[1],
                         headroom=stacked[2], obstacle=tops, stacked=stacked)


def describe_ground_ahead(environment, path, profile: GroundProfile, s_from: float,
                          s_to: float, sole: float, config: FootstepConfig,
                          hip_half_width: float, foot_width: float,
                          direction: str = 'ahead') -> str:
    """
    Why no footstep can be placed ahead, in a user's words with the number, or ''.

    The first sample of either foot's track between arc lengths ``s_from`` and ``s_to`` (m)
    where a foot cannot stand relative to the stance sole height ``sole`` (m): ground that
    rises more than ``max_step_up`` (a wall reads as its top), falls more than
    ``max_step_down``, ends, or has less than ``min_headroom`` above it. ``path`` is the one
    the profile was sampled along (tracks ``hip_half_width`` m either side, read on
    ``SOLE_LINES`` across a sole ``foot_width`` m wide); distances are from its start (the
    pelvis), m, and told ``direction`` of the actor: 'ahead', or 'behind' along a path walked
    backward.

    Returns
    -------
    str
        e.g. 'the next rise is 0.35 m, 0.52 m ahead; the legs climb at most 0.30 m', or ''
        when every foothold ahead has ground a foot could stand on (the window is refused
        for its steps together: flatness, slope, swing height).

    """
    s = profile.arc_lengths()
    ahead = np.flatnonzero((s >= s_from) & (s <= s_to))
    if ahead.size == 0:
        return ''
    height, headroom = profile.height[:, ahead], profile.headroom[:, ahead]
    with np.errstate(invalid='ignore'):
        drop = height < sole - config.max_step_down
        blocked = np.isnan(height) | drop | (headroom < config.min_headroom)
    columns = np.flatnonzero(blocked.any(axis=0))
    if columns.size == 0:
        return ''
    column = int(columns[0])
    side = int(np.flatnonzero(blocked[:, column])[0])
    distance = float(s[ahead[column]])
    offset = (hip_half_width if side == 0 else -hip_half_width) + foot_width * np.array(
        SOLE_LINES)
    xy = path.offset_poses(np.full(offset.size, distance), offset)[:, :2]
    where = f'{distance:.2f} m {direction}'
    if drop[side, column]:
        return (f'the next drop is {sole - height[side, column]:.2f} m, {where}; the legs '
                f'step down at most {config.max_step_down:.2f} m')
    if not np.isnan(height[side, column]):
        return (f'an overhang {headroom[side, column]:.2f} m above the ground {where}; the '
                f'legs need {config.min_headroom:.2f} m')
    top, _ = environment.ground_height(xy, sole + 10.0)
    below, _ = environment.ground_height(xy, sole + config.max_step_up)
    rise = float(np.fmax.reduce(top)) - sole
    if rise > config.max_step_up:
        return (f'the next rise is {rise:.2f} m, {where}; the legs climb at most '
                f'{config.max_step_up:.2f} m')
    if np.isnan(below).any():
        return f'the ground ends {where}'
    fall = sole - float(below.min())
    if fall > config.max_step_down:
        return (f'the next drop is {fall:.2f} m, {where}; the legs step down at most '
                f'{config.max_step_down:.2f} m')
    return ''
