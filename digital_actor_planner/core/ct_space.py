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
Configuration-time space of one upper-body branch (paper §5.2).

The pelvis trajectory q_R(t) and the legs are fixed by the locomotion planner (§4), and the
branches planned before this one are fixed by the priority order of §5 (waist, then left arm,
then right arm). What remains is the branch's own joints plus time: the CT-space. A state is a
pair ``(q, i)``: the branch configuration ``q`` (d,) rad at frame index ``i`` of the time grid.

The interface is shaped like OMPL's space-time planning (``SpaceTimeStateSpace``): ``bounds``,
``distance``, ``interpolate``, ``is_valid(q, i)`` and ``check_motion(a, b)``, where a motion is
legal only forward in time, within the joint speed limits and collision-free at every frame,
and their batch forms (``valid_rows``, ``first_invalid``, ``first_legal_motion``,
``first_invalid_path``). A planner checks states only through these methods; its compiled
kernels are run by ``run_checks``, which hands them the space's compiled checks.

Motions are interpolated in deviation from the objective O(t) (§5.1) rather than in absolute
joint values, so a motion between two states on the objective follows the objective exactly and
a constant deviation rides on top of the swinging arm pattern.

Collision checking is compiled, a batch of rows at a time: a broad phase (per row, axis-aligned
boxes of the branch's shapes against the environment's triangles and the rest of the body, then
the separating axis test of the oriented boxes holding them) and the exact test of the shapes it
leaves (:func:`.convex.touches_triangle`, :func:`.convex.touches_shape`: GJK), over the body
of :mod:`.body_model` (its kinematics, shapes and poses over the step), using the shapes and
environment meshes of :class:`~digital_actor_planner.core.collision.BodyCollision` when it
provides them.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np

from .body_model import (BodyKinematics, BodyShapes, candidates_meeting, Chain, JointStep,
                         link_poses, place_shapes, STEP_TABLE_TYPES, TimedBody)
from .collision import half_extents
from .convex import SAT_MARGIN, touches_shape, touches_triangle
from .jit import float_array, kernel

#: Relative slack on the joint speed limits, for rounding in interpolation.
SPEED_TOLERANCE = 1e-6
UPPER_BODY_BRANCHES = ('waist', 'left_arm', 'right_arm')
#: Kept triangles up to which a batch's boxes are tested against all of them at once.
FEW_TRIANGLES = 64
#: Rows x shapes x triangles above which contacts are first cut by the shapes' swept boxes.
SWEPT_CONTACTS = 4096


@kernel('void(f8[:, :], i8[::1], f8[:, ::1], i8[::1], '
        'f8[:, :, :, ::1], f8[:, :, ::1], i8[::1], f8[:, :, :, ::1], f8[:, :, ::1], '
        'f8[:, :, ::1], f8[:, :, ::1], i8[::1], i8[::1], f8[:, ::1], f8[:, :, ::1], b1[::1], '
        'i8[::1], f8[:, ::1], f8[:, :, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], '
        'b1[::1], ' + STEP_TABLE_TYPES + ')')
def _branch_boxes(q, frames, body_frames, indices, body_rotations, body_positions, links,
                  shape_rotation, shape_centre, shape_lower, shape_upper, checked, shape_links,
                  offsets, turns, turned, kinds, halves, rotation, centre, low, high, held,
                  parent, child, origin_rotation, step_turned, origin_translation, offset_axis,
                  offset_length, has_offset, joint, kind, axis_coordinate, axis_sign, axis):
    """
    Compute :meth:`CTSpace._shape_boxes` in one pass, in place.

    :meth:`CTSpace._shape_boxes` in one pass, into ``rotation`` (m, n, 3, 3), ``centre``, ``low``
    and ``high`` (m, n, 3), and ``held`` (m,): whether the row is where the body holds the branch.

    A row whose branch values ``q`` (m, d) are the body's at its frame (``body_frames`` at
    ``indices``) takes the body's poses and boxes of the ``checked`` shapes; the others are
    posed by :func:`link_poses` over the chain's ``links`` (their poses read from
    ``body_rotations`` and ``body_positions``, the step table last), :func:`place_shapes`
    and the boxes of :func:`collision.half_extents`: bit for bit the poses and boxes of the
    whole body built at the row's configuration (the same kernels, the same arithmetic).
    """
    m, n, d = q.shape[0], checked.shape[0], indices.shape[0]
    moved = np.empty(m, dtype=np.int64)
    count = 0
    for r in range(m):
        f = frames[r]
        held[r] = True
        for j in range(d):
            if not q[r, j] == body_frames[f, indices[j]]:
                held[r] = False
                break
        if not held[r]:
            moved[count] = r
            count += 1
            continue
        for c in range(n):
            s = checked[c]
            rotation[r, c] = shape_rotation[f, s]
            centre[r, c] = shape_centre[f, s]
            low[r, c] = shape_lower[f, s]
            high[r, c] = shape_upper[f, s]
    if count:
        links_count = links.shape[0]
        full = np.empty((count, body_frames.shape[1]))
        rotations = np.empty((count, links_count, 3, 3))
        positions = np.empty((count, links_count, 3))
        for i in range(count):
            r = moved[i]
            f = frames[r]
            full[i] = body_frames[f]
            for j in range(d):
                full[i, indices[j]] = q[r, j]
            for k in range(links_count):
                rotations[i, k] = body_rotations[f, links[k]]
                positions[i, k] = body_positions[f, links[k]]
        link_poses(full, rotations, positions, parent, child, origin_rotation, step_turned,
                   origin_translation, offset_axis, offset_length, has_offset, joint, kind,
                   axis_coordinate, axis_sign, axis)
        placed = np.empty((count, n, 3, 3))
        placed_centre = np.empty((count, n, 3))
        place_shapes(rotations, positions, shape_links, offsets, turns, turned, np.arange(n),
                     placed, placed_centre)
        extent = half_extents(kinds, halves, placed)
        for i in range(count):
            r = moved[i]
            rotation[r] = placed[i]
            centre[r] = placed_centre[i]
            for c in range(n):
                for e in range(3):
                    low[r, c, e] = placed_centre[i, c, e] - extent[i, c, e]
                    high[r, c, e] = placed_centre[i, c, e] + extent[i, c, e]


@kernel('b1[::1](f8[:, :, ::1], f8[:, :, ::1], f8[:, ::1], f8[:, ::1], b1, i8[::1], i8[::1], '
        'f8[:, :, ::1], f8[:, :, ::1], f8[:, :, :, ::1], f8[:, :, ::1], f8[:, ::1], '
        'f8[:, :, :], f8[:, :, :, :], f8[:, :, :], f8[:, :], f8, i8[::1], f8[:, :], i8[::1], '
        'f8[:, :], i8[::1], b1[::1])')
def _row_collisions(low, high, triangle_lower, triangle_upper, swept, frames, pair_column,
                    pair_lower, pair_upper, rotation, centre, half, corners, pair_rotation,
                    pair_centre, pair_half, margin, kinds, shape_half, pair_kinds,
                    pair_shape_half, pair_other, skip):
    """
    Whether each row of a branch's batch touches the environment or the body: (m,) bool.

    The broad phase (the boxes along the world axes, cut by each shape's box swept over the
    rows when ``swept``, then the separating axis test of the oriented boxes holding the
    shapes, ``margin`` apart) and, for what it leaves, the exact test of the shapes
    themselves (:func:`convex.touching`): the branch's shape (``kinds`` (n,), ``shape_half``
    (n, 3)) against a triangle, or against a pair's other shape (``pair_kinds`` (P,),
    ``pair_shape_half`` (P, 3)) at the row's frame. Pair p's branch shape is column
    ``pair_column[p]``, its other shape is body shape ``pair_other[p]`` of the body's
    (k, S, ...) boxes ``pair_lower``/``pair_upper`` and poses ``pair_rotation``/
    ``pair_centre``, with box half extents ``pair_half[p]``. A row stops at its first contact;
    the shape and triangle of the last contact found are tried first on the next row.
    Rows where ``skip`` are known to touch nothing: reported so without a test (nor a part in
    the swept boxes).
    """
    m, n, count = low.shape[0], low.shape[1], triangle_lower.shape[0]
    pairs = pair_column.shape[0]
    hit = np.zeros(m, dtype=np.bool_)
    every = np.arange(count)
    # Per shape, the triangles its boxes may meet: all of them, or those the shape's box swept
    # over the rows meets.
    starts = np.zeros(n + 1, dtype=np.int64)
    candidates = every if not swept else np.empty(n * count, dtype=np.int64)
    lowest, highest = np.empty(3), np.empty(3)
    for c in range(n):
        if not swept:
            starts[c + 1] = count
            continue
        for axis in range(3):
            lowest[axis], highest[axis] = np.inf, -np.inf
            for r in range(m):
                if not skip[r]:
                    lowest[axis] = min(lowest[axis], low[r, c, axis])
                    highest[axis] = max(highest[axis], high[r, c, axis])
        meeting = candidates_meeting(lowest, highest, triangle_lower, triangle_upper, every)
        starts[c + 1] = starts[c] + meeting.shape[0]
        candidates[starts[c]:starts[c + 1]] = meeting
    # Row by row; the shape and triangle that touched the row before are tried first (rows of
    # a batch are mostly neighbouring frames of a motion, and a row that touches is decided by
    # its first contact: the same answers, fewer exact tests).
    witness_shape, witness_triangle = -1, -1
    for r in range(m):
        if skip[r]:
            continue
        if witness_shape >= 0:
            c, t = witness_shape, witness_triangle
            if (high[r, c, 0] >= triangle_lower[t, 0] and low[r, c, 0] <= triangle_upper[t, 0]
                    and high[r, c, 1] >= triangle_lower[t, 1]
                    and low[r, c, 1] <= triangle_upper[t, 1]
                    and high[r, c, 2] >= triangle_lower[t, 2]
                    and low[r, c, 2] <= triangle_upper[t, 2]
                    and touches_triangle(kinds[c], shape_half[c], half[c], rotation[r, c],
                                         centre[r, c], corners[t], margin)):
                hit[r] = True
                continue
        for c in range(n):
            if not swept:
                first, last = 0, count
            else:
                first, last = starts[c], starts[c + 1]
            for k in range(first, last):
                t = candidates[k]
                if c == witness_shape and t == witness_triangle:
                    continue
                meets = True
                for axis in range(3):
                    if not (high[r, c, axis] >= triangle_lower[t, axis]
                            and low[r, c, axis] <= triangle_upper[t, axis]):
                        meets = False
                        break
                if meets and touches_triangle(kinds[c], shape_half[c], half[c],
                                              rotation[r, c], centre[r, c], corners[t],
                                              margin):
                    hit[r] = True
                    witness_shape, witness_triangle = c, t
                    break
            if hit[r]:
                break
    for r in range(m):
        if hit[r] or skip[r]:
            continue
        f = frames[r]
        for p in range(pairs):
            c, o = pair_column[p], pair_other[p]
            meets = True
            for axis in range(3):
                if not (high[r, c, axis] >= pair_lower[f, o, axis]
                        and low[r, c, axis] <= pair_upper[f, o, axis]):
                    meets = False
                    break
            if meets and touches_shape(kinds[c], shape_half[c], half[c], rotation[r, c],
                                       centre[r, c], pair_kinds[p], pair_shape_half[p],
                                       pair_half[p], pair_rotation[f, o], pair_centre[f, o],
                                       margin):
                hit[r] = True
                break
    return hit


@kernel('b1[::1](f8[:, :], f8[::1], f8[::1])')
def _within(q, lower, upper):
    """Whether each row of ``q`` (m, d) lies in [lower, upper] (d,): (m,) bool."""
    out = np.empty(q.shape[0], dtype=np.bool_)
    for r in range(q.shape[0]):
        inside = True
        for j in range(q.shape[1]):
            if not (q[r, j] >= lower[j] and q[r, j] <= upper[j]):
                inside = False
                break
        out[r] = inside
    return out


@kernel('b1(i8, i8, i8)')
def _sweeps(rows, shapes, triangles):
    """
    Return whether a batch of rows first cuts the (shape, triangle) pairs by swept boxes.

    Whether a batch of ``rows`` of a branch's ``shapes`` against ``triangles`` kept triangles first
    cuts the (shape, triangle) pairs by each shape's box swept over the rows (which also drops the
    triangles far from every box): many triangles, or many tests.
    """
    return rows > 1 and (triangles > FEW_TRIANGLES or rows * shapes * triangles > SWEPT_CONTACTS)


#: numba type of a branch's row memo (see illegal_rows): (frame, the row's bits, zero-padded
#: to MEMO_WIDTH joints) -> 1 illegal, 0 legal. Passed on its own, not inside the tables: numba
#: types a dictionary inside a tuple argument through its slow path, dearer than the check.
ROW_MEMO_TYPE = 'DictType(UniTuple(i8, 5), i8)'
#: Widest branch whose rows are remembered (the key holds the frame and this many joints).
MEMO_WIDTH = 4
# numba type of CTSpace._check_tables, the tuple illegal_rows takes: the joint limits,
# clear_until, _branch_boxes' tables, the step table, _row_collisions' tables.
CHECK_TABLES_TYPE = (
    'Tuple((f8[::1], f8[::1], i8, '
    'f8[:, ::1], i8[::1], f8[:, :, :, ::1], f8[:, :, ::1], i8[::1], f8[:, :, :, ::1], '
    'f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], i8[::1], i8[::1], f8[:, ::1], '
    'f8[:, :, ::1], b1[::1], i8[::1], f8[:, ::1], ' + STEP_TABLE_TYPES + ', '
    'f8[:, ::1], f8[:, ::1], i8[::1], f8[:, ::1], f8[:, :, :], f8[:, :], f8, i8[::1], '
    'f8[:, :], i8[::1], f8[:, :], i8[::1]))')
#: numba types of what :meth:`CTSpace.run_checks` hands a planner's kernel after the kernel's
#: own arguments: the objective (k, d), the time grid (k,), ``frame_step`` (k - 1, 1),
#: ``speed_cap`` (d,), the check tables and the row memo.
SPACE_ARGUMENTS_TYPE = ('f8[:, :], f8[:], f8[:, :], f8[:], ' + CHECK_TABLES_TYPE + ', '
                        + ROW_MEMO_TYPE)


@kernel(ROW_MEMO_TYPE + '()')
def _empty_row_memo():
    """Return an empty row memo (typed by a first entry, removed at once)."""
    memo = {(-1, 0, 0, 0, 0): np.int64(0)}
    del memo[(-1, 0, 0, 0, 0)]
    return memo


@kernel('UniTuple(i8, 5)(i8[:, ::1], i8[::1], i8)')
def _row_key(bits, frames, r):
    """
    Return row ``r``'s key in the row memo: its frame and its joints' bits.

    Row ``r``'s key in the row memo: its frame and its joints' bits (``bits`` (m, d), d <=
    :data:`MEMO_WIDTH`, the rows viewed as int64), zero-padded.
    """
    d = bits.shape[1]
    return (frames[r], bits[r, 0], bits[r, 1] if d > 1 else 0, bits[r, 2] if d > 2 else 0,
            bits[r, 3] if d > 3 else 0)


@kernel('b1[::1](f8[:, :], i8[::1], ' + CHECK_TABLES_TYPE + ')')
def _check_rows(q, frames, tables):
    """
    :func:`illegal_rows` of every row, none of them remembered: (m,) bool.

    :func:`_branch_boxes` poses the branch's shapes, :func:`_row_collisions` tests them (rows
    where the body holds the branch at frames before ``clear_until`` skipped: the body's own
    check found them clear), then the limits as :func:`_within` tests them: the answers of
    those kernels called one by one, from one call (the pairs cut by swept boxes where
    :func:`_sweeps` says so).
    """
    (lower, upper, clear_until,
     body_frames, indices, body_rotations, body_positions, links, shape_rotation,
     shape_centre, shape_lower, shape_upper, checked, shape_links, offsets, turns,
     turned, kinds, halves,
     parent, child, origin_rotation, step_turned, origin_translation, offset_axis,
     offset_length, has_offset, joint, kind, axis_coordinate, axis_sign, axis,
     triangle_lower, triangle_upper, pair_column, half, corners, pair_box_half,
     margin, checked_kinds, checked_half, pair_kinds, pair_half, pair_other) = tables
    m, n = q.shape[0], checked.shape[0]
    swept = _sweeps(m, n, triangle_lower.shape[0])
    rotation = np.empty((m, n, 3, 3))
    centre = np.empty((m, n, 3))
    low = np.empty((m, n, 3))
    high = np.empty((m, n, 3))
    held = np.empty(m, dtype=np.bool_)
    _branch_boxes(q, frames, body_frames, indices, body_rotations, body_positions, links,
                  shape_rotation, shape_centre, shape_lower, shape_upper, checked, shape_links,
                  offsets, turns, turned, kinds, halves, rotation, centre, low, high, held,
                  parent, child, origin_rotation, step_turned, origin_translation, offset_axis,
                  offset_length, has_offset, joint, kind, axis_coordinate, axis_sign, axis)
    known = np.empty(m, dtype=np.bool_)
    for r in range(m):
        known[r] = held[r] and frames[r] < clear_until
    illegal = _row_collisions(low, high, triangle_lower, triangle_upper, swept, frames,
                              pair_column, shape_lower, shape_upper, rotation, centre, half,
                              corners, shape_rotation, shape_centre, pair_box_half, margin,
                              checked_kinds, checked_half, pair_kinds, pair_half, pair_other,
                              known)
    inside = _within(q, lower, upper)
    for r in range(m):
        illegal[r] = illegal[r] or not inside[r]
    return illegal


@kernel('b1[::1](f8[:, :], i8[::1], ' + CHECK_TABLES_TYPE + ', ' + ROW_MEMO_TYPE + ')')
def illegal_rows(q, frames, tables, memo):
    """
    Return whether each row of a batch is illegal: (m,) bool.

    :meth:`CTSpace._illegal`: whether each row of a batch (``q`` (m, d) at ``frames``) is illegal,
    outside the joint limits or touching the environment or the body: (m,) bool. ``tables``:
    the space's check tables; ``memo``: its row memo (:meth:`CTSpace.run_checks`).

    A row's answer depends on the row alone (its configuration, its frame) while the body
    holds still, and searches check the same rows again (backtracking, motions sharing their
    first frames; 14-30 % of the rows on the slowest steps): the answers are remembered in
    ``memo``, keyed by the frame and the row's bits, and the rows not in it are checked
    (:func:`_check_rows`) in one batch. A branch wider than :data:`MEMO_WIDTH` joints
    is checked without it.
    """
    m, d = q.shape
    if d > MEMO_WIDTH:
        return _check_rows(q, frames, tables)
    bits = np.ascontiguousarray(q).view(np.int64)
    illegal = np.empty(m, dtype=np.bool_)
    todo = np.empty(m, dtype=np.int64)
    count = 0
    for r in range(m):
        known = memo.get(_row_key(bits, frames, r), -1)
        if known >= 0:
            illegal[r] = known == 1
        else:
            todo[count] = r
            count += 1
    if count == 0:
        return illegal
    if count == m:
        answers = _check_rows(q, frames, tables)
    else:
        batch = np.empty((count, d))
        batch_frames = np.empty(count, dtype=np.int64)
        for t in range(count):
            batch[t] = q[todo[t]]
            batch_frames[t] = frames[todo[t]]
        answers = _check_rows(batch, batch_frames, tables)
    for t in range(count):
        r = todo[t]
        illegal[r] = answers[t]
        memo[_row_key(bits, frames, r)] = 1 if answers[t] else 0
    return illegal


@kernel('i8[::1](f8[:, :], f8, f8[:, :, ::1], f8[:, :, ::1], i8[:], i8[:])')
def _reachable_pairs(centre, reach2, shape_lower, shape_upper, obstacle, pair_obstacle):
    """
    Return the indices of the pairs of a branch whose other shape it can reach during the step.

    An ``obstacle`` shape (O,) is within reach when its box comes within ``sqrt(reach2)`` of
    ``centre`` (k, 3) at some frame; pair p's obstacle is ``pair_obstacle[p]``.
    """
    k, count = centre.shape[0], obstacle.shape[0]
    reachable = np.zeros(count, dtype=np.bool_)
    for o in range(count):
        s = obstacle[o]
        for f in range(k):
            total = 0.0
            for e in range(3):
                gap = max(max(shape_lower[f, s, e] - centre[f, e], 0.0),
                          centre[f, e] - shape_upper[f, s, e])
                total += gap * gap
            if total <= reach2:
                reachable[o] = True
                break
    kept = np.empty(pair_obstacle.shape[0], dtype=np.int64)
    n = 0
    for p in range(pair_obstacle.shape[0]):
        if reachable[pair_obstacle[p]]:
            kept[n] = p
            n += 1
    return kept[:n].copy()


@kernel('Tuple((f8[:, ::1], i8))(f8[:, :], f8[:], f8[:, :], f8[:], f8[:], i8, f8[:], i8)')
def motion_path(objective, times, frame_step, speed_cap, qa, ia, qb, ib):
    """
    :meth:`CTSpace._motion_rows`: the configurations at frames ia+1..

    of the motion (qa, ia) -> (qb, ib), its deviation from the ``objective`` (k, d) interpolated
    linearly in ``times`` (:meth:`CTSpace.motion_frames`, the same arithmetic), up to the frame
    before the first whose change from the frame before exceeds ``speed_cap`` (d,) over
    ``frame_step`` (k - 1, 1); and that frame, or -1 when there is none.
    """
    d = objective.shape[1]
    count = ib - ia
    rows = np.empty((count, d))
    da = np.empty(d)
    change = np.empty(d)
    for j in range(d):
        da[j] = qa[j] - objective[ia, j]
        change[j] = (qb[j] - objective[ib, j]) - da[j]
    span = times[ib] - times[ia]
    previous = np.empty(d)
    for j in range(d):
        previous[j] = objective[ia, j] + da[j] + 0.0 * change[j]
    for i in range(count):
        f = ia + 1 + i
        share = (times[f] - times[ia]) / span
        fast = False
        for j in range(d):
            rows[i, j] = objective[f, j] + da[j] + share * change[j]
            if abs(rows[i, j] - previous[j]) / frame_step[f - 1, 0] > speed_cap[j]:
                fast = True
        if fast:
            return rows[:i].copy(), f
        for j in range(d):
            previous[j] = rows[i, j]
    return rows, -1


@kernel('Tuple((f8[:, ::1], i8[::1], i8[::1], i8[::1]))(f8[:, :], f8[:], f8[:, :], f8[:], '
        'f8[:, ::1], i8[::1], f8[:, ::1], i8[::1])')
def _motion_paths(objective, times, frame_step, speed_cap, qa, ia, qb, ib):
    """
    Return :func:`motion_path` of several motions in one batch.

    :func:`motion_path` of several motions (qa[i], ia[i]) -> (qb[i], ib[i]) in one batch: their
    rows one after the other (m, d), each row's frame (m,), where each motion's rows end (M,), and
    each motion's first speed violation, -1 or, for a motion that does not go forward in time (no
    rows), its start frame (M,).
    """
    count, d = ia.shape[0], objective.shape[1]
    total = 0
    for i in range(count):
        total += max(ib[i] - ia[i], 0)
    rows = np.empty((total, d))
    frames = np.empty(total, dtype=np.int64)
    ends = np.empty(count, dtype=np.int64)
    late = np.empty(count, dtype=np.int64)
    n = 0
    for i in range(count):
        if ib[i] <= ia[i]:
            late[i] = ia[i]
        else:
            path, late[i] = motion_path(objective, times, frame_step, speed_cap, qa[i], ia[i],
                                        qb[i], ib[i])
            for r in range(path.shape[0]):
                for j in range(d):
                    rows[n, j] = path[r, j]
                frames[n] = ia[i] + 1 + r
                n += 1
        ends[i] = n
    return rows[:n].copy(), frames[:n].copy(), ends, late


@kernel('Tuple((i8[::1], i8))(f8[:, :], f8[:], f8[:, :], f8[:], f8[:, ::1], i8[::1], '
        'f8[:, ::1], i8[::1], b1, i8, ' + CHECK_TABLES_TYPE + ', ' + ROW_MEMO_TYPE + ')')
def _motion_failures(objective, times, frame_step, speed_cap, qa, ia, qb, ib, stop_at_legal,
                     first, tables, memo):
    """
    Return the first illegal frame of each motion in order, -1 for a legal one.

    :meth:`CTSpace._failures`: the first illegal frame of each motion (qa[i], ia[i]) -> (qb[i],
    ib[i]) in order, -1 for a legal one, and the configurations checked.

    The motions' rows are :func:`_motion_paths`'; they are judged by :func:`illegal_rows`,
    with ``first`` <= 0 all in one batch, else in waves along the motions (``first`` rows of
    every motion still open, then twice as many each wave), so that rows after a motion's
    first illegal one are seldom checked. A motion whose rows are all legal fails at its speed
    violation, if any. With ``stop_at_legal`` the answers end at the first legal motion.
    Returns (answers (n,), configurations checked).
    """
    rows, frames, ends, late = _motion_paths(objective, times, frame_step, speed_cap, qa, ia,
                                             qb, ib)
    count = ia.shape[0]
    answers = np.empty(count, dtype=np.int64)
    answered = 0
    checks = 0
    open_ = -3  # no answer yet
    results = np.full(count, open_, dtype=np.int64)
    position = np.empty(count, dtype=np.int64)
    for i in range(count):
        position[i] = 0 if i == 0 else ends[i - 1]
    size = rows.shape[0] if first <= 0 else first
    done = 0
    while done < count:
        # The next rows of every motion still open (all of them at once when first <= 0).
        total = 0
        for i in range(done, count):
            if results[i] == open_:
                total += min(position[i] + size, ends[i]) - position[i]
        picked = np.empty(total, dtype=np.int64)
        n = 0
        for i in range(done, count):
            if results[i] == open_:
                for r in range(position[i], min(position[i] + size, ends[i])):
                    picked[n] = r
                    n += 1
        checks += total
        illegal = np.zeros(0, dtype=np.bool_)
        if total:
            batch = np.empty((total, rows.shape[1]))
            batch_frames = np.empty(total, dtype=np.int64)
            for r in range(total):
                batch[r] = rows[picked[r]]
                batch_frames[r] = frames[picked[r]]
            illegal = illegal_rows(batch, batch_frames, tables, memo)
        local = 0
        for i in range(done, count):
            if results[i] != open_:
                continue
            end = min(position[i] + size, ends[i])
            for r in range(local, local + end - position[i]):
                if illegal[r]:
                    results[i] = frames[picked[r]]
                    break
            if results[i] == open_ and end == ends[i]:
                results[i] = late[i] if late[i] >= 0 else -1
            local += end - position[i]
            position[i] = end
        while done < count and results[done] != open_:
            answers[answered] = results[done]
            answered += 1
            if stop_at_legal and results[done] < 0:
                return answers[:answered].copy(), checks
            done += 1
        size *= 2
    return answers[:answered].copy(), checks


#: Motions after the first that first_legal_goal checks in its first wave, rows of each.
OTHERS_WAVE = 8


@kernel('Tuple((i8, i8[::1], i8))(f8[:, :], f8[:], f8[:, :], f8[:], f8[::1], i8, '
        'f8[:, ::1], i8[::1], i8, ' + CHECK_TABLES_TYPE + ', ' + ROW_MEMO_TYPE + ')')
def first_legal_goal(objective, times, frame_step, speed_cap, start, here, goals, arrivals,
                     first_answer, tables, memo):
    """
    Check the motions from a start to each goal in order, up to the first legal one.

    :meth:`CTSpace.first_legal_motion`: the motions from (``start`` (d,), ``here``) to each of
    ``goals`` (m, d) at ``arrivals`` (m,), checked in order up to the first legal one.

    The first goal (the best one, usually legal) is checked alone, all its rows in one batch,
    unless ``first_answer`` (>= -1) already gives its first illegal frame (-2: not known); the
    others, when it fails, in one batch read goal by goal, in waves of :data:`OTHERS_WAVE`
    rows each and twice as many each wave (they usually fail within a few frames of the
    start). Returns (index of the first legal goal or -1, the first illegal frame of each goal
    checked, -1 for the legal one, configurations checked).
    """
    m, d = goals.shape
    answers = np.empty(m, dtype=np.int64)
    if m == 0:
        return -1, answers, 0
    checks = 0
    qa = np.empty((m, d))
    ia = np.empty(m, dtype=np.int64)
    for i in range(m):
        for j in range(d):
            qa[i, j] = start[j]
        ia[i] = here
    if first_answer >= -1:
        answers[0] = first_answer
    else:
        first, more = _motion_failures(objective, times, frame_step, speed_cap, qa[:1].copy(),
                                       ia[:1].copy(), goals[:1].copy(), arrivals[:1].copy(),
                                       True, 0, tables, memo)
        answers[0] = first[0]
        checks += more
    if answers[0] < 0 or m == 1:
        return 0 if answers[0] < 0 else -1, answers[:1].copy(), checks
    others, more = _motion_failures(objective, times, frame_step, speed_cap, qa[1:].copy(),
                                    ia[1:].copy(), goals[1:].copy(), arrivals[1:].copy(), True,
                                    OTHERS_WAVE, tables, memo)
    checks += more
    for r in range(others.shape[0]):
        answers[1 + r] = others[r]
        if others[r] < 0:
            return 1 + r, answers[:2 + r].copy(), checks
    return -1, answers[:1 + others.shape[0]].copy(), checks


def branch_layout(kinematics: BodyKinematics, shapes: BodyShapes, branch: str,
                  checked_links: Sequence[str], obstacle_links: Sequence[str]) -> tuple:
    """
    Return the model-only data of a branch, built once and kept in ``shapes.branch_layouts``.

    Returns
    -------
    tuple
        (steps that move with the branch, checked shapes (n,) int, steps needed for the
        checks, shape pairs (P, 2) int, link at the centre of its reach, reach radius m, the
        pairs' other shapes once each (O,) int, each pair's index into them (P,) int, whether
        each pair's other shape is itself checked (P,) bool).

    """
    key = (branch, tuple(checked_links), tuple(obstacle_links), id(kinematics))
    layout = shapes.branch_layouts.get(key)
    if layout is not None:
        return layout
    skeleton = kinematics.skeleton
    joint_names = tuple(skeleton.joint_names[i] for i in skeleton.branch(branch))
    steps = kinematics.subtree_steps(joint_names)
    moving = {step.child for step in steps}
    checked = shapes.shapes_of(checked_links)
    checked = checked[np.isin(shapes.link[checked], list(moving))]
    # Only the links on the way to the checked shapes matter for validity.
    needed = set(shapes.link[checked].tolist())
    parent_of = {step.child: step.parent for step in steps}
    for link in list(needed):
        while link in parent_of:
            link = parent_of[link]
            needed.add(link)
    check_steps = tuple(step for step in steps if step.child in needed)
    pairs = shapes.pairs(checked, shapes.shapes_of(obstacle_links))
    first, reach = _reach_bound(shapes, steps, checked)
    obstacles, pair_obstacle = np.unique(pairs[:, 1], return_inverse=True)
    layout = (steps, checked, check_steps, pairs, first, reach, obstacles,
              pair_obstacle.ravel(), np.isin(pairs[:, 1], checked))
    shapes.branch_layouts[key] = layout
    return layout


@dataclass(frozen=True)
class BranchModel:
    """What a branch's CT-space needs that depends on the model only (see :func:`branch_model`)."""

    layout: tuple
    indices: np.ndarray
    joint_names: Tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    speed_limit: np.ndarray
    lower_tolerant: np.ndarray
    upper_tolerant: np.ndarray
    speed_cap: np.ndarray
    #: Per pair of the layout: its other shape and the column of its branch shape.
    pair_other: np.ndarray
    pair_column: np.ndarray
    checked_box_half: np.ndarray
    chain: Chain
    chain_links: np.ndarray
    #: _branch_boxes' arguments after the body's: the checked shapes and where they sit.
    shape_tables: tuple


def branch_model(kinematics: BodyKinematics, shapes: BodyShapes, branch: str,
                 checked_links: Sequence[str], obstacle_links: Sequence[str]) -> BranchModel:
    """
    Return the branch's layout and the tables its CT-space builds from it, built once.

    The branch's layout (:func:`branch_layout`) and the tables its CT-space builds from it, built
    once and kept in ``shapes.branch_layouts``.
    """
    key = ('model', branch, tuple(checked_links), tuple(obstacle_links), id(kinematics))
    model = shapes.branch_layouts.get(key)
    if model is not None:
        return model
    layout = branch_layout(kinematics, shapes, branch, checked_links, obstacle_links)
    skeleton = kinematics.skeleton
    indices = np.asarray(skeleton.branch(branch), dtype=np.int64)
    checked, check_steps, pairs = layout[1], layout[2], layout[3]
    lower, upper = skeleton.lower[indices], skeleton.upper[indices]
    speed_limit = skeleton.velocity_limit[indices]
    chain = kinematics.chain(check_steps)
    place = {link: i for i, link in enumerate(chain.links.tolist())}
    model = BranchModel(
        layout=layout, indices=indices,
        joint_names=tuple(skeleton.joint_names[i] for i in indices),
        lower=lower, upper=upper, speed_limit=speed_limit,
        lower_tolerant=lower - 1e-9, upper_tolerant=upper + 1e-9,
        speed_cap=speed_limit * (1 + SPEED_TOLERANCE),
        pair_other=np.ascontiguousarray(pairs[:, 1], dtype=np.int64),
        pair_column=np.searchsorted(checked, pairs[:, 0]),
        checked_box_half=shapes.box_half[checked],
        chain=chain, chain_links=np.asarray(chain.links, dtype=np.int64),
        shape_tables=(
            np.asarray(checked, dtype=np.int64),
            np.array([place[link] for link in shapes.link[checked]], dtype=np.int64),
            np.ascontiguousarray(shapes.origin_translation[checked]),
            np.ascontiguousarray(shapes.origin_rotation[checked]),
            ~shapes.identity_origin[checked], shapes.kind_code[checked],
            shapes.half[checked]))
    shapes.branch_layouts[key] = model
    return model


def _reach_bound(shapes: BodyShapes, steps: Sequence[JointStep],
                 checked: np.ndarray) -> Tuple[int, float]:
    """
    Link at the centre and radius (m) of a ball holding the checked shapes at any pose.

    The centre is the branch's first joint, which the branch itself cannot move; the radius
    is the longest chain of joint offsets from it plus the shape's own extent.
    """
    if not steps:
        return 0, 0.0
    first = steps[0].child
    link_reach = {first: 0.0}
    for step in steps[1:]:
        link_reach[step.child] = (link_reach.get(step.parent, 0.0)
                                  + float(np.linalg.norm(step.origin_translation)))
    reach = 0.0
    for shape in checked:
        radius = float(np.linalg.norm(shapes.half[shape]))
        offset = float(np.linalg.norm(shapes.origin_translation[shape]))
        reach = max(reach, link_reach.get(int(shapes.link[shape]), 0.0) + offset + radius)
    return first, reach


class CTSpace:
    """
    Configuration-time space of one branch, with OMPL-shaped queries (paper §5.2).

    Parameters
    ----------
    branch
        'waist', 'left_arm' or 'right_arm'.
    body
        The actor over the step, with the earlier branches already fixed.
    times
        (k,) frame times, s, strictly increasing.
    objective
        (k, d) the branch's objective configurations O(t_i), rad.
    checked_links
        Links whose shapes are this branch's responsibility.
    obstacle_links
        Links of the actor's own body this branch must not touch (adjacent ones are skipped).
    time_weight
        Weight of time in :meth:`distance`, rad/s.

    """

    def __init__(self, branch: str, body: TimedBody, times: np.ndarray, objective: np.ndarray,
                 checked_links: Sequence[str], obstacle_links: Sequence[str],
                 time_weight: float = 1.0):
        self.branch = branch
        self.body = body
        # What depends on the model only is worked out once per branch and reused every step.
        model = branch_model(body.kinematics, body.shapes, branch, checked_links,
                             obstacle_links)
        self.indices = model.indices.copy()
        self.joint_names = model.joint_names
        self.times = np.asarray(times, dtype=float)
        self.objective = np.asarray(objective, dtype=float)
        k, d = self.objective.shape
        if self.times.shape != (k,) or d != len(self.indices):
            raise ValueError(f'objective shape {self.objective.shape} does not match times '
                             f'{self.times.shape} and branch {branch!r} ({len(self.indices)})')
        self.lower, self.upper, self.speed_limit = model.lower, model.upper, model.speed_limit
        # The joint limits with the tolerance of within_bounds, worked out once.
        self._lower_tolerant, self._upper_tolerant = model.lower_tolerant, model.upper_tolerant
        #: (d,) joint speeds a motion may not exceed (the limits with their tolerance), rad/s.
        self.speed_cap = model.speed_cap
        #: (k - 1, 1) time from each frame to the next, s.
        self.frame_step = (self.times[1:] - self.times[:-1])[:, None]
        self.time_weight = float(time_weight)
        #: steps: the steps to re-evaluate when the branch moves (all links it carries).
        (self.steps, self.checked, self._check_steps, pairs, first, self._reach, obstacle,
         pair_obstacle, _) = model.layout
        self._reach_centre = body.positions[:, first]
        # Body shapes the branch can never reach during the step need no checks (each obstacle
        # shape tested once, however many of the branch's shapes it pairs with). The others
        # are read where the body holds them (they do not move while this branch is planned).
        kept = _reachable_pairs(self._reach_centre, self._reach ** 2, body.shape_lower,
                                body.shape_upper, obstacle, pair_obstacle)
        self.pairs = pairs[kept]
        self._pair_other = other = model.pair_other[kept]
        self._pair_column = model.pair_column[kept]
        self._checked_box_half = model.checked_box_half
        self._pair_box_half = body.shapes.box_half[other]
        # The shapes themselves, for the exact tests (kind codes and padded half extents).
        self._checked_kinds, self._checked_half = model.shape_tables[5], model.shape_tables[6]
        self._pair_kinds = body.shapes.kind_code[other]
        self._pair_half = body.shapes.half[other]
        # The links the checks need, in a compact layout, and where the checked shapes sit on
        # them (kinematics of the branch's few links, not of the whole body, per batch).
        self._chain = model.chain
        # _branch_boxes' arguments that stay the same while the branch is planned (the body's
        # arrays are only ever written in place).
        self._box_tables = (body.frames, model.indices, body.rotations, body.positions,
                            model.chain_links, body.shape_rotation, body.shape_centre,
                            body.shape_lower, body.shape_upper) + model.shape_tables
        self._prepare_environment()
        # Frames [0, clear_until) where the branch, where the body holds it, touches nothing.
        self._clear_until = body.clear_until.get(branch, 0)
        # illegal_rows' arguments after the batch's own, the same while the branch is planned
        # (handed to a planner's compiled kernels by run_checks; CHECK_TABLES_TYPE).
        self._check_tables = (
            self._lower_tolerant, self._upper_tolerant, int(self._clear_until),
            *self._box_tables, *self._chain.step_table, self._triangle_lower,
            self._triangle_upper, self._pair_column, self._checked_box_half,
            self._triangle_corners, self._pair_box_half, SAT_MARGIN, self._checked_kinds,
            self._checked_half, self._pair_kinds, self._pair_half, self._pair_other)
        # The answers of the rows checked so far (illegal_rows): valid as long as the tables,
        # while the body holds still.
        self._row_memo = _empty_row_memo()
        self.checks = 0

    def _prepare_environment(self) -> None:
        """Keep only triangles the branch could reach during the step (§5: broad phase)."""
        env = self.body.environment
        centre, reach = self._reach_centre, self._reach
        lower = centre.min(axis=0) - reach
        upper = centre.max(axis=0) + reach
        near = self.body.triangles_near(lower, upper)
        self._triangle_lower = env.lower[near]
        self._triangle_upper = env.upper[near]
        self._triangle_corners = env.corners[near]

    # -- OMPL-shaped space ---------------------------------------------------------------
    @property
    def dimension(self) -> int:
        """Return the number of branch joints d."""
        return len(self.indices)

    @property
    def bounds(self) -> Tuple[np.ndarray, np.ndarray]:
        """Return the joint bounds: lower (d,) and upper (d,), rad."""
        return self.lower, self.upper

    @property
    def frame_count(self) -> int:
        """Return the number of frames k of the time grid."""
        return len(self.times)

    def distance(self, a: Tuple[np.ndarray, int], b: Tuple[np.ndarray, int]) -> float:
        """Return the distance between CT states: joint distance in rad plus weighted time gap."""
        (qa, ia), (qb, ib) = a, b
        return float(np.linalg.norm(np.asarray(qa) - np.asarray(qb))
                     + self.time_weight * abs(self.times[ib] - self.times[ia]))

    def deviation(self, q: np.ndarray, i: int) -> np.ndarray:
        """Deviation of configuration(s) q from the objective at frame(s) i: same shape, rad."""
        return np.asarray(q) - self.objective[i]

    def motion_frames(self, a: Tuple[np.ndarray, int], b: Tuple[np.ndarray, int]) -> np.ndarray:
        """
        Return the configurations at frames ia..ib of the motion a -> b: (ib - ia + 1, d), rad.

        Interpolates the deviation from the objective linearly in time, so a motion between
        states on the objective follows it exactly.
        """
        (qa, ia), (qb, ib) = a, b
        objective = self.objective[ia:ib + 1]
        times = self.times[ia:ib + 1]
        da = np.asarray(qa) - objective[0]
        db = np.asarray(qb) - objective[-1]
        span = times[-1] - times[0]
        s = (times - times[0]) / span if span > 0 else np.zeros(len(times))
        return objective + da + s[:, None] * (db - da)

    def interpolate(self, a: Tuple[np.ndarray, int], b: Tuple[np.ndarray, int],
                    s: float) -> Tuple[np.ndarray, float]:
        """State a fraction s in [0, 1] of the way from a to b: (q (d,), t s)."""
        (qa, ia), (qb, ib) = a, b
        t = (1 - s) * self.times[ia] + s * self.times[ib]
        objective = np.array([np.interp(t, self.times, column) for column in self.objective.T])
        da = np.asarray(qa) - self.objective[ia]
        db = np.asarray(qb) - self.objective[ib]
        return objective + da + s * (db - da), t

    def within_bounds(self, q: np.ndarray) -> np.ndarray:
        """Whether each configuration is within the joint limits: (...,) bool."""
        if q.ndim == 2 and q.dtype == np.float64:
            return _within(q, self._lower_tolerant, self._upper_tolerant)
        return np.all((q >= self._lower_tolerant) & (q <= self._upper_tolerant), axis=-1)

    def is_valid(self, q: np.ndarray, i: int) -> bool:
        """Whether branch configuration q (d,) is legal at frame i (limits, no collision)."""
        return self.first_invalid(np.asarray(q, dtype=float)[None], np.array([i])) < 0

    def check_motion(self, a: Tuple[np.ndarray, int], b: Tuple[np.ndarray, int]) -> bool:
        """Whether the motion a -> b is legal (forward in time, speeds, collision-free)."""
        return self.first_invalid_motion(a, b) < 0

    def first_invalid_motion(self, a: Tuple[np.ndarray, int],
                             b: Tuple[np.ndarray, int]) -> int:
        """
        First illegal frame of the motion a -> b, or -1 when it is legal.

        A motion backwards or standing still in time is illegal at ``a``'s frame; a speed
        violation is reported at the frame it ends on.
        """
        _, failures = self.first_legal_motion(a, [b])
        return failures[0]

    def first_legal_motion(self, a: Tuple[np.ndarray, int],
                           goals: Sequence[Tuple[np.ndarray, int]],
                           first_failure: Optional[int] = None) -> Tuple[int, List[int]]:
        """
        Check motions from ``a`` to each goal in order; stop at the first legal one.

        One kernel (:func:`first_legal_goal`): the first goal (the best one, usually legal)
        checked alone; all the others then in one batch, its answers read goal by goal.
        ``first_failure``: the first goal's first illegal frame (-1: legal) where it is
        known already (:meth:`rows_and_path` checked its motion), None where it is not.

        Returns
        -------
        tuple
            (index of the first legal goal or -1, first illegal frame of each goal checked,
            -1 for the legal one).

        """
        qa, ia = a
        if not goals:
            return -1, []
        targets = np.array([q for q, _ in goals], dtype=float).reshape(len(goals), -1)
        arrivals = np.array([frame for _, frame in goals], dtype=np.int64)
        chosen, failures, checks = first_legal_goal(
            self.objective, self.times, self.frame_step, self.speed_cap,
            np.array(qa, dtype=float), int(ia), targets, arrivals,
            -2 if first_failure is None else int(first_failure), self._check_tables,
            self._row_memo)
        self.checks += checks
        return int(chosen), failures.tolist()

    def run_checks(self, kernel: Callable, *arguments) -> tuple:
        """
        Run a planner's compiled kernel that checks states of this space; return its answers.

        Compiled code cannot call this object's methods, so a planner's compiled twin (the
        CT-roadmap's expansion) is handed, after its own ``arguments``, what this space's
        compiled checks take (:data:`SPACE_ARGUMENTS_TYPE`: the objective, the time grid, the
        frame steps, the speed caps, the check tables and the row memo), and checks states
        only by passing them on to :func:`illegal_rows`, :func:`motion_path` and
        :func:`first_legal_goal`, the compiled forms of :meth:`valid_rows` and
        :meth:`first_legal_motion`. The kernel returns the number of configurations it checked
        last; they are counted in :attr:`checks`.

        Returns
        -------
        tuple
            The kernel's answers, without the count of configurations checked.

        """
        *answers, checks = kernel(*arguments, self.objective, self.times, self.frame_step,
                                  self.speed_cap, self._check_tables, self._row_memo)
        self.checks += int(checks)
        return tuple(answers)

    def first_invalid_path(self, waypoints: Sequence[Tuple[np.ndarray, int]]) -> int:
        """
        First illegal frame along a chain of motions through ``waypoints``, or -1.

        Each motion is checked as :meth:`first_invalid_motion` checks it (forward in time,
        speeds, collisions at every frame after its start), all of them in one batch, read
        motion by motion up to the first illegal frame.

        Parameters
        ----------
        waypoints
            (q (d,) rad, frame index) pairs, frames strictly increasing; the first one is taken
            as legal (the chain's start).

        """
        if len(waypoints) < 2:
            return -1
        for bad in self._failures(list(zip(waypoints[:-1], waypoints[1:])), False, 0):
            if bad >= 0:
                return bad
        return -1

    def rows_and_path(self, q: np.ndarray, frames: np.ndarray,
                      waypoints: Sequence[Tuple[np.ndarray, int]]) -> Tuple[np.ndarray, int]:
        """
        :meth:`valid_rows` of a batch and :meth:`first_invalid_path`, in one batch.

        Returns
        -------
        tuple
            ((m,) bool legality of the rows, first illegal frame along the path or -1).

        """
        q = np.asarray(q, dtype=float)
        frames = np.asarray(frames)
        m = len(frames)
        if len(waypoints) < 2:
            return self.valid_rows(q, frames), -1
        path, path_frames, segments, early = self._motion_batch(
            list(zip(waypoints[:-1], waypoints[1:])))
        # The rows, then the motions, in one batch (counted as _failures counts them).
        rows = np.concatenate([q, path])
        self.checks += len(rows)
        illegal = self._illegal(rows, np.concatenate([frames, path_frames]))
        legal = ~illegal[:m]
        for (begin, end), late in zip(segments, early):
            along = np.flatnonzero(illegal[m + begin:m + end])
            if len(along):
                return legal, int(path_frames[begin + along[0]])
            if late >= 0:
                return legal, int(late)
        return legal, -1

    def _failures(self, motions: Sequence[tuple], stop_at_legal: bool, first: int) -> List[int]:
        """
        Return the first illegal frame of each motion in order, -1 for a legal one.

        The first illegal frame of each motion ((qa, ia), (qb, ib)) in order, -1 for a legal one
        (the rows are counted in ``checks``).

        With ``first`` <= 0 every row is checked in one batch; else in waves along the
        motions, ``first`` rows of each motion still open, then twice as many each wave (so
        rows after a motion's first illegal one are seldom checked; the answers are the same).
        With ``stop_at_legal`` the answers end at the first legal motion. A motion whose rows
        are all legal is illegal at its speed violation, one that does not go forward in time
        at its start frame (:func:`_motion_failures`).
        """
        answers, checks = _motion_failures(self.objective, self.times, self.frame_step,
                                           self.speed_cap, *self._motion_ends(motions),
                                           stop_at_legal, first, self._check_tables,
                                           self._row_memo)
        self.checks += checks
        return answers.tolist()

    def _motion_ends(self, motions: Sequence[tuple]) -> tuple:
        """
        Return the end points of motions as the motion kernels take them.

        The end points of motions ((qa, ia), (qb, ib)) as the motion kernels take them: (qa (n, d),
        ia (n,), qb (n, d), ib (n,)).
        """
        count = len(motions)
        qa, qb = np.empty((count, self.dimension)), np.empty((count, self.dimension))
        ia, ib = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
        for i, ((a, frame_a), (b, frame_b)) in enumerate(motions):
            qa[i], ia[i], qb[i], ib[i] = a, frame_a, b, frame_b
        return qa, ia, qb, ib

    def _motion_batch(self, motions: Sequence[tuple]) -> tuple:
        """
        Return the rows of motions for one check.

        The rows of motions ((qa, ia), (qb, ib)) for one check: (q (m, d) rad, frames (m,),
        segments [(begin, end)] per motion, early: each motion's speed violation frame or -1, its
        start frame for one that does not go forward in time).
        """
        q, frames, ends, late = _motion_paths(self.objective, self.times, self.frame_step,
                                              self.speed_cap, *self._motion_ends(motions))
        ends = ends.tolist()
        return q, frames, list(zip([0] + ends[:-1], ends)), late.tolist()

    def _motion_rows(self, qa: np.ndarray, ia: int, qb: np.ndarray,
                     ib: int) -> Tuple[np.ndarray, int]:
        """
        Return the configurations at frames ia+1..

        of the motion to (qb, ib) that keep to the speed limits, and the frame of the first speed
        violation (-1 when none).
        """
        if ib <= ia:
            return np.zeros((0, self.dimension)), ia
        rows, late = motion_path(self.objective, self.times, self.frame_step,
                                 self.speed_cap, float_array(qa), int(ia), float_array(qb),
                                 int(ib))
        return rows, int(late)

    def first_invalid(self, q: np.ndarray, frames: np.ndarray) -> int:
        """
        Row of the first illegal configuration in a batch, or -1 when all are legal.

        Parameters
        ----------
        q
            (m, d) branch configurations, rad.
        frames
            (m,) frame index of each row, in increasing order.

        Returns
        -------
        int
            The first row outside the joint limits or in collision with the environment or the
            rest of the actor, or -1.

        """
        frames = np.asarray(frames)
        self.checks += len(frames)
        if not len(frames):
            return -1
        bad = np.flatnonzero(self._illegal(np.asarray(q, dtype=float), frames))
        return -1 if not len(bad) else int(np.searchsorted(frames, frames[bad[0]]))

    def valid_rows(self, q: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """
        Legality of each configuration of a batch: (m,) bool.

        Parameters
        ----------
        q
            (m, d) branch configurations, rad.
        frames
            (m,) frame index of each row, any order.

        """
        frames = np.asarray(frames)
        q = np.asarray(q, dtype=float)
        m = len(frames)
        self.checks += m
        if not m:
            return np.zeros(0, dtype=bool)
        return ~self._illegal(q, frames)

    def _shape_boxes(self, q: np.ndarray, frames: np.ndarray) -> tuple:
        """
        Return the poses and boxes of the branch's checked shapes for a batch of rows.

        Poses and boxes of the branch's checked shapes for a batch of rows (what
        :func:`illegal_rows` works out first, as the checks see it; the tests read it here).

        Rows where the branch is where the body already holds it (the objective, or the start
        at frame 0, before the branch is fixed) take the body's poses; only the others need
        kinematics.

        Returns
        -------
        tuple of numpy.ndarray
            Rotations (m, n, 3, 3), centres (m, n, 3), box corners (m, n, 3) x 2, m, and
            whether each row is where the body holds the branch (m,).

        """
        m, n = len(frames), len(self.checked)
        rotation, centre = np.empty((m, n, 3, 3)), np.empty((m, n, 3))
        low, high = np.empty((m, n, 3)), np.empty((m, n, 3))
        held = np.empty(m, dtype=np.bool_)
        _branch_boxes(q, frames.astype(np.int64, copy=False), *self._box_tables, rotation,
                      centre, low, high, held, *self._chain.step_table)
        return rotation, centre, low, high, held

    def _illegal(self, q: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """
        Which rows of a batch are illegal, all rows at once: (m,) bool.

        A row is illegal outside the joint limits (with :meth:`within_bounds`' tolerance) or
        where the branch touches the environment or the body: the broad phase (boxes, the
        separating axis test) and the exact test of the shapes it leaves, in one kernel
        (:func:`illegal_rows`). Rows where the body holds the branch, at frames where the
        check of the body's own motion found that the branch touches nothing
        (``TimedBody.clear_until``), are not tested again: the same tests gave that answer
        (the same poses; the pairs and triangles here are among those checked there).
        """
        frames = np.ascontiguousarray(frames, dtype=np.int64)  # the kernels' index type
        return illegal_rows(q, frames, self._check_tables, self._row_memo)
