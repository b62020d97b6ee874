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
The actor pipeline: commands in, timed 22-DOF frames out, one step at a time (§3.2, Figure 2).

Data flows one way: command -> predicted path -> ground profile -> footstep window -> leg motion
and pelvis trajectory -> upper body -> frames. If a planner fails the step is not taken: the
actor holds a stable stance and reports ``stuck`` with the reason until a new command (the user
steering away) makes a step feasible again.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
import time as _time
from typing import Optional, Tuple

import numpy as np

from .collision import BodyCollision
from .environment import Environment, finite_numbers, SceneError
from .footsteps import (describe_ground_ahead, FootstepConfig, FootstepPlanner, FootstepWindow,
                        LEFT, RIGHT, sample_ground_profile)
from .gait import (foot_pose_on, GaitConfig, GaitError, hold_frames, leg_inverse_kinematics,
                   Stance, standing_stance, StepMotion, WalkGenerator, with_at_rest)
from .path import predict_path
from .settings import check_settings, ConfigError, declared_settings, require, setting
from .skeleton import Skeleton
from .upper_body import motion_patterns, UpperBodyConfig, UpperBodyPlanner

LEG_LINKS = ('pelvis', 'left_hip', 'left_thigh', 'left_shank', 'left_foot', 'right_hip',
             'right_thigh', 'right_shank', 'right_foot')


@dataclass(frozen=True)
class ActorConfig:
    """
    Settings of the whole pipeline. Speeds in m/s and rad/s, lengths in m, times in s.

    Why each rule and default is as it is: docs/LOWER_BODY.md and docs/UPPER_BODY.md.
    """

    # The fastest the gait walks: steps of GaitConfig.fast_step_length at about its quickest
    # cadence the joints' speed limits allow (0.52 s); a faster command could only lengthen
    # the steps, and longer steps are slowed down further than they gain (see
    # bench/bench_walk_speeds.py --flat).
    max_linear_speed: float = setting(
        1.0, 0.0, 3.0, 'Forward speed limit; commands beyond it are clamped. The default is the '
        'fastest the gait walks: above it the steps would slow down.', 'm/s', low_open=True)
    max_angular_speed: float = setting(
        1.0, 0.0, 3.0, 'Turning speed limit; commands beyond it are clamped.', 'rad/s',
        low_open=True)
    hold_time: float = setting(0.1, 0.0, 1.0, 'Length of a block that holds a stance.', 's',
                               low_open=True)
    nominal_step_time: float = setting(
        0.65, 0.0, None, 'Duration of a step at walking speed.', 's', low_open=True)
    max_attempts: int = setting(6, 1, None, 'Footstep windows tried for one step.')
    verify_collisions: bool = setting(True, doc='Check every step against the scene in 3D.')
    plan_upper_body: bool = setting(True, doc='Plan the upper body (paper §5).')
    upper_body_preview: float = setting(
        0.5, 0.0, None, 'How far past a step the upper body is planned ahead.', 's')
    # The preview covers at least this distance of the pelvis moving on (m; see _preview).
    upper_body_preview_distance: float = setting(
        0.5, 0.0, None, 'Distance of the pelvis moving on the preview covers at least.', 'm')
    # A step whose upper body is blocked in the preview less than this after the step's end
    # is not taken: it would leave an arm or the waist where the next step cannot go on
    # (between two pillars, with the pelvis carrying it into one). Another footstep is tried,
    # or the actor stops before the obstacle instead of in it.
    upper_body_preview_margin: float = setting(
        0.1, 0.0, None, 'A step blocked in the preview less than this after its end is not '
        'taken.', 's')
    # Receding horizon: a branch that left its motion pattern in the last step's plan starts
    # its search along that plan's preview, where it still applies (see _seeds): the steps
    # after the first one at an obstacle mostly find their way there at once.
    upper_body_seed: bool = setting(
        True, doc="Start a branch's search along the last plan's preview.")
    # When every footstep tried failed for the upper body, the first of them is tried once more
    # from a standstill after a pause this long (s, 0: never): with the pelvis still, an arm can
    # get clear before the step moves the body (an arm between a pillar and the turned body).
    upper_body_pause: float = setting(
        0.2, 0.0, 2.0, 'Pause before the last try of a step from a standstill (0: never).', 's')
    # When a tight turn (|w| >= 0.2 rad/s, radius v / |w| under PIVOT_RADIUS, a turn on the
    # spot too) finds no footstep along its arc (facing an edge the arc's footholds reach over
    # it; the inner foot would meet the outer one), the actor pivots instead: the swing foot
    # lands beside the stance foot, turned up to this far (rad) towards the turn, and the
    # pelvis turns half as far about the stance hip (0: never).
    pivot_turn: float = setting(
        0.8, 0.0, 1.0, 'Largest turn of a pivot where a tight turn finds no footstep (0: never).',
        'rad')
    # Where no pivot of the foot due to swing can be taken, the foot that landed last may pivot
    # instead (both feet are down between steps).
    pivot_either_foot: bool = setting(
        True, doc='Where the foot due to swing cannot pivot, let the other one pivot.')
    # The landing foot may point at most this far (rad) towards the stance foot's side (toes
    # in), against hip_yaw_limit x 1.5 outwards: pigeon-toed feet turn both thighs in, and with
    # the hips flexed the knees meet (a turn reversed mid-walk made them pass through each
    # other). The path's heading is caught up by the next steps, whose feet may toe out.
    max_toe_in: float = setting(
        0.35, 0.0, 1.0, 'How far a landing foot may point towards the stance foot.', 'rad')
    # Where the window's next footstep swings the other foot over ground more than
    # follow_check_rise (m) above the foot's sole and higher than where it lands
    # (FOLLOW_OVER_LANDING), the leg motion of that footstep is generated too before this step
    # is taken (check_follow). A rear foot that must follow the front one over a block from
    # just behind its face can pass the knee's limit (the sole tips toes-down at the ankle's
    # limit, so it must rise higher still), and once the front foot is over there is no step
    # left: a 0.24 m high, 0.31 m long block met in 20 phases at 0.6-1.1 m/s, 39 of 60 walks
    # crossed without the check, 60 with it. Asked from 3 cm: a rear foot lifted over a 3.5 cm
    # bump just before a 0.17 m step down passed the knee's limit too (bench_terrain random
    # course 38); at 0.1 m that was not asked.
    check_follow: bool = setting(
        True, doc="Generate the window's next footstep too where it swings over high ground.")
    follow_check_rise: float = setting(
        0.03, 0.0, 1.0, 'How high above the sole ground must rise for check_follow.', 'm')
    upper_body_attempts: int = setting(
        6, 0, None, 'Footsteps tried for the upper body before the step is refused.')
    # Backward walking (a mouse drag downwards, negative linear speed; see docs/backward.md).
    # False: the paper's actor, which walks forward only (a backward command becomes 0).
    allow_backward: bool = setting(
        True, doc="Walk backward on a negative linear speed; false: the paper's actor, which "
        'walks forward only (a negative linear speed becomes 0).')
    # Fastest backward walk, m/s: people walk backward at about half their forward speed, with
    # shorter steps that the hip's extension range bounds.
    max_backward_speed: float = setting(
        0.5, 0.0, 3.0, 'Backward speed limit: a negative linear speed is clamped to -this.',
        'm/s', low_open=True, rule='max_backward_speed <= max_linear_speed')
    # The footstep lengths of a backward window, m (the forward ones: step_length_min/max).
    backward_step_length_min: float = setting(
        0.10, 0.05, 1.0, 'Shortest backward step.', 'm',
        rule='backward_step_length_min < backward_step_length_max')
    backward_step_length_max: float = setting(
        0.40, 0.05, 1.0, 'Longest backward step.', 'm',
        rule='backward_step_length_min < backward_step_length_max')
    # The largest step up and down a backward step takes, m. Up, the landing foot is behind
    # the hip and higher, its shank leaning forward over a flat sole: from 0.14 m the ankle
    # passes its dorsiflexion limit at touchdown (a backward flight of 0.15 m risers is
    # refused by the window, a clean stop, rather than by the legs).
    backward_max_step_up: float = setting(0.12, 0.0, None, 'Highest backward step up.', 'm')
    backward_max_step_down: float = setting(
        0.20, 0.0, None, 'Deepest backward step down.', 'm')
    footsteps: FootstepConfig = field(default_factory=FootstepConfig)
    gait: GaitConfig = field(default_factory=GaitConfig)
    # The upper-body planner's settings (upper_body.UpperBodyConfig); None: its defaults. Not
    # built here: the upper-body planner's module is loaded only where it plans.
    upper_body: Optional[UpperBodyConfig] = None

    def __post_init__(self):
        """Check every field against its declaration and the cross-field rules."""
        check_settings(self)
        require(isinstance(self.footsteps, FootstepConfig), 'footsteps', self.footsteps,
                f'footsteps must be a FootstepConfig, got {self.footsteps!r}')
        require(isinstance(self.gait, GaitConfig), 'gait', self.gait,
                f'gait must be a GaitConfig, got {self.gait!r}')
        if self.upper_body is not None:
            from .upper_body import UpperBodyConfig
            require(isinstance(self.upper_body, UpperBodyConfig), 'upper_body', self.upper_body,
                    f'upper_body must be an UpperBodyConfig or None, got {self.upper_body!r}')
        require(self.max_backward_speed <= self.max_linear_speed, 'max_backward_speed',
                self.max_backward_speed, f'max_backward_speed {self.max_backward_speed} must '
                f'not exceed max_linear_speed {self.max_linear_speed} m/s')
        require(self.backward_step_length_min < self.backward_step_length_max,
                'backward_step_length_min', self.backward_step_length_min,
                f'backward_step_length_min {self.backward_step_length_min} must be below '
                f'backward_step_length_max {self.backward_step_length_max}')

    @classmethod
    def from_settings(cls, **values) -> 'ActorConfig':
        """
        Return the config with the given settings of its own and of its parts.

        Parameters
        ----------
        values
            Settings by name: fields of :class:`FootstepConfig`, :class:`GaitConfig`,
            ``upper_body.UpperBodyConfig`` or this class (their names do not overlap).

        Raises
        ------
        ConfigError
            A bad value, or a name that is no setting (naming it).

        """
        parts = {'footsteps': {}, 'gait': {}, 'upper_body': {}, 'own': {}}
        owners = [(FootstepConfig, 'footsteps'), (GaitConfig, 'gait'), (cls, 'own')]
        for name, value in values.items():
            part = next((p for owner, p in owners if name in declared_settings(owner)), None)
            if part is None and len(owners) == 3:
                from .upper_body import UpperBodyConfig
                owners.append((UpperBodyConfig, 'upper_body'))
                part = 'upper_body' if name in declared_settings(UpperBodyConfig) else None
            if part is None:
                raise ConfigError(name, value, f'{name} is no setting of the actor')
            parts[part][name] = value
        upper_body = owners[3][0](**parts['upper_body']) if parts['upper_body'] else None
        return cls(footsteps=FootstepConfig(**parts['footsteps']),
                   gait=GaitConfig(**parts['gait']), upper_body=upper_body, **parts['own'])

    @property
    def frame_rate(self) -> float:
        """Return the rate of the planned frames, Hz (``gait.frame_rate``)."""
        return self.gait.frame_rate

    def backward_footstep_config(self) -> FootstepConfig:
        """
        Return the footstep settings of a backward window.

        The footstep settings with this config's backward lengths and step heights.
        """
        return replace(self.footsteps, step_length_min=self.backward_step_length_min,
                       step_length_max=self.backward_step_length_max,
                       max_step_up=self.backward_max_step_up,
                       max_step_down=self.backward_max_step_down)


def validate(config: ActorConfig) -> None:
    """Raise :class:`ConfigError` naming the first bad field of ``config`` or its parts."""
    config.footsteps.__post_init__()
    config.gait.__post_init__()
    config.__post_init__()


#: How far (m) the ground a swing passes over must rise above where it lands for the actor to
#: check that the window's next footstep can follow (see ``ActorConfig.check_follow``).
FOLLOW_OVER_LANDING = 0.02
#: Turns tighter than this radius (m) pivot where their arc is refused (see ``pivot_turn``).
PIVOT_RADIUS = 0.5
#: Where a pivot's landing foot may go along the pelvis's heading from beside the stance foot,
#: in the order tried, m; None: where the swinging foot stands (it turns in place: a foot behind
#: the other need not swing forward).
PIVOT_SHIFTS = (0.0, 0.1, -0.1, 0.2, None)
#: How far two pivots in a row must turn the pelvis in the commanded direction, rad.
PIVOT_MIN_TURN = 0.05
#: How far ahead along the new direction of travel the swinging foot must stand for the other
#: to swing instead when the actor sets off the other way from a standstill, m.
REVERSAL_STAGGER = 0.05
#: How far a foot may land from its planned foothold before its support is judged again, m.
LANDING_DRIFT = 0.02
#: A zero command after a step that landed in a split stance stops there: the pelvis slows
#: to rest over this long (s), the feet still, instead of a closing step (people stop so).
SETTLE_TIME = 0.05
#: Where between the ankles (the fraction of the way from the rear one, along the line
#: joining them) the settled pelvis must stand for the split stance to be held.
SPLIT_STANCE_RANGE = (0.2, 0.8)
#: How far apart along the pelvis's heading the ankles must stand for a split stance, m
#: (nearer, or farther, the closing step brings the feet side by side: from a wider stance
#: the rear foot's first step on would pass the joint speed limits).
SPLIT_STANCE_LENGTHS = (0.1, 0.5)


@dataclass(frozen=True)
class StepBlock:
    """
    A block of committed frames.

    Attributes
    ----------
    status
        'walking', 'idle' or 'stuck'.
    reason
        Why the actor is stuck (or what it did), '' when walking normally.
    times
        (k,) s on the actor's clock (it starts at 0 at construction).
    frames, velocities
        (k, 22) joint positions (rad or m) and velocities (rad/s or m/s).
    footsteps
        (n, 4) x, y, z, yaw of the planned footstep window (empty when none).
    path
        (p, 3) x, y, z of the predicted path (empty when idle).
    planning_time
        Wall time spent planning this block, s.
    category
        'level', 'uphill', 'downhill', 'closing', 'settling' (the pelvis slowing to rest in
        a split stance), 'pivot' or '' for hold blocks.

    """

    status: str
    reason: str
    times: np.ndarray
    frames: np.ndarray
    velocities: np.ndarray
    footsteps: np.ndarray
    path: np.ndarray
    planning_time: float
    category: str = ''


def start_configuration(environment: Environment, start, skeleton: Skeleton) -> np.ndarray:
    """
    Place the actor's neutral standing configuration at a start pose.

    The actor stands on the lowest walkable surface under its soles and pelvis, so a start in
    a wall, under a table or under a beam puts it at floor level (where it collides) rather
    than on top: ``root_z`` = that ground + ``skeleton.leg.standing_height`` + 2 mm.

    Parameters
    ----------
    environment
        The world.
    start
        (x m, y m, yaw rad).
    skeleton
        The actor model.

    Returns
    -------
    numpy.ndarray
        (22,) float64 configuration, rad or m.

    Raises
    ------
    SceneError
        ``start`` is not 3 finite numbers, or there is no ground below it.

    """
    x, y, yaw = finite_numbers(list(start) if isinstance(start, (list, tuple, np.ndarray))
                               else start, 3, 'start', 'start pose')
    q = skeleton.neutral().copy()
    q[skeleton.index['root_x']], q[skeleton.index['root_y']] = x, y
    q[skeleton.index['root_yaw']] = yaw
    leg = skeleton.leg
    # Sole corners of both feet and the pelvis, in the pelvis frame (§4: feet under the hips).
    points = np.array([[0.0, 0.0]] + [[dx, side * leg.hip_half_width + dy]
                                      for side in (1.0, -1.0)
                                      for dx in (-leg.heel, leg.toe)
                                      for dy in (-leg.foot_width / 2, leg.foot_width / 2)])
    c, s = math.cos(yaw), math.sin(yaw)
    xy = points @ np.array([[c, s], [-s, c]]) + (x, y)
    ground = environment.lowest_ground(xy)
    if np.all(np.isnan(ground)):
        raise SceneError(f'no ground below the start pose ({x:g}, {y:g}, yaw {yaw:g})')
    q[skeleton.index['root_z']] = float(np.nanmin(ground)) + leg.standing_height + 0.002
    return q


class Actor:
    """
    A digital actor walking where it is told (the whole planning system of the paper).

    Parameters
    ----------
    skeleton
        The 22-DOF model.
    environment
        The world (:class:`environment.Environment`).
    config
        Pipeline settings.
    start
        (x, y, yaw) start pose, m and rad.
    upper_body_planner
        Optional planner for §5 with ``plan(times, frames)``; by default one is built when
        ``config.plan_upper_body`` is set.
    body_collision
        Optional :class:`collision.BodyCollision` used to verify each step in 3D.

    """

    def __init__(self, skeleton: Skeleton, environment, config: ActorConfig = ActorConfig(),
                 start: Tuple[float, float, float] = (0.0, 0.0, 0.0),
                 upper_body_planner=None, body_collision=None):
        validate(config)
        self.skeleton = skeleton
        self.environment = environment
        self.config = config
        self._footstep_config = config.footsteps
        self._planner = FootstepPlanner(self._footstep_config, skeleton.leg)
        # Backward the window runs along the path behind the actor, where its heel leads: the
        # same search over that ground profile with the sole's ends exchanged (and the
        # backward lengths and step heights).
        self._backward_leg = replace(skeleton.leg, heel=skeleton.leg.toe, toe=skeleton.leg.heel)
        self._backward_footstep_config = config.backward_footstep_config()
        self._backward_planner = FootstepPlanner(self._backward_footstep_config,
                                                 self._backward_leg)
        self._walk = WalkGenerator(skeleton, config.gait, self._footstep_config)
        self._collision = body_collision or BodyCollision(skeleton, environment)
        self._leg_links = LEG_LINKS
        self._path_steps = np.arange(24.0)
        self._root_columns = skeleton.branch('root')
        self._lower_body = np.concatenate([skeleton.branch(b) for b in
                                           ('root', 'left_leg', 'right_leg')])
        self._lower_velocity_limit = skeleton.velocity_limit[self._lower_body]
        if upper_body_planner is None and config.plan_upper_body:
            upper_body_planner = UpperBodyPlanner(
                skeleton, self._collision, config.upper_body or UpperBodyConfig(),
                rng=np.random.default_rng(0))
        self._upper = upper_body_planner
        q = start_configuration(environment, start, skeleton)
        sole = q[skeleton.index['root_z']] - skeleton.leg.standing_height - 0.002
        self._stance = self._start_stance(float(start[0]), float(start[1]), float(start[2]),
                                          float(sole))
        self._configuration = self._standing_configuration()
        self._time = 0.0
        self._command = (0.0, 0.0)
        self._previous_length = 0.0
        self._window: Optional[FootstepWindow] = None
        self._window_command = None
        self.status = 'idle'
        self.reason = ''
        self._failure = None
        self._steps = 0
        # Receding horizon: (step count, times (s,) s, {branch: (s, d) deviations from the
        # motion pattern, rad}) of the last committed step's upper-body plan from where the
        # next step starts, for the branches that searched; and the same of the latest plan
        # (kept when its step is committed).
        self._upper_seed = None
        self._preview_plan = None
        # (step count after the last pivot, pelvis heading before it, rad).
        self._last_pivot = None
        # Whether the last step of a footstep window walked backward (None: none yet).
        self._walked_backward: Optional[bool] = None
        # (22,) velocity of the last committed frame, rad/s or m/s.
        self._velocity = np.zeros(len(skeleton.joint_names))

    # -- state ---------------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Return the end time of everything committed so far, s."""
        return self._time

    @property
    def configuration(self) -> np.ndarray:
        """Return the last committed frame, (22,) rad or m."""
        return self._configuration.copy()

    @property
    def command(self) -> Tuple[float, float]:
        """Return the (clamped) command in force: linear m/s, angular rad/s."""
        return self._command

    @property
    def stance(self) -> Stance:
        """Return the double-support state after the last committed step."""
        return self._stance

    def set_command(self, linear: float, angular: float) -> Optional[str]:
        """
        Set the velocity command (the mouse drag of §3.1).

        A negative ``linear`` walks backward, up to ``max_backward_speed``, along the arc
        ``cmd_vel`` means (the actor keeps facing against its travel and turns at
        ``angular``). With ``allow_backward`` off (the paper's actor walks forward only) it
        becomes 0.

        Parameters
        ----------
        linear
            Forward speed, m/s (negative: backward); clamped to the config's limits.
        angular
            Turn rate, rad/s (positive: to the left); clamped to ``max_angular_speed``.

        Returns
        -------
        str or None
            A warning when the command was clamped.

        Raises
        ------
        ValueError
            When a value is NaN or infinite (the command is not applied).

        """
        if not (np.isfinite(linear) and np.isfinite(angular)):
            raise ValueError(f'command must be finite, got linear={linear}, angular={angular}')
        cfg = self.config
        slowest = -cfg.max_backward_speed if cfg.allow_backward else 0.0
        v = float(min(max(linear, slowest), cfg.max_linear_speed))
        w = float(min(max(angular, -cfg.max_angular_speed), cfg.max_angular_speed))
        self._command = (v, w)
        if v != linear or w != angular:
            return (f'command ({linear:g}, {angular:g}) clamped to ({v:g}, {w:g}): limits are '
                    f'linear [{slowest:g}, {cfg.max_linear_speed:g}] m/s, angular '
                    f'+-{cfg.max_angular_speed:g} rad/s')
        return None

    # -- planning ----------------------------------------------------------------------
    def plan_next(self) -> StepBlock:
        """
        Plan and commit the next block of frames (one step, or a short hold).

        Returns
        -------
        StepBlock
            The committed block on the actor's clock: a step, or a hold of ``hold_time`` s
            when the command is zero or no step can be taken.

        """
        started = _time.perf_counter()
        v, w = self._command
        if abs(v) < 1e-3 and abs(w) < 1e-3:
            if not self._stance.at_rest:
                block = self._settling_step(started)
                if block is None:
                    block = self._closing_step(started)
                if block is not None:
                    return block
            return self._hold('idle', '', started)
        # Nothing has changed since the last failed attempt: the answer is the same (§3.2,
        # the actor stays stuck until the user steers it somewhere else).
        if self._failure is not None and self._failure[0] == (self._steps, v, w):
            return self._stuck(self._failure[1], started, np.zeros((0, 4)), np.zeros((0, 3)))
        return self._walk_step(v, w, started)

    def _start_stance(self, x: float, y: float, yaw: float, sole: float) -> Stance:
        """
        Return the stance standing at (x, y, yaw), m and rad.

        Each foot rests on the ground under it, at its own height and pitch (``_sole_rest``),
        where both can; else both stand level at sole height ``sole``, m (the lowest ground
        under them: a start in an obstacle collides there and ``check_start`` says so).
        """
        level = standing_stance(self.skeleton, x, y, yaw, sole)
        leg = self.skeleton.leg
        feet = []
        for foot in level.feet:
            # On a slope the uphill foot stands higher than the lowest ground under both:
            # each foot rests near the lowest ground under itself.
            under = self.environment.lowest_ground(self._sole_points(
                foot.xy, foot.yaw, np.array([-leg.heel, leg.toe])).reshape(-1, 2))
            near = float(np.nanmin(under)) if np.isfinite(under).any() else sole
            rest = self._sole_rest(foot.xy, foot.yaw, near)
            if rest is None:
                return level
            feet.append(foot_pose_on(foot.xy, foot.yaw, rest[0], rest[1], leg))
        z = min(foot.z for foot in feet) + leg.thigh + leg.shank - 0.03
        return Stance(np.array([x, y, z, yaw]), (feet[0], feet[1]), level.stance_side, True)

    def _standing_configuration(self) -> np.ndarray:
        """
        Return the configuration of the initial stance, (22,) rad or m.

        The skeleton's neutral pose with the stance's pelvis, the legs reaching its feet and the
        arms in their motion pattern.
        """
        q = self.skeleton.neutral()
        q[self.skeleton.branch('root')] = self._stance.pelvis
        leg = self.skeleton.leg
        for side, name in ((LEFT, 'left_leg'), (RIGHT, 'right_leg')):
            foot = self._stance.feet[side]
            offset = leg.hip_half_width if side == LEFT else -leg.hip_half_width
            yaw = self._stance.pelvis[3]
            hip = np.array([[self._stance.pelvis[0] - np.sin(yaw) * offset,
                             self._stance.pelvis[1] + np.cos(yaw) * offset,
                             self._stance.pelvis[2]]])
            ankle = np.array([[foot.xy[0], foot.xy[1], foot.z]])
            joints, _, _ = leg_inverse_kinematics(leg, hip, ankle, np.array([foot.yaw]),
                                                  np.array([yaw]), np.array([foot.pitch]))
            q[self.skeleton.branch(name)] = joints[0]
        return self._with_patterns(q[None, :])[0]

    def _with_patterns(self, frames: np.ndarray) -> np.ndarray:
        return motion_patterns(self.skeleton, frames)

    def _hold(self, status: str, reason: str, started: float, footsteps=None,
              path=None) -> StepBlock:
        cfg = self.config
        times, frames = hold_frames(self._configuration, self._time, cfg.hold_time,
                                    cfg.frame_rate)
        self._stance = with_at_rest(self._stance, True)
        self._velocity = np.zeros_like(self._velocity)
        self._time = float(times[-1])
        self.status, self.reason = status, reason
        empty = np.zeros((0, 4)), np.zeros((0, 3))
        return StepBlock(status, reason, times, frames, np.zeros_like(frames),
                         empty[0] if footsteps is None else footsteps,
                         empty[1] if path is None else path,
                         _time.perf_counter() - started)

    def _commit(self, status: str, reason: str, times: np.ndarray, frames: np.ndarray,
                stance: Stance, footsteps: np.ndarray, path: np.ndarray, started: float,
                category: str) -> StepBlock:
        previous = np.concatenate([self._configuration[None, :], frames])
        velocities = (previous[1:] - previous[:-1]) * self.config.frame_rate
        absolute = self._time + times
        self._configuration = frames[-1].copy()
        self._velocity = velocities[-1].copy()
        self._stance = stance
        self._steps += 1
        self._time = float(absolute[-1])
        self.status, self.reason = status, reason
        return StepBlock(status, reason, absolute, frames, velocities, footsteps, path,
                         _time.perf_counter() - started, category)

    def _upper_body(self, times: np.ndarray, frames: np.ndarray):
        """Fill the motion patterns, then let the §5 planner make the upper body compliant."""
        frames = self._with_patterns(frames)
        if self._upper is None:
            return frames, True, ''
        # Continuity: frame 0 is the previous step's configuration, its planned upper body
        # included.
        k = frames.shape[0] + 1
        full = np.empty((k, frames.shape[1]))
        full[0] = self._configuration
        full[1:] = frames
        full_times = np.empty(k)
        full_times[0] = 0.0
        full_times[1:] = times
        # Receding horizon: plan over this step plus a preview of the pelvis carrying on, so
        # the waist starts to bend before an obstacle is reached; commit only this step.
        preview = self._preview(full_times, full)
        seeds = self._seeds(full_times if preview is None else preview[0])
        # Only passed when there are any (a planner given to the constructor may not take them).
        seeded = {'seeds': seeds} if seeds else {}
        self._preview_plan = None
        plan = None
        if preview is not None:
            plan = self._upper.plan(*preview, preview_from=k, **seeded)
            if plan.ok:
                # The next step starts at this one's last frame: this plan's rest seeds it, for
                # the branches that left their motion pattern (the others' preview holds the
                # pattern of legs that stop).
                searched = {}
                for name, record in plan.per_branch.items():
                    if not record['fast']:
                        columns = self.skeleton.branch(name)
                        searched[name] = (plan.frames[k - 1:, columns]
                                          - preview[1][k - 1:, columns])
                if searched:
                    self._preview_plan = (self._steps + 1,
                                          preview[0][k - 1:] - preview[0][k - 1], searched)
            margin = int(round(self.config.upper_body_preview_margin * self.config.frame_rate))
            if not plan.ok and k <= plan.blocked_frame < k + margin:
                # Blocked right after the step: the step's end is most likely a dead end (the
                # plan without the preview would take the step into it).
                return frames, False, f'{plan.reason}, just after the step'
        # Blocked within the step's own frames, the plan without the preview meets the same
        # obstacle there: only a block in the preview leaves it a chance.
        if plan is None or (not plan.ok and not 0 <= plan.blocked_frame < k):
            if seeds:
                seeded = {'seeds': {name: seed[:k] for name, seed in seeds.items()}}
            plan = self._upper.plan(full_times, full, **seeded)
        if not plan.ok:
            return frames, False, plan.reason
        return plan.frames[1:k], True, ''

    def _seeds(self, times: np.ndarray) -> dict:
        """
        Return the previous step's plan from where this step starts, where it still applies.

        It applies when this step directly follows that one (nothing else was committed in
        between) with the same frame times.

        Returns
        -------
        dict
            Branch name -> (s, d) deviations from the motion pattern, rad, s <= len(times).

        """
        if self._upper_seed is None or not self.config.upper_body_seed:
            return {}
        steps, seed_times, seeds = self._upper_seed
        count = min(len(seed_times), len(times))
        if (steps != self._steps or count < 2
                or not np.allclose(seed_times[:count], times[:count], rtol=0.0, atol=1e-9)):
            return {}
        return {name: seed[:count] for name, seed in seeds.items()}

    def _preview(self, times: np.ndarray, frames: np.ndarray):
        """
        Extend a step's frames by ``upper_body_preview`` s of the pelvis moving on.

        The preview is longer when that covers less than ``upper_body_preview_distance``, up to
        three times as long. Returns (times, frames), s and rad or m, with the preview's frames
        after the step's; None where there is no preview (``upper_body_preview`` 0, or fewer
        than three frames).
        """
        duration = self.config.upper_body_preview
        if duration <= 0 or frames.shape[0] < 3:
            return None
        dt = 1.0 / self.config.frame_rate
        root = self._root_columns
        span = min(frames.shape[0] - 1, int(round(0.2 * self.config.frame_rate)))
        velocity = (frames[-1, root] - frames[-1 - span, root]) / (span * dt)
        velocity[2] = 0.0
        # A slow walk sees less ground ahead in the same time: the waist bending under a low
        # beam must start when the head is still some way from it, whatever the speed.
        speed = float(np.hypot(velocity[0], velocity[1]))
        distance = self.config.upper_body_preview_distance
        if speed * duration < distance:
            duration = min(distance / max(speed, 1e-6), 3.0 * duration)
        count = int(round(duration * self.config.frame_rate))
        steps = np.arange(1, count + 1)[:, None] * dt
        extra = np.repeat(frames[-1:], count, axis=0)
        extra[:, root] = frames[-1, root] + velocity * steps
        extra = self._with_patterns(extra)
        return (np.concatenate([times, times[-1] + steps[:, 0]]), np.vstack([frames, extra]))

    def _verify(self, frames: np.ndarray) -> Optional[str]:
        """3D check of the legs against the environment at a subset of frames."""
        if not self.config.verify_collisions:
            return None
        index, links = self._collision.first_collision(frames, self._leg_links)
        if index < 0:
            return None
        depths = self._collision.penetration(frames[index], links)
        link, depth = max(depths.items(), key=lambda item: item[1])
        return (f'the legs would touch the environment: the {link.replace("_", " ")} would be '
                f'{max(1.0, 1e3 * depth):.0f} mm into an obstacle')

    def _walk_step(self, v: float, w: float, started: float) -> StepBlock:
        cfg = self.config
        # Backward (v <= -1e-3; a pure turn walks forward) the same stages run along the path
        # behind the actor, with the planner of backward windows; ``leg`` is the sole as that
        # path sees it, its heel leading.
        backward = v <= -1e-3
        if backward:
            fcfg, leg = self._backward_footstep_config, self._backward_leg
            planner = self._backward_planner
        else:
            fcfg, leg, planner = self._footstep_config, self.skeleton.leg, self._planner
        reversing = self._walked_backward is not None and self._walked_backward != backward
        if reversing and not self._stance.at_rest:
            # The pelvis moves the other way: the actor stops (feet side by side) first.
            block = self._closing_step(started, 'walking', '')
            if block is not None:
                return block
        stance = self._stance
        x, y, _, yaw = stance.pelvis
        horizon = fcfg.window_steps * fcfg.step_length_max + 1.0
        path = predict_path(x, y, yaw, v if backward else max(v, 0.0), w, horizon,
                            cfg.gait.min_turn_speed)
        stance_foot = stance.feet[stance.stance_side]
        swing_foot = stance.feet[1 - stance.stance_side]
        stance_s = path.project(stance_foot.xy)
        swing_s = path.project(swing_foot.xy)
        if reversing and stance.at_rest and swing_s > stance_s + REVERSAL_STAGGER:
            # From a standstill with the feet apart (stopped at an obstacle), the foot ahead in
            # the new direction of travel stays down: the one behind steps past it, instead of
            # the window drawing it back to a step length beside the other.
            stance = replace(stance, stance_side=1 - stance.stance_side)
            stance_foot, swing_foot = swing_foot, stance_foot
            stance_s, swing_s = swing_s, stance_s
        s_start = min(stance_s, swing_s) - leg.heel - 0.06
        s_end = stance_s + fcfg.window_steps * fcfg.step_length_max + leg.toe + 0.06
        # Side 0 of the profile is the left foot's track (right of a backward path).
        profile = sample_ground_profile(self.environment, path, s_start, s_end, 0.02,
                                        path.track_sign * leg.hip_half_width, leg.foot_width,
                                        stance_foot.sole, fcfg.max_step_up, fcfg.window_steps)
        path_points = self._path_points(path, s_end)
        s_init = float(min(max(self._walk.preferred_step_length(abs(v), cfg.nominal_step_time),
                               fcfg.step_length_min), fcfg.step_length_max))
        init_index = int(min(max(round((s_init - fcfg.step_length_min) / fcfg.step_increment),
                                 0), fcfg.step_intervals))
        start = None
        if self._window is not None and self._window_command == (v, w):
            # §4.2: slide the window by one step; the new last step starts at s_init.
            start = tuple(self._window.indices[1:]) + (init_index,)
        # The pelvis may turn at most max_heading_change per step (hip yaw range, §4).
        max_length = cfg.gait.max_heading_change / max(abs(path.curvature), 1e-9)
        if max_length < fcfg.step_length_min:
            max_length = fcfg.step_length_min
        reason = 'no collision-free footstep window' + (' behind the actor' if backward else '')
        banned, upper_failures = [], 0
        first_blocked = None  # the first footstep the upper body could not take
        for _ in range(cfg.max_attempts):
            window = planner.plan(profile, stance.stance_side, stance_s, stance_foot.sole,
                                  swing_s, swing_foot.sole, s_init, self._previous_length,
                                  start=start, banned_first=tuple(banned),
                                  max_length=max_length)
            if window is None:
                break
            footsteps = self._footstep_poses(path, window)
            try:
                motion = self._generate(stance, path, window, v)
            except GaitError as error:
                banned.append(window.indices[0])
                reason = f'the legs cannot take the step: {error}'
                start = None
                continue
            collision = self._verify(motion.frames)
            if collision is not None:
                banned.append(window.indices[0])
                reason = collision
                start = None
                continue
            follow = self._follow_failure(profile, stance, stance_s, path, window, motion, v,
                                          leg)
            if follow is not None:
                banned.append(window.indices[0])
                reason = follow
                start = None
                continue
            frames, ok, upper_reason = self._upper_body(motion.times, motion.frames)
            if not ok:
                # §3.2: the step is not taken; another footstep may leave the upper body time.
                reason = f'upper body blocked: {upper_reason}'
                upper_failures += 1
                if first_blocked is None:
                    first_blocked = (window, footsteps, motion)
                if upper_failures >= cfg.upper_body_attempts:
                    break
                banned.append(window.indices[0])
                start = None
                continue
            self._window, self._window_command = window, (v, w)
            self._previous_length = float(window.lengths[0])
            self._upper_seed = self._preview_plan
            self._walked_backward = backward
            return self._commit('walking', '', motion.times, frames, motion.stance, footsteps,
                                path_points, started, motion.category)
        if first_blocked is not None and cfg.upper_body_pause > 0:
            block = self._paused_step(stance, path, v, w, first_blocked, path_points, started)
            if block is not None:
                return block
        block = self._pivot_step(stance, v, w, started)
        if block is None and self.config.pivot_either_foot:
            # Both feet are down: the foot that landed last may swing instead (beside a
            # table's corner every move of the other leg swings its thigh into the edge).
            block = self._pivot_step(replace(stance, stance_side=1 - stance.stance_side), v, w,
                                     started)
        if block is not None:
            return block
        if reason.startswith('no collision-free footstep window') and ':' not in reason:
            why = describe_ground_ahead(self.environment, path, profile, stance_s + leg.toe,
                                        s_end, stance_foot.sole, fcfg, leg.hip_half_width,
                                        leg.foot_width, 'behind' if backward else 'ahead')
            reason += f': {why}' if why else ''
        self._failure = ((self._steps, v, w), reason)
        return self._stuck(reason, started, np.zeros((0, 4)), path_points)

    def _pivot_step(self, stance: Stance, v: float, w: float,
                    started: float) -> Optional[StepBlock]:
        """
        Commit a step turning the actor about its stance hip (see ``ActorConfig.pivot_turn``).

        The swing foot lands under its hip, the stance hip stays over the stance ankle and the
        pelvis turns to halfway between the feet. A foot on the turn's side (the left one in a
        left turn) lands turned from the stance foot, toes out, by ``pivot_turn`` or less (no
        faster than ``w``), else by half that; the other comes in parallel to the stance foot
        (turned in, the two would meet), else half-way or keeping its heading, and where only
        those turning the pelvis back are left, they are tried too, least first. Each landing is
        tried beside the stance foot, then along ``PIVOT_SHIFTS``, on the stance foot's level
        or the swinging foot's; the first the 3D check and the upper body accept is taken. Two
        pivots in a row turn the pelvis at least ``PIVOT_MIN_TURN`` on. None when the command
        is not a tight turn or no such step can be taken.
        """
        cfg, leg = self.config, self.skeleton.leg
        if cfg.pivot_turn <= 0 or abs(w) < 0.2 or abs(v) >= PIVOT_RADIUS * abs(w):
            return None
        foot = stance.feet[stance.stance_side]
        if abs(foot.pitch) > self._footstep_config.max_foot_pitch:
            return None
        swing_side = 1 - stance.stance_side
        toes_out = (swing_side == LEFT) == (w > 0)
        duration = self._walk.step_duration(0.3, 0.6, 0.0)
        # No faster than asked: the pelvis turns half the angle between the feet per step.
        spread = min(cfg.pivot_turn, 2.0 * abs(w) * duration)
        if toes_out:
            turns = (float(np.sign(w)) * spread, 0.5 * float(np.sign(w)) * spread)
        else:
            # From feet already apart (a V after an arc), coming all the way in parallel can
            # sweep the turning foot into the other: half-way, or keep its heading.
            now = float(stance.feet[swing_side].yaw - foot.yaw)
            turns = (0.0, 0.5 * now, now)
        offset = leg.hip_half_width if stance.stance_side == LEFT else -leg.hip_half_width
        # How far the pelvis, halfway between the feet, would turn with the command.
        direction = float(np.sign(w))
        heading = stance.pelvis[3]
        onward = {turn: direction * (foot.yaw + 0.5 * turn - heading) for turn in turns}
        tries = [turn for turn in turns if onward[turn] >= -1e-3]
        if not toes_out:
            # Feet in a V opened against the turn (a turn reversed mid-walk): keeping the
            # swing foot's heading turns the legs in, and squaring the feet turns the pelvis
            # back. Squaring them up is what lets the next step, the other foot's, turn toes
            # out: if nothing else can be taken the pelvis may turn back, least first.
            tries += sorted((turn for turn in turns if onward[turn] < -1e-3),
                            key=lambda turn: -onward[turn])
        if self._last_pivot is not None and self._last_pivot[0] == self._steps:
            # Two pivots in a row must turn the pelvis on: feet that can land only where the
            # heading stays (beside a stair's nosing) would otherwise step on the spot for ever.
            already = direction * (heading - self._last_pivot[1])
            tries = [turn for turn in tries if already + onward[turn] > PIVOT_MIN_TURN]
        # Beside the stance foot first; then a little ahead or behind it (beside a foot at a
        # stair's nosing, the other lands on the tread, not across the riser); last, turning
        # where it stands (a foot behind the other beside a table: its thigh need not swing
        # forward under the edge).
        for shift in PIVOT_SHIFTS:
            for turn in tries:
                motion = self._pivot_motion(stance, foot, turn, offset, duration, shift)
                if motion is None:
                    continue
                # A landing the 3D check or the upper body refuses (a thigh under a table's
                # edge) leaves the other landings to try.
                block = self._checked_step_to_rest(motion, started, 'walking', '', 'pivot')
                if block is not None:
                    self._last_pivot = (self._steps, heading)
                    return block
        return None

    def _checked_step_to_rest(self, motion: StepMotion, started: float, status: str,
                              reason: str, category: str) -> Optional[StepBlock]:
        """
        Commit a step that ends at rest off the footstep window (a pivot, a closing step).

        The step is committed once it is 3D-checked and its upper body planned; None when
        either fails.
        """
        if self._verify(motion.frames) is not None:
            return None
        frames, ok, _ = self._upper_body(motion.times, motion.frames)
        if not ok:
            return None
        self._window = None
        self._previous_length = 0.0
        return self._commit(status, reason, motion.times, frames,
                            with_at_rest(motion.stance, True), np.zeros((0, 4)),
                            np.zeros((0, 3)), started, category)

    def _pivot_motion(self, stance: Stance, foot, turn: float, offset: float,
                      duration: float, shift: Optional[float]) -> Optional[StepMotion]:
        """
        Generate the pivot's leg motion for one landing of the swing foot.

        The swing foot lands ``turn`` rad from the stance foot's heading and ``shift`` m ahead
        of it along the pelvis's new heading (None: as far ahead as the swinging foot stands);
        the pelvis ends halfway. None where the sole would not rest (``_sole_rest``) or the
        step cannot be made.
        """
        landing_yaw = foot.yaw + turn
        pelvis_yaw = 0.5 * (foot.yaw + landing_yaw)
        across = np.array([-np.sin(pelvis_yaw), np.cos(pelvis_yaw)])
        ahead = np.array([np.cos(pelvis_yaw), np.sin(pelvis_yaw)])
        if shift is None:
            beside = foot.xy - 2.0 * offset * across
            shift = float((stance.feet[1 - stance.stance_side].xy - beside) @ ahead)
        pelvis_xy = foot.xy - offset * across + 0.5 * shift * ahead
        landing_xy = pelvis_xy - offset * across + 0.5 * shift * ahead
        rest = self._sole_rest(landing_xy, landing_yaw, foot.sole)
        swing_sole = stance.feet[1 - stance.stance_side].sole
        if rest is None and abs(swing_sole - foot.sole) > 0.05:
            # Or on the level the swinging foot stands on (feet on two treads).
            rest = self._sole_rest(landing_xy, landing_yaw, swing_sole)
        if rest is None:
            return None
        sole, pitch = rest
        target = np.array([pelvis_xy[0], pelvis_xy[1], pelvis_yaw])
        if abs(sole - foot.sole) > 0.05:
            duration = self._walk.step_duration(0.3, 0.6, sole - foot.sole)
        try:
            return self._timed_step(stance, landing_xy, landing_yaw, sole, pitch, target,
                                    duration, to_rest=True)
        except GaitError:
            return None

    def _sole_points(self, xy: np.ndarray, yaw: float, lengths: np.ndarray) -> np.ndarray:
        """
        Return points under a sole at ankle ``xy`` heading ``yaw``, (len(lengths), 3, 2), m.

        The points lie at ``lengths`` (m, heel < 0) along the sole, each at its two edges and
        on its centre line.
        """
        along = np.array([np.cos(yaw), np.sin(yaw)])
        side = np.array([-along[1], along[0]])
        return (xy + lengths[:, None, None] * along
                + np.array([-0.5, 0.0, 0.5])[None, :, None] * self.skeleton.leg.foot_width * side)

    def _sole_rest(self, xy: np.ndarray, yaw: float, near: float):
        """
        Return (sole height under the ankle m, pitch rad) of a foot put down at ``xy``.

        The foot's ankle stands at ``xy`` heading ``yaw`` and its sole within 5 cm of sole
        height ``near``; None where it cannot rest.

        The ground under the sole's centre line and edges (heel, middle, toe): across the foot
        it rests on the highest point and must be flat within the footstep planner's
        ``flatness_tolerance``; along it a plane is fitted (no steeper than ``max_foot_pitch``)
        whose highest point it rests on, with no dip under it deeper than that tolerance. The
        3D check after this only looks for collisions.
        """
        leg, fcfg = self.skeleton.leg, self._footstep_config
        lengths = np.array([-leg.heel, 0.5 * (leg.toe - leg.heel), leg.toe])
        points = self._sole_points(xy, yaw, lengths)
        ground, _ = self.environment.ground_height(points.reshape(-1, 2), near + 0.05)
        if np.isnan(ground).any():
            return None
        ground = ground.reshape(3, 3)
        top = ground.max(axis=1)
        if (top - ground.min(axis=1)).max() > fcfg.flatness_tolerance:
            return None
        centred = lengths - lengths.mean()
        slope = float(centred @ top / (centred @ centred))
        if abs(np.arctan(slope)) > fcfg.max_foot_pitch:
            return None
        height = top - slope * lengths
        sole = float(height.max())
        if sole - float(height.min()) > fcfg.flatness_tolerance or abs(sole - near) > 0.05:
            return None
        return sole, float(np.arctan(slope))

    def _paused_step(self, stance: Stance, path, v: float, w: float, blocked, path_points,
                     started: float) -> Optional[StepBlock]:
        """
        Commit the footstep the upper body could not take, from a standstill after a pause.

        The step is generated again from rest (the pelvis eases in, as after a stop) and
        preceded by ``upper_body_pause`` s of the current configuration, during which the upper
        body may move while the rest of the body stands (§5's planner over the whole block).
        None when the upper body cannot take it this way either.
        """
        cfg = self.config
        window, footsteps, motion = blocked
        if not stance.at_rest:
            # From rest the pelvis eases in: another motion, generated and checked again.
            try:
                motion = self._generate(with_at_rest(stance, True), path, window, v)
            except GaitError:
                return None
            if self._verify(motion.frames) is not None:
                return None
        count = max(1, int(round(cfg.upper_body_pause * cfg.frame_rate)))
        pause = np.repeat(self._configuration[None, :], count, axis=0)
        times = np.concatenate([np.arange(1, count + 1) / cfg.frame_rate,
                                motion.times + count / cfg.frame_rate])
        frames, ok, _ = self._upper_body(times, np.vstack([pause, motion.frames]))
        if not ok:
            return None
        self._window, self._window_command = window, (v, w)
        self._previous_length = float(window.lengths[0])
        self._walked_backward = v <= -1e-3
        return self._commit('walking', '', times, frames, motion.stance, footsteps,
                            path_points, started, motion.category)

    def _stuck(self, reason: str, started: float, footsteps, path_points) -> StepBlock:
        self._window = None
        return self._hold('stuck', reason, started, footsteps, path_points)

    def _follow_failure(self, profile, stance: Stance, stance_s: float, path,
                        window: FootstepWindow, motion, v: float, leg) -> Optional[str]:
        """
        Return why the window's second footstep cannot follow this step, or None.

        Only where that footstep swings the other foot over ground (the profile's swing
        obstacle between the toe it lifts and the heel it lands) higher than its sole by
        ``follow_check_rise`` and than its landing by ``FOLLOW_OVER_LANDING``, and only its leg
        motion (the next window may choose another footstep; this one it starts from).
        ``leg``: the sole as the path sees it (heel and toe exchanged walking backward).
        """
        if window.arc_lengths.size < 2 or not self.config.check_follow:
            return None
        top = profile.swing_top(int(window.sides[1]), stance_s + leg.toe,
                                float(window.arc_lengths[1]) - leg.heel)
        # NaN (nothing to pass over) asks nothing. Up a flight the foot passes over the tread
        # between, lower than where it lands.
        if not top > max(stance.feet[stance.stance_side].sole + self.config.follow_check_rise,
                         float(window.heights[1]) + FOLLOW_OVER_LANDING):
            return None
        following = replace(window, lengths=window.lengths[1:], indices=window.indices[1:],
                            arc_lengths=window.arc_lengths[1:], heights=window.heights[1:],
                            pitches=window.pitches[1:], sides=window.sides[1:])
        try:
            self._generate(motion.stance, path, following, v, motion.frames[-1])
        except GaitError as error:
            return f'the legs cannot take the step: the other foot could not follow ({error})'
        return None

    def _generate(self, stance: Stance, path, window: FootstepWindow, v: float,
                  configuration: Optional[np.ndarray] = None):
        """
        Generate the leg motion of the window's first footstep from ``stance``.

        ``configuration`` is the frame it starts from, (22,) rad or m (default: the actor's
        current one).
        """
        leg = self.skeleton.leg
        s1 = float(window.arc_lengths[0])
        side = int(window.sides[0])
        offset = path.track_sign * (leg.hip_half_width if side == LEFT else -leg.hip_half_width)
        stance_s = s1 - float(window.lengths[0])
        # The landing foothold and heading and the middle of the step, from one call; the
        # headings the way the actor faces (against a backward path).
        poses = path.offset_poses(np.array([s1, 0.5 * (stance_s + s1)]), np.array([offset, 0.0]))
        poses[:, 2] += path.facing_offset
        landing_yaw = float(poses[0, 2])
        landing_xy = poses[0, :2]
        middle = poses[1]
        # The hip yaw range bounds how far the feet may point apart (a turn reversed mid-walk):
        # the new foot turns at most that far from the stance foot, and much less towards it
        # (max_toe_in); the path catches up.
        stance_yaw = stance.feet[stance.stance_side].yaw
        limit = 1.5 * float(self.skeleton.upper[self.skeleton.index['left_hip_yaw']])
        toe_in = min(self.config.max_toe_in, limit)
        low, high = (-toe_in, limit) if side == LEFT else (-limit, toe_in)
        turn = float(min(max((landing_yaw - stance_yaw + np.pi) % (2 * np.pi) - np.pi,
                             low), high))
        landing_yaw = stance_yaw + turn
        middle[2] = stance_yaw + 0.5 * turn
        rise = float(window.heights[0]) - stance.feet[stance.stance_side].sole
        duration = self._walk.step_duration(float(window.lengths[0]), abs(v), rise)
        # The window's pitch rises along the path: towards the heel on a backward one.
        pitch = -float(window.pitches[0]) if path.backward else float(window.pitches[0])
        return self._timed_step(stance, landing_xy, landing_yaw, float(window.heights[0]),
                                pitch, middle, duration, configuration=configuration)

    def _timed_step(self, stance, landing_xy, landing_yaw, sole, pitch, target, duration,
                    to_rest=False, configuration=None):
        """Generate a step, slowing it down until every joint respects its speed limit."""
        rate = self.config.frame_rate
        if configuration is None:
            configuration = self._configuration
        for _ in range(3):
            motion = self._walk.step(stance, landing_xy, landing_yaw, sole, pitch, target,
                                     duration, self._obstacles, to_rest=to_rest)
            lower = self._lower_body
            frames = np.concatenate([configuration[None, lower], motion.frames[:, lower]])
            # np.diff without its wrapper: the same differences.
            speed = np.abs(frames[1:] - frames[:-1]) * rate / self._lower_velocity_limit
            ratio = float(speed.max())
            if ratio <= 0.95:
                self._check_landing(motion.stance.feet[1 - stance.stance_side], landing_xy)
                return motion
            duration = np.ceil(duration * ratio / 0.85 * rate) / rate
        raise GaitError(f'step needs joint speeds {ratio:.2f} x the limits')

    def _check_landing(self, foot, planned_xy: np.ndarray) -> None:
        """
        Raise GaitError if a foot that landed away from its planned foothold is not resting.

        Without hip roll a foot lands where its hip's plane allows: in a tight turn whose
        landing heading is bounded (``max_toe_in``) that can be tens of centimetres from the
        foothold the footstep planner judged, and off a block's side it landed at the block's
        height over the floor, with no foot down at the next lift-off. A landing more than
        ``LANDING_DRIFT`` from its foothold is judged again where it is, by the footstep
        planner's rule for a sole at an edge: ground within ``flatness_tolerance`` under the
        ankle and under ``min_support_fraction`` of the sole (points 3 across, 7 along; higher
        ground is left to the 3D check).
        """
        if float(np.hypot(*(foot.xy - planned_xy))) <= LANDING_DRIFT:
            return
        leg, fcfg = self.skeleton.leg, self._footstep_config
        lengths = np.linspace(-leg.heel, leg.toe, 7)
        points = self._sole_points(foot.xy, foot.yaw, lengths)
        sole = foot.sole + lengths * np.tan(foot.pitch)
        ground, _ = self.environment.ground_height(points.reshape(-1, 2), foot.sole + 0.05)
        with np.errstate(invalid='ignore'):
            # NaN (no ground there) supports nothing.
            supported = ground.reshape(7, 3) >= sole[:, None] - fcfg.flatness_tolerance
        ankle = int(np.abs(lengths).argmin())
        if not supported[ankle, 1] or supported.mean() < fcfg.min_support_fraction:
            raise GaitError('the landing foot would not rest on the ground where its hip '
                            'puts it')

    def _settling_step(self, started: float) -> Optional[StepBlock]:
        """
        Stop in the split stance the last step landed in, or None where it is not stable.

        The pelvis keeps its height and slows from its velocity at the step's end to rest over
        ``SETTLE_TIME`` with both feet still; the stance is held when the ankles stand
        ``SPLIT_STANCE_LENGTHS`` apart along the heading and the settled pelvis
        stands within ``SPLIT_STANCE_RANGE`` of the way between them (its weight over the
        support of both feet). Each leg keeps its last frame's joints plus the change of its
        inverse kinematics as the hip moves, so the first frame follows on from the last.
        """
        stance, skeleton = self._stance, self.skeleton
        cfg, leg, index = self.config, skeleton.leg, skeleton.index
        q0 = self._configuration
        x0, y0, z0, yaw0 = (float(q0[index[name]]) for name in
                            ('root_x', 'root_y', 'root_z', 'root_yaw'))
        velocity = self._velocity[[index['root_x'], index['root_y'], index['root_yaw']]]
        k = max(1, int(round(SETTLE_TIME * cfg.frame_rate)))
        tau = np.arange(1, k + 1) / k
        # The velocity falls linearly to 0: the pelvis travels half as far as at full speed.
        travel = k / cfg.frame_rate * (tau - 0.5 * tau ** 2)
        x = x0 + velocity[0] * travel
        y = y0 + velocity[1] * travel
        yaw = yaw0 + velocity[2] * travel
        rear, front = sorted(stance.feet, key=lambda foot: float(
            foot.xy @ np.array([np.cos(yaw0), np.sin(yaw0)])))
        apart = front.xy - rear.xy
        length = float(np.hypot(*apart))
        heading = np.array([np.cos(yaw[-1]), np.sin(yaw[-1])])
        if not SPLIT_STANCE_LENGTHS[0] <= abs(float(apart @ heading)) <= \
                SPLIT_STANCE_LENGTHS[1]:
            return None
        fraction = float((np.array([x[-1], y[-1]]) - rear.xy) @ apart) / length ** 2
        if not SPLIT_STANCE_RANGE[0] <= fraction <= SPLIT_STANCE_RANGE[1]:
            return None
        frames = np.repeat(q0[None, :], k, axis=0)
        frames[:, index['root_x']], frames[:, index['root_y']] = x, y
        frames[:, index['root_yaw']] = yaw
        for side, name in ((LEFT, 'left_leg'), (RIGHT, 'right_leg')):
            foot = stance.feet[side]
            offset = leg.hip_half_width if side == LEFT else -leg.hip_half_width
            hips_x = np.concatenate([[x0], x]) - np.sin(np.concatenate([[yaw0], yaw])) * offset
            hips_y = np.concatenate([[y0], y]) + np.cos(np.concatenate([[yaw0], yaw])) * offset
            hips = np.column_stack([hips_x, hips_y, np.full(k + 1, z0)])
            ankles = np.repeat([[foot.xy[0], foot.xy[1], foot.z]], k + 1, axis=0)
            joints, _, reach = leg_inverse_kinematics(
                leg, hips, ankles, np.full(k + 1, foot.yaw), np.concatenate([[yaw0], yaw]),
                np.full(k + 1, foot.pitch))
            if not np.isfinite(joints).all() or float(reach.max()) > 1.0:
                return None
            columns = skeleton.branch(name)
            frames[:, columns] = q0[columns] + joints[1:] - joints[0]
        if np.any(frames < skeleton.lower - 1e-9) or np.any(frames > skeleton.upper + 1e-9):
            return None
        settled = Stance(np.array([x[-1], y[-1], z0, yaw[-1]]), stance.feet, stance.stance_side,
                         True)
        motion = StepMotion(tau * k / cfg.frame_rate, frames, settled, 'settling', 0.0, 0.0)
        return self._checked_step_to_rest(motion, started, 'idle', 'stopping', 'settling')

    def _closing_step(self, started: float, status: str = 'idle',
                      reason: str = 'stopping') -> Optional[StepBlock]:
        """
        Bring the feet side by side when the command stops, or before walking the other way.

        So the actor stops within a step. ``status`` and ``reason`` are those of the committed
        block; None where no closing step can be taken, or none is needed.
        """
        leg = self.skeleton.leg
        stance = self._stance
        foot = stance.feet[stance.stance_side]
        swing_side = 1 - stance.stance_side
        offset = 2 * (leg.hip_half_width if swing_side == LEFT else -leg.hip_half_width)
        landing_xy = foot.xy + offset * np.array([-np.sin(foot.yaw), np.cos(foot.yaw)])
        sole = foot.sole
        middle_xy = foot.xy + 0.5 * (landing_xy - foot.xy)
        target = np.array([middle_xy[0], middle_xy[1], foot.yaw])
        ground, _ = self.environment.ground_height(landing_xy[None, :], sole + 0.05)
        if np.isnan(ground[0]) or abs(ground[0] - sole) > 0.01 or abs(foot.pitch) > 0.05:
            return None
        swing = stance.feet[swing_side]
        distance = float(np.linalg.norm(swing.xy - landing_xy))
        if distance < 0.02:
            self._stance = with_at_rest(stance, True)
            return None
        duration = self._walk.step_duration(max(distance, 0.3), 0.6, abs(swing.sole - sole))
        try:
            motion = self._timed_step(stance, landing_xy, foot.yaw, sole, 0.0, target, duration,
                                      to_rest=True)
        except GaitError:
            return None
        return self._checked_step_to_rest(motion, started, status, reason, 'closing')

    def _obstacles(self, xy: np.ndarray, z_ref: float) -> np.ndarray:
        """Heights a swinging sole must clear at ``xy`` (NaN over empty space)."""
        height, _ = self.environment.ground_height(xy, z_ref)
        missing = np.isnan(height)
        if missing.any():
            top, _ = self.environment.ground_height(xy[missing], z_ref + 3.0)
            height[missing] = top
        return height

    def _footstep_poses(self, path, window: FootstepWindow) -> np.ndarray:
        leg = self.skeleton.leg
        offsets = np.where(window.sides == LEFT, leg.hip_half_width, -leg.hip_half_width)
        poses = path.offset_poses(window.arc_lengths, path.track_sign * offsets)
        out = np.empty((window.arc_lengths.size, 4))
        out[:, :2] = poses[:, :2]
        out[:, 2] = window.heights
        out[:, 3] = poses[:, 2] + path.facing_offset
        return out

    def _path_points(self, path, s_end: float) -> np.ndarray:
        # np.linspace(0, end, 24) without its overhead: the same values.
        end = max(s_end, 0.1)
        s = self._path_steps * (end / 23)
        s[-1] = end
        out = path.poses(s)
        out[:, 2] = self._stance.feet[0].sole
        return out


def run_commands(actor: Actor, times, linear, angular, on_warning=None):
    """
    Drive an actor with a timed command stream until the stream's end time.

    Each command holds from its time until the next one (as a mouse teleop's stream would);
    the last time is the end of the run. Blocks are planned back to back, each with the command
    in force at its start.

    Parameters
    ----------
    actor
        The actor to drive (its clock is used as is).
    times, linear, angular
        (c,) command times (s, increasing), forward speeds (m/s) and turn rates (rad/s).
    on_warning
        Optional callable (index, message) told when a command had to be clamped.

    Returns
    -------
    list of StepBlock

    """
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or np.any(np.diff(times) <= 0):
        raise ValueError(f'command times must be a non-empty increasing sequence, got {times}')
    blocks, row, warned = [], 0, set()
    while actor.time < times[-1] - 1e-9:
        while row + 1 < times.size and times[row + 1] <= actor.time + 1e-9:
            row += 1
        active = times[row] <= actor.time + 1e-9
        warning = actor.set_command(float(linear[row]) if active else 0.0,
                                    float(angular[row]) if active else 0.0)
        if warning and active and row not in warned and on_warning is not None:
            warned.add(row)
            on_warning(row, warning)
        blocks.append(actor.plan_next())
    return blocks
