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
The independent judge of a timed 22-DOF trajectory against an environment.

The courses' tests use this to decide whether a walk "works": no link deeper
in the environment than a few millimetres, a foot always down, joint limits, no NaN, no jumps,
no sliding stance foot, the two legs not in each other. It deliberately shares nothing with
the planners' shortcuts (the ground height map, the sagittal leg model): geometry is the URDF's
collision shapes placed by the skeleton's forward kinematics and tested with FCL against the
meshes and each other, every frame (or every
``stride``-th frame for the geometric criteria).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Dict, Iterable, List, Optional, Tuple

from digital_actor_planner.core.collision import BodyCollision, shape_geometry, shape_reach
import fcl
import numpy as np
import trimesh

FEET = ('left_foot', 'right_foot')
# The links of each leg judged against the other leg's (a hip width apart, the hips' own
# shapes cannot meet).
LEGS = (('left_thigh', 'left_shank', 'left_foot'), ('right_thigh', 'right_shank', 'right_foot'))
# A sole corner this close to a surface bears weight (stance), m.
STANCE_GAP = 0.010
# Thickness of the slab standing for the sole when measuring its gap to the ground, m.
_SOLE_THICKNESS = 0.002


@dataclass(frozen=True)
class CheckReport:
    """
    What :func:`check_trajectory` found; ``ok`` when nothing exceeds a tolerance.

    Times are trajectory times (s). ``penetration`` maps each checked link to its largest
    penetration depth (m) and ``penetration_time`` to when it happened. ``foot_down_gap`` is the
    worst sole-to-surface gap of the nearer foot (m), at ``foot_down_time``, measured exactly on
    frames where no sole is within the foot-down tolerance (0.0 when every frame has a foot
    down). ``position_violations``, ``velocity_violations`` and ``jumps`` hold
    (joint, time, value, allowed) tuples, the worst per joint. ``non_finite_times`` lists frames
    with NaN/inf. ``slip`` maps each foot to its largest horizontal stance slip (m), at
    ``slip_time``. ``max_jump_ratio`` is the largest per-frame change over velocity limit x dt.
    ``leg_contacts`` holds (left link, right link, first time, frames) for each pair of links of
    the two legs that interpenetrate by more than ``leg_contact_tol`` on some checked frame.
    """

    frames: int
    frames_checked: int
    penetration: Dict[str, float]
    penetration_time: Dict[str, float]
    foot_down_gap: float
    foot_down_time: float
    position_violations: Tuple[Tuple[str, float, float, float], ...]
    velocity_violations: Tuple[Tuple[str, float, float, float], ...]
    jumps: Tuple[Tuple[str, float, float, float], ...]
    max_jump_ratio: float
    non_finite_times: Tuple[float, ...]
    slip: Dict[str, float]
    slip_time: Dict[str, float]
    tolerances: Dict[str, float] = field(default_factory=dict)
    leg_contacts: Tuple[Tuple[str, str, float, int], ...] = ()

    @property
    def non_finite(self) -> bool:
        """Whether any frame holds NaN or inf."""
        return bool(self.non_finite_times)

    @property
    def ok(self) -> bool:
        """Whether every criterion holds."""
        return not self.failures()

    def failures(self) -> List[str]:
        """Human-readable failures, each naming the link or joint and the time."""
        tol = self.tolerances
        out = []
        if self.non_finite_times:
            times = ', '.join(f'{t:.3f}' for t in self.non_finite_times[:5])
            out.append(f'{len(self.non_finite_times)} frame(s) hold NaN/inf (t = {times} s)')
        for link, depth in sorted(self.penetration.items()):
            allowed = tol['foot_rest_tol'] if link in FEET else tol['penetration_tol']
            if depth > allowed:
                out.append(f'{link} penetrates the environment by {depth * 1000:.1f} mm at '
                           f't = {self.penetration_time[link]:.3f} s (allowed '
                           f'{allowed * 1000:.1f} mm)')
        if self.foot_down_gap > tol['foot_down_tol']:
            out.append(f'no foot down at t = {self.foot_down_time:.3f} s: nearest sole is '
                       f'{self.foot_down_gap * 1000:.1f} mm above a surface (allowed '
                       f'{tol["foot_down_tol"] * 1000:.1f} mm)')
        for joint, time, value, bound in self.position_violations:
            out.append(f'joint {joint} = {value:.6g} outside its limit {bound:.6g} at '
                       f't = {time:.3f} s')
        for joint, time, speed, limit in self.velocity_violations:
            out.append(f'joint {joint} moves at {speed:.4g}/s, over 1.05 x its velocity limit '
                       f'{limit:.4g}/s at t = {time:.3f} s')
        for joint, time, change, allowed in self.jumps:
            out.append(f'joint {joint} jumps by {change:.4g} in one frame at t = {time:.3f} s '
                       f'(allowed {allowed:.4g})')
        for foot, slip in sorted(self.slip.items()):
            if slip > tol['slip_tol']:
                out.append(f'stance foot {foot} slides {slip * 1000:.1f} mm ending at '
                           f't = {self.slip_time[foot]:.3f} s (allowed '
                           f'{tol["slip_tol"] * 1000:.1f} mm)')
        for left, right, time, count in self.leg_contacts:
            out.append(f'{left} and {right} pass into each other (by more than '
                       f'{tol["leg_contact_tol"] * 1000:.1f} mm) at t = {time:.3f} s and on '
                       f'{count - 1} more checked frame(s)')
        return out


def _positive(name: str, value) -> float:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
        raise ValueError(f'{name} must be a finite number >= 0, got {value!r}')
    return float(value)


def _worst_per_joint(names, excess: np.ndarray, times: np.ndarray, values: np.ndarray,
                     allowed: np.ndarray) -> Tuple[Tuple[str, float, float, float], ...]:
    """(joint, time, value, allowed) at each joint's largest positive ``excess``: (k, 22)."""
    out = []
    if excess.size == 0:
        return ()
    worst = np.argmax(excess, axis=0)
    for j, name in enumerate(names):
        i = worst[j]
        if excess[i, j] > 0:
            out.append((name, float(times[i]), float(values[i, j]), float(allowed[i, j])))
    return tuple(out)


class _Soles:
    """FCL probes at the soles: slabs around the sole plane and spheres at its corners."""

    def __init__(self, skeleton, environment, foot_down_tol: float):
        self.environment = environment
        self.shape_index = {}
        self.size = {}
        for i, shape in enumerate(skeleton.collision_shapes):
            if shape.link in FEET and shape.kind == 'box' and shape.link not in self.shape_index:
                self.shape_index[shape.link] = i
                self.size[shape.link] = np.asarray(shape.size, dtype=float)
        missing = [f for f in FEET if f not in self.shape_index]
        if missing:
            raise ValueError(f'the skeleton has no box collision shape for {missing}')

        def slab(foot, thickness):
            box = fcl.Box(self.size[foot][0], self.size[foot][1], thickness)
            return fcl.CollisionObject(box, fcl.Transform())

        # The exact sole, and slabs reaching STANCE_GAP / foot_down_tol either side of it.
        self.sole = {foot: slab(foot, _SOLE_THICKNESS) for foot in FEET}
        self.stance_probe = {foot: slab(foot, 2 * STANCE_GAP) for foot in FEET}
        self.down_probe = {foot: slab(foot, 2 * max(foot_down_tol, 1e-6)) for foot in FEET}
        self.corner = fcl.CollisionObject(fcl.Sphere(STANCE_GAP), fcl.Transform())
        self.request = fcl.DistanceRequest()
        self.collision_request = fcl.CollisionRequest()

    def corners(self, foot: str, transform: np.ndarray) -> np.ndarray:
        """(4, 3) world positions of the bottom corners of a foot box at ``transform``."""
        length, width, height = self.size[foot]
        local = np.array([[sx * length / 2, sy * width / 2, -height / 2, 1.0]
                          for sx in (-1, 1) for sy in (-1, 1)])
        return (local @ transform.T)[:, :3]

    def _touches(self, obj) -> bool:
        return any(fcl.collide(obj, target, self.collision_request, fcl.CollisionResult())
                   for target in self.environment.objects)

    def _place(self, obj, foot: str, transform: np.ndarray):
        """Centre a sole probe on the bottom face of a foot box at ``transform``."""
        offset = transform[:3, :3] @ np.array([0.0, 0.0, -self.size[foot][2] / 2])
        obj.setTransform(fcl.Transform(transform[:3, :3], transform[:3, 3] + offset))
        return obj

    def in_stance(self, foot: str, transform: np.ndarray) -> bool:
        """Whether the sole is within STANCE_GAP of a surface (or in it)."""
        return self._touches(self._place(self.stance_probe[foot], foot, transform))

    def down(self, foot: str, transform: np.ndarray) -> bool:
        """Whether the sole is within foot_down_tol of a surface (or in it)."""
        return self._touches(self._place(self.down_probe[foot], foot, transform))

    def sole_gap(self, foot: str, transform: np.ndarray) -> float:
        """Distance from a foot's sole (bottom face) to the environment, m (0 in contact)."""
        obj = self._place(self.sole[foot], foot, transform)
        best = math.inf
        for target in self.environment.objects:
            if fcl.collide(obj, target, self.collision_request, fcl.CollisionResult()):
                return 0.0
            best = min(best, fcl.distance(obj, target, self.request, fcl.DistanceResult()))
        return max(0.0, best + _SOLE_THICKNESS / 2)

    def corners_in_contact(self, corners: np.ndarray) -> List[bool]:
        """Whether each sole corner is within STANCE_GAP of a surface."""
        out = []
        for point in corners:
            self.corner.setTranslation(np.asarray(point, dtype=float))
            out.append(self._touches(self.corner))
        return out


def _leg_contacts(skeleton, transforms: np.ndarray, times: np.ndarray,
                  tol: float) -> Tuple[Tuple[str, str, float, int], ...]:
    """
    Find the pairs of links of the two legs that interpenetrate.

    Pairs of links of the two legs interpenetrating by more than ``tol`` (m): each shape is shrunk
    by half of it and tested with FCL where the bounding spheres overlap.

    ``transforms`` (k, S, 4, 4) places every collision shape at the checked frames, whose
    times are ``times`` (k,).
    """
    shapes = skeleton.collision_shapes
    sides = [[i for i, shape in enumerate(shapes) if shape.link in links] for links in LEGS]
    objects = {i: fcl.CollisionObject(shape_geometry(shapes[i], -tol / 2)[0], fcl.Transform())
               for i in sides[0] + sides[1]}
    request = fcl.CollisionRequest()
    out = []
    for a in sides[0]:
        for b in sides[1]:
            reach = (shape_reach(shape_geometry(shapes[a])[1])
                     + shape_reach(shape_geometry(shapes[b])[1]))
            gap = np.linalg.norm(transforms[:, a, :3, 3] - transforms[:, b, :3, 3], axis=1)
            first, count = None, 0
            for row in np.flatnonzero(gap < reach):
                objects[a].setTransform(fcl.Transform(transforms[row, a, :3, :3],
                                                      transforms[row, a, :3, 3]))
                objects[b].setTransform(fcl.Transform(transforms[row, b, :3, :3],
                                                      transforms[row, b, :3, 3]))
                if fcl.collide(objects[a], objects[b], request, fcl.CollisionResult()):
                    count += 1
                    first = float(times[row]) if first is None else first
            if count:
                out.append((shapes[a].link, shapes[b].link, first, count))
    return tuple(out)


def _buried_depths(skeleton, environment, transforms: np.ndarray) -> np.ndarray:
    """
    How deep each shape's centre is buried inside a solid: (k, S) m, 0 where it is not.

    FCL tests surfaces, so a shape wholly inside a solid touches no triangle. A centre is inside
    when the first surface straight above it faces up (a solid's top, or a height-field terrain
    above it); the depth is what lifts the whole shape out through that surface.
    """
    k, count = transforms.shape[:2]
    if k == 0:
        return np.zeros((0, count))
    world = trimesh.util.concatenate([trimesh.Trimesh(m.vertices, m.faces, process=False)
                                      for m in environment.meshes])
    centres = transforms[:, :, :3, 3].reshape(-1, 3)
    directions = np.tile([0.0, 0.0, 1.0], (len(centres), 1))
    locations, rays, triangles = world.ray.intersects_location(centres, directions,
                                                               multiple_hits=False)
    depth = np.zeros(len(centres))
    facing_up = world.face_normals[triangles, 2] > 0
    rays, locations = rays[facing_up], locations[facing_up]
    if len(rays):
        rotation = transforms[:, :, :3, :3].reshape(-1, 3, 3)[rays]
        # Reach of each shape below its centre: its support along -z.
        reach = np.zeros(len(rays))
        shape_of = np.tile(np.arange(count), k)[rays]
        for s, shape in enumerate(skeleton.collision_shapes):
            mask = shape_of == s
            if not np.any(mask):
                continue
            z_axis = rotation[mask, 2, :]  # world z in the shape frame
            if shape.kind == 'box':
                reach[mask] = np.abs(z_axis) @ (np.asarray(shape.size, dtype=float) / 2)
            elif shape.kind == 'cylinder':
                along = np.minimum(np.abs(z_axis[:, 2]), 1.0)
                reach[mask] = (shape.size[0] * np.sqrt(1.0 - along ** 2)
                               + shape.size[1] / 2 * along)
            else:
                reach[mask] = shape.size[0]
        depth[rays] = locations[:, 2] - centres[rays, 2] + reach
    return depth.reshape(k, count)


def check_trajectory(skeleton, environment, times, frames, *, penetration_tol: float = 0.003,
                     foot_rest_tol: float = 0.015, foot_down_tol: float = 0.025,
                     slip_tol: float = 0.01, leg_contact_tol: float = 0.003,
                     stride: int = 1,
                     links: Optional[Iterable[str]] = None) -> CheckReport:
    """
    Judge a timed trajectory: collisions, a foot down, limits, NaN, jumps, stance slip.

    Parameters
    ----------
    skeleton
        :class:`skeleton.Skeleton` (joint order, limits, collision shapes).
    environment
        :class:`environment.Environment`.
    times
        (k,) strictly increasing frame times, s.
    frames
        (k, 22) configurations, rad or m.
    penetration_tol
        Largest allowed penetration of any link but the feet, m.
    foot_rest_tol
        Largest allowed penetration of a foot resting on a surface, m.
    foot_down_tol
        At every checked frame one sole must be within this distance of a surface, m.
    slip_tol
        Largest horizontal motion of a sole corner while it bears weight (within 10 mm of a
        surface over a run of frames), m.
    leg_contact_tol
        Largest allowed interpenetration of a thigh, shank or foot with a link of the other
        leg, m (each shape shrunk by half of it must not touch the other).
    stride
        Check the geometric criteria on every ``stride``-th frame (and the last one); limits,
        speeds, jumps and NaN are always checked on every frame.
    links
        Links whose penetration is checked; default all links with collision shapes.

    Returns
    -------
    CheckReport

    """
    times = np.asarray(times, dtype=float)
    frames = np.asarray(frames, dtype=float)
    count = len(skeleton.joint_names)
    if times.ndim != 1 or len(times) == 0:
        raise ValueError(f'times must have shape (k,) with k >= 1, got {times.shape}')
    if frames.shape != (len(times), count):
        raise ValueError(f'frames must have shape ({len(times)}, {count}), got {frames.shape}')
    if not np.all(np.isfinite(times)):
        bad = int(np.flatnonzero(~np.isfinite(times))[0])
        raise ValueError(f'times must be finite; times[{bad}] = {times[bad]}')
    steps = np.diff(times)
    if np.any(steps <= 0):
        bad = int(np.flatnonzero(steps <= 0)[0])
        raise ValueError(f'times must increase strictly: times[{bad}] = {times[bad]} and '
                         f'times[{bad + 1}] = {times[bad + 1]}')
    if not (isinstance(stride, (int, np.integer)) and stride >= 1):
        raise ValueError(f'stride must be an integer >= 1, got {stride!r}')
    tolerances = {'penetration_tol': _positive('penetration_tol', penetration_tol),
                  'foot_rest_tol': _positive('foot_rest_tol', foot_rest_tol),
                  'foot_down_tol': _positive('foot_down_tol', foot_down_tol),
                  'slip_tol': _positive('slip_tol', slip_tol),
                  'leg_contact_tol': _positive('leg_contact_tol', leg_contact_tol)}
    names = skeleton.joint_names

    finite = np.all(np.isfinite(frames), axis=1)
    non_finite_times = tuple(float(t) for t in times[~finite])
    clean = np.where(np.isfinite(frames), frames, 0.0)

    # Position limits, every frame (1e-6 tolerance).
    lower = np.broadcast_to(skeleton.lower, clean.shape)
    upper = np.broadcast_to(skeleton.upper, clean.shape)
    below, above = lower - clean, clean - upper
    excess = np.where(finite[:, None], np.maximum(below, above) - 1e-6, -np.inf)
    bound = np.where(below > above, lower, upper)
    position_violations = _worst_per_joint(names, excess, times, clean, bound)

    # Speeds and jumps from finite differences between consecutive finite frames.
    velocity_violations, jumps, max_jump_ratio = (), (), 0.0
    if len(times) > 1:
        change = np.abs(np.diff(clean, axis=0))
        pair_ok = (finite[1:] & finite[:-1])[:, None]
        dt = steps[:, None]
        limit = np.broadcast_to(skeleton.velocity_limit, change.shape)
        speed = change / dt
        velocity_violations = _worst_per_joint(
            names, np.where(pair_ok, speed - 1.05 * limit, -np.inf), times[1:], speed,
            1.05 * limit)
        allowed = 1.5 * limit * dt
        jumps = _worst_per_joint(names, np.where(pair_ok, change - allowed, -np.inf),
                                 times[1:], change, allowed)
        ratios = np.where(pair_ok, change / (limit * dt), 0.0)
        max_jump_ratio = float(ratios.max()) if ratios.size else 0.0

    # Geometry on the checked frames.
    checked = np.arange(0, len(times), stride)
    if checked[-1] != len(times) - 1:
        checked = np.append(checked, len(times) - 1)
    checked = checked[finite[checked]]
    body = BodyCollision(skeleton, environment)
    link_list = list(body.links if links is None else links)
    penetration = {link: 0.0 for link in link_list if link in body.link_shapes}
    penetration_time = {link: float(times[0]) for link in penetration}
    soles = _Soles(skeleton, environment, tolerances['foot_down_tol'])
    shape_transforms = (skeleton.shape_transforms(skeleton.forward_kinematics(clean[checked]))
                        if len(checked) else np.zeros((0, len(skeleton.collision_shapes), 4, 4)))
    buried = _buried_depths(skeleton, environment, shape_transforms)
    link_shapes = {link: [i for i, shape in enumerate(skeleton.collision_shapes)
                          if shape.link == link] for link in penetration}
    foot_down_gap, foot_down_time = 0.0, float(times[0])
    corner_runs = {foot: [None] * 4 for foot in FEET}
    slip = dict.fromkeys(FEET, 0.0)
    slip_time = {foot: float(times[0]) for foot in FEET}
    for row, i in enumerate(checked):
        q = clean[i]
        t = float(times[i])
        # No link inside the environment (feet may rest on a surface).
        for link, depth in body.penetration(q, penetration).items():
            depth = max(depth, float(buried[row, link_shapes[link]].max()))
            if depth > penetration[link]:
                penetration[link], penetration_time[link] = depth, t
        down = False
        for foot in FEET:
            transform = shape_transforms[row, soles.shape_index[foot]]
            # A foot in a surface is down (its depth is judged above); a probe deep inside a
            # solid would not touch its surface.
            sunk = buried[row, soles.shape_index[foot]] > 0 or body.collides(q, (foot,))
            stance = sunk or soles.in_stance(foot, transform)
            down = down or stance or soles.down(foot, transform)
            _track_slip(foot, soles, transform, stance, t, corner_runs, slip, slip_time)
        if not down:
            gap = min(soles.sole_gap(foot, shape_transforms[row, soles.shape_index[foot]])
                      for foot in FEET)
            if gap > foot_down_gap:
                foot_down_gap, foot_down_time = gap, t

    leg_contacts = _leg_contacts(skeleton, shape_transforms, times[checked],
                                 tolerances['leg_contact_tol'])
    return CheckReport(frames=len(times), frames_checked=len(checked), penetration=penetration,
                       penetration_time=penetration_time, foot_down_gap=float(foot_down_gap),
                       foot_down_time=foot_down_time, position_violations=position_violations,
                       velocity_violations=velocity_violations, jumps=jumps,
                       max_jump_ratio=max_jump_ratio, non_finite_times=non_finite_times,
                       slip=slip, slip_time=slip_time, tolerances=tolerances,
                       leg_contacts=leg_contacts)


def _track_slip(foot: str, soles: _Soles, transform: np.ndarray, stance: bool, time: float,
                corner_runs: Dict[str, list], slip: Dict[str, float],
                slip_time: Dict[str, float]) -> None:
    """
    Follow each sole corner through its runs of contact; record its horizontal drift.

    A foot rolling over its heel or toe keeps those corners fixed while the others lift, so
    tracking corners (not the sole's centre) tells rolling from sliding.
    """
    if not stance:
        corner_runs[foot] = [None] * 4
        return
    corners = soles.corners(foot, transform)
    contact = soles.corners_in_contact(corners)
    runs = corner_runs[foot]
    for c in range(4):
        if not contact[c]:
            runs[c] = None
            continue
        if runs[c] is None:
            runs[c] = corners[c, :2].copy()
            continue
        drift = float(np.hypot(*(corners[c, :2] - runs[c])))
        if drift > slip[foot]:
            slip[foot], slip_time[foot] = drift, time
