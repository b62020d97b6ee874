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
The upper body's kinematics and the body over a step, as the CT-space checks see them (§5).

:class:`BodyKinematics` evaluates the skeleton's forward kinematics in batches, as link
rotations and positions, over all links or only a branch's subtree (compiled,
:func:`link_poses`). :class:`BodyShapes` holds the actor's collision shapes (FCL objects, the
boxes holding them, the pairs of shapes worth checking) and the per-branch data built once from
the model. :class:`EnvironmentIndex` holds the environment's triangles as boxes for the broad
phase. :class:`TimedBody` is the actor over the frames of one step, as far as the locomotion
planner and the branches planned so far fix it: its link and shape poses at every frame, the
triangles near it, and what the check of its own motion found.

The contact tests themselves are :mod:`.convex`'s (the separating axis tests of the shapes'
boxes, then GJK on the shapes); the boxes of turned shapes are :mod:`.collision`'s.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Dict, List, Optional, Sequence, Tuple

import fcl
import numpy as np

from .collision import axis_extent, half_extents, KIND_CODES
from .convex import SAT_MARGIN, touches_shape, touches_triangle
from .jit import float_array, kernel
from .skeleton import Skeleton

#: Links this many joints apart or closer are adjacent and never checked against each other.
ADJACENT_JOINTS = 2
#: Room around the actor's shapes over a step for the triangles kept per step, m (about the
#: reach of a bending trunk or a raised arm beyond its place in the motion pattern).
NEAR_MARGIN = 0.6
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
def link_poses(q, rotations, positions, parent, child, origin_rotation, turned,
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
def place_shapes(rotations, positions, links, offsets, turns, turned, slots, rotation,
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
    place_shapes(rotations, positions, links, offsets, turns, turned, slots, shape_rotation,
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
                extent = axis_extent(kinds[i], halves[i], shape_rotation[f, s], e)
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


# numba types of a step table (_step_table's arrays, in order), as link_poses takes them.
STEP_TABLE_TYPES = ('i8[::1], i8[::1], f8[:, :, ::1], b1[::1], f8[:, ::1], i8[::1], f8[::1], '
                    'b1[::1], i8[::1], i8[::1], i8[::1], f8[::1], f8[:, ::1]')


@kernel('i8[::1](f8[::1], f8[::1], f8[:, ::1], f8[:, ::1], i8[::1])')
def candidates_meeting(lower, upper, box_lower, box_upper, candidates):
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

    The tests a branch's CT-space makes of its rows (boxes, cut first by each shape's box swept
    over the frames, and a pair by the boxes ``swept_lower``/``swept_upper`` (S, 3) its shapes
    sweep over every frame; the separating axis test ``margin`` apart; then the shapes
    themselves, ``kinds`` and padded ``halves`` (S, 3): :func:`convex.touches_triangle`,
    :func:`convex.touches_shape`), frame by frame, a group left out once it has touched,
    stopping when every group has.
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
        meeting = candidates_meeting(lowest, highest, triangle_lower, triangle_upper, near)
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
                if meets and touches_triangle(kinds[s], halves[s], box_half[s],
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
            if meets and touches_shape(kinds[a], halves[a], box_half[a], shape_rotation[f, a],
                                       shape_centre[f, a], kinds[b], halves[b], box_half[b],
                                       shape_rotation[f, b], shape_centre[f, b], margin):
                found[g] = f
                left -= 1
        if left == 0:
            break
    return found


@kernel('b1(f8[::1], f8[::1], f8[::1], f8[::1])')
def _box_within(lower, upper, outer_lower, outer_upper):
    """Whether the box [lower, upper] (3,) lies within [outer_lower, outer_upper]."""
    for e in range(3):
        if lower[e] < outer_lower[e] or upper[e] > outer_upper[e]:
            return False
    return True


@dataclass(frozen=True)
class JointStep:
    """
    One joint of the model as :func:`link_poses` evaluates it.

    Its ``parent`` and ``child`` link rows, its origin (``origin_rotation``, None where the
    origin does not turn, and ``origin_translation``, m), its configuration index ``joint``
    (-1: fixed), ``kind`` (its URDF type), unit ``axis`` and, where the axis is a
    coordinate axis, its ``axis_coordinate`` (-1 otherwise) and ``axis_sign``.
    """

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
class Chain:
    """
    A set of joint steps laid out over a compact array of only the links they touch.

    ``links`` lists the links the steps start from, then each step's child; ``step_table``
    holds the steps as :func:`link_poses` reads them, over those links' rows.
    """

    links: np.ndarray
    step_table: tuple


def _step_table(steps: Sequence[JointStep], parents: Sequence[int],
                children: Sequence[int]) -> tuple:
    """
    Return joint steps as the arrays :func:`link_poses` reads.

    Joint steps as the arrays :func:`link_poses` reads, their parent and child links at rows
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
            steps.append(JointStep(
                parent=order[joint.parent], child=order[joint.child],
                origin_rotation=None if np.allclose(rotation, np.eye(3)) else rotation.copy(),
                origin_translation=joint.origin[:3, 3].copy(),
                joint=skeleton.index.get(joint.name, -1), kind=joint.kind, axis=joint.axis,
                axis_coordinate=coordinate, axis_sign=sign,
                has_offset=bool(np.any(joint.origin[:3, 3] != 0.0)),
                offset_axis=offset_axis,
                offset_length=float(joint.origin[offset_axis, 3]) if offset_axis >= 0 else 0.0))
        self.steps: Tuple[JointStep, ...] = tuple(steps)
        self.link_count = len(skeleton.link_names)
        # Per set of steps, its arrays for link_poses over every link (_step_arrays) and its
        # compact chain (chain), each built once.
        self._layouts: Dict[tuple, tuple] = {}
        self._chains: Dict[Tuple[int, ...], Chain] = {}

    def chain(self, steps: Sequence[JointStep]) -> Chain:
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
        chain = Chain(links=np.array(links, dtype=int),
                      step_table=_step_table(steps, [place[st.parent] for st in steps],
                                             [place[st.child] for st in steps]))
        self._chains[key] = chain
        return chain

    def chain_poses(self, q: np.ndarray, rotations: np.ndarray, positions: np.ndarray,
                    chain: Chain) -> None:
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
        link_poses(float_array(q), rotations, positions, *chain.step_table)

    def subtree_steps(self, joint_names: Sequence[str]) -> Tuple[JointStep, ...]:
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

    def _step_arrays(self, steps: Sequence[JointStep]) -> tuple:
        """Return the steps as :func:`link_poses` reads them over every link, once per set."""
        key = tuple(step.child for step in steps)
        arrays = self._layouts.get(key)
        if arrays is None:
            arrays = _step_table(steps, [st.parent for st in steps], [st.child for st in steps])
            self._layouts[key] = arrays
        return arrays

    def poses(self, q: np.ndarray, rotations: Optional[np.ndarray] = None,
              positions: Optional[np.ndarray] = None,
              steps: Optional[Sequence[JointStep]] = None) -> Tuple[np.ndarray, np.ndarray]:
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
        link_poses(float_array(q), rotations, positions, *self._step_arrays(steps))
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
        # Kind codes of collision.half_extents (with ``half``, its padded half extents).
        self.kind_code = np.array([KIND_CODES[k] for k in self.kind], dtype=np.int64)
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
        place_shapes(rotations, positions, self.link[shapes], self.origin_translation[shapes],
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
        extent = half_extents(self.kind_code[shapes], self.half[shapes], float_array(rotation))
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
        return candidates_meeting(float_array(lower).reshape(3), float_array(upper).reshape(3),
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
        return candidates_meeting(lower, upper, environment.lower, environment.upper,
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
                   steps: Sequence[JointStep]) -> None:
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
