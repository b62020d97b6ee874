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
The footstep window's search (§4.2) as compiled kernels.

:meth:`footsteps.FootstepPlanner.plan` hands the profile's samples and the layout of the
window's foothold table here. One call (:func:`window_search`) searches: a breadth-first search
from the start configuration to the nearest collision-free one, then hill-climbing on the
effort while a neighbour improves it, then (``greedy_restart``) a second climb from a
configuration built footstep by footstep. It judges the footholds of the table (every
foothold the window can reach, :func:`_judge_sole`) as it first reads them: a sixth of them
at the median on the courses' windows, at most three fifths; :func:`exhaustive_search` builds
the whole table first (:func:`foothold_tables`). No Python runs between the configurations it
judges.

A configuration (j_0, ..., j_{n-1}) of interval indices is numbered in base m + 1, footstep 0
the most significant digit; its first L footsteps (a prefix) are numbered the same way, and
its row in the prefix memo is that number after the rows of the shorter prefixes (1 to L - 1
footsteps: m + 1, (m + 1) ** 2, ... rows). Three memos live for one search:

- ``feasible[number]``: the effort of a configuration judged, NaN where it is not
  collision-free (their count is the window's ``evaluated``); :func:`window_search` keeps it
  in arrays over every configuration where there are at most
  :data:`DENSE_CONFIGURATIONS`, in this dictionary past that;
- ``prefixes[row]``: the state after a prefix, (effort, arc length, sole height, length,
  cumulative interval index, 1), the cumulative index -1 where the prefix already fails, and
  all 0 where it is not known; a configuration is judged from the longest prefix known, so
  neighbours that share their first footsteps (hill-climbing changes one or two) reuse them,
  with the same sums in the same order. An array over every prefix of 1 to n - 1 footsteps
  (the paper's window: 210 rows), or of as many footsteps as fit in :data:`PREFIX_ROWS`
  (longer ones are not remembered); the exhaustive search's has no rows: it judges each
  configuration whole;
- ``swings[key]``: whether a foot can swing from one foothold to the next, 1 or 0, -1 not
  known yet (the key numbers the footstep, the foothold it leaves (-1: where the foot stands
  now) and where it lands): an array over every key, none where there would be more than
  :data:`SWING_KEYS`.

The last two are arrays rather than numba dictionaries, whose lookups hash their keys and whose
insertions can resize them.

The arithmetic is the plain effort's term by term (the readable search of record,
:func:`footstep_window.search_footstep_window`):
the squares are ``x ** two`` with ``two`` = 2.0 read from ``numbers``, because numba turns a
constant square into ``x * x``, which differs from the C library's ``pow`` (what Python's
``**`` calls) in the last bit for about one value in 1,200. Without numba the same functions run
as Python.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import kernel

#: Indices into the ``numbers`` array of :func:`window_search` (see
#: ``FootstepPlanner._search_constants``, whose first NUMBER_COUNT they are).
(STANCE_S, STANCE_HEIGHT, SWING_S, SWING_HEIGHT, S_INIT, PREVIOUS_LENGTH, UP, DOWN,
 W_LENGTH, W_HEIGHT, W_PITCH, W_SMOOTH, SPAN, UP_RANGE, PITCH_RANGE, TOE, HEEL, S0, DS,
 MAX_SWING, LIFT_ROOM, LIFT_RISE, LIFT_STEP_UP, TWO, MIN_HEADROOM, MAX_PITCH, TOLERANCE,
 MIN_FRACTION) = range(28)
NUMBER_COUNT = 28


@kernel('Tuple((b1, f8, f8))(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8, f8, i8, f8, f8, f8, f8, '
        'f8, f8, f8)', inline=True)
def _judge_sole(high, low, headroom, s0, ds, row, sn, heel, toe, min_headroom, max_pitch,
                tolerance, min_fraction):
    """
    Judge one sole of :func:`judge_footholds`: (ok, height, pitch).

    One sole of :func:`judge_footholds`, its ankle at arc length ``sn`` on side ``row``: (ok,
    height, pitch). A maximum or minimum over a NaN sample is NaN, as NumPy's: a missing sample
    makes the sole neither flat nor supported at an edge.
    """
    samples = high.shape[1]
    # The samples from the heel to the toe, none beyond them.
    i0 = int(math.ceil((sn - heel - s0) / ds - 1e-9))
    i1 = int(math.floor((sn + toe - s0) / ds + 1e-9))
    if i0 < 0 or i1 >= samples or i1 < i0:
        return False, math.nan, 0.0
    # One pass: the headroom, the sum of the slope's fit and whether a sample is missing.
    # The least-squares slope through evenly spaced samples: their mean is the middle of
    # the first and the last, and the squares of their distances from it sum to
    # ds^2 W (W^2 - 1) / 12. Two samples or fewer fit no slope.
    width = i1 - i0 + 1
    middle = s0 + (0.5 * ds) * (i0 + i1) - sn
    total = 0.0
    clean = True
    for i in range(i0, i1 + 1):
        if not headroom[row, i] >= min_headroom:  # NaN has no headroom either
            return False, math.nan, 0.0
        h = high[row, i]
        total += ((s0 + ds * i - sn) - middle) * h
        if h != h or low[row, i] != low[row, i]:
            clean = False
    slope = 0.0
    if width > 2:
        slope = total / max((ds * ds / 12.0) * width * (width * width - 1), 1e-30)
    pitch = math.atan(slope)
    # The sole rests on the highest point above the fitted plane and must not bridge a dip
    # below it deeper than the tolerance. Without a NaN the plain comparisons give the
    # NaN-propagating ones' answers, faster.
    lift, dip, top = -np.inf, np.inf, -np.inf
    if clean and slope == slope:
        for i in range(i0, i1 + 1):
            plane = slope * (s0 + ds * i - sn)
            h = high[row, i]
            above, below = h - plane, low[row, i] - plane
            if above > lift:
                lift = above
            if below < dip:
                dip = below
            if h > top:
                top = h
    else:
        for i in range(i0, i1 + 1):
            plane = slope * (s0 + ds * i - sn)
            above, below, h = high[row, i] - plane, low[row, i] - plane, high[row, i]
            if lift == lift and (above != above or above > lift):
                lift = above
            if dip == dip and (below != below or below < dip):
                dip = below
            if top == top and (h != h or h > top):
                top = h
    if abs(pitch) <= max_pitch and lift - dip <= tolerance:
        return True, lift, pitch
    # At an edge a flat sole may overhang lower ground: the ankle's sample (the lower of
    # two as near) and its neighbours on the sole must be supported, and most of the sole.
    # Not the pitch limit: the plane through the overhung ground tilts too (a heel over a
    # stair's nosing, 0.2 m lower, tilted it past the limit).
    level = top - tolerance
    ankle = int(min(max(math.ceil((sn - s0) / ds - 0.5), i0), i1))
    supported, around = 0, True
    for i in range(i0, i1 + 1):
        if high[row, i] >= level and low[row, i] >= level:
            supported += 1
        elif ankle - 1 <= i <= ankle + 1:
            around = False
    if around and supported / width >= min_fraction:
        return True, top, 0.0
    return False, math.nan, pitch


@kernel('Tuple((b1[::1], f8[::1], f8[::1]))(f8[:, ::1], f8[:, ::1], f8[:, ::1], f8, f8, '
        'readonly(i8[::1]), '
        'f8[::1], f8, f8, f8, f8, f8, f8)')
def judge_footholds(high, low, headroom, s0, ds, side, s, heel, toe, min_headroom, max_pitch,
                    tolerance, min_fraction):
    """
    Judge every sole in one pass, as :meth:`footsteps.FootstepPlanner.footholds` does.

    :meth:`footsteps.FootstepPlanner.footholds` for every sole in one pass (see there for the
    rules): :func:`_judge_sole` of each.

    Returns (ok, sole height under the ankle (NaN where not ok), pitch of the sole's plane,
    the C library's arctangent of its slope: 0 on an edge and where the sole is not usable).
    """
    count = s.shape[0]
    ok = np.zeros(count, dtype=np.bool_)
    height = np.full(count, np.nan)
    pitch = np.zeros(count)
    for n in range(count):
        ok[n], height[n], pitch[n] = _judge_sole(high, low, headroom, s0, ds, side[n], s[n],
                                                 heel, toe, min_headroom, max_pitch,
                                                 tolerance, min_fraction)
    return ok, height, pitch


#: The most rows the prefix memo of one search may have (48 bytes each, zeroed for every
#: search): the prefixes of up to as many footsteps as fit are remembered.
PREFIX_ROWS = 1 << 12
#: The most keys the swing memo of one search may have (a byte each, set for every search;
#: the paper's window: 5,043); a window with more remembers no swing.
SWING_KEYS = 1 << 16
#: The answer of ``feasible`` for a configuration not judged yet (an effort is >= 0).
_UNJUDGED = -1.0

#: The foothold table and the numbers every kernel below reads: (ok (T,) bool, height (T,) m,
#: pitch (T,) rad: footstep i's foothold when the indices of footsteps 0..i sum to c is entry
#: bounds[i] + c; bounds (n + 1,); offsets (T,) m beyond the stance foot; obstacle (2, K) m,
#: the profile's swing obstacle with -inf over empty space; sides (n,); lengths (m + 1,) m;
#: last sample index of the profile; numbers (NUMBER_COUNT,)).
TABLES_TYPE = ('Tuple((b1[::1], f8[::1], f8[::1], readonly(i8[::1]), readonly(f8[::1]), '
               'f8[:, ::1], readonly(i8[::1]), readonly(f8[::1]), i8, f8[::1]))')
#: What a window's search is given (see ``FootstepPlanner.search_profile``), in four pieces:
#: only four arrays for numba to unbox (each array costs its unboxing, more in the walk,
#: cold): the profile's samples (4, 2, K): height, low, headroom and
#: obstacle with -inf over empty space (``GroundProfile.stacked``); the planner's numbers
#: (:data:`NUMBER_COUNT`), the footstep lengths (m + 1,) m and the offset beyond the stance
#: foot (T,) m of each entry of the foothold table, in one array; the layout: n, m, bounds
#: (n + 1,), sides (n,) and the side of each entry of the table (T,), in one array; the
#: window's own numbers, in the order of :data:`WINDOW_NUMBERS` (the search writes them into
#: a copy of the planner's: in Python eight assignments to an array cost about as long as
#: the whole of the search's setting-up).
PROFILE_TYPE = ('Tuple((f8[:, :, ::1], readonly(f8[::1]), readonly(i8[::1]), '
                'UniTuple(f8, 8)))')
#: The window's own numbers in a :data:`PROFILE_TYPE`, as indices into ``numbers``: the stance
#: and the swing foot's arc length and sole height, the neutral footstep length, the length of
#: the step just taken, the profile's first arc length and its spacing.
WINDOW_NUMBERS = (STANCE_S, STANCE_HEIGHT, SWING_S, SWING_HEIGHT, S_INIT, PREVIOUS_LENGTH, S0, DS)
_FEASIBLE_TYPE = 'DictType(i8, f8)'
_PREFIXES_TYPE = 'f8[:, ::1]'
_SWINGS_TYPE = 'i1[::1]'
#: The banned interval indices (m + 1,) bool, read-only (the planner's shared none-banned).
_BANNED = 'readonly(b1[::1])'


@kernel('readonly(i8[::1])(' + PROFILE_TYPE + ')', inline=True)
def _entry_sides(profile):
    """Return the side of each entry of the foothold table (T,), from a :data:`PROFILE_TYPE`."""
    layout = profile[2]
    n = layout[0]
    return layout[2 * n + 3:]


@kernel(TABLES_TYPE + '(' + PROFILE_TYPE + ')', inline=True)
def _unjudged_tables(profile):
    """
    Return :func:`foothold_tables` before any entry is judged.

    :func:`foothold_tables` before any entry is judged (not ok, height NaN, pitch 0):
    :func:`window_search` judges the entries it reads, as it first reads them. Its numbers are the
    planner's with the window's own (:data:`WINDOW_NUMBERS`) written in.
    """
    samples, constants, layout, window = profile
    n, m = layout[0], layout[1]
    numbers = constants[:NUMBER_COUNT].copy()
    for k in range(len(WINDOW_NUMBERS)):
        numbers[WINDOW_NUMBERS[k]] = window[k]
    lengths = constants[NUMBER_COUNT:NUMBER_COUNT + m + 1]
    offsets = constants[NUMBER_COUNT + m + 1:]
    count = offsets.shape[0]
    return (np.zeros(count, dtype=np.bool_), np.full(count, np.nan), np.zeros(count),
            layout[2:n + 3], offsets, samples[3], layout[n + 3:2 * n + 3], lengths,
            samples.shape[2] - 1, numbers)


@kernel(TABLES_TYPE + '(' + PROFILE_TYPE + ')')
def foothold_tables(profile):
    """
    Return the window's foothold table and the profile's obstacles, judged.

    The window's foothold table (:func:`_judge_sole` of every entry, as :func:`judge_footholds`
    judges them, written into :func:`_unjudged_tables`' arrays) and the profile's obstacle with
    -inf over empty space: the :data:`TABLES_TYPE` the searches read, from the :data:`PROFILE_TYPE`
    they are given (:func:`window_search` judges its entries as it reads them instead).
    """
    samples, entry_sides = profile[0], _entry_sides(profile)
    high, low, headroom = samples[0], samples[1], samples[2]
    tables = _unjudged_tables(profile)
    ok, height, pitch, offsets, numbers = tables[0], tables[1], tables[2], tables[4], tables[9]
    for entry in range(ok.shape[0]):
        ok[entry], height[entry], pitch[entry] = _judge_sole(
            high, low, headroom, numbers[S0], numbers[DS], entry_sides[entry],
            numbers[STANCE_S] + offsets[entry], numbers[HEEL], numbers[TOE],
            numbers[MIN_HEADROOM], numbers[MAX_PITCH], numbers[TOLERANCE],
            numbers[MIN_FRACTION])
    return tables


@kernel('Tuple((' + _FEASIBLE_TYPE + ', ' + _PREFIXES_TYPE + ', ' + _SWINGS_TYPE
        + '))(i8, i8, b1)', inline=True)
def _empty_memos(n, m, resume):
    """
    Return empty ``feasible``, ``prefixes`` and ``swings`` memos for one search.

    Empty ``feasible``, ``prefixes`` and ``swings`` memos for one search of a window of ``n``
    footsteps and ``m`` intervals; ``prefixes`` without rows unless ``resume``. The dictionary
    typed by a first entry (computed, not a literal value: a literal one would be part of its
    type), removed at once.
    """
    feasible = {-1: math.nan}
    del feasible[-1]
    rows, power = 0, 1
    if resume:
        for _ in range(n - 1):
            power *= m + 1
            if rows + power > PREFIX_ROWS:
                break
            rows += power
    keys = n * (n * m + 2) ** 2
    return (feasible, np.zeros((rows, 6)),
            np.full(keys if keys <= SWING_KEYS else 0, -1, dtype=np.int8))


@kernel('void(i8, i8, i8[::1])')
def _digits(number, base, config):
    """Write configuration ``number``'s interval indices into ``config`` (its numbering undone)."""
    for i in range(config.shape[0] - 1, -1, -1):
        config[i] = number % base
        number //= base


@kernel('f8(f8, f8, f8, f8, f8[::1])', inline=True)
def _step_cost(length, rise, pitch, length_before, numbers):
    """
    Return one footstep's share of the effort.

    One footstep's share of the effort: length off the neutral one, height change, sole pitch and
    change of length, each normalised by its range, in the plain effort's order (the squares as
    ``** two``, see the module's docstring).
    """
    two, span = numbers[TWO], numbers[SPAN]
    return (numbers[W_LENGTH] * ((length - numbers[S_INIT]) / span) ** two
            + numbers[W_HEIGHT] * (rise / numbers[UP_RANGE]) ** two
            + numbers[W_PITCH] * (pitch / numbers[PITCH_RANGE]) ** two
            + numbers[W_SMOOTH] * ((length - length_before) / span) ** two)


@kernel('f8(i8, i8, ' + TABLES_TYPE + ')', inline=True)
def _rise_ahead(row, cumulative, tables):
    """
    Return how far the ground ahead of a foothold's toe rises above its sole's plane, m.

    How far the ground within ``lift_room`` ahead of a foothold's toe rises above its sole's plane
    carried on, m: -inf where nothing does (or no room is asked for), NaN where the foothold has no
    height. :meth:`footsteps.FootstepPlanner.rise_ahead` of one foothold of the table (row ``row``,
    cumulative interval index ``cumulative``).
    """
    ok, height, pitch, bounds, offsets, obstacle, sides, lengths, last, numbers = tables
    entry = bounds[row] + cumulative
    sole = height[entry]
    if sole != sole:  # NaN: no foothold there
        return math.nan
    lift_room = numbers[LIFT_ROOM]
    if lift_room <= 0:
        return -math.inf
    toe, s0, ds = numbers[TOE], numbers[S0], numbers[DS]
    s = numbers[STANCE_S] + offsets[entry]
    first = int(math.floor((s + toe - s0) / ds + 1e-9))
    end = int(math.floor((s + (toe + lift_room) - s0) / ds + 1e-9))
    slope = math.tan(pitch[entry])
    side = sides[row]
    value = -math.inf
    for j in range(first + 1, end + 1):
        j = min(max(j, 0), last)
        past = obstacle[side, j]
        if past != -math.inf:
            rise = past - slope * (s0 + ds * j - s) - sole
            if rise > value:
                value = rise
    return value


@kernel('b1(i8, f8, f8, f8, f8, i8, i8, ' + TABLES_TYPE + ')', inline=True)
def _swing_clear(side, s_from, h_from, s_to, h_to, from_row, from_cumulative, tables):
    """
    Return whether a foot can swing from one foothold to the next over the obstacles.

    Whether a foot can swing from one foothold (arc length, sole height) to the next over the
    profile's obstacles, at most ``max_swing_height`` above the higher of the two; where it leaves
    a foothold the window placed (``from_row`` >= 0, with its cumulative index), that foothold must
    also let it lift off (``FootstepConfig.lift_room``).
    """
    ok, height, pitch, bounds, offsets, obstacle, sides, lengths, last, numbers = tables
    toe, heel, s0, ds = numbers[TOE], numbers[HEEL], numbers[S0], numbers[DS]
    i0 = max(int(math.floor((s_from + toe - s0) / ds)), 0)
    i1 = min(int(math.ceil((s_to - heel - s0) / ds)), last)
    if i1 >= i0:
        # -inf (empty space) passes: there is nothing to hit.
        top = obstacle[side, i0]
        for i in range(i0 + 1, i1 + 1):
            if obstacle[side, i] > top:
                top = obstacle[side, i]
        higher = h_to if h_to > h_from else h_from
        if top > higher + numbers[MAX_SWING]:
            return False
    if from_row < 0:
        return True
    climb = h_to - h_from
    allowed = numbers[LIFT_RISE] + (0.0 if 0.0 > climb else climb)
    if numbers[LIFT_STEP_UP] < allowed:
        allowed = numbers[LIFT_STEP_UP]
    return _rise_ahead(from_row, from_cumulative, tables) <= allowed


@kernel('f8(i8[::1], ' + _BANNED + ', ' + TABLES_TYPE + ', ' + _PREFIXES_TYPE + ', '
        + _SWINGS_TYPE + ')', inline=True)
def _effort(config, banned_first, tables, prefixes, swings):
    """
    Return the effort of a configuration, NaN if it is not collision-free.

    Effort of a configuration, NaN if it is not collision-free, resumed from the longest prefix of
    it already in ``prefixes`` (and adding its own). Compiled into both searches rather than called
    (a call reference-counts every array it is given, the table's too).
    """
    ok, height, pitch, bounds, offsets, obstacle, sides, lengths, last, numbers = tables
    if banned_first[config[0]]:
        return math.nan
    n = config.shape[0]
    base = lengths.shape[0]
    rows = prefixes.shape[0]
    effort, s, height_before = 0.0, numbers[STANCE_S], numbers[STANCE_HEIGHT]
    length_before, cumulative = numbers[PREVIOUS_LENGTH], 0
    # Where the next two footsteps' feet swing from (each from where it was two footsteps
    # before, the same side): the cumulative index of that foothold (-1: where the foot stands
    # now: the swing foot for footstep 0, the stance foot for footstep 1), its arc length and
    # sole height.
    origin, s_from, h_from = -1, numbers[SWING_S], numbers[SWING_HEIGHT]
    origin_next, s_next, h_next = -1, s, height_before
    # The longest prefix remembered: prefixes are written footstep by footstep, so the ones
    # remembered of a configuration are its first 1, 2, ... footsteps. ``number`` numbers
    # the prefix so far, ``offset`` is the first row of the next longer prefixes, ``power``
    # their count over ``base``.
    start, number, offset, power = 0, 0, 0, 1
    while start < n - 1:
        row = offset + number * base + config[start]
        if row >= rows or prefixes[row, 5] == 0.0:
            break
        if prefixes[row, 4] < 0:
            return math.nan
        effort, s, height_before, length_before = (prefixes[row, 0], prefixes[row, 1],
                                                   prefixes[row, 2], prefixes[row, 3])
        cumulative = int(prefixes[row, 4])
        origin, s_from, h_from = origin_next, s_next, h_next
        origin_next, s_next, h_next = cumulative, s, height_before
        number = number * base + config[start]
        power *= base
        offset += power
        start += 1
    up, down = numbers[UP], numbers[DOWN]
    spots = (bounds[-1] - bounds[-2]) + 1  # cumulative indices 0..n m, and -1
    for i in range(start, n):
        j = config[i]
        number = number * base + j
        row = offset + number  # past the rows when the prefix is not remembered
        power *= base
        offset += power
        length = lengths[j]
        s += length
        cumulative += j
        entry = bounds[i] + cumulative
        if not ok[entry]:
            if row < rows:
                prefixes[row, 4], prefixes[row, 5] = -1.0, 1.0
            return math.nan
        hold_height = height[entry]
        rise = hold_height - height_before
        if rise > up or -rise > down:
            if row < rows:
                prefixes[row, 4], prefixes[row, 5] = -1.0, 1.0
            return math.nan
        swing_key = (i * spots + origin + 1) * spots + cumulative
        clear = swings[swing_key] if swing_key < swings.shape[0] else -1
        if clear < 0:
            clear = 1 if _swing_clear(sides[i], s_from, h_from, s, hold_height,
                                      i - 2 if i >= 2 else -1, origin, tables) else 0
            if swing_key < swings.shape[0]:
                swings[swing_key] = clear
        if clear == 0:
            if row < rows:
                prefixes[row, 4], prefixes[row, 5] = -1.0, 1.0
            return math.nan
        effort += _step_cost(length, rise, pitch[entry], length_before, numbers)
        if row < rows:  # never a whole configuration's: its state is never resumed from
            prefixes[row, 0], prefixes[row, 1], prefixes[row, 2] = effort, s, hold_height
            prefixes[row, 3], prefixes[row, 4], prefixes[row, 5] = length, cumulative, 1.0
        origin, s_from, h_from = origin_next, s_next, h_next
        origin_next, s_next, h_next = cumulative, s, hold_height
        height_before, length_before = hold_height, length
    return effort


@kernel('f8[:, ::1](i8[::1], ' + TABLES_TYPE + ')', inline=True)
def _footholds_of(config, tables):
    """
    Return a configuration's footholds, (4, n).

    A configuration's footholds, (4, n): the footstep lengths (m), the footholds' arc lengths along
    the path (m, the stance foot's plus the running sum of the lengths), sole heights (m) and
    pitches (rad). One array: boxing it for Python costs a third of four.
    """
    ok, height, pitch, bounds, offsets, obstacle, sides, lengths, last, numbers = tables
    n = config.shape[0]
    footholds = np.empty((4, n))
    cumulative, total = 0, 0.0
    for i in range(n):
        cumulative += config[i]
        footholds[0, i] = lengths[config[i]]
        total += footholds[0, i]
        footholds[1, i] = numbers[STANCE_S] + total
        footholds[2, i] = height[bounds[i] + cumulative]
        footholds[3, i] = pitch[bounds[i] + cumulative]
    return footholds


#: What :func:`window_search` and :func:`exhaustive_search` return: the configuration's
#: number (base m + 1, footstep 0 the most significant digit), -1 when none is
#: collision-free; :func:`_footholds_of` of it ((4, 0) when there is none); its effort;
#: configurations judged. A number, not an array of indices: boxing an array for Python costs
#: more than the lookup (the planner looks the indices up).
_RESULT_TYPE = 'Tuple((i8, f8[:, ::1], f8, i8))'


#: The most configurations a window may have for the search to remember which it judged in
#: arrays over all of them (the paper's n = 3, m = 13: 2,744; 9 bytes each, one of them zeroed
#: for every search); past it, in a dictionary.
DENSE_CONFIGURATIONS = 1 << 16


@kernel(_RESULT_TYPE + '(i8, ' + _BANNED + ', ' + _BANNED + ', b1, ' + PROFILE_TYPE + ')')
def window_search(start, banned_first, banned_lengths, greedy_restart, profile):
    """
    Search one window (§4.2): breadth-first to a feasible one, then hill-climbing.

    §4.2's search of one window: (configuration (n,) interval indices, empty when no configuration
    is collision-free; its footholds (4, n), :func:`_footholds_of`; its effort; configurations
    judged).

    ``start``: the configuration the breadth-first search starts from, numbered (base m + 1,
    footstep 0 the most significant digit: one number to pass, not an array); ``banned_first``
    (m + 1,): the interval indices the first footstep must not take; ``banned_lengths``
    (m + 1,): those no footstep may take; ``greedy_restart``: climb a second time from a
    configuration built footstep by footstep and keep the better; ``profile``:
    :data:`PROFILE_TYPE`.

    One function: the search's own steps (the memo of judged configurations, the
    breadth-first search, the climbs) are its inner functions, which numba compiles into it,
    so that they pass nothing between them; the effort (:func:`_effort`, shared with
    :func:`exhaustive_search`) is compiled in too. Numba copies an inner function into every
    place that calls it, so the search is one loop over batches of configurations judged at
    one place (the start, a breadth-first expansion, a climb's neighbours): the judging, the
    foothold rules in it and the effort are compiled once, about half the code of calling the
    judging from each step, which matters in the walk, where the search's code is no longer
    in the processor's caches.
    """
    samples, entry_sides = profile[0], _entry_sides(profile)
    high, low, headroom = samples[0], samples[1], samples[2]
    tables = _unjudged_tables(profile)
    ok, height, pitch, bounds, offsets, obstacle, sides, lengths, last, numbers = tables
    n = sides.shape[0]
    base = banned_lengths.shape[0]
    m = base - 1
    # The configurations judged: their efforts (NaN where not collision-free), in arrays over
    # every configuration where there are few enough of them, else in ``table``.
    configurations = 1
    for _ in range(n):
        configurations *= base
        if configurations > DENSE_CONFIGURATIONS:
            configurations = 0
            break
    # The search's small arrays in one allocation each (each has a fixed cost): which entries
    # of the foothold table are judged and which configurations; the indices (see their uses).
    flags = np.zeros(ok.shape[0] + configurations, dtype=np.uint8)
    read, judged = flags[:ok.shape[0]], flags[ok.shape[0]:]
    efforts = np.empty(configurations)
    work = np.zeros(11 * n + 2 + base, dtype=np.int64)
    config, strides, batch = work[:n], work[n:2 * n], work[2 * n:6 * n]
    places, budget, origin = work[6 * n:7 * n], work[7 * n:8 * n], work[8 * n:9 * n]
    partial, reach, order = work[9 * n:10 * n + 1], work[10 * n + 1:11 * n + 2], work[11 * n + 2:]
    # The foothold table judged entry by entry, as the search first reads an entry (a sixth
    # of them at the median): ``ensure(entry)`` judges it if it is not yet and answers
    # whether it is ok. The effort reads only the entries of configurations whose entries the
    # search has read (up to the first that is not ok, where it stops too).
    stance_s, s0, ds, heel, toe = (numbers[STANCE_S], numbers[S0], numbers[DS], numbers[HEEL],
                                   numbers[TOE])
    min_headroom, max_pitch = numbers[MIN_HEADROOM], numbers[MAX_PITCH]
    tolerance, min_fraction = numbers[TOLERANCE], numbers[MIN_FRACTION]

    def ensure(entry):
        if not read[entry]:
            read[entry] = 1
            ok[entry], height[entry], pitch[entry] = _judge_sole(
                high, low, headroom, s0, ds, entry_sides[entry], stance_s + offsets[entry],
                heel, toe, min_headroom, max_pitch, tolerance, min_fraction)
        return ok[entry]

    def lands(config):
        # Whether every footstep of ``config`` has a foothold where it lands.
        cumulative = 0
        for i in range(n):
            cumulative += config[i]
            if not ensure(bounds[i] + cumulative):
                return False
        return True

    table, prefixes, swings = _empty_memos(n, m, True)

    def known(number):
        if configurations:
            return efforts[number] if judged[number] else _UNJUDGED
        return table.get(number, _UNJUDGED)

    def remember(number, value):
        if configurations:
            judged[number] = 1
            efforts[number] = value
        else:
            table[number] = value

    def evaluate(number):
        # The effort of configuration ``number`` (its indices left in ``config``), NaN if it
        # is not collision-free, remembered; and 1 where it is judged here, 0 where it was
        # already.
        value = known(number)
        if value != _UNJUDGED:  # True for NaN
            return value, 0
        rest = number
        for i in range(n - 1, -1, -1):
            config[i] = rest % base
            rest //= base
        value = math.nan
        for i in range(n):
            if banned_lengths[config[i]]:
                remember(number, value)
                return value, 1
        # Most configurations the breadth-first search meets on stairs land on a riser: their
        # footholds alone answer (the effort would stop at the same foothold).
        if lands(config):
            value = _effort(config, banned_first, tables, prefixes, swings)
        remember(number, value)
        return value, 1

    def greedy():
        # A configuration built footstep by footstep, each the cheapest given the ones before
        # by the effort's terms (not the swing test: the caller judges the whole
        # configuration), numbered; -1 when some footstep has no usable foothold.
        up, down = numbers[UP], numbers[DOWN]
        two, span, s_init = numbers[TWO], numbers[SPAN], numbers[S_INIT]
        w_length, w_height, w_pitch = numbers[W_LENGTH], numbers[W_HEIGHT], numbers[W_PITCH]
        w_smooth, up_range = numbers[W_SMOOTH], numbers[UP_RANGE]
        pitch_range = numbers[PITCH_RANGE]
        # The length term of each interval, the same for every footstep, and the intervals in
        # the order of it (nearest the neutral length first; the lengths ascend): the
        # cheapest candidate tends to come first, and once a length term alone exceeds the
        # best so far so do all after it.
        length_terms = np.empty(base)
        for j in range(base):
            length_terms[j] = w_length * ((lengths[j] - s_init) / span) ** two
        right = 0
        while right < base and lengths[right] < s_init:
            right += 1
        left = right - 1
        for k in range(base):
            if right >= base or (left >= 0 and length_terms[left] <= length_terms[right]):
                order[k] = left
                left -= 1
            else:
                order[k] = right
                right += 1
        seed = 0
        cumulative, height_before = 0, numbers[STANCE_HEIGHT]
        length_before = numbers[PREVIOUS_LENGTH]
        for i in range(n):
            # The cheapest candidate, the shortest of equals (as scanning them shortest first).
            best, best_cost = -1, math.inf
            for k in range(base):
                j = order[k]
                if length_terms[j] > best_cost:
                    break
                if banned_lengths[j] or (i == 0 and banned_first[j]):
                    continue
                entry = bounds[i] + cumulative + j
                if not ensure(entry):
                    continue
                rise = height[entry] - height_before
                if rise > up or -rise > down:
                    continue
                # _step_cost's sum term by term, given up once it exceeds the best so far (or
                # equals it for a longer interval): the terms are >= 0 (weights >= 0,
                # squares), so the rest could only add to it. The same value as _step_cost
                # where it finishes.
                cost = length_terms[j]
                if cost > best_cost or (cost == best_cost and j > best):
                    continue
                cost = cost + w_height * (rise / up_range) ** two
                if cost > best_cost or (cost == best_cost and j > best):
                    continue
                cost = cost + w_pitch * (pitch[entry] / pitch_range) ** two
                if cost > best_cost or (cost == best_cost and j > best):
                    continue
                cost = cost + w_smooth * ((lengths[j] - length_before) / span) ** two
                if cost < best_cost or (cost == best_cost and j < best):
                    best, best_cost = j, cost
            if best < 0:
                return -1
            seed = seed * base + best
            cumulative += best
            height_before, length_before = height[bounds[i] + cumulative], lengths[best]
        return seed

    # The search is one loop over batches of configurations, each judged in turn at one place
    # (so that numba compiles the judging, the foothold rules and the effort's call once):
    #
    # - START: the start configuration alone;
    # - BREADTH: the breadth-first search from it to the nearest collision-free configuration,
    #   over the paper's single-footstep moves (footstep by footstep, shorter before longer),
    #   as first in, first out: a batch of the configurations it reaches next, each judged as
    #   it is reached, the first found free ending the search. Without a queue: with these
    #   moves the order in which such a search reaches the configurations is known beforehand
    #   (see ``level`` below), so they are enumerated in it; the same configurations judged,
    #   the same found first, as the queue's (the tests' plain search keeps one);
    # - CLIMB: hill-climbing, a batch per move: the neighbours of the current configuration,
    #   in order each footstep one interval shorter, then longer, each followed by that change
    #   with the next footstep changed the opposite way (so the footholds after them stay;
    #   without it hill-climbing stalls on ridges of the effort), to the best of them while it
    #   lowers the effort by more than 1e-12;
    # - RESTART (``greedy_restart``, once the first climb ends): the configuration built
    #   footstep by footstep, alone, climbed from in turn where it is collision-free. On stairs
    #   and blocks the feasible configurations fall apart into basins (a foothold on every tread
    #   or on every other one) and the first climb cannot leave its basin. The second climb's
    #   result is kept where it is better by more than 1e-12.
    start_phase, breadth, climb, restart = 0, 1, 2, 3
    stride = 1
    for i in range(n - 1, -1, -1):
        strides[i] = stride
        stride *= base
    batch[0] = start
    size = 1
    phase = start_phase
    # The breadth-first search's order. A queue reaches a configuration first from the
    # first-reached neighbour one move nearer the start; by induction the configurations
    # ``level`` moves away come in the order of their offsets from the start taken footstep
    # by footstep: footstep 0's offset -level, ..., -1, then +level, ..., +1, then 0, each
    # followed by the offsets of the footsteps after it over the moves left in the same order
    # (the last footstep's: -moves, then +moves). Those outside [0, m] are passed over, as the
    # queue never holds them (a neighbour nearer the start of one inside lies inside too).
    # State: the level, the footstep whose offset comes next (-1: the level is done), each
    # footstep's place in its order (``places``) and the moves left for it and those after
    # it (``budget``), the numbers of the configuration's first footsteps (``partial``) and
    # the most moves the footsteps from each on can take inside [0, m] (``reach``); the
    # start's interval indices (``origin``).
    level, depth = 0, -1
    rest = start
    for i in range(n - 1, -1, -1):
        origin[i] = rest % base
        rest //= base
        reach[i] = reach[i + 1] + max(origin[i], m - origin[i])
    current, value = -1, math.nan  # the configuration climbed from, its effort
    judged_count = 0  # configurations judged
    result, effort = -1, math.nan  # the first climb's
    while True:
        # Judge the batch.
        found, best, best_value = -1, -1, value
        for k in range(size):
            number = batch[k]
            judged_value, fresh = evaluate(number)
            judged_count += fresh
            if phase == climb:
                if judged_value < best_value - 1e-12:  # False for NaN
                    best, best_value = number, judged_value
            elif judged_value == judged_value:
                found = number
                break
        # What comes next.
        if phase == climb and best >= 0:
            current, value = best, best_value
        elif phase == climb:
            # The climb ends here.
            if result < 0:
                result, effort = current, value
                if not greedy_restart:
                    break
                seed = greedy()
                if seed < 0 or seed == current:
                    break
                batch[0] = seed
                size = 1
                phase = restart
                continue
            if value < effort - 1e-12:
                result, effort = current, value
            break
        elif found >= 0:
            phase, current, value = climb, found, known(found)
        elif phase == restart:  # the greedy configuration is not collision-free
            break
        else:
            if phase == start_phase:
                # No configuration can be collision-free if some footstep has no foothold in
                # reach: the breadth-first search would judge every one.
                for i in range(n):
                    usable = False
                    for entry in range(bounds[i], bounds[i + 1]):
                        if ensure(entry):
                            usable = True
                            break
                    if not usable:
                        return -1, np.empty((4, 0)), math.nan, judged_count
            # The breadth-first search: the next configurations in its order.
            phase = breadth
            size = 0
            while size < batch.shape[0]:
                if depth < 0:
                    level += 1
                    if level > reach[0]:
                        break
                    depth, budget[0], places[0] = 0, level, -1
                places[depth] += 1
                place, moves = places[depth], budget[depth]
                if depth == n - 1:
                    if place > (1 if moves else 0):
                        depth -= 1
                        continue
                    offset = moves if place else -moves
                else:
                    if place > 2 * moves:
                        depth -= 1
                        continue
                    offset = place - moves if place < moves else 2 * moves - place
                j = origin[depth] + offset
                if j < 0 or j > m:
                    continue
                partial[depth + 1] = partial[depth] + j * strides[depth]
                if depth == n - 1:
                    batch[size] = partial[n]
                    size += 1
                elif moves - abs(offset) <= reach[depth + 1]:
                    budget[depth + 1] = moves - abs(offset)
                    depth += 1
                    places[depth] = -1
            if size == 0:
                return -1, np.empty((4, 0)), math.nan, judged_count
            continue
        # The neighbours of ``current`` to climb to.
        rest = current
        for i in range(n - 1, -1, -1):
            config[i] = rest % base
            rest //= base
        size = 0
        for i in range(n):
            for delta in (-1, 1):
                if not 0 <= config[i] + delta <= m:
                    continue
                batch[size] = current + delta * strides[i]
                size += 1
                if i + 1 < n and 0 <= config[i + 1] - delta <= m:
                    batch[size] = current + delta * (strides[i] - strides[i + 1])
                    size += 1
    rest = result
    for i in range(n - 1, -1, -1):
        config[i] = rest % base
        rest //= base
    return result, _footholds_of(config, tables), effort, judged_count


@kernel(_RESULT_TYPE + '(i8, i8, ' + PROFILE_TYPE + ')')
def exhaustive_search(n, m, profile):
    """
    Return the optimum over every configuration of the window, the first of equals.

    The optimum over every configuration of the window, the first of equals: as
    :func:`window_search` returns it, the configurations judged (m + 1) ** n. For benchmarks, what
    :func:`window_search` is measured against: each configuration judged whole by :func:`_effort`
    (its prefix memo has no rows: nothing of another configuration is resumed or written), the
    swing tests remembered, as the plain effort judges them.
    """
    tables = foothold_tables(profile)
    _, prefixes, swings = _empty_memos(n, m, False)
    base = m + 1
    total = base ** n
    banned = np.zeros(base, dtype=np.bool_)
    config = np.zeros(n, dtype=np.int64)
    best, best_effort = -1, math.inf
    for number in range(total):
        _digits(number, base, config)
        value = _effort(config, banned, tables, prefixes, swings)
        if value < best_effort:  # False for NaN
            best, best_effort = number, value
    if best < 0:
        return best, np.empty((4, 0)), best_effort, total
    _digits(best, base, config)
    return best, _footholds_of(config, tables), best_effort, total
