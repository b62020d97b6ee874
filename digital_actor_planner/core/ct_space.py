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
legal only forward in time, within the joint speed limits and collision-free at every frame.

Motions are interpolated in deviation from the objective O(t) (§5.1) rather than in absolute
joint values, so a motion between two states on the objective follows the objective exactly and
a constant deviation rides on top of the swinging arm pattern.

Collision checking is compiled, a batch of rows at a time: a broad phase (per row, axis-aligned
boxes of the branch's shapes against the environment's triangles and the rest of the body, then
the separating axis test of the oriented boxes holding them) and the exact test of the shapes it
leaves (:func:`.convex.touching`, GJK), using the shapes and environment meshes of
:class:`~digital_actor_planner.core.collision.BodyCollision` when it provides them.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Dict, List, Optional, Sequence, Tuple

import fcl
import numpy as np

from .collision import _extent, _half_extents, _KIND_CODES
from .convex import touching, TRIANGLE
from .jit import float_array, kernel
from .skeleton import Skeleton

#: Relative slack on the joint speed limits, for rounding in interpolation.
SPEED_TOLERANCE = 1e-6
#: Links this many joints apart or closer are adjacent and never checked against each other.
ADJACENT_JOINTS = 2
UPPER_BODY_BRANCHES = ('waist', 'left_arm', 'right_arm')
#: Kept triangles up to which a batch's boxes are tested against all of them at once.
FEW_TRIANGLES = 64
#: Rows x shapes x triangles above which contacts are first cut by the shapes' swept boxes.
SWEPT_CONTACTS = 4096
#: Room around the actor's shapes over a step for the triangles kept per step, m (about the
#: reach of a bending trunk or a raised arm beyond its place in the motion pattern).
NEAR_MARGIN = 0.6
#: Gap, m, beyond which the separating axis test of oriented boxes lets a pair that the boxes
#: along the world axes could not tell apart skip the exact test: far more than its
#: tolerances, so a pair it skips is one the exact test would find apart (the same plans,
#: fewer exact tests).
SAT_MARGIN = 1e-3
_IDENTITY = np.eye(3)
_IDENTITY.setflags(write=False)


def _axis_code(axis: np.ndarray) -> Tuple[int, float]:
    """Return (coordinate, sign) for a coordinate axis, or (-1, 0) for a general one."""
    nonzero = np.flatnonzero(np.abs(axis) > 1e-12)
    if len(nonzero) == 1:
        return int(nonzero[0]), float(np.sign(axis[nonzero[0]]))
    return -1, 0.0


@kernel('void(f8[:, :], f8[:, :, :, :], f8[:, :, :], i8[::1], i8[::1], f8[:, :, ::1], '
        'b1[::1], f8[:, ::1], i8[::1], f8[::1], b1[::1], i8[::1], i8[::1], i8[::1], f8[::1], '
        'f8[:, ::1])')
def _link_poses(q, rotations, positions, parent, child, origin_rotation, turned,
                origin_translation, offset_axis, offset_length, has_offset, joint, kind,
                axis_coordinate, axis_sign, axis):
    """
    :meth:`BodyKinematics.poses` of a sequence of joint steps for every frame, in place.

    Per step (arrays over the steps): its ``parent`` and ``child`` link rows; its origin's
    rotation (where ``turned``) and translation (where ``has_offset``; along one coordinate
    axis ``offset_axis`` >= 0 by ``offset_length``); its configuration index ``joint`` (-1
    fixed) and ``kind`` (1 revolute, 2 prismatic); its unit ``axis``, a coordinate axis
    ``axis_coordinate`` >= 0 with ``axis_sign`` where it is one.
    """
    base = np.empty((3, 3))
    turn = np.empty((3, 3))
    for f in range(q.shape[0]):
        for i in range(parent.shape[0]):
            p, c = parent[i], child[i]
            for r in range(3):
                if offset_axis[i] >= 0:
                    shift = rotations[f, p, r, offset_axis[i]] * offset_length[i]
                elif has_offset[i]:
                    shift = (rotations[f, p, r, 0] * origin_translation[i, 0]
                             + rotations[f, p, r, 1] * origin_translation[i, 1]
                             + rotations[f, p, r, 2] * origin_translation[i, 2])
                else:
                    shift = 0.0
                positions[f, c, r] = positions[f, p, r] + shift
            if turned[i]:
                for r in range(3):
                    for col in range(3):
                        base[r, col] = (rotations[f, p, r, 0] * origin_rotation[i, 0, col]
                                        + rotations[f, p, r, 1] * origin_rotation[i, 1, col]
                                        + rotations[f, p, r, 2] * origin_rotation[i, 2, col])
            else:
                for r in range(3):
                    for col in range(3):
                        base[r, col] = rotations[f, p, r, col]
            if joint[i] < 0 or kind[i] == 2:
                for r in range(3):
                    for col in range(3):
                        rotations[f, c, r, col] = base[r, col]
                if joint[i] >= 0:
                    value = q[f, joint[i]]
                    for r in range(3):
                        if axis_coordinate[i] >= 0:
                            along = base[r, axis_coordinate[i]] * axis_sign[i]
                        else:
                            along = (base[r, 0] * axis[i, 0] + base[r, 1] * axis[i, 1]
                                     + base[r, 2] * axis[i, 2])
                        positions[f, c, r] += along * value
                continue
            a = axis_coordinate[i]
            if a >= 0:
                # A revolute joint about coordinate axis a: the product with its rotation
                # matrix keeps column a and mixes the other two, b = a + 1 and e = a + 2
                # (mod 3): b' = cos b + sin e, e' = cos e - sin b. The written-out product's
                # third terms are products with 0: the same numbers (a zero's sign aside).
                angle = q[f, joint[i]] * axis_sign[i]
                cos, sin = math.cos(angle), math.sin(angle)
                b, e = (a + 1) % 3, (a + 2) % 3
                for r in range(3):
                    rotations[f, c, r, a] = base[r, a]
                    rotations[f, c, r, b] = base[r, b] * cos + base[r, e] * sin
                    rotations[f, c, r, e] = base[r, e] * cos + base[r, b] * -sin
                continue
            x, y, z = axis[i, 0], axis[i, 1], axis[i, 2]
            cos, sin = math.cos(q[f, joint[i]]), math.sin(q[f, joint[i]])
            t = 1.0 - cos
            turn[0, 0], turn[0, 1], turn[0, 2] = t * x * x + cos, t * x * y - sin * z, \
                t * x * z + sin * y
            turn[1, 0], turn[1, 1], turn[1, 2] = t * x * y + sin * z, t * y * y + cos, \
                t * y * z - sin * x
            turn[2, 0], turn[2, 1], turn[2, 2] = t * x * z - sin * y, t * y * z + sin * x, \
                t * z * z + cos
            for r in range(3):
                for col in range(3):
                    rotations[f, c, r, col] = (base[r, 0] * turn[0, col]
                                               + base[r, 1] * turn[1, col]
                                               + base[r, 2] * turn[2, col])


@kernel('void(f8[:, :, :, :], f8[:, :, :], i8[::1], f8[:, ::1], f8[:, :, ::1], b1[::1], '
        'i8[::1], f8[:, :, :, ::1], f8[:, :, ::1])')
def _place_shapes(rotations, positions, links, offsets, turns, turned, slots, rotation,
                  centre):
    """
    Place the shapes' world poses over frames into ``rotation`` and ``centre``.

    Shapes' world poses over frames, into ``rotation`` (k, S, 3, 3) and ``centre`` (k, S, 3) at
    their ``slots``: shape i hangs from link row ``links[i]`` at ``offsets[i]`` (m, in the link's
    frame), turned by ``turns[i]`` where ``turned[i]``.
    """
    for f in range(rotations.shape[0]):
        for i in range(links.shape[0]):
            link, s = links[i], slots[i]
            for r in range(3):
                centre[f, s, r] = positions[f, link, r] + (
                    rotations[f, link, r, 0] * offsets[i, 0]
                    + rotations[f, link, r, 1] * offsets[i, 1]
                    + rotations[f, link, r, 2] * offsets[i, 2])
                for c in range(3):
                    if turned[i]:
                        rotation[f, s, r, c] = (rotations[f, link, r, 0] * turns[i, 0, c]
                                                + rotations[f, link, r, 1] * turns[i, 1, c]
                                                + rotations[f, link, r, 2] * turns[i, 2, c])
                    else:
                        rotation[f, s, r, c] = rotations[f, link, r, c]


@kernel('void(f8[:, :, :, :], f8[:, :, :], i8[::1], f8[:, ::1], f8[:, :, ::1], b1[::1], '
        'i8[::1], f8[:, ::1], i8[::1], f8[:, :, :, ::1], f8[:, :, ::1], f8[:, :, ::1], '
        'f8[:, :, ::1], f8[:, ::1], f8[:, ::1])')
def _pose_shapes_into(rotations, positions, links, offsets, turns, turned, kinds, halves,
                      slots, shape_rotation, shape_centre, shape_lower, shape_upper,
                      swept_lower, swept_upper):
    """
    Pose some shapes and bound their boxes in place, swept over the k frames.

    :meth:`BodyShapes.poses` and :meth:`BodyShapes.bounds` of some shapes (their links, origins,
    kind codes and half extents; one row each) written in place at their ``slots`` of a body's (k,
    S, ...) pose and box arrays, and their boxes swept over the k frames into
    ``swept_lower``/``swept_upper`` (S, 3): the same kernels and arithmetic, without the copies of
    scattering the results from Python, nor temporary arrays (the memory a step's body takes is
    much of what a first plan after other work waits for).
    """
    k, n = rotations.shape[0], links.shape[0]
    _place_shapes(rotations, positions, links, offsets, turns, turned, slots, shape_rotation,
                  shape_centre)
    for i in range(n):
        s = slots[i]
        for e in range(3):
            swept_lower[s, e] = np.inf
            swept_upper[s, e] = -np.inf
    for f in range(k):
        for i in range(n):
            s = slots[i]
            for e in range(3):
                extent = _extent(kinds[i], halves[i], shape_rotation[f, s], e)
                low = shape_centre[f, s, e] - extent
                high = shape_centre[f, s, e] + extent
                shape_lower[f, s, e] = low
                shape_upper[f, s, e] = high
                swept_lower[s, e] = min(swept_lower[s, e], low)
                swept_upper[s, e] = max(swept_upper[s, e], high)


@kernel('b1(f8[:, ::1], i8[::1], f8[:, :], b1[::1])')
def _write_columns(frames, indices, values, changed):
    """
    Write ``values`` (k, d) into the ``indices`` columns of ``frames`` (k, n).

    Write ``values`` (k, d) into the ``indices`` columns of ``frames`` (k, n); False (and nothing
    written) when they already hold them (as ``np.array_equal``: a NaN differs). ``changed`` (k,):
    set where a frame's values differ (left as it is elsewhere).
    """
    same = True
    for f in range(values.shape[0]):
        for j in range(indices.shape[0]):
            if not frames[f, indices[j]] == values[f, j]:
                same = False
                changed[f] = True
    if same:
        return False
    for f in range(values.shape[0]):
        for j in range(indices.shape[0]):
            frames[f, indices[j]] = values[f, j]
    return True


# numba types of a step table (_step_table's arrays, in order), as _link_poses takes them.
_STEP_TABLE_TYPES = ('i8[::1], i8[::1], f8[:, :, ::1], b1[::1], f8[:, ::1], i8[::1], f8[::1], '
                     'b1[::1], i8[::1], i8[::1], i8[::1], f8[::1], f8[:, ::1]')


@kernel('void(f8[:, :], i8[::1], f8[:, ::1], i8[::1], '
        'f8[:, :, :, ::1], f8[:, :, ::1], i8[::1], f8[:, :, :, ::1], f8[:, :, ::1], '
        'f8[:, :, ::1], f8[:, :, ::1], i8[::1], i8[::1], f8[:, ::1], f8[:, :, ::1], b1[::1], '
        'i8[::1], f8[:, ::1], f8[:, :, :, ::1], f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], '
        'b1[::1], ' + _STEP_TABLE_TYPES + ')')
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
    posed by :func:`_link_poses` over the chain's ``links`` (their poses read from
    ``body_rotations`` and ``body_positions``, the step table last), :func:`_place_shapes`
    and the boxes of :func:`collision._half_extents`: bit for bit the poses and boxes of the
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
        _link_poses(full, rotations, positions, parent, child, origin_rotation, step_turned,
                    origin_translation, offset_axis, offset_length, has_offset, joint, kind,
                    axis_coordinate, axis_sign, axis)
        placed = np.empty((count, n, 3, 3))
        placed_centre = np.empty((count, n, 3))
        _place_shapes(rotations, positions, shape_links, offsets, turns, turned, np.arange(n),
                      placed, placed_centre)
        extent = _half_extents(kinds, halves, placed)
        for i in range(count):
            r = moved[i]
            rotation[r] = placed[i]
            centre[r] = placed_centre[i]
            for c in range(n):
                for e in range(3):
                    low[r, c, e] = placed_centre[i, c, e] - extent[i, c, e]
                    high[r, c, e] = placed_centre[i, c, e] + extent[i, c, e]


@kernel('UniTuple(f8, 3)(f8[:, :], f8[:, :], i8)')
def _column_dots(rotation_a, rotation_b, i):
    """Column i of A's rotation dotted with each column of B's."""
    return ((rotation_a[0, i] * rotation_b[0, 0] + rotation_a[1, i] * rotation_b[1, 0]
             + rotation_a[2, i] * rotation_b[2, 0]),
            (rotation_a[0, i] * rotation_b[0, 1] + rotation_a[1, i] * rotation_b[1, 1]
             + rotation_a[2, i] * rotation_b[2, 1]),
            (rotation_a[0, i] * rotation_b[0, 2] + rotation_a[1, i] * rotation_b[1, 2]
             + rotation_a[2, i] * rotation_b[2, 2]))


@kernel('b1(f8[:, :], f8[:], f8[:], f8[:, :], f8[:], f8[:], f8)')
def _boxes_apart(rotation_a, centre_a, half_a, rotation_b, centre_b, half_b, margin):
    """
    Return whether two oriented boxes are more than ``margin`` apart (separating axes).

    Whether two oriented boxes are more than ``margin`` apart along one of the 15 axes of the
    separating axis test (box axes are the rotations' columns, half extents in them).

    True only for boxes that do not touch: a conservative test, never True for boxes whose
    gap is less than ``margin`` (m). Near-parallel edge axes are skipped (their face axes
    decide).
    """
    # The centre offset and the axes of B in A's frame, as tuples (no arrays to allocate:
    # this runs for every pair of boxes that meet).
    dx, dy, dz = (centre_b[0] - centre_a[0], centre_b[1] - centre_a[1],
                  centre_b[2] - centre_a[2])
    offset = (dx * rotation_a[0, 0] + dy * rotation_a[1, 0] + dz * rotation_a[2, 0],
              dx * rotation_a[0, 1] + dy * rotation_a[1, 1] + dz * rotation_a[2, 1],
              dx * rotation_a[0, 2] + dy * rotation_a[1, 2] + dz * rotation_a[2, 2])
    turn = (_column_dots(rotation_a, rotation_b, 0), _column_dots(rotation_a, rotation_b, 1),
            _column_dots(rotation_a, rotation_b, 2))
    size = ((abs(turn[0][0]), abs(turn[0][1]), abs(turn[0][2])),
            (abs(turn[1][0]), abs(turn[1][1]), abs(turn[1][2])),
            (abs(turn[2][0]), abs(turn[2][1]), abs(turn[2][2])))
    for i in range(3):  # A's axes
        reach = (half_a[i] + half_b[0] * size[i][0] + half_b[1] * size[i][1]
                 + half_b[2] * size[i][2])
        if abs(offset[i]) > reach + margin:
            return True
    for j in range(3):  # B's axes
        reach = (half_b[j] + half_a[0] * size[0][j] + half_a[1] * size[1][j]
                 + half_a[2] * size[2][j])
        distance = offset[0] * turn[0][j] + offset[1] * turn[1][j] + offset[2] * turn[2][j]
        if abs(distance) > reach + margin:
            return True
    for i in range(3):  # A's axis i x B's axis j, in A's frame
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            length = np.sqrt(max(1.0 - size[i][j] * size[i][j], 0.0))
            if length < 1e-6:
                continue
            reach = (half_a[i1] * size[i2][j] + half_a[i2] * size[i1][j]
                     + half_b[j1] * size[i][j2] + half_b[j2] * size[i][j1])
            distance = offset[i2] * turn[i1][j] - offset[i1] * turn[i2][j]
            if abs(distance) > reach + margin * length:
                return True
    return False


@kernel('b1(f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8[:], f8)')
def _triangle_apart_along(x, y, z, a0, a1, a2, b0, b1, b2, d0, d1, d2, half, margin):
    """
    Return whether a box and a triangle are more than ``margin`` apart along one axis.

    Whether a box (half extents ``half``, centred at the origin of its frame) and a triangle
    (corners a, b, d in that frame) are more than ``margin`` apart along the axis (x, y, z), which
    need not be a unit vector (a near-zero one parts nothing).
    """
    length = np.sqrt(x * x + y * y + z * z)
    if length < 1e-12:
        return False
    reach = half[0] * abs(x) + half[1] * abs(y) + half[2] * abs(z)
    p0 = a0 * x + a1 * y + a2 * z
    p1 = b0 * x + b1 * y + b2 * z
    p2 = d0 * x + d1 * y + d2 * z
    return (min(p0, p1, p2) > reach + margin * length
            or max(p0, p1, p2) < -reach - margin * length)


@kernel('b1(f8[:, :], f8[:], f8[:], f8[:, :], f8)')
def _box_triangle_apart(rotation, centre, half, corners, margin):
    """
    Return whether an oriented box and a triangle are more than ``margin`` apart.

    Whether an oriented box and a triangle (corners (3, 3), m) are more than ``margin`` apart along
    one of the 13 axes of the separating axis test (a conservative test, as in
    :func:`_boxes_apart`). Scalars only: it runs for every box and triangle that meet.
    """
    # The corners in the box's frame: a, b, d.
    x, y, z = corners[0, 0] - centre[0], corners[0, 1] - centre[1], corners[0, 2] - centre[2]
    a0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    a1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    a2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    x, y, z = corners[1, 0] - centre[0], corners[1, 1] - centre[1], corners[1, 2] - centre[2]
    b0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    b1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    b2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    x, y, z = corners[2, 0] - centre[0], corners[2, 1] - centre[1], corners[2, 2] - centre[2]
    d0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    d1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    d2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    # The box's axes.
    if (min(a0, b0, d0) > half[0] + margin or max(a0, b0, d0) < -half[0] - margin
            or min(a1, b1, d1) > half[1] + margin or max(a1, b1, d1) < -half[1] - margin
            or min(a2, b2, d2) > half[2] + margin or max(a2, b2, d2) < -half[2] - margin):
        return True
    # The edges a -> b, b -> d, d -> a.
    e0, e1, e2 = b0 - a0, b1 - a1, b2 - a2
    f0, f1, f2 = d0 - b0, d1 - b1, d2 - b2
    g0, g1, g2 = a0 - d0, a1 - d1, a2 - d2
    # The triangle's normal, then each box axis crossed with each edge.
    return (_triangle_apart_along(e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0,
                                  a0, a1, a2, b0, b1, b2, d0, d1, d2, half, margin)
            or _triangle_apart_along(0.0, -e2, e1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(0.0, -f2, f1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(0.0, -g2, g1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(e2, 0.0, -e0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(f2, 0.0, -f0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(g2, 0.0, -g0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-e1, e0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-f1, f0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-g1, g0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin))


@kernel('b1(i8, f8[:], f8[:], f8[:, :], f8[:], f8[:, :], f8)')
def _touches_triangle(kind, half, box_half, rotation, centre, corners, margin):
    """
    Return whether a shape touches a triangle (``corners`` (3, 3)).

    Whether a shape (kind code, padded ``half`` extents, its box's ``box_half``, posed at
    ``rotation``, ``centre``) touches a triangle (``corners`` (3, 3)): the separating axis test of
    the box holding the shape (``margin`` apart), then the exact test.
    """
    # A shape's corners are not read: the triangle's stand in for them.
    return (not _box_triangle_apart(rotation, centre, box_half, corners, margin)
            and touching(kind, half, rotation, centre, corners, TRIANGLE, half, rotation,
                         centre, corners))


@kernel('b1(i8, f8[:], f8[:], f8[:, :], f8[:], i8, f8[:], f8[:], f8[:, :], f8[:], f8)')
def _touches_shape(kind_a, half_a, box_a, rotation_a, centre_a, kind_b, half_b, box_b,
                   rotation_b, centre_b, margin):
    """
    Return whether two shapes (as in :func:`_touches_triangle`) touch.

    Whether two shapes (as in :func:`_touches_triangle`) touch: the separating axis test of their
    boxes, then the exact test.
    """
    # A shape's corners are not read: its rotation stands in for them.
    return (not _boxes_apart(rotation_a, centre_a, box_a, rotation_b, centre_b, box_b, margin)
            and touching(kind_a, half_a, rotation_a, centre_a, rotation_a, kind_b, half_b,
                         rotation_b, centre_b, rotation_b))


@kernel('i8[::1](f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], i8[::1])')
def _candidates_meeting(lower, upper, box_lower, box_upper, candidates):
    """
    Return the ``candidates`` whose boxes meet the box [lower, upper] (3,), in order.

    The ``candidates`` (indices into the (T, 3) box corners), in order, whose boxes meet the box
    [lower, upper] (3,): the answers of a test of every box.
    """
    out = np.empty(candidates.shape[0], dtype=np.int64)
    n = 0
    for i in range(candidates.shape[0]):
        t = candidates[i]
        # Branches (and, not &): a mesh's triangles lie near each other, so the answers come
        # in runs and the branches are predicted (3.5x faster than without on uneven ground).
        if (box_upper[t, 0] >= lower[0] and box_lower[t, 0] <= upper[0]
                and box_upper[t, 1] >= lower[1] and box_lower[t, 1] <= upper[1]
                and box_upper[t, 2] >= lower[2] and box_lower[t, 2] <= upper[2]):
            out[n] = t
            n += 1
    return out[:n].copy()


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
        meeting = _candidates_meeting(lowest, highest, triangle_lower, triangle_upper, every)
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
                    and _touches_triangle(kinds[c], shape_half[c], half[c], rotation[r, c],
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
                if meets and _touches_triangle(kinds[c], shape_half[c], half[c],
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
            if meets and _touches_shape(kinds[c], shape_half[c], half[c], rotation[r, c],
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


#: numba type of a branch's row memo (see _illegal_rows): (frame, the row's bits, zero-padded
#: to MEMO_WIDTH joints) -> 1 illegal, 0 legal. Passed on its own, not inside the tables: numba
#: types a dictionary inside a tuple argument through its slow path, dearer than the check.
ROW_MEMO_TYPE = 'DictType(UniTuple(i8, 5), i8)'
#: Widest branch whose rows are remembered (the key holds the frame and this many joints).
MEMO_WIDTH = 4
# numba type of CTSpace.check_tables, the tuple _illegal_rows takes: the joint limits,
# clear_until, _branch_boxes' tables, the step table, _row_collisions' tables.
CHECK_TABLES_TYPE = (
    'Tuple((f8[::1], f8[::1], i8, '
    'f8[:, ::1], i8[::1], f8[:, :, :, ::1], f8[:, :, ::1], i8[::1], f8[:, :, :, ::1], '
    'f8[:, :, ::1], f8[:, :, ::1], f8[:, :, ::1], i8[::1], i8[::1], f8[:, ::1], '
    'f8[:, :, ::1], b1[::1], i8[::1], f8[:, ::1], ' + _STEP_TABLE_TYPES + ', '
    'f8[:, ::1], f8[:, ::1], i8[::1], f8[:, ::1], f8[:, :, :], f8[:, :], f8, i8[::1], '
    'f8[:, :], i8[::1], f8[:, :], i8[::1]))')


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
    :func:`_illegal_rows` of every row, none of them remembered: (m,) bool.

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
def _illegal_rows(q, frames, tables, memo):
    """
    Return whether each row of a batch is illegal: (m,) bool.

    :meth:`CTSpace._illegal`: whether each row of a batch (``q`` (m, d) at ``frames``) is illegal,
    outside the joint limits or touching the environment or the body: (m,) bool. ``tables``:
    :attr:`CTSpace.check_tables`; ``memo``: :attr:`CTSpace.row_memo`.

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


@kernel('i8[::1](i8[::1], i8[::1], i8[::1], i8, f8[:, :, ::1], f8[:, :, ::1], '
        'f8[:, :, :, ::1], f8[:, :, ::1], f8[:, ::1], i8[::1], f8[:, ::1], f8[:, ::1], '
        'f8[:, ::1], f8[:, :, :], i8[::1], i8[:, :], f8[:, ::1], f8[:, ::1], f8)')
def _first_contacts(frames, checked, group, count, shape_lower, shape_upper, shape_rotation,
                    shape_centre, box_half, kinds, halves, triangle_lower, triangle_upper,
                    corners, near, pairs, swept_lower, swept_upper, margin):
    """
    Return the first colliding frame per group of shapes, or -1.

    :meth:`TimedBody.first_collisions` on the poses and boxes the body holds: per group
    (``group[s]`` in [0, ``count``) for each ``checked`` shape s), the first of the ``frames`` (m,)
    where one of its shapes touches an environment triangle of ``near`` (indices into
    ``triangle_lower`` ... ``corners``) or the other shape of one of its ``pairs`` (P, 2) of body
    shapes, or -1.

    The tests of :func:`_row_collisions` (boxes, cut first by each shape's box swept over the
    frames, and a pair by the boxes ``swept_lower``/``swept_upper`` (S, 3) its shapes sweep
    over every frame; the separating axis test ``margin`` apart; then the shapes themselves,
    ``kinds`` and padded ``halves`` (S, 3), :func:`convex.touching`), frame by frame, a group
    left out once it has touched, stopping when every group has.
    """
    m, n, count_pairs = frames.shape[0], checked.shape[0], pairs.shape[0]
    found = np.full(count, -1, dtype=np.int64)
    # Per checked shape, the triangles its box swept over the frames meets.
    starts = np.zeros(n + 1, dtype=np.int64)
    candidates = np.empty(n * near.shape[0], dtype=np.int64)
    lowest, highest = np.empty(3), np.empty(3)
    for c in range(n):
        s = checked[c]
        for axis in range(3):
            lowest[axis], highest[axis] = np.inf, -np.inf
            for r in range(m):
                lowest[axis] = min(lowest[axis], shape_lower[frames[r], s, axis])
                highest[axis] = max(highest[axis], shape_upper[frames[r], s, axis])
        meeting = _candidates_meeting(lowest, highest, triangle_lower, triangle_upper, near)
        total = starts[c] + meeting.shape[0]
        candidates[starts[c]:total] = meeting
        starts[c + 1] = total
    # The pairs whose shapes' boxes over every frame meet.
    active = np.zeros(count_pairs, dtype=np.bool_)
    for p in range(count_pairs):
        a, b = pairs[p, 0], pairs[p, 1]
        active[p] = True
        for axis in range(3):
            if not (swept_upper[a, axis] >= swept_lower[b, axis]
                    and swept_lower[a, axis] <= swept_upper[b, axis]):
                active[p] = False
    left = count
    for r in range(m):
        f = frames[r]
        for c in range(n):
            s = checked[c]
            g = group[s]
            if found[g] >= 0:
                continue
            for k in range(starts[c], starts[c + 1]):
                t = candidates[k]
                meets = True
                for axis in range(3):
                    if not (shape_upper[f, s, axis] >= triangle_lower[t, axis]
                            and shape_lower[f, s, axis] <= triangle_upper[t, axis]):
                        meets = False
                        break
                if meets and _touches_triangle(kinds[s], halves[s], box_half[s],
                                               shape_rotation[f, s], shape_centre[f, s],
                                               corners[t], margin):
                    found[g] = f
                    left -= 1
                    break
        for p in range(count_pairs):
            if not active[p]:
                continue
            a, b = pairs[p, 0], pairs[p, 1]
            g = group[a]
            if found[g] >= 0:
                continue
            meets = True
            for axis in range(3):
                if not (shape_upper[f, a, axis] >= shape_lower[f, b, axis]
                        and shape_lower[f, a, axis] <= shape_upper[f, b, axis]):
                    meets = False
                    break
            if meets and _touches_shape(kinds[a], halves[a], box_half[a], shape_rotation[f, a],
                                        shape_centre[f, a], kinds[b], halves[b], box_half[b],
                                        shape_rotation[f, b], shape_centre[f, b], margin):
                found[g] = f
                left -= 1
        if left == 0:
            break
    return found


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
def _motion_path(objective, times, frame_step, speed_cap, qa, ia, qb, ib):
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
    Return :func:`_motion_path` of several motions in one batch.

    :func:`_motion_path` of several motions (qa[i], ia[i]) -> (qb[i], ib[i]) in one batch: their
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
            path, late[i] = _motion_path(objective, times, frame_step, speed_cap, qa[i], ia[i],
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

    The motions' rows are :func:`_motion_paths`'; they are judged by :func:`_illegal_rows`,
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
            illegal = _illegal_rows(batch, batch_frames, tables, memo)
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


@kernel('b1(f8[::1], f8[::1], f8[::1], f8[::1])')
def _box_within(lower, upper, outer_lower, outer_upper):
    """Whether the box [lower, upper] (3,) lies within [outer_lower, outer_upper]."""
    for e in range(3):
        if lower[e] < outer_lower[e] or upper[e] > outer_upper[e]:
            return False
    return True


@dataclass(frozen=True)
class _Step:
    parent: int
    child: int
    origin_rotation: Optional[np.ndarray]
    origin_translation: np.ndarray
    joint: int
    kind: str
    axis: np.ndarray
    axis_coordinate: int
    axis_sign: float
    has_offset: bool
    # An offset along one coordinate axis: its coordinate (-1 otherwise) and length, m.
    offset_axis: int
    offset_length: float


@dataclass(frozen=True)
class _Chain:
    """
    A set of joint steps laid out over a compact array of only the links they touch.

    ``links`` lists the links the steps start from, then each step's child; ``step_table``
    holds the steps as :func:`_link_poses` reads them, over those links' rows.
    """

    links: np.ndarray
    step_table: tuple


def _step_table(steps: Sequence[_Step], parents: Sequence[int], children: Sequence[int]) -> tuple:
    """
    Return joint steps as the arrays :func:`_link_poses` reads.

    Joint steps as the arrays :func:`_link_poses` reads, their parent and child links at rows
    ``parents`` and ``children`` of the pose arrays.
    """
    count = len(steps)
    return (np.array(parents, dtype=np.int64).reshape(count),
            np.array(children, dtype=np.int64).reshape(count),
            np.array([np.eye(3) if st.origin_rotation is None else st.origin_rotation
                      for st in steps], dtype=float).reshape(count, 3, 3),
            np.array([st.origin_rotation is not None for st in steps], dtype=np.bool_),
            np.array([st.origin_translation for st in steps], dtype=float).reshape(count, 3),
            np.array([st.offset_axis for st in steps], dtype=np.int64),
            np.array([st.offset_length for st in steps], dtype=float),
            np.array([st.has_offset for st in steps], dtype=np.bool_),
            np.array([st.joint for st in steps], dtype=np.int64),
            np.array([2 if st.kind == 'prismatic' else 1 for st in steps], dtype=np.int64),
            np.array([st.axis_coordinate for st in steps], dtype=np.int64),
            np.array([st.axis_sign for st in steps], dtype=float),
            np.array([st.axis for st in steps], dtype=float).reshape(count, 3))


class BodyKinematics:
    """
    Batched forward kinematics as link rotations and positions, fast for small batches.

    Equivalent to :meth:`Skeleton.forward_kinematics`, but it keeps rotations (3, 3) and
    positions (3,) apart, rotates about coordinate axes by mixing two columns, and can re-evaluate
    only a subtree, which is what a branch planner needs on its hot path.

    Parameters
    ----------
    skeleton
        The actor model.

    """

    def __init__(self, skeleton: Skeleton):
        self.skeleton = skeleton
        order = {name: i for i, name in enumerate(skeleton.link_names)}
        joints = sorted(skeleton.joints, key=lambda j: order[j.child])
        steps = []
        for joint in joints:
            rotation = joint.origin[:3, :3]
            coordinate, sign = _axis_code(joint.axis)
            along = np.flatnonzero(joint.origin[:3, 3] != 0.0)
            offset_axis = int(along[0]) if len(along) == 1 else -1
            steps.append(_Step(
                parent=order[joint.parent], child=order[joint.child],
                origin_rotation=None if np.allclose(rotation, np.eye(3)) else rotation.copy(),
                origin_translation=joint.origin[:3, 3].copy(),
                joint=skeleton.index.get(joint.name, -1), kind=joint.kind, axis=joint.axis,
                axis_coordinate=coordinate, axis_sign=sign,
                has_offset=bool(np.any(joint.origin[:3, 3] != 0.0)),
                offset_axis=offset_axis,
                offset_length=float(joint.origin[offset_axis, 3]) if offset_axis >= 0 else 0.0))
        self.steps: Tuple[_Step, ...] = tuple(steps)
        self.link_count = len(skeleton.link_names)
        # Per set of steps, its arrays for _link_poses over every link (_step_arrays) and its
        # compact chain (chain), each built once.
        self._layouts: Dict[tuple, tuple] = {}
        self._chains: Dict[Tuple[int, ...], _Chain] = {}

    def chain(self, steps: Sequence[_Step]) -> _Chain:
        """Return the compact layout of ``steps`` for :meth:`chain_poses` (built once per set)."""
        key = tuple(step.child for step in steps)
        chain = self._chains.get(key)
        if chain is not None:
            return chain
        children = [step.child for step in steps]
        starts = []
        for step in steps:
            if step.parent not in children and step.parent not in starts:
                starts.append(step.parent)
        links = starts + children
        place = {link: i for i, link in enumerate(links)}
        chain = _Chain(links=np.array(links, dtype=int),
                       step_table=_step_table(steps, [place[st.parent] for st in steps],
                                              [place[st.child] for st in steps]))
        self._chains[key] = chain
        return chain

    def chain_poses(self, q: np.ndarray, rotations: np.ndarray, positions: np.ndarray,
                    chain: _Chain) -> None:
        """
        Evaluate a chain's steps in place over compact poses of its links.

        The same numbers as :meth:`poses` with the chain's steps (the same kernel, the same
        arithmetic), but over (k, C) arrays of the C links of ``chain.links`` instead of every
        link: what a branch's small batches need.

        Parameters
        ----------
        q
            (k, 22) configurations, rad or m.
        rotations, positions
            (k, C, 3, 3) and (k, C, 3) poses of ``chain.links``: those of the links the chain
            starts from are read, the others written.
        chain
            From :meth:`chain`.

        """
        _link_poses(float_array(q), rotations, positions, *chain.step_table)

    def subtree_steps(self, joint_names: Sequence[str]) -> Tuple[_Step, ...]:
        """Return the steps that move when any of the named joints moves, in evaluation order."""
        moving = set()
        for name in joint_names:
            moving.add(self.skeleton.link_index[
                next(j.child for j in self.skeleton.joints if j.name == name)])
        out = []
        for step in self.steps:
            if step.child in moving or step.parent in moving:
                moving.add(step.child)
                out.append(step)
        return tuple(out)

    def _step_arrays(self, steps: Sequence[_Step]) -> tuple:
        """Return the steps as :func:`_link_poses` reads them over every link, once per set."""
        key = tuple(step.child for step in steps)
        arrays = self._layouts.get(key)
        if arrays is None:
            arrays = _step_table(steps, [st.parent for st in steps], [st.child for st in steps])
            self._layouts[key] = arrays
        return arrays

    def poses(self, q: np.ndarray, rotations: Optional[np.ndarray] = None,
              positions: Optional[np.ndarray] = None,
              steps: Optional[Sequence[_Step]] = None) -> Tuple[np.ndarray, np.ndarray]:
        """
        Link poses for a batch of configurations.

        Parameters
        ----------
        q
            (k, 22) configurations, rad or m.
        rotations, positions
            (k, L, 3, 3) and (k, L, 3) poses to update in place (only ``steps`` are evaluated);
            allocated and fully evaluated when omitted.
        steps
            The joint steps to evaluate, in order (default: all).

        Returns
        -------
        tuple of numpy.ndarray
            Rotations (k, L, 3, 3) (columns are the link axes in the world frame) and positions
            (k, L, 3), m, in ``skeleton.link_names`` order.

        """
        k = q.shape[0]
        if rotations is None:
            rotations = np.empty((k, self.link_count, 3, 3))
            positions = np.empty((k, self.link_count, 3))
            rotations[:, 0] = _IDENTITY
            positions[:, 0] = 0.0
        steps = self.steps if steps is None else steps
        _link_poses(float_array(q), rotations, positions, *self._step_arrays(steps))
        return rotations, positions


class BodyShapes:
    """
    The actor's collision shapes: FCL objects, box bounds and the pairs worth checking.

    Parameters
    ----------
    skeleton
        The actor model.
    padding
        Safety margin added to every shape, m (>= 0).

    """

    def __init__(self, skeleton: Skeleton, padding: float = 0.0):
        if not (np.isfinite(padding) and padding >= 0.0):
            raise ValueError(f'padding must be a finite distance >= 0 m, got {padding}')
        self.skeleton = skeleton
        self.padding = float(padding)
        shapes = skeleton.collision_shapes
        self.link = np.array([skeleton.link_index[s.link] for s in shapes])
        self.origin_rotation = np.stack([s.origin[:3, :3] for s in shapes])
        self.origin_translation = np.stack([s.origin[:3, 3] for s in shapes])
        self.kind = tuple(s.kind for s in shapes)
        self.identity_origin = np.array([np.allclose(s.origin[:3, :3], np.eye(3))
                                         for s in shapes])
        self.objects = []
        # Per-shape parameters of the box bound: half extents (box), (radius, half length)
        # (cylinder) or radius (sphere), all padded.
        self.half = np.zeros((len(shapes), 3))
        for i, shape in enumerate(shapes):
            if shape.kind == 'box':
                half = np.asarray(shape.size) / 2 + padding
                geometry = fcl.Box(*(2 * half))
            elif shape.kind == 'cylinder':
                half = np.array([shape.size[0] + padding, shape.size[1] / 2 + padding, 0.0])
                geometry = fcl.Cylinder(half[0], 2 * half[1])
            else:
                half = np.array([shape.size[0] + padding, 0.0, 0.0])
                geometry = fcl.Sphere(half[0])
            self.half[i] = half
            self.objects.append(fcl.CollisionObject(geometry, fcl.Transform()))
        #: (S, 3) half extents of a box holding each shape in its own frame (a cylinder's
        #: axis is its z axis, as in FCL), m: the separating axis tests' boxes.
        self.box_half = np.array([h if kind == 'box' else (h[0], h[0], h[1]) if
                                  kind == 'cylinder' else (h[0], h[0], h[0])
                                  for kind, h in zip(self.kind, self.half)], dtype=float)
        self._request = fcl.CollisionRequest()
        self._result = fcl.CollisionResult()
        # Kind codes of collision._half_extents (with ``half``, its padded half extents).
        self.kind_code = np.array([_KIND_CODES[k] for k in self.kind], dtype=np.int64)
        self._tree_distance = self._link_tree_distances()
        #: Per branch CT-space, the data that depends on the model only (built once).
        self.branch_layouts: Dict[tuple, tuple] = {}
        # Per set of links, the shape table of the shapes on them (see TimedBody.set_branch).
        self._link_shapes: Dict[frozenset, tuple] = {}
        #: The shape table of every shape (TimedBody's poses).
        self.every_table = self.shape_table(np.arange(len(shapes)))

    def _link_tree_distances(self) -> np.ndarray:
        names = self.skeleton.link_names
        neighbours: Dict[int, List[int]] = {i: [] for i in range(len(names))}
        index = self.skeleton.link_index
        for joint in self.skeleton.joints:
            a, b = index[joint.parent], index[joint.child]
            neighbours[a].append(b)
            neighbours[b].append(a)
        distance = np.full((len(names), len(names)), np.iinfo(np.int32).max // 2)
        for start in range(len(names)):
            distance[start, start] = 0
            frontier = [start]
            while frontier:
                nxt = []
                for a in frontier:
                    for b in neighbours[a]:
                        if distance[start, b] > distance[start, a] + 1:
                            distance[start, b] = distance[start, a] + 1
                            nxt.append(b)
                frontier = nxt
        return distance

    def shapes_of(self, link_names: Sequence[str]) -> np.ndarray:
        """Return the indices of the shapes attached to the named links: (n,) int."""
        links = [self.skeleton.link_index[name] for name in link_names]
        return np.flatnonzero(np.isin(self.link, links))

    def shapes_of_links(self, links) -> np.ndarray:
        """Return the indices of the shapes attached to links given by index: (n,) int."""
        return np.flatnonzero(np.isin(self.link, list(links)))

    def pairs(self, shapes_a: np.ndarray, shapes_b: np.ndarray) -> np.ndarray:
        """Return shape pairs on links more than ``ADJACENT_JOINTS`` joints apart, (P, 2) int."""
        a, b = np.meshgrid(shapes_a, shapes_b, indexing='ij')
        a, b = a.ravel(), b.ravel()
        keep = self._tree_distance[self.link[a], self.link[b]] > ADJACENT_JOINTS
        return np.stack([a[keep], b[keep]], axis=1)

    def poses(self, rotations: np.ndarray, positions: np.ndarray,
              shapes: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """World poses of some shapes: rotations (k, n, 3, 3) and centres (k, n, 3), m."""
        shapes = np.asarray(shapes, dtype=np.int64)
        k = rotations.shape[0]
        rotation, centre = np.empty((k, len(shapes), 3, 3)), np.empty((k, len(shapes), 3))
        _place_shapes(rotations, positions, self.link[shapes], self.origin_translation[shapes],
                      self.origin_rotation[shapes], ~self.identity_origin[shapes],
                      np.arange(len(shapes)), rotation, centre)
        return rotation, centre

    def shape_table(self, shapes: np.ndarray) -> tuple:
        """
        Return what :func:`_pose_shapes_into` reads of some shapes.

        What :func:`_pose_shapes_into` reads of some shapes (kept per set of shapes by the caller):
        (links, origin translations, origin rotations, whether turned, kind codes, half extents,
        the shapes' indices).
        """
        shapes = np.asarray(shapes, dtype=np.int64)
        return (self.link[shapes], self.origin_translation[shapes],
                self.origin_rotation[shapes], ~self.identity_origin[shapes],
                self.kind_code[shapes], self.half[shapes], shapes)

    def bounds(self, rotation: np.ndarray, centre: np.ndarray,
               shapes: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Axis-aligned boxes around shapes posed at (k, n): lower and upper corners (k, n, 3)."""
        shapes = np.asarray(shapes, dtype=np.int64)
        extent = _half_extents(self.kind_code[shapes], self.half[shapes], float_array(rotation))
        return centre - extent, centre + extent

    def collides(self, shape: int, rotation: np.ndarray, centre: np.ndarray,
                 other) -> bool:
        """Return whether shape ``shape`` posed at (rotation, centre) touches ``other``."""
        obj = self.objects[shape]
        obj.setTransform(fcl.Transform(rotation, centre))
        # The contact count says it; one result serves every call.
        if fcl.collide(obj, other, self._request, self._result):
            del self._result.contacts[:]
            return True
        return False


class EnvironmentIndex:
    """
    The environment's triangles as boxes for the broad phase, and FCL models per mesh.

    Parameters
    ----------
    meshes
        trimesh.Trimesh objects (world frame, m).
    objects
        Optional FCL collision objects, one per mesh (e.g. from ``BodyCollision``); built from
        the meshes when omitted.

    """

    def __init__(self, meshes: Sequence, objects: Optional[Sequence] = None):
        lower, upper, owner, corners = [], [], [], []
        built = []
        for i, mesh in enumerate(meshes):
            vertices = np.asarray(mesh.vertices, dtype=float)
            faces = np.asarray(mesh.faces, dtype=int)
            if len(faces) == 0:
                continue
            if not np.all(np.isfinite(vertices)):
                raise ValueError(f'environment mesh {i} has non-finite vertices')
            triangles = vertices[faces]
            corners.append(triangles)
            lower.append(triangles.min(axis=1))
            upper.append(triangles.max(axis=1))
            owner.append(np.full(len(faces), i))
            if objects is None:
                model = fcl.BVHModel()
                model.beginModel(len(vertices), len(faces))
                model.addSubModel(vertices, faces)
                model.endModel()
                built.append(fcl.CollisionObject(model, fcl.Transform()))
        self.objects = list(objects) if objects is not None else built
        if objects is not None and len(self.objects) != len(meshes):
            raise ValueError(f'{len(self.objects)} FCL objects for {len(meshes)} meshes')
        if lower:
            self.lower = np.concatenate(lower)
            self.upper = np.concatenate(upper)
            self.owner = np.concatenate(owner)
            #: (T, 3, 3) corners of every triangle, m.
            self.corners = np.concatenate(corners)
        else:
            self.corners = np.zeros((0, 3, 3))
            self.lower = np.zeros((0, 3))
            self.upper = np.zeros((0, 3))
            self.owner = np.zeros(0, dtype=int)
        # Every triangle, as the candidates of triangles_near.
        self._every = np.arange(len(self.lower), dtype=np.int64)
        if objects is None:
            # Map mesh index -> object index (empty meshes were skipped).
            kept = [i for i, mesh in enumerate(meshes) if len(mesh.faces)]
            self._object_of = {mesh: j for j, mesh in enumerate(kept)}
        else:
            self._object_of = {i: i for i in range(len(meshes))}

    def object_of(self, mesh: int):
        """Return the FCL object of mesh ``mesh``."""
        return self.objects[self._object_of[mesh]]

    def triangles_near(self, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """
        Return the indices of triangles whose boxes overlap the box [lower, upper] (3,) m.

        The indices are int64, in order.
        """
        return _candidates_meeting(float_array(lower).reshape(3), float_array(upper).reshape(3),
                                   self.lower, self.upper, self._every)


class TimedBody:
    """
    The actor over the frames of one step, as far as it is fixed, with fast branch checks.

    Holds the link poses at every frame for the current frames (lower body, root and the
    branches planned so far) and answers, for one branch, which frames of a candidate motion are
    in collision.

    Parameters
    ----------
    kinematics, shapes, environment
        Shared model objects.
    frames
        (k, 22) configurations, rad or m.

    """

    def __init__(self, kinematics: BodyKinematics, shapes: BodyShapes,
                 environment: EnvironmentIndex, frames: np.ndarray):
        self.kinematics = kinematics
        self.shapes = shapes
        self.environment = environment
        self.frames = np.array(frames, dtype=float)
        self.rotations, self.positions = kinematics.poses(self.frames)
        self._shape_poses()
        #: Branch name -> frame f: at frames [0, f) the branch's checked shapes, where the
        #: body holds them, touch neither the environment nor the body (set by the planner
        #: that checked the body's own motion, :meth:`set_clear`; forgotten when a branch is
        #: fixed). A branch's CT-space does not test such rows again.
        self.clear_until: Dict[str, int] = {}
        # Branch name -> (f, frames changed since): a clear_until forgotten when branches were
        # fixed, with the frames they changed (see frames_to_recheck).
        self._stale: Dict[str, Tuple[int, np.ndarray]] = {}
        # The environment's triangles near the actor over the step, and the box they were
        # found for: one scan of the whole environment per step.
        self._near = None
        self._near_lower = self._near_upper = None

    def triangles_near(self, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """
        Return the indices of the triangles whose boxes meet the box [lower, upper] (3,) m.

        The same indices, in the same order, as ``environment.triangles_near``, but searched
        among the triangles near the actor during the step (found once per step, with room for
        the branches' reach) instead of among all the environment's triangles.
        """
        lower, upper = float_array(lower).reshape(3), float_array(upper).reshape(3)
        environment = self.environment
        return _candidates_meeting(lower, upper, environment.lower, environment.upper,
                                   self._step_near(lower, upper))

    def _step_near(self, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """
        Return the triangles near the actor over the step: (N,) int64 indices.

        The triangles near the actor over the step: (N,) int64 indices, a superset of those meeting
        the box [lower, upper] or any shape's box swept over the step (found once per step, again
        only when a box reaches past where they were searched).
        """
        if self._near is None or not _box_within(lower, upper, self._near_lower,
                                                 self._near_upper):
            box_lower = np.minimum(lower, self.swept_lower.min(axis=0) - NEAR_MARGIN)
            box_upper = np.maximum(upper, self.swept_upper.max(axis=0) + NEAR_MARGIN)
            self._near = self.environment.triangles_near(box_lower, box_upper)
            self._near_lower, self._near_upper = box_lower, box_upper
        return self._near

    def _shape_poses(self) -> None:
        k, count = self.frames.shape[0], len(self.shapes.kind)
        #: (k, S, 3, 3), (k, S, 3) world poses and (k, S, 3) box corners of every shape.
        self.shape_rotation = np.empty((k, count, 3, 3))
        self.shape_centre = np.empty((k, count, 3))
        self.shape_lower = np.empty((k, count, 3))
        self.shape_upper = np.empty((k, count, 3))
        #: (S, 3) box corners of every shape swept over the step, m.
        self.swept_lower = np.empty((count, 3))
        self.swept_upper = np.empty((count, 3))
        self._pose_shapes(self.shapes.every_table)

    def _pose_shapes(self, table: tuple) -> None:
        """
        Pose the shapes of a :meth:`BodyShapes.shape_table` at every frame, in place.

        Pose the shapes of a :meth:`BodyShapes.shape_table` at every frame, with their boxes and
        swept boxes, in place.
        """
        _pose_shapes_into(self.rotations, self.positions, *table, self.shape_rotation,
                          self.shape_centre, self.shape_lower, self.shape_upper,
                          self.swept_lower, self.swept_upper)

    def first_collision(self, checked: np.ndarray, pairs: np.ndarray,
                        frames: Optional[np.ndarray] = None) -> int:
        """
        Return the first frame at which a checked shape touches something, or -1.

        First frame at which a checked shape touches the environment or its pair's shape, or -1:
        :meth:`first_collisions` with all the shapes in one group (the same parameters).
        """
        return self.first_collisions(checked, pairs, None, 1, frames)[0]

    def first_collisions(self, checked: np.ndarray, pairs: np.ndarray,
                         group: Optional[np.ndarray], count: int,
                         frames: Optional[np.ndarray] = None) -> List[int]:
        """
        Per group of checked shapes, the first frame at which one of them touches something.

        Uses the poses the body already holds (no kinematics), in one compiled pass
        (:func:`_first_contacts`): the broad phase, then the exact test of the shapes, frame by
        frame, each group left out once it has collided, stopping when every group has.

        Parameters
        ----------
        checked
            (n,) shapes to check.
        pairs
            (P, 2) shape pairs (a checked shape, a body shape it must not touch).
        group
            (S,) group of each body shape (read for the checked ones, in [0, count)), or None
            (one group).
        count
            Number of groups.
        frames
            (m,) frame indices to check, in increasing order (default: every frame).

        Returns
        -------
        list of int
            Per group, the first frame in collision, or -1.

        """
        frames = (np.arange(len(self.frames)) if frames is None
                  else np.asarray(frames, dtype=np.int64))
        if not len(frames) or not len(checked):
            return [-1] * count
        environment = self.environment
        shapes = self.shapes
        checked = np.asarray(checked, dtype=np.int64)
        group = (np.zeros(len(shapes.kind), dtype=np.int64) if group is None
                 else np.asarray(group, dtype=np.int64))
        return _first_contacts(
            frames, checked, group, count, self.shape_lower, self.shape_upper,
            self.shape_rotation, self.shape_centre, shapes.box_half, shapes.kind_code,
            shapes.half, environment.lower, environment.upper, environment.corners,
            # The boxes swept over the whole step hold those at the frames checked.
            self.triangles_near(self.swept_lower[checked].min(axis=0),
                                self.swept_upper[checked].max(axis=0)),
            np.asarray(pairs, dtype=np.int64).reshape(-1, 2), self.swept_lower,
            self.swept_upper, SAT_MARGIN).tolist()

    def posed_shape(self, frame: int, shape: int) -> fcl.CollisionObject:
        """Return the FCL object of body shape ``shape``, placed where it is at ``frame``."""
        target = self.shapes.objects[shape]
        target.setTransform(fcl.Transform(self.shape_rotation[frame, shape],
                                          self.shape_centre[frame, shape]))
        return target

    def set_clear(self, name: str, first: int) -> None:
        """
        Record the first frame at which branch ``name``'s shapes touch something.

        Record that branch ``name``'s shapes, where the body holds them, first touch something at
        frame ``first`` (-1: at none), every frame before it checked.
        """
        self.clear_until[name] = len(self.frames) if first < 0 else int(first)
        self._stale.pop(name, None)

    def frames_to_recheck(self, name: str) -> Optional[np.ndarray]:
        """
        Return the frames where branch ``name``'s contacts are not known, or None.

        Frames where branch ``name``'s contacts are not known since branches were fixed: those they
        changed before the first contact found earlier, and every frame from that contact on
        (sorted, int64); None when nothing is known (check every frame). The first contact among
        them is the body's first contact for the branch.
        """
        stale = self._stale.get(name)
        if stale is None:
            return None
        clear, changed = stale
        return np.concatenate([np.flatnonzero(changed[:clear]),
                               np.arange(clear, len(self.frames))]).astype(np.int64)

    def collides(self, frame: int, shape: int, target: fcl.CollisionObject) -> bool:
        """Whether body shape ``shape``, where it is at ``frame``, touches ``target``."""
        return self.shapes.collides(shape, self.shape_rotation[frame, shape],
                                    self.shape_centre[frame, shape], target)

    def set_branch(self, indices: np.ndarray, values: np.ndarray,
                   steps: Sequence[_Step]) -> None:
        """Fix a planned branch: write its (k, d) values and update the poses of its subtree."""
        changed = np.zeros(len(self.frames), dtype=np.bool_)
        if not _write_columns(self.frames, np.asarray(indices, dtype=np.int64),
                              float_array(values), changed):
            return  # the branch follows the motion already in place (its fast path)
        # What was found of the body's motion no longer holds for the other branches where
        # this one moved.
        for name, clear in self.clear_until.items():
            self._stale[name] = (clear, changed.copy())
        for name, (clear, before) in self._stale.items():
            before |= changed
        self.clear_until.clear()
        self.kinematics.poses(self.frames, self.rotations, self.positions, steps)
        # Only the shapes the branch carries have moved.
        links = frozenset(step.child for step in steps)
        table = self.shapes._link_shapes.get(links)
        if table is None:
            table = self.shapes._link_shapes[links] = self.shapes.shape_table(
                self.shapes.shapes_of_links(links))
        self._pose_shapes(table)


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
class _BranchModel:
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
    chain: _Chain
    chain_links: np.ndarray
    #: _branch_boxes' arguments after the body's: the checked shapes and where they sit.
    shape_tables: tuple


def branch_model(kinematics: BodyKinematics, shapes: BodyShapes, branch: str,
                 checked_links: Sequence[str], obstacle_links: Sequence[str]) -> _BranchModel:
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
    model = _BranchModel(
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


def _reach_bound(shapes: BodyShapes, steps: Sequence[_Step],
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
        #: _illegal_rows' arguments after the batch's own, the same while the branch is planned
        #: (the roadmap's kernels that check rows take them too; CHECK_TABLES_TYPE).
        self.check_tables = (
            self._lower_tolerant, self._upper_tolerant, int(self._clear_until),
            *self._box_tables, *self._chain.step_table, self._triangle_lower,
            self._triangle_upper, self._pair_column, self._checked_box_half,
            self._triangle_corners, self._pair_box_half, SAT_MARGIN, self._checked_kinds,
            self._checked_half, self._pair_kinds, self._pair_half, self._pair_other)
        #: The answers of the rows checked so far (_illegal_rows): valid as long as the tables,
        #: while the body holds still.
        self.row_memo = _empty_row_memo()
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
            -2 if first_failure is None else int(first_failure), self.check_tables,
            self.row_memo)
        self.checks += checks
        return int(chosen), failures.tolist()

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
                                           stop_at_legal, first, self.check_tables,
                                           self.row_memo)
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
        rows, late = _motion_path(self.objective, self.times, self.frame_step,
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
        :func:`_illegal_rows` works out first, as the checks see it; the tests read it here).

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
        (:func:`_illegal_rows`). Rows where the body holds the branch, at frames where the
        check of the body's own motion found that the branch touches nothing
        (``TimedBody.clear_until``), are not tested again: the same tests gave that answer
        (the same poses; the pairs and triangles here are among those checked there).
        """
        frames = np.ascontiguousarray(frames, dtype=np.int64)  # the kernels' index type
        return _illegal_rows(q, frames, self.check_tables, self.row_memo)
