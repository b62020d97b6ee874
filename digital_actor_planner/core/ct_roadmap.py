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
The CT-roadmap: best-first planning forward in configuration-time space (paper §5.2).

The roadmap's nodes are branch configurations stored as deviations from the objective O(t)
(§5.1), so a node means the same posture relative to the motion pattern at any time and the
roadmap stays useful from one step to the next. It starts with the branch's common motion
patterns (the objective itself, bent and turned waists, flexed arms) and grows a node at
distance r whenever the search is stuck.

The search (Figure 5) only moves forward in time. From the current state it tries the
neighbouring nodes in order of closeness to the objective at their arrival time; when every
advance fails it grows a new node at distance r; when that does not bring the search forward
in time either it backtracks to an earlier state: the latest one from which a node that is
legal at the blocking frame can be reached in time, else the previous one. The goal is any
legal configuration at the final frame k.

A roadmap may also prefer lasting postures: where the objective is blocked ahead, a neighbour
that, held, stays legal to the end of the blocked stretch ranks before any that does not, and
from a state before the stretch, while such a neighbour is legal, the others are left for
later. Best-first on closeness alone takes the closest posture that is legal for now; beside a
long obstacle that is often one that fails half-way along it, when a motion to a lasting
posture can no longer be made in time, so the search creeps on through ever larger deviations
(an arm swung far back past a table rather than a flexed elbow). With the preference, a
lasting neighbour whose motion fails sends the search back (§5.2's backtracking) to start that
motion earlier; only when that finds nothing are the other neighbours and growth tried from
the state.

A search may also be given a preview: frames past the step's own ones, planned so the posture
can start to change before an obstacle is reached but not required of the step. Backtracking
that is blocked inside the preview has its own small budget; when it is spent the search gives
up and reports the block as one in the preview, so the caller can plan the step alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import time
from typing import Dict, List, Optional, Tuple

import numpy as np

from .ct_space import (CHECK_TABLES_TYPE, CTSpace, first_legal_goal, illegal_rows, motion_path,
                       ROW_MEMO_TYPE, SPACE_ARGUMENTS_TYPE)
from .jit import kernel


@dataclass(frozen=True)
class SearchResult:
    """
    Outcome of one CT-roadmap search.

    Attributes
    ----------
    ok
        Whether a legal motion reaches the final frame.
    path
        (k, d) branch configurations at every frame, rad; on failure the best partial motion
        followed by the objective (do not execute it).
    blocked_frame
        On failure, the frame index the search could not get past; -1 on success.
    nodes
        States expanded.
    backtracks
        Backtracking steps taken.
    grown
        Nodes added to the roadmap by this search.
    preview_backtracks
        Backtracking steps taken from a block inside the preview.
    gave_up_in_preview
        Whether the search stopped because its preview backtracking budget was spent.
    seeded
        Last frame the search reached along its seed before it searched on (0: no seed, or
        the seed's first motion was illegal).

    """

    ok: bool
    path: np.ndarray
    blocked_frame: int
    nodes: int
    backtracks: int
    grown: int
    preview_backtracks: int = 0
    gave_up_in_preview: bool = False
    seeded: int = 0


@dataclass
class _State:
    deviation: np.ndarray
    frame: int
    # Ranked neighbours left to try, once ranked: (targets (c, d) as deviations, arrivals (c,),
    # the targets rounded to 1e-3 rad (c, d): their keys in the search's tried ones).
    candidates: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    grew: bool = False
    # Only lasting neighbours were offered from here; ``relaxed``: the others are offered too.
    lasting_only: bool = False
    relaxed: bool = False
    failures: List[int] = field(default_factory=list)
    # A sub-goal set by backtracking: until frame ``until`` only nodes legal there are used.
    until: int = -1
    allowed: Optional[np.ndarray] = None
    relay: bool = False
    # Reached by following the objective hold_frames at a time in one check (see _follow).
    followed: bool = False
    # States passed on the way to this one, pushed before it (as if reached one by one).
    via: List['_State'] = field(default_factory=list)
    # On the objective: following it to the final frame was tried before the neighbours were
    # ranked (they are ranked only if the search comes back here).
    tried_objective: bool = False


#: Every how many grid frames the first pass of the lasting check looks (see _lasting).
COARSE_STRIDE = 4
# (last frame, spacing) -> CTRoadmap._objective_grid.
_GRIDS: Dict[Tuple[int, int], np.ndarray] = {}


@kernel('f8[:, ::1](f8[:, :], f8[:], f8[:, ::1], i8[::1], f8[:], f8[:])')
def _stack_path(objective, times, deviations, frames, lower, upper):
    """
    Return :meth:`CTRoadmap._path` of states, interpolated and clipped to the limits.

    :meth:`CTRoadmap._path` of states (``deviations`` (s, d) from the ``objective`` (k, d) at
    ``frames`` (s,)): each motion between successive states interpolated as
    :meth:`CTSpace.motion_frames` does it (the same operations in the same order, so the same
    numbers), a later motion writing over the frame it shares with the one before, the last state
    held to the final frame, then clipped to [lower, upper].
    """
    k, d = objective.shape
    out = np.empty((k, d))
    for i in range(k):
        for j in range(d):
            out[i, j] = objective[i, j]
    for j in range(d):
        out[0, j] = objective[0, j] + deviations[0, j]
    da = np.empty(d)
    db = np.empty(d)
    for n in range(frames.shape[0] - 1):
        fa, fb = frames[n], frames[n + 1]
        for j in range(d):
            # motion_frames' deviations of its end points, from their configurations.
            da[j] = (objective[fa, j] + deviations[n, j]) - objective[fa, j]
            db[j] = (objective[fb, j] + deviations[n + 1, j]) - objective[fb, j]
        span = times[fb] - times[fa]
        for i in range(fa, fb + 1):
            share = (times[i] - times[fa]) / span if span > 0 else 0.0
            for j in range(d):
                out[i, j] = objective[i, j] + da[j] + share * (db[j] - da[j])
    end = frames[frames.shape[0] - 1]
    for i in range(end, k):
        for j in range(d):
            out[i, j] = objective[i, j] + deviations[frames.shape[0] - 1, j]
    for i in range(k):
        for j in range(d):
            out[i, j] = min(max(out[i, j], lower[j]), upper[j])
    return out


@kernel('UniTuple(i8[::1], 2)(b1[::1])')
def _horizon_tables(free):
    """:class:`_Horizon`'s ``next_free`` (k + 1,) and ``run_start`` (k,) for ``free`` (k,)."""
    k = free.shape[0]
    last = k - 1
    next_free = np.empty(k + 1, dtype=np.int64)
    next_free[k] = last
    for i in range(k - 1, -1, -1):
        next_free[i] = i if free[i] else next_free[i + 1]
    run_start = np.empty(k, dtype=np.int64)
    for i in range(k):
        run_start[i] = run_start[i - 1] if i > 0 and not free[i] and not free[i - 1] else i
    return next_free, run_start


@kernel('i8[::1](f8[:, :], f8[:], f8)')
def _travel(change, rate, step):
    """
    Return :meth:`CTRoadmap._travel_frames` of changes (n, d) at joint speeds ``rate``.

    :meth:`CTRoadmap._travel_frames` of changes (n, d) at joint speeds ``rate`` (d,), frames
    ``step`` s apart: the same arithmetic as NumPy's (largest time over the joints, rounded up to
    whole frames, at least 1).
    """
    out = np.empty(change.shape[0], dtype=np.int64)
    for i in range(change.shape[0]):
        seconds = 0.0
        for j in range(change.shape[1]):
            seconds = max(seconds, abs(change[i, j]) / rate[j])
        out[i] = max(1, int(math.ceil(seconds / step - 1e-9)))
    return out


def _travel_over(times: np.ndarray, change: np.ndarray, rate: np.ndarray):
    """
    Return the frames of ``times`` needed to change by ``change`` at joint speeds ``rate``.

    Frames of ``times`` (k,) needed to change by ``change`` (..., d) at joint speeds ``rate`` (d,)
    rad/s, the frames taken as evenly spaced: an int (an int array for a batch of changes), at
    least 1.
    """
    step = (times[-1] - times[0]) / max(len(times) - 1, 1)
    change = np.asarray(change, dtype=np.float64)
    frames = _travel(change.reshape(-1, change.shape[-1]), rate, float(step))
    return int(frames[0]) if change.ndim == 1 else frames.reshape(change.shape[:-1])


@kernel('Tuple((f8[:, ::1], i8[::1], f8[::1], i8, b1[::1], i8[::1], f8[::1], f8[:, ::1], '
        'f8[:, ::1]))(readonly(f8[:, :]), f8[::1], i8, i8, i8, b1, b1, b1, f8[:], f8[:], i8, '
        'b1[::1], f8[:], f8[:, :])')
def _neighbour_table(nodes, deviation, here, last, hold_frames, with_objective, on_objective,
                     approach_first, times, rate, hold_end, free, weights, objective):
    """
    Return the neighbours :func:`_expand` ranks for a state, in one pass.

    The neighbours :func:`_expand` ranks for a state, in one pass: targets (m, d) as deviations,
    arrival frames (m,), closeness (m,), the index of the approach hold or -1, and for the ranking:
    whether each is the current posture held (m,), its arrival as ranked (later first for holds
    and, on the objective, for all: negated), closeness rounded to 1e-6 and targets to 1e-3
    (NumPy's rounding), and the configurations (``objective`` at the arrivals plus the targets).

    In order: the objective followed to the final frame (``with_objective``); each of
    ``nodes`` at its arrival at joint speeds ``rate`` (a node the remaining time does not
    reach steered as far towards it as it allows; the current posture held ``hold_frames``);
    the current posture held to ``hold_end`` less the way back to the objective, or, with
    ``approach_first``, up to the frame before the objective is next blocked (``free``); and
    the current posture held ``hold_frames``. The same arithmetic as the NumPy it replaces
    (:func:`_travel`'s timing, the steering share, the weighted norm summed joint by joint).
    """
    n, d = nodes.shape
    step = (times[times.shape[0] - 1] - times[0]) / max(times.shape[0] - 1, 1)
    size = n + 3
    targets = np.empty((size, d))
    frames = np.empty(size, dtype=np.int64)
    row = 0
    if with_objective:
        for j in range(d):
            targets[0, j] = 0.0
        frames[0] = last
        row = 1
    change = np.empty(d)
    for i in range(n):
        seconds = 0.0
        moved = False
        for j in range(d):
            change[j] = nodes[i, j] - deviation[j]
            if change[j] != 0.0:
                moved = True
            seconds = max(seconds, abs(change[j]) / rate[j])
        travel = hold_frames
        if moved:
            travel = max(1, int(math.ceil(seconds / step - 1e-9)))
        arrival = here + travel
        if arrival > last:
            share = (last - here) / travel
            for j in range(d):
                targets[row, j] = deviation[j] + share * change[j]
            arrival = last
        else:
            for j in range(d):
                targets[row, j] = nodes[i, j]
        frames[row] = arrival
        row += 1
    approach = -1
    held = min(here + hold_frames, last)
    if hold_end > held and not on_objective:
        seconds = 0.0
        for j in range(d):
            seconds = max(seconds, abs(deviation[j]) / rate[j])
        back = max(1, int(math.ceil(seconds / step - 1e-9)))
        end = hold_end - back if hold_end < last else hold_end
        if end > here + hold_frames:
            for j in range(d):
                targets[row, j] = deviation[j]
            frames[row] = end
            row += 1
    elif approach_first and not on_objective:
        for f in range(here, free.shape[0]):
            if not free[f]:
                if f - here - 1 > hold_frames:
                    approach = row
                    for j in range(d):
                        targets[row, j] = deviation[j]
                    frames[row] = f - 1
                    row += 1
                break
    for j in range(d):
        targets[row, j] = deviation[j]
    frames[row] = held
    row += 1
    targets = targets[:row].copy()
    frames = frames[:row].copy()
    closeness = np.empty(row)
    holds = np.empty(row, dtype=np.bool_)
    ranked_frames = np.empty(row, dtype=np.int64)
    q = np.empty((row, d))
    for i in range(row):
        total = 0.0
        holds[i] = True
        for j in range(d):
            total += weights[j] * (targets[i, j] * targets[i, j])
            if targets[i, j] != deviation[j]:
                holds[i] = False
            q[i, j] = objective[frames[i], j] + targets[i, j]
        closeness[i] = math.sqrt(total)
        ranked_frames[i] = -frames[i] if holds[i] or on_objective else frames[i]
    # np.round with ``out``: the form every numba release compiles (before 0.57, the only one
    # for arrays).
    return (targets, frames, closeness, approach, holds, ranked_frames,
            np.round(closeness, 6, np.empty_like(closeness)),
            np.round(targets, 3, np.empty_like(targets)), q)


@kernel('Tuple((b1[::1], i8))(f8[:, ::1], i8[::1], i8[::1], i8, i8, i8, i8, b1[::1], '
        'i1[:, ::1], f8[:, :], ' + CHECK_TABLES_TYPE + ', ' + ROW_MEMO_TYPE + ')')
def _lasting_table(targets, ids, arrivals, begin, end, spacing, stride, free, held, objective,
                   tables, memo):
    """
    Return whether each held target lasts through the blocked stretch [``begin``, ``end``].

    :meth:`CTRoadmap._lasting` for the blocked stretch [``begin``, ``end``]: whether each of
    ``targets`` (m, d), held from its ``arrivals`` (m,), lasts through it, and the configurations
    checked.

    ``held`` (postures, frames) caches what is known of a posture (``ids`` (m,): each
    target's row, one per posture rounded to 1e-4 rad) at a frame: -1 unknown, 0 illegal, 1
    legal; it is read and written here. A moved target is checked on its grid (the stretch's
    start if it arrives before it, every ``spacing``-th frame after its arrival, the end),
    first every ``stride``-th grid frame from the end (a coarse pass), then the rest; a
    target that does not move lasts where ``free`` (the objective legal) holds to the end.
    The checks are :func:`illegal_rows`' over the rows not known yet, in the order of the
    targets and their grids, a later answer for the same posture and frame written over an
    earlier one.
    """
    m, d = targets.shape
    lasting = np.ones(m, dtype=np.bool_)
    # Each moved target's grid, one after the other (at most ``room`` frames each).
    room = (end - begin) // spacing + 3
    grid = np.empty(m * room, dtype=np.int64)
    starts = np.zeros(m + 1, dtype=np.int64)
    has_grid = np.zeros(m, dtype=np.bool_)
    total = 0
    for i in range(m):
        starts[i] = total
        arrival = arrivals[i]
        if arrival > end:
            continue
        moved = False
        for j in range(d):
            if targets[i, j] != 0.0:
                moved = True
        if not moved:
            for f in range(arrival, end + 1):
                if not free[f]:
                    lasting[i] = False
                    break
            continue
        has_grid[i] = True
        if arrival < begin:
            grid[total] = begin
            total += 1
        for f in range(max(arrival, begin) // spacing * spacing + spacing, end, spacing):
            grid[total] = f
            total += 1
        grid[total] = end
        total += 1
    starts[m] = total
    checks = 0
    rows = np.empty(total, dtype=np.int64)
    frames = np.empty(total, dtype=np.int64)
    for coarse in (True, False):
        count = 0
        for i in range(m):
            if not has_grid[i] or not lasting[i]:
                continue
            length = starts[i + 1] - starts[i]
            # The grid from its end every stride-th frame (coarse), or all of it.
            picks = (length + stride - 1) // stride if coarse else length
            for p in range(picks):
                frame = grid[starts[i] + length - 1 - p * stride] if coarse else grid[
                    starts[i] + p]
                known = held[ids[i], frame]
                if known < 0:
                    rows[count] = i
                    frames[count] = frame
                    count += 1
                elif known == 0:
                    lasting[i] = False
        if count:
            q = np.empty((count, d))
            batch_frames = frames[:count].copy()
            for r in range(count):
                for j in range(d):
                    q[r, j] = objective[batch_frames[r], j] + targets[rows[r], j]
            illegal = illegal_rows(q, batch_frames, tables, memo)
            checks += count
            for r in range(count):
                legal = not illegal[r]
                held[ids[rows[r]], batch_frames[r]] = 1 if legal else 0
                lasting[rows[r]] = lasting[rows[r]] and legal
    return lasting, checks


@kernel('Tuple((f8[::1], i8))(f8[::1], f8[::1], i8, f8, f8[:], f8[:], f8[:], f8[:, :], '
        'f8[:], f8[:])')
def _grown_node(direction, deviation, frame, radius, weights, times, rate, objective, lower,
                upper):
    """
    Return :meth:`CTRoadmap._grow`'s node in a random ``direction`` (d,).

    :meth:`CTRoadmap._grow`'s node in a random ``direction`` (d,): the state's ``deviation`` moved
    ``radius`` along it (scaled to unit weighted norm), arriving at joint speeds ``rate`` no later
    than the final frame, kept within [``lower``, ``upper``]; as (deviation, arrival frame), with
    the NumPy arithmetic it replaces.
    """
    d = deviation.shape[0]
    last = times.shape[0] - 1
    total = 0.0
    for j in range(d):
        total += weights[j] * direction[j] * direction[j]
    norm = math.sqrt(total)
    moved = np.empty(d)
    seconds = 0.0
    for j in range(d):
        moved[j] = deviation[j] + radius * (direction[j] / norm)
        seconds = max(seconds, abs(moved[j] - deviation[j]) / rate[j])
    step = (times[last] - times[0]) / max(last, 1)
    arrival = min(frame + max(1, int(math.ceil(seconds / step - 1e-9))), last)
    out = np.empty(d)
    for j in range(d):
        q = min(max(objective[arrival, j] + moved[j], lower[j]), upper[j])
        out[j] = q - objective[arrival, j]
    return out, arrival


#: numba type of a search's tried neighbours (see _expand): (arrival frame, the target
#: deviation rounded to 1e-3 rad, zero-padded to four joints) -> True.
VISITED_TYPE = 'DictType(UniTuple(f8, 5), b1)'
#: numba type of _Horizon.postures: a deviation rounded to 1e-4 rad (zero-padded to four
#: joints) -> its row of _Horizon.held.
POSTURES_TYPE = 'DictType(UniTuple(f8, 4), i8)'


@kernel(VISITED_TYPE + '()')
def _empty_visited():
    """Return an empty set of tried neighbours (typed by a first entry, removed at once)."""
    visited = {(-1.0, 0.0, 0.0, 0.0, 0.0): np.bool_(True)}
    del visited[(-1.0, 0.0, 0.0, 0.0, 0.0)]
    return visited


@kernel(POSTURES_TYPE + '()')
def _empty_postures():
    """Return an empty numbering of postures (typed by a first entry, removed at once)."""
    postures = {(0.0, 0.0, 0.0, 0.0): np.int64(0)}
    del postures[(0.0, 0.0, 0.0, 0.0)]
    return postures


@kernel('f8(f8)')
def _unsigned_zero(value):
    """
    Return ``value`` with a zero of either sign as 0.0.

    ``value`` with a zero of either sign as 0.0: numba's dictionaries compare float keys bit by
    bit, where -0.0 (a deviation rounded from a tiny negative one) and 0.0 differ, unlike Python's.
    """
    return 0.0 if value == 0.0 else value


@kernel('UniTuple(f8, 4)(f8[:, ::1], i8)')
def _padded(rows, i):
    """
    Return row ``i`` of ``rows`` (m, d), zero-padded to four values, as a dictionary key.

    Row ``i`` of ``rows`` (m, d), d <= 4, zero-padded to four values, as a dictionary key (zeros
    unsigned, :func:`_unsigned_zero`).
    """
    d = rows.shape[1]
    return (_unsigned_zero(rows[i, 0]), _unsigned_zero(rows[i, 1]) if d > 1 else 0.0,
            _unsigned_zero(rows[i, 2]) if d > 2 else 0.0,
            _unsigned_zero(rows[i, 3]) if d > 3 else 0.0)


@kernel('UniTuple(f8, 5)(i8, f8[:, ::1], i8)')
def _visited_key(arrival, rounded, i):
    """
    Return the key of a neighbour among a search's tried ones.

    The key of the neighbour (arrival frame, row ``i`` of ``rounded``, its target rounded to 1e-3
    rad) among a search's tried ones.
    """
    padded = _padded(rounded, i)
    return (float(arrival), padded[0], padded[1], padded[2], padded[3])


@kernel('Tuple((b1[::1], i1[:, ::1], i8))(f8[:, ::1], i8[::1], i8, i8, b1[::1], i8[::1], '
        'i1[:, ::1], ' + POSTURES_TYPE + ', ' + SPACE_ARGUMENTS_TYPE + ')')
def _lasting_from(targets, arrivals, here, hold_frames, free, next_free, held, postures,
                  objective, times, frame_step, speed_cap, tables, memo):
    """
    Return :meth:`CTRoadmap._lasting`: whether each held target lasts through the blockage.

    :meth:`CTRoadmap._lasting`: whether each of ``targets`` (m, d), held from its ``arrivals``
    (m,), lasts through the first blocked stretch from ``here`` on (all True where there is none),
    ``held`` (a larger copy where new postures outgrew it), and the configurations checked.

    Each posture (a target rounded to 1e-4 rad) is numbered in ``postures`` as it first
    appears (its row of ``held``), then :func:`_lasting_table` answers. The arguments from
    ``objective`` on are the space's (:meth:`CTSpace.run_checks`).
    """
    m = targets.shape[0]
    begin = -1
    for f in range(here, free.shape[0]):
        if not free[f]:
            begin = f
            break
    if begin < 0:
        return np.ones(m, dtype=np.bool_), held, 0
    rounded = np.round(targets, 4, np.empty_like(targets))  # ``out``: as in _neighbour_table
    ids = np.empty(m, dtype=np.int64)
    for i in range(m):
        key = _padded(rounded, i)
        number = postures.get(key, -1)
        if number < 0:
            number = len(postures)
            postures[key] = number
        ids[i] = number
    if len(postures) > held.shape[0]:
        grown = np.full((2 * len(postures), held.shape[1]), -1, dtype=np.int8)
        grown[:held.shape[0]] = held
        held = grown
    lasting, checks = _lasting_table(targets, ids, arrivals, begin, next_free[begin],
                                     hold_frames, COARSE_STRIDE, free, held, objective,
                                     tables, memo)
    return lasting, held, checks


@kernel('i8[::1](i8[::1], f8[::1], b1, b1[::1])')
def _ranking(ranked_frames, ranked_closeness, with_lasting, lasting):
    """
    Return the order :func:`numpy.lexsort` gives the ranking keys.

    The order :func:`numpy.lexsort` gives the keys (``ranked_frames``, ``ranked_closeness``), with
    ``~lasting`` as the first key when ``with_lasting``: row indices, ties in row order.
    """
    m = ranked_frames.shape[0]
    order = np.empty(m, dtype=np.int64)
    for i in range(m):
        # Insertion sort (stable): a few dozen rows at most.
        j = i
        while j > 0:
            other = order[j - 1]
            if with_lasting and lasting[other] != lasting[i]:
                before = lasting[i]
            elif ranked_closeness[i] != ranked_closeness[other]:
                before = ranked_closeness[i] < ranked_closeness[other]
            else:
                before = ranked_frames[i] < ranked_frames[other]
            if not before:
                break
            order[j] = other
            j -= 1
        order[j] = i
    return order


@kernel('i8(f8[::1], i8, f8[:, ::1], i8[::1], i8[::1])')
def _longest_hold(deviation, arrival, before, before_arrivals, failures):
    """
    Return the arrival frame of the longest legal hold of ``deviation`` (d,).

    Arrival frame of a hold of ``deviation`` (d,) chosen to ``arrival``, made as long as the failed
    longer holds of it checked before show it is legal.

    A longer hold that failed was legal up to the frame before it failed, and of two holds
    the longer ranks first (see _neighbour_table): the hold goes on to there in this advance
    rather than hold_frames at a time. ``before`` (c, d), ``before_arrivals`` (c,): the
    motions checked before, in order, with their first illegal frames ``failures`` (c,).
    """
    for i in range(before.shape[0]):
        same = True
        for j in range(deviation.shape[0]):
            if before[i, j] != deviation[j]:
                same = False
        if same and before_arrivals[i] > arrival and failures[i] - 1 > arrival:
            arrival = failures[i] - 1
    return arrival


@kernel('Tuple((i8, f8[::1], i8, b1, f8[:, ::1], i8[::1], f8[:, ::1], i8[::1], b1, '
        'i1[:, ::1], i8))(f8[::1], i8, b1, f8[:, ::1], i8[::1], f8[:, ::1], b1, b1, b1, i8, '
        'readonly(f8[:, :]), b1, readonly(f8[:, :]), f8[:], i8, b1, i8, b1[::1], i8[::1], '
        'i1[:, ::1], ' + POSTURES_TYPE + ', ' + VISITED_TYPE + ', f8[:], '
        + SPACE_ARGUMENTS_TYPE + ')')
def _expand(deviation, here, has_candidates, candidate_targets, candidate_frames,
            candidate_keys, followed, tried_objective, relaxed, until, allowed, sub_goal,
            nodes, weights, max_candidates, prefer_lasting, hold_frames, free, next_free,
            held, postures, visited, rate, objective, times, frame_step, speed_cap, tables,
            memo):
    """
    Advance from a state at ``here`` as :meth:`CTRoadmap._advance` does.

    :meth:`CTRoadmap._advance` from a state at ``here`` with ``deviation`` (d,), past the shortcuts
    it takes on the objective: rank the neighbours (once per state: ``has_candidates`` says whether
    ``candidate_targets``, ``candidate_frames`` and ``candidate_keys`` hold the ones left from an
    earlier visit), then try the untried ones in order.

    The state's other fields: ``followed``, ``tried_objective``, ``relaxed``, ``until``, and
    ``allowed`` (the nodes of a sub-goal, used while ``sub_goal``); the roadmap's ``nodes``,
    ``weights``, ``max_candidates`` and ``prefer_lasting``; the horizon's ``hold_frames``,
    ``free``, ``next_free``, ``held`` and ``postures``; ``visited``, the search's tried
    neighbours (added to here); the joint speeds ``rate`` of the search; then the space's
    arguments (``objective`` to ``memo``, handed over by :meth:`CTSpace.run_checks`), read
    only by the space's compiled checks but for the objective and the time grid.

    The ranking is :func:`_neighbour_table`'s, lasting postures first where the roadmap
    prefers them (:func:`_lasting_from`), the neighbours' end points checked in one batch with
    the motion to the best untried one (read up to ``max_candidates`` legal ones, holds
    always); on the objective the best one (following it) is tried at once, and the motions
    are tried in order (:func:`ct_space.first_legal_goal`, the first goal's answer taken from
    that batch where it checked its motion), a hold chosen made as long as the failed
    longer holds before it allow (:func:`_longest_hold`). One call instead of about five
    kernels and their Python. The compiled twin of :func:`best_first_expansion`, the code of
    record (the same answers, the same configurations checked).

    Returns (1 and a child's deviation and arrival, whether it keeps the state's sub-goal, or
    0), the neighbours left to try (targets, arrivals, keys), the failures to add to the
    state's, whether the state now offers lasting neighbours only, ``held`` (a larger copy
    where it grew), and the configurations checked.
    """
    d = deviation.shape[0]
    last = objective.shape[0] - 1
    on_objective = True
    for j in range(d):
        if deviation[j] != 0.0:
            on_objective = False
    checks = 0
    lasting_only = False
    start = np.empty(d)
    for j in range(d):
        start[j] = objective[here, j] + deviation[j]
    targets, arrivals, keys = candidate_targets, candidate_frames, candidate_keys
    count = arrivals.shape[0]
    failures = np.empty(count + 2 + (0 if has_candidates else max(nodes.shape[0],
                                                                  allowed.shape[0]) + 4),
                        dtype=np.int64)
    failed = 0
    # The motion checked with the neighbours' end points: its goal, arrival, rows' answers.
    motion_goal = np.empty(d)
    motion_arrival = -1
    motion_illegal = np.zeros(0, dtype=np.bool_)
    motion_late = -1
    if not has_candidates:
        # Backtracking set a sub-goal: stay among the nodes legal at the blocking frame.
        in_sub_goal = sub_goal and here < until
        approach_first = prefer_lasting and not relaxed
        # Following the objective to the goal is the best advance there is. Steer towards the
        # nodes as far as the remaining time allows. Holding the posture: first past the
        # stretch where the objective is blocked (one long advance, ending where a return to
        # the objective would arrive as it becomes legal), else for hold_frames. Before a
        # blocked stretch, a search that prefers lasting postures holds a lasting one up to it
        # in one advance, not hold_frames at a time (re-ranking the same neighbours at every
        # hold costs the table's arm several holds to get there); from the stretch on,
        # hold_frames at a time (held into it in one advance, the arm that meets the second
        # pillar swings back about three times further than it needs). Equally close: sooner
        # arrival first, except holds and the objective, longest first.
        (table_targets, table_frames, closeness, approach, holds, ranked_frames,
         ranked_closeness, rounded, q) = _neighbour_table(
            allowed if in_sub_goal else nodes, deviation, here, last, hold_frames,
            on_objective and not in_sub_goal, on_objective, approach_first, times, rate,
            next_free[min(here + hold_frames, last)], free, weights, objective)
        m = table_frames.shape[0]
        lasting = np.ones(m, dtype=np.bool_)
        if approach_first:
            lasting, held, more = _lasting_from(table_targets, table_frames, here,
                                                hold_frames, free, next_free, held, postures,
                                                objective, times, frame_step, speed_cap,
                                                tables, memo)
            checks += more
        order = _ranking(ranked_frames, ranked_closeness, approach_first, lasting)
        if approach >= 0 and not lasting[m - 1]:
            # The posture does not last through the stretch (held from hold_frames on, checked
            # on _lasting_from's grid): ranked at every hold on the way.
            kept = 0
            for p in range(m):
                if order[p] != approach:
                    order[kept] = order[p]
                    kept += 1
            order = order[:kept].copy()
        # The motion to the best untried neighbour, usually the next motion checked.
        extra = np.zeros((0, d))
        if not on_objective and not followed:
            for p in range(order.shape[0]):
                i = order[p]
                if _visited_key(table_frames[i], rounded, i) not in visited:
                    motion_arrival = table_frames[i]
                    for j in range(d):
                        motion_goal[j] = objective[motion_arrival, j] + table_targets[i, j]
                    if motion_arrival > here:
                        extra, motion_late = motion_path(objective, times, frame_step,
                                                         speed_cap, start, here, motion_goal,
                                                         motion_arrival)
                    break
        total = m + extra.shape[0]
        batch = np.empty((total, d))
        batch_frames = np.empty(total, dtype=np.int64)
        for r in range(m):
            for j in range(d):
                batch[r, j] = q[r, j]
            batch_frames[r] = table_frames[r]
        for r in range(extra.shape[0]):
            for j in range(d):
                batch[m + r, j] = extra[r, j]
            batch_frames[m + r] = here + 1 + r
        checks += total
        illegal = illegal_rows(batch, batch_frames, tables, memo)
        if extra.shape[0] == 0:
            motion_arrival = -1  # nothing checked ahead
        else:
            motion_illegal = illegal[m:].copy()
        # End points in collision cannot start a legal motion: read in order up to the
        # max_candidates-th legal one (holding the current posture kept whatever its rank).
        legal = np.zeros(m, dtype=np.bool_)
        found = 0
        for p in range(order.shape[0]):
            i = order[p]
            legal[i] = not illegal[i]
            if legal[i]:
                found += 1
                if found == max_candidates:
                    break
        for i in range(m):
            if holds[i]:
                legal[i] = not illegal[i]
        if approach_first and free[here]:
            some_lasting = False
            some_other = False
            for i in range(m):
                if legal[i]:
                    if lasting[i]:
                        some_lasting = True
                    else:
                        some_other = True
            if some_lasting and some_other:
                # Leaving the objective before a blocked stretch: lasting neighbours only, until
                # backtracking for them has failed (see CTRoadmap.solve). Inside the stretch
                # they only rank first (filtering there too made the arms backtrack ten times
                # between the pillars).
                for i in range(m):
                    legal[i] = legal[i] and lasting[i]
                lasting_only = True
        # The max_candidates closest legal neighbours, plus holding the current posture.
        picked = np.empty(m, dtype=np.int64)
        count = 0
        ranked = 0
        for p in range(order.shape[0]):
            i = order[p]
            if not legal[i]:
                continue
            ranked += 1
            if ranked <= max_candidates or holds[i]:
                picked[count] = i
                count += 1
        if followed:
            # The search already went on from here along the objective.
            kept = 0
            for c in range(count):
                i = picked[c]
                moved = False
                for j in range(d):
                    if table_targets[i, j] != 0.0:
                        moved = True
                if moved or table_frames[i] > here + hold_frames:
                    picked[kept] = i
                    kept += 1
            count = kept
        targets = np.empty((count, d))
        arrivals = np.empty(count, dtype=np.int64)
        keys = np.empty((count, d))
        for c in range(count):
            i = picked[c]
            for j in range(d):
                targets[c, j] = table_targets[i, j]
                keys[c, j] = rounded[i, j]
            arrivals[c] = table_frames[i]
        if count and on_objective and not followed:
            # On the objective: follow it as far as it is legal (one motion check).
            first_target = targets[0].copy()
            first_arrival = arrivals[0]
            targets, arrivals, keys = targets[1:].copy(), arrivals[1:].copy(), keys[1:].copy()
            count -= 1
            if not tried_objective:
                goal = np.empty((1, d))
                for j in range(d):
                    goal[0, j] = objective[first_arrival, j] + first_target[j]
                _, answers, more = first_legal_goal(objective, times, frame_step, speed_cap,
                                                    start, here, goal,
                                                    np.array([first_arrival]), -2, tables, memo)
                checks += more
                bad = answers[0]
                if bad < 0:
                    return (1, first_target, first_arrival, first_arrival < until, targets,
                            arrivals, keys, failures[:failed].copy(), lasting_only, held,
                            checks)
                failures[failed] = bad
                failed += 1
                zero = True
                for j in range(d):
                    if first_target[j] != 0.0:
                        zero = False
                if zero and bad - 1 > here:
                    # Following the objective is legal up to the frame before the obstacle.
                    return (1, np.zeros(d), bad - 1, False, targets, arrivals, keys,
                            failures[:failed].copy(), lasting_only, held, checks)
    # The untried neighbours, in order; all of them are marked tried.
    fresh = np.empty(count, dtype=np.int64)
    fresh_count = 0
    for c in range(count):
        key = _visited_key(arrivals[c], keys, c)
        if key not in visited:
            visited[key] = True
            fresh[fresh_count] = c
            fresh_count += 1
    nothing = np.zeros((0, d))
    none = np.zeros(0, dtype=np.int64)
    if fresh_count == 0:
        return (0, deviation, -1, False, nothing, none, nothing, failures[:failed].copy(),
                lasting_only, held, checks)
    goals = np.empty((fresh_count, d))
    goal_frames = np.empty(fresh_count, dtype=np.int64)
    for f in range(fresh_count):
        c = fresh[f]
        for j in range(d):
            goals[f, j] = objective[arrivals[c], j] + targets[c, j]
        goal_frames[f] = arrivals[c]
    # The first goal alone (its answer read from the batch above when that checked its
    # motion), then the others in waves (first_legal_goal, as CTSpace.first_legal_motion).
    first_answer = -2
    if motion_arrival >= 0 and goal_frames[0] == motion_arrival:
        same = True
        for j in range(d):
            if goals[0, j] != motion_goal[j]:
                same = False
        if same:
            first_answer = -1
            for r in range(motion_illegal.shape[0]):
                if motion_illegal[r]:
                    first_answer = here + 1 + r
                    break
            if first_answer < 0 and motion_late >= 0:
                first_answer = motion_late
    chosen, answers, more = first_legal_goal(objective, times, frame_step, speed_cap, start,
                                             here, goals, goal_frames, first_answer, tables,
                                             memo)
    checks += more
    for r in range(answers.shape[0]):
        if answers[r] >= 0:
            failures[failed] = answers[r]
            failed += 1
    if chosen < 0:
        return (0, deviation, -1, False, nothing, none, nothing, failures[:failed].copy(),
                lasting_only, held, checks)
    # Keep the untried neighbours for when the search comes back here.
    left = fresh_count - chosen - 1
    left_targets = np.empty((left, d))
    left_arrivals = np.empty(left, dtype=np.int64)
    left_keys = np.empty((left, d))
    for f in range(left):
        c = fresh[chosen + 1 + f]
        for j in range(d):
            left_targets[f, j] = targets[c, j]
            left_keys[f, j] = keys[c, j]
        left_arrivals[f] = arrivals[c]
    c = fresh[chosen]
    target = targets[c].copy()
    arrival = arrivals[c]
    holding = True
    for j in range(d):
        if target[j] != deviation[j]:
            holding = False
    if holding:
        before = fresh[:chosen]
        arrival = _longest_hold(target, arrival, targets[before], arrivals[before],
                                answers[:chosen].copy())
    return (1, target, arrival, arrival < until, left_targets, left_arrivals, left_keys,
            failures[:failed].copy(), lasting_only, held, checks)


#: The expansions of a state :class:`CTRoadmap` can run (its ``search`` argument).
ROADMAP_SEARCHES = ('compiled', 'readable')


@dataclass(frozen=True)
class Expansion:
    """
    What one expansion of a search state found (:func:`best_first_expansion`).

    Attributes
    ----------
    child
        (deviation (d,) rad, arrival frame, whether it keeps the state's sub-goal) of the
        legal advance found, or None.
    left
        The ranked neighbours not tried yet: (targets (c, d) as deviations, rad, arrivals (c,),
        the targets rounded to 1e-3 rad (c, d)).
    failures
        The first illegal frame of each motion that failed.
    lasting_only
        Whether the state now offers lasting neighbours only.

    """

    child: Optional[Tuple[np.ndarray, int, bool]]
    left: Tuple[np.ndarray, np.ndarray, np.ndarray]
    failures: List[int]
    lasting_only: bool


def best_first_expansion(roadmap: 'CTRoadmap', space: CTSpace, state: _State,
                         horizon: _Horizon, speed_fraction: float, visited) -> Expansion:
    """
    Expand one state of §5.2's best-first search: the first legal advance to a neighbour.

    The neighbours are ranked once per state (the roadmap's nodes reached at joint speeds,
    the objective followed, the posture held; closest to the objective first, lasting
    postures first where the roadmap prefers them); their end points are checked in one
    batch, and the motions to the untried ones in rank order up to the first legal one. On
    the objective its best neighbour, following it, is tried at once. The search talks to
    the space only through its interface (``valid_rows``, ``rows_and_path``,
    ``first_invalid_motion``, ``first_legal_motion``). The code of record of the compiled
    ``_expand``, which gives the same answers and the same checks counted.

    Parameters
    ----------
    roadmap
        The branch's roadmap (nodes, weights, candidates per state, lasting preference).
    space
        The branch's CT-space for this step.
    state
        The state expanded (its ranked neighbours are kept on it by the caller).
    horizon
        The search's horizon (where the objective is legal).
    speed_fraction
        Fraction of the joint speed limits used when timing motions.
    visited
        The search's tried neighbours (``_empty_visited``), added to here.

    Returns
    -------
    Expansion

    """
    here, deviation = state.frame, state.deviation
    on_objective = not np.any(deviation)
    start = space.objective[here] + deviation
    failures: List[int] = []
    lasting_only = False
    known_motion = None  # (goal, arrival, first illegal frame) of a motion checked ahead
    if state.candidates is None:
        ranking = _rank_neighbours(roadmap, space, state, horizon, speed_fraction, visited)
        targets, arrivals, keys, lasting_only, known_motion = ranking
        if len(arrivals) and on_objective and not state.followed:
            # §5.2 on the objective: its best neighbour is following it (one motion check).
            first_target, first_arrival = targets[0], int(arrivals[0])
            targets, arrivals, keys = targets[1:], arrivals[1:], keys[1:]
            if not state.tried_objective:
                bad = space.first_invalid_motion(
                    (start, here), (space.objective[first_arrival] + first_target,
                                    first_arrival))
                if bad < 0:
                    return Expansion((first_target.copy(), first_arrival,
                                      first_arrival < state.until),
                                     (targets, arrivals, keys), failures, lasting_only)
                failures.append(bad)
                if not np.any(first_target) and bad - 1 > here:
                    # Following the objective is legal up to the frame before the obstacle.
                    return Expansion((np.zeros_like(deviation), bad - 1, False),
                                     (targets, arrivals, keys), failures, lasting_only)
    else:
        targets, arrivals, keys = state.candidates
    nothing = (np.zeros((0, len(deviation))), np.zeros(0, dtype=np.int64),
               np.zeros((0, len(deviation))))

    # The untried neighbours in rank order; all of them are marked tried.
    fresh = []
    for c in range(len(arrivals)):
        key = _visited_key(int(arrivals[c]), keys, c)
        if key not in visited:
            visited[key] = True
            fresh.append(c)
    if not fresh:
        return Expansion(None, nothing, failures, lasting_only)
    goals = [(space.objective[arrivals[c]] + targets[c], int(arrivals[c])) for c in fresh]
    first_failure = None
    if known_motion is not None and known_motion[1] == goals[0][1] \
            and np.array_equal(known_motion[0], goals[0][0]):
        first_failure = known_motion[2]
    chosen, answers = space.first_legal_motion((start, here), goals, first_failure)
    failures.extend(bad for bad in answers if bad >= 0)
    if chosen < 0:
        return Expansion(None, nothing, failures, lasting_only)
    left = fresh[chosen + 1:]
    c = fresh[chosen]
    target, arrival = targets[c].copy(), int(arrivals[c])
    if np.array_equal(target, deviation):
        # Holding the posture: a longer hold of it that failed was legal up to the frame
        # before it failed (and ranked first): hold on to there in this advance.
        for before, bad in zip(fresh[:chosen], answers[:chosen]):
            if (np.array_equal(targets[before], target) and arrivals[before] > arrival
                    and bad - 1 > arrival):
                arrival = bad - 1
    return Expansion((target, arrival, arrival < state.until),
                     (targets[left], arrivals[left], keys[left]), failures, lasting_only)


def _rank_neighbours(roadmap: 'CTRoadmap', space: CTSpace, state: _State, horizon: _Horizon,
                     speed_fraction: float, visited) -> tuple:
    """
    Return the neighbours of a state in rank order whose end points are legal.

    The neighbours of a state in rank order whose end points are legal: the closest
    ``max_candidates``, and holding the current posture whatever its rank (targets (c, d), arrivals
    (c,), keys (c, d)); whether only lasting ones are offered; and the motion to the best untried
    one, checked in the same batch as the end points ((goal, arrival, first illegal frame) or
    None).
    """
    here, deviation = state.frame, state.deviation
    hold_frames = horizon.hold_frames
    on_objective = not np.any(deviation)
    # Backtracking set a sub-goal: stay among the nodes legal at the blocking frame.
    in_sub_goal = state.allowed is not None and here < state.until
    approach_first = roadmap.prefer_lasting and not state.relaxed
    (targets, arrivals, approach, holds, ranked_frames, ranked_closeness, rounded,
     q) = _neighbours(state.allowed if in_sub_goal else roadmap.nodes, space, state, horizon,
                      speed_fraction * space.speed_limit, roadmap.weights, approach_first,
                      on_objective and not in_sub_goal)
    m = len(arrivals)
    lasting = np.ones(m, dtype=bool)
    if approach_first:
        lasting = _lasting_neighbours(space, horizon, here, targets, arrivals)
    # Closest first; equally close, sooner first (holds and on the objective: later first);
    # lasting ones before the others where the roadmap prefers them.
    keys_in_order = (ranked_frames, ranked_closeness) + ((~lasting,) if approach_first else ())
    order = [int(i) for i in np.lexsort(keys_in_order)]
    if approach >= 0 and not lasting[m - 1]:
        # The posture does not last through the stretch: held hold_frames at a time instead.
        order.remove(approach)
    # The motion to the best untried neighbour, usually the next motion checked, goes with
    # the end points in one batch.
    motion = None
    if not on_objective and not state.followed:
        for i in order:
            if _visited_key(int(arrivals[i]), rounded, i) not in visited:
                motion = (space.objective[arrivals[i]] + targets[i], int(arrivals[i]))
                break
    known_motion = None
    if motion is not None and motion[1] > here:
        before = space.checks
        rows_legal, bad = space.rows_and_path(q, arrivals, [(space.objective[here] + deviation,
                                                             here), motion])
        if space.checks - before > m:  # the motion had rows to check
            known_motion = (motion[0], motion[1], bad)
    else:
        rows_legal = space.valid_rows(q, arrivals)
    # End points in collision cannot start a legal motion: read in rank order up to the
    # max_candidates-th legal one (holding the current posture kept whatever its rank).
    legal = np.zeros(m, dtype=bool)
    found = 0
    for i in order:
        legal[i] = rows_legal[i]
        found += bool(legal[i])
        if found == roadmap.max_candidates:
            break
    legal[holds] = rows_legal[holds]
    lasting_only = False
    if approach_first and horizon.free[here] and (legal & lasting).any() \
            and (legal & ~lasting).any():
        # Leaving the objective before a blocked stretch: lasting neighbours only, until
        # backtracking for them has failed (see CTRoadmap.solve).
        legal &= lasting
        lasting_only = True
    picked = [i for i in order if legal[i]]
    picked = [i for rank, i in enumerate(picked) if rank < roadmap.max_candidates or holds[i]]
    if state.followed:
        # The search already went on from here along the objective.
        picked = [i for i in picked if np.any(targets[i]) or arrivals[i] > here + hold_frames]
    picked = np.array(picked, dtype=np.int64)
    return (targets[picked], arrivals[picked], rounded[picked], lasting_only, known_motion)


def _lasting_neighbours(space: CTSpace, horizon: _Horizon, here: int, targets: np.ndarray,
                        arrivals: np.ndarray) -> np.ndarray:
    """
    Return whether each neighbour, held from its arrival, lasts through the blockage ahead.

    Whether each neighbour, held from its arrival, lasts through the blocked stretch ahead: the
    readable ``CTRoadmap._lasting``, through the space's ``valid_rows``.

    The stretch is the first one from ``here`` on where the objective is blocked, to the frame
    it is legal again. A moved posture must be legal on a grid over it (the stretch's start
    if it arrives earlier, every ``hold_frames``-th frame after its arrival, the stretch's
    end), every :data:`COARSE_STRIDE`-th grid frame from the end first; the objective itself
    lasts where it is legal. What is known of a posture (rounded to 1e-4 rad) at a frame is
    kept in the horizon for the whole search.

    Parameters
    ----------
    space, horizon
        The branch's CT-space and the search's horizon.
    here
        Frame of the state the neighbours leave from.
    targets, arrivals
        (m, d) neighbours as deviations from the objective, rad, and (m,) their arrivals.

    Returns
    -------
    numpy.ndarray
        (m,) bool; all True when the objective is legal from ``here`` to the last frame.

    """
    m, spacing = len(arrivals), horizon.hold_frames
    blocked = np.flatnonzero(~horizon.free[here:])
    if not len(blocked):
        return np.ones(m, dtype=bool)
    begin = here + int(blocked[0])
    end = int(horizon.next_free[begin])
    # Each posture numbered as it first appears: its row of what is known (horizon.held).
    rounded = np.round(targets, 4)
    ids = []
    for i in range(m):
        key = _padded(rounded, i)
        if key not in horizon.postures:
            horizon.postures[key] = len(horizon.postures)
        ids.append(horizon.postures[key])
    if len(horizon.postures) > horizon.held.shape[0]:
        held = np.full((2 * len(horizon.postures), horizon.held.shape[1]), -1, dtype=np.int8)
        held[:horizon.held.shape[0]] = horizon.held
        horizon.held = held
    lasting = np.ones(m, dtype=bool)
    grids = {}
    for i in range(m):
        arrival = int(arrivals[i])
        if arrival > end:
            continue
        if not np.any(targets[i]):
            lasting[i] = bool(horizon.free[arrival:end + 1].all())
            continue
        grids[i] = (([begin] if arrival < begin else [])
                    + list(range(max(arrival, begin) // spacing * spacing + spacing, end,
                                 spacing)) + [end])
    for coarse in (True, False):
        rows, frames = [], []
        for i, grid in grids.items():
            if not lasting[i]:
                continue
            for frame in (grid[::-1][::COARSE_STRIDE] if coarse else grid):
                known = horizon.held[ids[i], frame]
                if known < 0:
                    rows.append(i)
                    frames.append(frame)
                elif known == 0:
                    lasting[i] = False
        if rows:
            frames = np.array(frames, dtype=np.int64)
            legal = space.valid_rows(space.objective[frames] + targets[rows], frames)
            for i, frame, is_legal in zip(rows, frames.tolist(), legal.tolist()):
                horizon.held[ids[i], frame] = 1 if is_legal else 0
                lasting[i] = lasting[i] and is_legal
    return lasting


def _neighbours(nodes: np.ndarray, space: CTSpace, state: _State, horizon: _Horizon,
                rate: np.ndarray, weights: np.ndarray, approach_first: bool,
                with_objective: bool) -> tuple:
    """
    Return the neighbours of a state before they are ranked: the readable ``_neighbour_table``.

    In order: the objective followed to the final frame (``with_objective``); each of
    ``nodes`` (n, d) at its arrival at joint speeds ``rate`` (d,) rad/s (one the remaining
    time does not reach steered as far towards it as it allows; the current posture held
    ``hold_frames``); the current posture held past the blocked stretch ahead, ending where
    the way back to the objective would arrive as it becomes legal, or, with
    ``approach_first``, up to the frame before the objective is next blocked; and the current
    posture held ``hold_frames``.

    Returns
    -------
    tuple
        (targets (m, d) as deviations, rad; arrivals (m,); the approach hold's row or -1;
        holds (m,) whether each holds the current posture; the arrival as ranked (m,), later
        first for holds and on the objective (negated); closeness to the objective rounded to
        1e-6 (m,); the targets rounded to 1e-3 rad (m, d); the configurations (m, d), rad).

    """
    here, deviation = state.frame, state.deviation
    last, hold_frames = space.frame_count - 1, horizon.hold_frames
    on_objective = not np.any(deviation)
    times = space.times
    step = (times[-1] - times[0]) / max(len(times) - 1, 1)

    def travel(change):
        # Frames to make ``change`` at ``rate``: the slowest joint's time in whole frames.
        seconds = 0.0
        for j in range(len(change)):
            seconds = max(seconds, abs(change[j]) / rate[j])
        return max(1, int(math.ceil(seconds / step - 1e-9)))

    targets, arrivals = [], []
    if with_objective:
        targets.append(np.zeros(len(deviation)))
        arrivals.append(last)
    for node in nodes:
        change = node - deviation
        arrival = here + (travel(change) if np.any(change != 0.0) else hold_frames)
        if arrival > last:
            share = (last - here) / (arrival - here)
            targets.append(deviation + share * change)
            arrivals.append(last)
        else:
            targets.append(node.copy())
            arrivals.append(arrival)
    approach = -1
    held = min(here + hold_frames, last)
    hold_end = int(horizon.next_free[held])
    if hold_end > held and not on_objective:
        end = hold_end - travel(deviation) if hold_end < last else hold_end
        if end > here + hold_frames:
            targets.append(deviation.copy())
            arrivals.append(end)
    elif approach_first and not on_objective:
        blocked = np.flatnonzero(~horizon.free[here:])
        if len(blocked) and blocked[0] - 1 > hold_frames:
            approach = len(arrivals)
            targets.append(deviation.copy())
            arrivals.append(here + int(blocked[0]) - 1)
    targets.append(deviation.copy())
    arrivals.append(held)
    targets = np.array(targets).reshape(len(arrivals), len(deviation))
    arrivals = np.array(arrivals, dtype=np.int64)
    closeness = np.array([math.sqrt(sum(w * (t * t) for w, t in zip(weights, target)))
                          for target in targets.tolist()])
    holds = np.all(targets == deviation, axis=1)
    ranked_frames = np.where(holds | on_objective, -arrivals, arrivals)
    return (targets, arrivals, approach, holds, ranked_frames, np.round(closeness, 6),
            np.round(targets, 3), space.objective[arrivals] + targets)


def objective_grid(last: int, spacing: int) -> np.ndarray:
    """
    Frames 0, ``spacing``, 2 ``spacing``, ...

    and ``last``: where a search first checks the objective (:meth:`CTRoadmap._objective_free`);
    made once per (last, spacing) and shared, never changed by a caller.
    """
    grid = _GRIDS.get((last, spacing))
    if grid is None:
        grid = _GRIDS[last, spacing] = np.unique(np.append(np.arange(0, last + 1, spacing),
                                                           last))
    return grid


def direct_return(objective: np.ndarray, times: np.ndarray, start: np.ndarray,
                  rate: np.ndarray) -> Optional[Tuple[int, np.ndarray]]:
    """
    Return the motion a search from a start off the objective tries first.

    The motion a search from a start off the objective tries first: straight back to it at joint
    speeds ``rate`` (d,), then along it (:meth:`CTRoadmap._return_directly`).

    Parameters
    ----------
    objective
        (k, d) the branch's objective, rad.
    times
        (k,) frame times, s.
    start
        (d,) the branch at frame 0, rad.
    rate
        (d,) joint speeds of the way back, rad/s (the search's: a fraction of the limits).

    Returns
    -------
    tuple or None
        (arrival frame, (k, d) motion: the deviation shrinking linearly in time from the
        start's to zero at the arrival, then the objective; not clipped to the joint limits),
        the numbers the search's path would hold; None where the search does not return
        directly (a start on the objective, or a way back that takes to the final frame).

    """
    deviation = start - objective[0]
    if not deviation.any():
        return None
    last = len(times) - 1
    arrival = _travel_over(times, deviation, rate)
    if arrival >= last:
        return None
    zero = np.zeros_like(deviation)
    unbounded = np.full(len(zero), np.inf)
    path = _stack_path(objective, times, np.array([deviation, zero, zero]),
                       np.array([0, arrival, last], dtype=np.int64), -unbounded, unbounded)
    return arrival, path


def warm_up(space: CTSpace, patterns: np.ndarray, weights: np.ndarray) -> None:
    """
    Call the kernels a search calls from Python once, on ``space``, answers thrown away.

    numba works out the types of a kernel's arguments the first time it meets them in a
    process (the check tables hold 45 arrays: about 2.5 ms for a search's kernels), a cost
    that would otherwise fall on the first step of a walk that searches. A throwaway roadmap
    of the branch's ``patterns`` and ``weights`` ranks and tries the neighbours of a state
    off the objective (the objective taken as blocked everywhere: the lasting check runs
    too), checks rows and a motion; no roadmap of a planner changes.
    """
    roadmap = CTRoadmap(patterns, weights, radius=0.1, max_nodes=len(patterns) + 1,
                        rng=np.random.default_rng(0), prefer_lasting=True)
    horizon = _Horizon(np.zeros(space.frame_count, dtype=bool), 1)
    deviation = np.full(space.dimension, 0.1)
    roadmap._advance(space, _State(deviation, 0), _empty_visited(), horizon, 1.0)
    space.valid_rows(space.objective[:2], np.arange(2))
    space.first_invalid_motion((space.objective[0], 0), (space.objective[1], 1))


class _Horizon:
    """
    Per search: where the objective is legal, and how far a posture is held from a frame.

    Parameters
    ----------
    free
        (k,) bool: whether the objective itself is legal at each frame.
    hold_frames
        Frames a posture is held for at least.

    """

    def __init__(self, free: np.ndarray, hold_frames: int):
        self.hold_frames = int(hold_frames)
        last = len(free) - 1
        # What is known of a posture (a deviation rounded to 1e-4 rad, numbered in
        # ``postures``) at each frame: -1 unknown, 0 illegal, 1 legal (see _lasting).
        self.postures = _empty_postures()
        self.held = np.full((16, last + 1), -1, dtype=np.int8)
        self.last = last
        self.free = np.ascontiguousarray(free, dtype=np.bool_)
        # next_free[i]: the first frame >= i where the objective is legal (last if none);
        # run_start[i]: the first frame of the blocked stretch holding i (i itself if free).
        self.next_free, self.run_start = _horizon_tables(self.free)

    def hold_end(self, here: int) -> int:
        """
        Return the frame a posture held from ``here`` is held to.

        Frame a posture held from ``here`` is held to: ``hold_frames`` on, then on to where the
        objective is legal again if it is blocked there.
        """
        end = min(here + self.hold_frames, self.last)
        return int(self.next_free[end])


class CTRoadmap:
    """
    A CT-roadmap for one branch, kept between successive plans.

    Parameters
    ----------
    patterns
        (n, d) initial nodes as deviations from the objective, rad (the common motion
        patterns; the zero deviation is always included).
    weights
        (d,) weights of the joints in the closeness measure, > 0.
    radius
        Distance r of a grown node from the current one (weighted norm), rad.
    max_nodes
        Largest roadmap size; the oldest grown nodes are forgotten first.
    max_candidates
        Neighbours tried per state, the closest to the objective first.
    rng
        Random generator for growth directions.
    prefer_lasting
        Rank neighbours that stay legal, held, to the end of the blocked stretch ahead before
        the others, and try the others only after backtracking for a lasting one failed.
    search
        How a state is expanded: ``'compiled'`` (one kernel, the runtime path) or
        ``'readable'`` (:func:`best_first_expansion`, the code of record, in plain Python
        through the space's interface). Both give the same result.

    """

    def __init__(self, patterns: np.ndarray, weights: np.ndarray, radius: float,
                 max_nodes: int, rng: np.random.Generator, max_candidates: int = 8,
                 prefer_lasting: bool = False, search: str = 'compiled'):
        if search not in ROADMAP_SEARCHES:
            raise ValueError(f'search must be one of {ROADMAP_SEARCHES}, got {search!r}')
        self.search = search
        patterns = np.atleast_2d(np.asarray(patterns, dtype=float))
        weights = np.asarray(weights, dtype=float)
        if patterns.shape[1] != weights.shape[0]:
            raise ValueError(f'patterns have {patterns.shape[1]} joints, weights '
                             f'{weights.shape[0]}')
        if not 1 <= patterns.shape[1] <= 4:
            # The search keys a tried neighbour and a posture by their joints zero-padded to
            # four (_visited_key, _padded): a wider branch would share keys.
            raise ValueError(f'a branch of 1 to 4 joints is searched, patterns have '
                             f'{patterns.shape[1]} joints')
        if not np.all(weights > 0):
            raise ValueError(f'weights must be > 0, got {weights}')
        if not radius > 0:
            raise ValueError(f'radius must be > 0 rad, got {radius}')
        zero = np.zeros((1, patterns.shape[1]))
        if not np.any(np.all(patterns == 0.0, axis=1)):
            patterns = np.vstack([zero, patterns])
        self.patterns = patterns
        self.weights = weights
        self.radius = float(radius)
        self.max_nodes = int(max_nodes)
        if not max_candidates >= 1:
            raise ValueError(f'max_candidates must be >= 1, got {max_candidates}')
        self.max_candidates = int(max_candidates)
        self.rng = rng
        self.grown_nodes = np.zeros((0, patterns.shape[1]))
        self._nodes = None
        # What _expand takes for a state not ranked yet, and for one without a sub-goal.
        d = patterns.shape[1]
        self._no_candidates = (np.zeros((0, d)), np.zeros(0, dtype=np.int64),
                               np.zeros((0, d)))
        self._no_nodes = np.zeros((0, d))
        self.prefer_lasting = bool(prefer_lasting)

    @property
    def nodes(self) -> np.ndarray:
        """
        Return all roadmap nodes as deviations from the objective: (n, d), rad.

        All roadmap nodes as deviations from the objective: (n, d), rad (read-only; made again only
        when a node is grown).
        """
        if self._nodes is None:
            self._nodes = np.vstack([self.patterns, self.grown_nodes])
            self._nodes.flags.writeable = False
        return self._nodes

    def closeness(self, deviation: np.ndarray) -> np.ndarray:
        """Weighted distance of deviation(s) (..., d) from the objective, rad."""
        return np.sqrt(np.sum(self.weights * np.square(deviation), axis=-1))

    def _add(self, deviation: np.ndarray) -> None:
        self._nodes = None
        self.grown_nodes = np.vstack([self.grown_nodes, deviation[None]])
        spare = self.max_nodes - len(self.patterns)
        if len(self.grown_nodes) > max(spare, 0):
            self.grown_nodes = self.grown_nodes[len(self.grown_nodes) - max(spare, 0):]

    # -- timing helpers ------------------------------------------------------------------
    @staticmethod
    def _travel_frames(space: CTSpace, frame: int, change: np.ndarray,
                       speed_fraction: float) -> np.ndarray:
        """
        Frames needed to change the deviation by ``change`` (..., d) at a fraction of the limit.

        Returns an int (or an int array for a batch of changes), at least 1.
        """
        return _travel_over(space.times, change, speed_fraction * space.speed_limit)

    # -- search --------------------------------------------------------------------------
    def solve(self, space: CTSpace, start: np.ndarray, hold_frames: int = 5,
              speed_fraction: float = 0.8, growth_attempts: int = 4,
              node_budget: int = 400, max_backtracks: int = 60,
              deadline: Optional[float] = None,
              check_budget: Optional[int] = None,
              preview_from: Optional[int] = None,
              preview_backtracks: int = 2,
              seed: Optional[np.ndarray] = None,
              growth_lower: Optional[np.ndarray] = None) -> SearchResult:
        """
        Search forward in time from ``start`` at frame 0 to any legal state at frame k-1.

        Parameters
        ----------
        space
            The branch's CT-space for this step.
        start
            (d,) branch configuration at frame 0, rad (must be legal).
        hold_frames
            Frames a node is held for when the search keeps the current posture.
        speed_fraction
            Fraction of the joint speed limits used when timing motions between nodes.
        growth_attempts
            Random directions tried when growing a node at distance r.
        node_budget, max_backtracks
            Search limits; exceeding either fails the search.
        deadline
            ``time.process_time()`` value (this process's CPU time, s) after which the search
            gives up (None: no limit). CPU time, not wall time: other programs taking the
            processor delay the search but do not spend its budget, so a loaded machine plans
            later, not differently. A budget far above need leaves the result unchanged.
        check_budget
            Configurations the search may check in ``space`` (None: no limit). A work budget:
            the same inputs give the same result however loaded the machine is.
        preview_from
            First frame of the preview (the step's own frame count), or None (no preview).
        preview_backtracks
            Backtracking steps the search may take from a block at a frame >= ``preview_from``
            before it gives up; they also count towards ``max_backtracks``.
        seed
            (s, d) deviations from the objective at frames 0..s-1, rad: a motion likely to be
            legal (the rest of the previous step's plan, receding horizon; row 0 is not used,
            the motion starts at ``start``). The search first goes along it, in states
            ``hold_frames`` apart, as far as it is legal and at most to the end of the last
            stretch within it where the objective is blocked, and searches on from there; it
            can backtrack into it like into any of its states.
        growth_lower
            (d,) lowest joint values the nodes grown at distance r may take, rad (None: the
            space's lower limits; a value below them is the limit).

        Returns
        -------
        SearchResult
            The motion over all k frames, or the frame the search could not get past.

        """
        last = space.frame_count - 1
        if preview_from is not None and not 0 < preview_from <= last:
            raise ValueError(f'preview_from must be in (0, {last}], got {preview_from}')
        if preview_backtracks < 0:
            raise ValueError(f'preview_backtracks must be >= 0, got {preview_backtracks}')
        start_state = _State(np.asarray(start, dtype=float) - space.objective[0], 0)
        stack = [start_state]
        # Where the objective itself is legal, in one batch over the step: it tells how long a
        # posture must be held to get past an obstacle (one long advance instead of creeping
        # hold_frames at a time). A fixed cost of about k / hold_frames configurations, outside
        # the search budget.
        grid = self._objective_grid(space, hold_frames)
        before = space.checks
        route = (None if seed is not None
                 else self._direct_route(space, start_state, speed_fraction))
        route_bad = None
        if route is None:
            legal = space.valid_rows(space.objective[grid], grid)
        else:
            # Unseeded, the search starts with _return_directly from the start: its motion
            # shares the horizon's broad phase (one batch instead of two, the same answers).
            legal, route_bad = space.rows_and_path(space.objective[grid], grid, route[1])
        route_rows = space.checks - before - len(grid)
        horizon = _Horizon(self._free_frames(grid, legal, last), hold_frames)
        seeded = 0
        if seed is not None:
            seeded = self._follow_seed(space, stack, seed, hold_frames, horizon)
        self._return_directly(space, stack, horizon, speed_fraction, route, route_bad)
        # The route's rows count towards the budget only where _return_directly would have
        # checked them itself (where the objective is free from the route's arrival on).
        unused = route is not None and not horizon.free[route[0]:].all()
        checks_limit = None if check_budget is None else (
            before + len(grid) + check_budget + (route_rows if unused else 0))
        visited = _empty_visited()
        jumps = set()
        known = {}
        nodes = backtracks = grown = in_preview = 0
        deepest_blocked = 0
        gave_up_in_preview = False
        while stack:
            state = stack[-1]
            if state.relay:
                # Relay states only mark departure points inside a checked motion.
                stack.pop()
                continue
            if state.frame >= last:
                return SearchResult(True, self._path(space, stack), -1, nodes, backtracks,
                                    grown, in_preview, seeded=seeded)
            nodes += 1
            if nodes > node_budget or backtracks > max_backtracks or (
                    checks_limit is not None and space.checks > checks_limit) or (
                    deadline is not None and time.process_time() > deadline):
                # Out of budget: the search got no further than the latest state it reached.
                deepest_blocked = max(deepest_blocked, max(s.frame for s in stack))
                break
            child = self._advance(space, state, visited, horizon, speed_fraction)
            if child is None and not state.grew and not state.lasting_only:
                # §5.2: every advance failed; grow a node at distance r.
                state.grew = True
                child = self._grow(space, state, speed_fraction, growth_attempts,
                                   growth_lower)
                grown += child is not None
            if child is not None:
                self._push(space, stack, child, hold_frames)
                continue
            # The farthest any advance got: the frame a new sub-goal must be legal at.
            blocked = max(state.failures) if state.failures else state.frame + 1
            deepest_blocked = max(deepest_blocked, blocked)
            # §5.2: the new node did not bring the search forward in time: backtrack.
            backtracks += 1
            if preview_from is not None and blocked >= preview_from:
                # The preview is an aid, not a goal of the step: a search stuck there gives up
                # early rather than spend the step's budget proving the preview infeasible.
                in_preview += 1
                if in_preview > preview_backtracks:
                    gave_up_in_preview = True
                    break
            passable = self._passable(space, blocked)
            jump = None if not passable else self._jump_back(
                space, stack, blocked, speed_fraction, jumps, horizon, known)
            if jump is not None:
                depth, child = jump
                del stack[depth + 1:]
                self._push(space, stack, child, hold_frames)
                continue
            if state.lasting_only:
                # No earlier start reaches a lasting posture: offer this state's other
                # neighbours, and growth, before leaving it (even where no node seems to pass
                # the frame the lasting ones failed at: the others may not go that way).
                state.lasting_only, state.relaxed, state.candidates = False, True, None
                continue
            if not passable:
                break
            stack.pop()
        path = self._path(space, stack) if stack else np.array(space.objective)
        return SearchResult(False, path, min(deepest_blocked, last), nodes, backtracks, grown,
                            in_preview, gave_up_in_preview, seeded)

    def _return_directly(self, space: CTSpace, stack: List[_State], horizon: _Horizon,
                         speed_fraction: float, route: Optional[tuple] = None,
                         route_bad: Optional[int] = None) -> bool:
        """
        Go back to the objective from a state off it and follow it, if that is legal.

        From a state off the objective with the objective free from where it can be reached on, go
        back to it and follow it to the final frame, if that is legal.

        This is the path best-first search takes first there (the objective is the closest
        neighbour, and following it to the final frame the best advance from it), checked in
        one batch without ranking the neighbours: the step after an obstacle, whose start is
        still off the pattern, mostly needs nothing else. Pushes the two states and returns
        True when legal; otherwise leaves the stack as it was. ``route``, ``route_bad``: the
        top state's :meth:`_direct_route` and its first illegal frame, when already checked.
        """
        if route is None:
            route = self._direct_route(space, stack[-1], speed_fraction)
            route_bad = None
        if route is None:
            return False
        arrival, waypoints = route
        if not horizon.free[arrival:].all():
            return False
        if route_bad is None:
            route_bad = space.first_invalid_path(waypoints)
        if route_bad >= 0:
            return False
        zero = np.zeros_like(stack[-1].deviation)
        stack.extend([_State(zero, arrival), _State(zero.copy(), space.frame_count - 1)])
        return True

    def _direct_route(self, space: CTSpace, state: _State,
                      speed_fraction: float) -> Optional[Tuple[int, list]]:
        """
        Return the way back from an off-objective state to the objective and along it.

        (arrival frame, waypoints) of the way back from an off-objective state to the objective and
        along it to the final frame; None on the objective or when the way back takes until the
        final frame.
        """
        if not state.deviation.any():
            return None
        last = space.frame_count - 1
        here = state.frame
        arrival = here + self._travel_frames(space, here, state.deviation, speed_fraction)
        if arrival >= last:
            return None
        objective = space.objective
        return arrival, [(objective[here] + state.deviation, here),
                         (objective[arrival], arrival), (objective[last], last)]

    def _follow_seed(self, space: CTSpace, stack: List[_State], seed: np.ndarray,
                     spacing: int, horizon: _Horizon) -> int:
        """
        Push states every ``spacing`` frames along a seed motion, as far as it is legal.

        The seed is followed only to the end of the last stretch within it where the objective
        is blocked (not at all if there is none): past it the search itself returns to the
        objective as soon as it can, where a seed held off it would be followed into every
        later step (each step's seed is the previous plan, whose return to the objective lay
        in its preview). The motions between the states (deviation interpolated linearly) are
        checked in one batch. Returns the frame of the last state pushed (0: none).
        """
        seed = np.asarray(seed, dtype=float)
        d = len(stack[0].deviation)
        if seed.ndim != 2 or seed.shape[1] != d or len(seed) < 1:
            raise ValueError(f'seed must have shape (s, {d}), got {seed.shape}')
        if not np.all(np.isfinite(seed)):
            raise ValueError('seed contains NaN or infinite values')
        end = min(len(seed), space.frame_count) - 1
        blocked = np.flatnonzero(~horizon.free[:end + 1])
        if not len(blocked):
            return 0
        end = min(end, int(horizon.next_free[blocked[-1]]))
        if end < 1:
            return 0
        frames = list(range(spacing, end, spacing)) + [end]
        objective = space.objective
        waypoints = [(objective[0] + stack[0].deviation, 0)] + [
            (objective[frame] + seed[frame], frame) for frame in frames]
        bad = space.first_invalid_path(waypoints)
        kept = [frame for frame in frames if bad < 0 or frame < bad]
        for frame in kept:
            stack.append(_State(seed[frame].copy(), frame))
        return kept[-1] if kept else 0

    @staticmethod
    def _objective_free(space: CTSpace, spacing: int) -> np.ndarray:
        """
        Whether the objective is legal at each frame, checked every ``spacing`` frames: (k,).

        A frame between two checked frames counts as blocked when either of them is, so the
        blocked stretches found cover the real ones up to ``spacing - 1`` frames either side.
        """
        grid = CTRoadmap._objective_grid(space, spacing)
        return CTRoadmap._free_frames(grid, space.valid_rows(space.objective[grid], grid),
                                      space.frame_count - 1)

    @staticmethod
    def _objective_grid(space: CTSpace, spacing: int) -> np.ndarray:
        """Frames :meth:`_objective_free` checks (:func:`objective_grid`)."""
        return objective_grid(space.frame_count - 1, spacing)

    @staticmethod
    def _free_frames(grid: np.ndarray, legal: np.ndarray, last: int) -> np.ndarray:
        """:meth:`_objective_free` from the legality of the objective at the grid frames."""
        free = np.ones(last + 1, dtype=bool)
        for i in np.flatnonzero(~legal):
            free[grid[max(i - 1, 0)] + 1:grid[min(i + 1, len(grid) - 1)]] = False
            free[grid[i]] = False
        return free

    @staticmethod
    def _lasting(space: CTSpace, horizon: _Horizon, here: int, targets: np.ndarray,
                 arrivals: np.ndarray) -> np.ndarray:
        """
        Whether each neighbour, held from its arrival, lasts through the blocked stretch ahead.

        The stretch is the first one from ``here`` on where the objective is blocked, to the
        frame it is legal again (or the last frame). A deviation held from its arrival (from
        the stretch's start if it arrives earlier) must be legal at the stretch's end and at
        every multiple of ``hold_frames`` before it, a fixed grid so that checks are shared
        between the states of a search (the arrival frame itself is left to the check of the
        neighbour's endpoint). A coarse pass over every fourth grid frame goes first. The
        objective itself lasts only where it is legal.

        Parameters
        ----------
        space
            The branch's CT-space.
        horizon
            The search's horizon (where the objective is legal; caches the checks).
        here
            Frame of the state the neighbours leave from.
        targets
            (m, d) neighbours as deviations from the objective, rad.
        arrivals
            (m,) int: their arrival frames.

        Returns
        -------
        numpy.ndarray
            (m,) bool; all True when the objective is legal from ``here`` to the last frame.

        """
        # A coarse pass first (most postures that do not last fail it), then the rest of the
        # grid for the postures left; one kernel (_lasting_from).
        lasting, horizon.held = space.run_checks(
            _lasting_from, targets, arrivals, here, horizon.hold_frames, horizon.free,
            horizon.next_free, horizon.held, horizon.postures)
        return lasting

    def _advance(self, space: CTSpace, state: _State, visited: set, horizon: _Horizon,
                 speed_fraction: float) -> Optional[_State]:
        """Try the ranked neighbours forward in time; return the first legal one."""
        on_objective = not np.any(state.deviation)
        if (state.candidates is None and not state.followed and on_objective
                and not state.relaxed):
            if not state.tried_objective:
                child = self._follow(space, state, horizon)
                if child is not None:
                    return child
                last = space.frame_count - 1
                if horizon.free[last] and not (state.allowed is not None
                                               and state.frame < state.until):
                    # Following the objective to the final frame is then the best-ranked
                    # neighbour: try it before ranking the others, which are seldom needed.
                    state.tried_objective = True
                    child = self._try(space, state, np.zeros_like(state.deviation), last)
                    if child is not None:
                        return child
        if self.search == 'readable':
            expansion = best_first_expansion(self, space, state, horizon, speed_fraction,
                                             visited)
            state.candidates = expansion.left
            state.lasting_only |= expansion.lasting_only
            state.failures.extend(expansion.failures)
            if expansion.child is None:
                return None
            deviation, arrival, inherit = expansion.child
            child = _State(deviation, int(arrival))
            if inherit:
                child.until, child.allowed = state.until, state.allowed
            return child
        # The rest in one kernel: rank the neighbours (once per state), then try the untried
        # ones in order.
        ranked = state.candidates is not None
        allowed = state.allowed
        (outcome, deviation, arrival, inherit, targets, arrivals, keys, failures, lasting_only,
         horizon.held) = space.run_checks(
            _expand, state.deviation, state.frame, ranked,
            *(state.candidates if ranked else self._no_candidates), state.followed,
            state.tried_objective, state.relaxed, state.until,
            self._no_nodes if allowed is None else allowed, allowed is not None, self.nodes,
            self.weights, self.max_candidates, self.prefer_lasting, horizon.hold_frames,
            horizon.free, horizon.next_free, horizon.held, horizon.postures, visited,
            speed_fraction * space.speed_limit)
        state.candidates = (targets, arrivals, keys)
        state.lasting_only |= lasting_only
        state.failures.extend(failures.tolist())
        if not outcome:
            return None
        child = _State(deviation, int(arrival))
        if inherit:
            child.until, child.allowed = state.until, state.allowed
        return child

    def _follow(self, space: CTSpace, state: _State, horizon: _Horizon) -> Optional[_State]:
        """
        Follow the objective from a state on it, hold_frames at a time, in one motion check.

        The states every hold_frames frames up to the last one before the objective is blocked
        are the ones keeping the objective one hold at a time would reach, but only one motion
        is checked and their neighbours are ranked only if the search comes back to them.
        When the objective is legal at the last frame the best advance is following it as far
        as it goes (``_try``), which the regular candidates do.
        """
        here, last = state.frame, space.frame_count - 1
        hold_frames = horizon.hold_frames
        zero = np.zeros_like(state.deviation)
        if here + hold_frames >= last or horizon.free[last]:
            return None
        bad = space.first_invalid_motion((space.objective[here], here),
                                         (space.objective[last], last))
        steps = (bad - 1 - here) // hold_frames if bad >= 0 else 0
        if steps < 1:
            return None
        chain = [_State(zero.copy(), here + hold_frames * i, followed=True)
                 for i in range(1, steps + 1)]
        child = chain[-1]
        child.via = chain[:-1]
        for link in chain:
            if link.frame < state.until:
                link.until, link.allowed = state.until, state.allowed
        return child

    def _try(self, space: CTSpace, state: _State, deviation: np.ndarray,
             arrival: int) -> Optional[_State]:
        """Check the motion to (deviation, arrival); on a collision remember where."""
        here = state.frame
        start = (space.objective[here] + state.deviation, here)
        goal = (space.objective[arrival] + deviation, arrival)
        bad = space.first_invalid_motion(start, goal)
        if bad < 0:
            child = _State(np.array(deviation), arrival)
            if arrival < state.until:
                child.until, child.allowed = state.until, state.allowed
            return child
        state.failures.append(bad)
        if not np.any(state.deviation) and not np.any(deviation) and bad - 1 > here:
            # Following the objective is legal up to the frame before the obstacle.
            return _State(np.zeros_like(deviation), bad - 1)
        return None

    def _grow(self, space: CTSpace, state: _State, speed_fraction: float,
              attempts: int, lower: Optional[np.ndarray] = None) -> Optional[_State]:
        """
        Grow a roadmap node at distance r from the current state (§5.2).

        Grow a roadmap node at distance r from the current state (§5.2), its joints no lower than
        ``lower`` (rad; None: the space's limits).
        """
        rate = speed_fraction * space.speed_limit
        lower = space.lower if lower is None else np.maximum(space.lower, lower)
        for _ in range(attempts):
            deviation, arrival = _grown_node(
                self.rng.normal(size=state.deviation.shape), state.deviation, state.frame,
                self.radius, self.weights, space.times, rate, space.objective, lower,
                space.upper)
            child = self._try(space, state, deviation, arrival)
            if child is not None:
                self._add(deviation)
                return child
        return None

    def _jump_back(self, space: CTSpace, stack: List[_State], blocked: int,
                   speed_fraction: float, jumps: set, horizon: _Horizon, known: dict,
                   targets: int = 4) -> Optional[Tuple[int, _State]]:
        """
        Backtrack to the latest earlier state that can reach a node legal at ``blocked``.

        For the few nodes closest to the objective that are legal at the blocking frame (those
        that can be held through the whole blocked stretch first), the latest departure that
        still gets there in time is found by bisection over the states on the stack. Returns
        (stack depth to keep, new state), or None.
        """
        nodes = self.nodes
        # Per search, what is known of a node at a blocking frame: backtracking often meets the
        # same blocking frame again, with the same roadmap nodes (plus any grown since).
        keys = [(blocked, tuple(node)) for node in nodes.tolist()]
        new = [i for i, key in enumerate(keys) if key not in known]
        if new:
            legal = space.valid_rows(space.objective[blocked] + nodes[new],
                                     np.full(len(new), blocked))
            through = np.zeros(len(new), dtype=bool)
            # Prefer the nodes that can be held through the whole stretch where the objective
            # is blocked (sampled every hold_frames): a node legal only at the blocking frame
            # leads to the next dead end a few frames earlier or later.
            end = horizon.hold_end(blocked)
            if end > blocked + 1 and legal.any():
                # From a little before the stretch: a bent posture meets an obstacle sooner.
                begin = max(1, horizon.run_start[min(blocked, horizon.last)]
                            - 2 * horizon.hold_frames)
                later = np.unique(np.append(np.arange(begin, end, horizon.hold_frames), end))
                candidates = np.array(new)[legal]
                rows = np.repeat(candidates, len(later))
                frames = np.tile(later, len(candidates))
                held = space.valid_rows(space.objective[frames] + nodes[rows], frames)
                through[legal] = held.reshape(len(candidates), len(later)).all(axis=1)
            for i, is_legal, is_through in zip(new, legal.tolist(), through.tolist()):
                known[keys[i]] = (is_legal, is_through)
        legal = np.array([known[key][0] for key in keys], dtype=bool)
        if not legal.any():
            return None
        through = np.array([known[key][1] for key in keys], dtype=bool)[legal]
        nodes = nodes[legal]
        ranks = np.lexsort((self.closeness(nodes), ~through))
        nodes = nodes[ranks]
        # A sub-goal already tried for this blocking frame led to a dead end: skip it (the
        # nodes rounded in one call: the same numbers, as Python floats).
        fresh = [(blocked, tuple(node)) not in jumps for node in np.round(nodes, 3).tolist()]
        nodes = nodes[np.array(fresh, dtype=bool)]
        earlier = [depth for depth in range(len(stack) - 1) if stack[depth].frame < blocked]
        for node in nodes[:targets]:
            jumps.add((blocked, tuple(np.round(node, 3))))
            low, high, best = 0, len(earlier) - 1, None
            while low <= high:
                middle = (low + high) // 2
                state = stack[earlier[middle]]
                change = node - state.deviation
                arrival = state.frame + self._travel_frames(space, state.frame, change,
                                                            speed_fraction)
                if arrival > blocked:
                    arrival = state.frame + self._travel_frames(space, state.frame, change, 1.0)
                child = None
                if arrival <= blocked:
                    failures = len(state.failures)
                    child = self._try(space, state, node, arrival)
                    del state.failures[failures:]
                if child is not None and child.frame == arrival:
                    best = (earlier[middle], child)
                    low = middle + 1
                else:
                    high = middle - 1
            if best is not None:
                depth, child = best
                if child.frame < blocked:
                    child.until, child.allowed = blocked, nodes
                return depth, child
        return None

    @staticmethod
    def _push(space: CTSpace, stack: List[_State], child: _State, spacing: int) -> None:
        """
        Push a state, with relay states every ``spacing`` frames along the motion to it.

        Deviations are interpolated linearly in time, so every piece of a checked motion is
        itself a legal motion: the relays are legal departure points for later backtracking.
        """
        for state in child.via:
            stack.append(state)
        child.via = []
        parent = stack[-1]
        for frame in range(parent.frame + spacing, child.frame - spacing // 2, spacing):
            share = (space.times[frame] - space.times[parent.frame]) / (
                space.times[child.frame] - space.times[parent.frame])
            relay = _State(parent.deviation + share * (child.deviation - parent.deviation),
                           frame, relay=True)
            stack.append(relay)
        stack.append(child)

    def _passable(self, space: CTSpace, frame: int, samples: int = 16) -> bool:
        """Whether any roadmap node or random configuration is legal at ``frame``."""
        nodes = self.nodes
        q = space.objective[frame] + nodes
        lower, upper = space.bounds
        random = lower + self.rng.random((samples, len(lower))) * (upper - lower)
        q = np.vstack([q, random])
        return bool(space.valid_rows(q, np.full(len(q), frame)).any())

    @staticmethod
    def _path(space: CTSpace, stack: List[_State]) -> np.ndarray:
        """
        Return the configuration at every frame along the states of the stack: (k, d), rad.

        The motions between the states as :meth:`CTSpace.motion_frames` gives them (one
        kernel, the same arithmetic), then the last state held to the final frame, within the
        joint limits.
        """
        deviations = np.array([state.deviation for state in stack], dtype=float)
        frames = np.array([state.frame for state in stack], dtype=np.int64)
        return _stack_path(space.objective, space.times, deviations, frames, space.lower,
                           space.upper)
