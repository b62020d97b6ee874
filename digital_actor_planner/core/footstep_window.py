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
§4.2's search of one footstep window, written out as the code of record.

A footstep configuration q_f = (j_1, ..., j_n) holds the interval index of each of the next n
footsteps: footstep i is ``lengths[j_i]`` long, one of the m + 1 lengths in [s_min, s_max].
:func:`search_footstep_window` is the paper's search: a breadth-first search from q_init to the
nearest collision-free configuration, then hill-climbing on the effort criterion to the best
neighbour until no neighbour is better. The caller executes s_1 only and starts the next window
from (s_2, ..., s_n, s_init) (``Actor``: "slide the window by one step").

The search sees the ground only through a :class:`FootholdTable` (every foothold the window can
reach, judged beforehand, and the profile's swing obstacle), as a planner sees only its space.
:func:`footstep_search.window_search` is its compiled twin, the runtime path
(``FootstepConfig.window_search``): the same configurations judged in the same order, the same
sums in the same order, so the same footsteps and efforts to the last bit; the twin is about an
order of magnitude faster (``bench/bench_footstep_window.py``, docs/READABLE_ALGORITHMS.md).
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Callable, Dict, FrozenSet, Iterator, Optional, Tuple

#: A footstep configuration: the interval index (0..m) of each footstep of the window.
Configuration = Tuple[int, ...]

#: How much a neighbour must lower the effort to be climbed to: differences in the last bits
#: of a sum are no improvement (the compiled twin uses the same margin).
IMPROVEMENT = 1e-12


@dataclass(frozen=True)
class WindowLimits:
    """
    What a window's footsteps must respect and how their effort is weighed.

    Attributes
    ----------
    lengths
        (m + 1,) the allowed footstep lengths, ascending, m.
    window_steps
        n, footsteps per window.
    max_step_up, max_step_down
        Largest rise and drop from one foothold to the next, m.
    max_swing_height
        How far above the higher of its two footholds a swinging foot may have to clear the
        ground between them, m.
    lift_rise, lift_step_up
        How far the ground ahead of a placed foot's toe may rise above its sole's plane for
        the foot to lift off again: ``lift_rise`` more as much as the next footstep on that
        side climbs, at most ``lift_step_up``, m (``FootstepConfig``).
    weight_length, weight_height, weight_pitch, weight_smooth
        The effort's weights (dimensionless).
    length_span, rise_range, pitch_range
        The ranges the effort's terms are normalised by: s_max - s_min (m), the largest
        step-up (m) and the largest sole pitch (rad).
    greedy_restart
        Climb once more from the configuration built footstep by footstep and keep the
        better result.

    """

    lengths: Tuple[float, ...]
    window_steps: int
    max_step_up: float
    max_step_down: float
    max_swing_height: float
    lift_rise: float
    lift_step_up: float
    weight_length: float
    weight_height: float
    weight_pitch: float
    weight_smooth: float
    length_span: float
    rise_range: float
    pitch_range: float
    greedy_restart: bool

    @property
    def intervals(self) -> int:
        """m, the intervals the footstep lengths are divided into."""
        return len(self.lengths) - 1


@dataclass(frozen=True)
class WindowFeet:
    """
    Where the window starts: the feet and the commanded stride, lengths in m.

    Attributes
    ----------
    stance_s, stance_height
        The foot that stays down: arc length along the path and sole height.
    swing_s, swing_height
        Where the foot that steps first lifts from.
    s_init
        The neutral footstep length (from the commanded speed).
    previous_length
        Length of the step just taken (for the smoothness term).

    """

    stance_s: float
    stance_height: float
    swing_s: float
    swing_height: float
    s_init: float
    previous_length: float


@dataclass(frozen=True)
class FootholdTable:
    """
    Every foothold a window can reach, judged beforehand.

    Footstep i's foothold depends only on the sum c of the interval indices of footsteps
    1..i + 1 (its arc length is the stance foot's + (i + 1) s_min + c increments): entry
    ``[i][c]`` of each table, c = 0..(i + 1) m.

    Attributes
    ----------
    ok
        Whether a sole can rest there (``FootstepPlanner.footholds``).
    height, pitch
        The sole's height under the ankle (m) and its pitch (rad, toes up positive).
    rise_ahead
        How far the ground within ``lift_room`` ahead of that sole's toe rises above its
        plane, m (``FootstepPlanner.rise_ahead``).
    sides
        (n,) side of each footstep, 0 left, 1 right.
    swing_top
        ``GroundProfile.swing_top``: the highest ground a foot on ``side`` swings over from a
        toe's arc length to a heel's, m (NaN over empty space only).
    toe, heel
        The sole's length in front of and behind the ankle, m.

    """

    ok: Tuple[Tuple[bool, ...], ...]
    height: Tuple[Tuple[float, ...], ...]
    pitch: Tuple[Tuple[float, ...], ...]
    rise_ahead: Tuple[Tuple[float, ...], ...]
    sides: Tuple[int, ...]
    swing_top: Callable[[int, float, float], float]
    toe: float
    heel: float


@dataclass(frozen=True)
class WindowSearchResult:
    """
    The configuration a window's search settled on.

    Attributes
    ----------
    configuration
        (n,) interval indices.
    effort
        Its effort criterion (dimensionless).
    evaluated
        Configurations whose feasibility was tested.

    """

    configuration: Configuration
    effort: float
    evaluated: int


def search_footstep_window(table: FootholdTable, limits: WindowLimits, feet: WindowFeet,
                           start: Configuration, banned_first: FrozenSet[int] = frozenset(),
                           banned_lengths: FrozenSet[int] = frozenset()
                           ) -> Optional[WindowSearchResult]:
    """
    Search one footstep window (§4.2): breadth-first to feasible, then hill-climbing.

    Parameters
    ----------
    table
        The footholds the window can reach.
    limits
        The window's rules and effort weights.
    feet
        The feet where the window starts.
    start
        q_init, (n,) interval indices: (s_init, ..., s_init) or the slid previous window.
    banned_first
        Interval indices the first footstep must not take (the walk could not realise them).
    banned_lengths
        Interval indices no footstep may take (too long for a tight turn).

    Returns
    -------
    WindowSearchResult or None
        None when no configuration of the window is collision-free.

    """
    m = limits.intervals
    judged: Dict[Configuration, Optional[float]] = {}

    def effort(configuration: Configuration) -> Optional[float]:
        # Each configuration is judged once; None: not collision-free.
        if configuration not in judged:
            judged[configuration] = configuration_effort(configuration, table, limits, feet,
                                                         banned_first, banned_lengths)
        return judged[configuration]

    # §4.2: breadth-first search from q_init to the first collision-free configuration,
    # moving one footstep by one interval at a time (footstep by footstep, shorter first).
    found = start if effort(start) is not None else None
    if found is None and not all(any(row) for row in table.ok):
        # Some footstep has no foothold in reach: no configuration can be collision-free.
        return None
    frontier, seen = deque([start]), {start}
    while found is None and frontier:
        for neighbour in _single_moves(frontier.popleft(), m):
            if neighbour in seen:
                continue
            seen.add(neighbour)
            if effort(neighbour) is not None:
                found = neighbour
                break
            frontier.append(neighbour)
    if found is None:
        return None

    # §4.2: hill-climbing on the effort from there.
    best = _hill_climb(found, effort, m)

    # On stairs and blocks the collision-free configurations fall apart into basins (a
    # foothold on every tread or on every other one) and one climb cannot leave its basin:
    # climb once more from the configuration built footstep by footstep, keep the better.
    if limits.greedy_restart:
        seed = greedy_configuration(table, limits, feet, banned_first, banned_lengths)
        if seed is not None and seed != best and effort(seed) is not None:
            other = _hill_climb(seed, effort, m)
            if effort(other) < effort(best) - IMPROVEMENT:
                best = other
    return WindowSearchResult(best, effort(best), len(judged))


def _single_moves(configuration: Configuration, m: int) -> Iterator[Configuration]:
    """List the breadth-first search's moves: one footstep one interval shorter, then longer."""
    for i, j in enumerate(configuration):
        for delta in (-1, 1):
            if 0 <= j + delta <= m:
                yield configuration[:i] + (j + delta,) + configuration[i + 1:]


def _climbing_moves(configuration: Configuration, m: int) -> Iterator[Configuration]:
    """
    List hill-climbing's neighbours: single moves and compensated pairs.

    Hill-climbing's neighbours: each single move, followed by that move with the next footstep
    changed the opposite way, so that the footholds after them stay where they are (without it the
    climb stalls on ridges of the effort).
    """
    n = len(configuration)
    for i, j in enumerate(configuration):
        for delta in (-1, 1):
            if not 0 <= j + delta <= m:
                continue
            yield configuration[:i] + (j + delta,) + configuration[i + 1:]
            if i + 1 < n and 0 <= configuration[i + 1] - delta <= m:
                yield (configuration[:i] + (j + delta, configuration[i + 1] - delta)
                       + configuration[i + 2:])


def _hill_climb(configuration: Configuration,
                effort: Callable[[Configuration], Optional[float]], m: int) -> Configuration:
    """
    Climb to the best collision-free neighbour while the effort falls.

    Move to the best collision-free neighbour while it lowers the effort (by more than
    :data:`IMPROVEMENT` than the best before it); the configuration where that ends.
    """
    value = effort(configuration)
    while True:
        best, best_value = None, value
        for neighbour in _climbing_moves(configuration, m):
            neighbour_value = effort(neighbour)
            if neighbour_value is not None and neighbour_value < best_value - IMPROVEMENT:
                best, best_value = neighbour, neighbour_value
        if best is None:
            return configuration
        configuration, value = best, best_value


def configuration_effort(configuration: Configuration, table: FootholdTable,
                         limits: WindowLimits, feet: WindowFeet,
                         banned_first: FrozenSet[int] = frozenset(),
                         banned_lengths: FrozenSet[int] = frozenset()) -> Optional[float]:
    """
    Return the effort criterion of a configuration, None where it is not collision-free.

    Each footstep from the stance foot on must land on a foothold, rise or drop no more than
    allowed, and its foot must swing there from where it was two footsteps before (the swing
    foot for the first footstep, the stance foot for the second) over the ground between.

    Parameters
    ----------
    configuration
        (n,) interval indices.
    table, limits, feet, banned_first, banned_lengths
        As :func:`search_footstep_window` takes them.

    Returns
    -------
    float or None
        The sum of :func:`step_effort` over the footsteps (dimensionless).

    """
    if configuration[0] in banned_first or any(j in banned_lengths for j in configuration):
        return None
    # Where the feet of the next two footsteps lift from: arc length, sole height and the
    # foothold's place (footstep, cumulative index) in the table where the window placed it.
    lifts_next = (feet.swing_s, feet.swing_height, None)
    lifts_after = (feet.stance_s, feet.stance_height, None)
    s, height_before, length_before = feet.stance_s, feet.stance_height, feet.previous_length
    cumulative, total = 0, 0.0
    for i, j in enumerate(configuration):
        length = limits.lengths[j]
        s += length
        cumulative += j
        if not table.ok[i][cumulative]:
            return None
        height = table.height[i][cumulative]
        rise = height - height_before
        if rise > limits.max_step_up or -rise > limits.max_step_down:
            return None
        s_from, height_from, placed = lifts_next
        if not swing_clear(table, limits, table.sides[i], (s_from, height_from), (s, height),
                           placed):
            return None
        total += step_effort(limits, feet, length, rise, table.pitch[i][cumulative],
                             length_before)
        lifts_next, lifts_after = lifts_after, (s, height, (i, cumulative))
        height_before, length_before = height, length
    return total


def swing_clear(table: FootholdTable, limits: WindowLimits, side: int,
                lift: Tuple[float, float], land: Tuple[float, float],
                placed: Optional[Tuple[int, int]] = None) -> bool:
    """
    Whether a foot can swing from one foothold to the next.

    Parameters
    ----------
    table, limits
        As :func:`search_footstep_window` takes them.
    side
        0 left, 1 right.
    lift, land
        (arc length, sole height) of the foothold the foot leaves and of the one it lands on,
        m.
    placed
        (footstep, cumulative index) of the foothold it leaves where the window placed it
        there: that foothold must then also let it lift off (``FootstepConfig.lift_room``).

    Returns
    -------
    bool

    """
    (s_from, height_from), (s_to, height_to) = lift, land
    # NaN (empty space only) passes: there is nothing to hit.
    top = table.swing_top(side, s_from + table.toe, s_to - table.heel)
    if top > max(height_from, height_to) + limits.max_swing_height:
        return False
    if placed is None:
        return True
    allowed = min(limits.lift_rise + max(height_to - height_from, 0.0), limits.lift_step_up)
    return table.rise_ahead[placed[0]][placed[1]] <= allowed


def step_effort(limits: WindowLimits, feet: WindowFeet, length: float, rise: float,
                pitch: float, length_before: float) -> float:
    """
    Return one footstep's share of the effort.

    One footstep's share of the effort: its length off the neutral one, its height change, its
    sole's pitch and its change of length, each normalised by its range and squared.

    Parameters
    ----------
    limits, feet
        As :func:`search_footstep_window` takes them.
    length, rise, pitch, length_before
        The footstep's length (m), rise (m), sole pitch (rad) and the length before it (m).

    Returns
    -------
    float
        Dimensionless.

    """
    return (limits.weight_length * ((length - feet.s_init) / limits.length_span) ** 2
            + limits.weight_height * (rise / limits.rise_range) ** 2
            + limits.weight_pitch * (pitch / limits.pitch_range) ** 2
            + limits.weight_smooth * ((length - length_before) / limits.length_span) ** 2)


def greedy_configuration(table: FootholdTable, limits: WindowLimits, feet: WindowFeet,
                         banned_first: FrozenSet[int] = frozenset(),
                         banned_lengths: FrozenSet[int] = frozenset()
                         ) -> Optional[Configuration]:
    """
    Build the configuration footstep by footstep, each the cheapest.

    The configuration built footstep by footstep, each the cheapest by :func:`step_effort` given
    the ones before (the shortest of equals), among footholds in step reach; not judged for the
    swings (the search judges it whole). None where some footstep has no candidate.

    Parameters
    ----------
    table, limits, feet, banned_first, banned_lengths
        As :func:`search_footstep_window` takes them.

    Returns
    -------
    Configuration or None

    """
    configuration: Configuration = ()
    cumulative, height_before, length_before = 0, feet.stance_height, feet.previous_length
    for i in range(limits.window_steps):
        candidates = []
        for j, length in enumerate(limits.lengths):
            if j in banned_lengths or (i == 0 and j in banned_first):
                continue
            if not table.ok[i][cumulative + j]:
                continue
            rise = table.height[i][cumulative + j] - height_before
            if rise > limits.max_step_up or -rise > limits.max_step_down:
                continue
            cost = step_effort(limits, feet, length, rise, table.pitch[i][cumulative + j],
                               length_before)
            candidates.append((cost, j))
        if not candidates:
            return None
        j = min(candidates)[1]
        configuration += (j,)
        cumulative += j
        height_before, length_before = table.height[i][cumulative], limits.lengths[j]
    return configuration
