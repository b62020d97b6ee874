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
The footstep window's effort written out plainly, in Python on lists.

The reference the compiled search (``core/footstep_search.py``) is tested against, term by term and
bit for bit.

Each function takes the ``FootstepPlanner`` whose settings and table layout it reads.
"""
from dataclasses import dataclass, field
import math
from typing import Dict, List, Optional, Tuple

import numpy as np


@dataclass
class Tables:
    """
    The window's footholds and a memo of swing tests as Python lists, for :func:`effort`.

    ``ok[i][c]``, ``height[i][c]``, ``pitch[i][c]``: the foothold of footstep i when the
    interval indices of footsteps 1..i+1 sum to c (its arc length depends only on that sum).
    ``obstacle[side]``: the profile's swing obstacle heights as a list, -inf over empty space
    (so a range maximum over a slice is the swing test's).
    ``reach``: the swing test's numbers as plain floats (sole toe and heel, the profile's first
    arc length, spacing and last sample index, the swing height limit), read once per plan.
    ``rise_ahead[(i, c)]``: how far the ground within ``lift_room`` ahead of that foothold's
    toe rises above its sole's plane, m (-inf where it does not; see ``FootstepConfig``),
    filled in by :func:`rise_ahead_at` for the footholds a swing leaves from.
    ``stance_s``, ``sides``: the window's stance arc length (m) and footstep sides.
    """

    ok: List[list]
    height: List[list]
    pitch: List[list]
    obstacle: Tuple[list, list] = ((), ())
    reach: tuple = ()
    stance_s: float = 0.0
    sides: tuple = ()
    rise_ahead: Dict[Tuple[int, int], float] = field(default_factory=dict)
    swings: Dict[tuple, bool] = field(default_factory=dict)


def search_tables(planner, profile, sides, stance_s) -> Tables:
    """Every foothold the window can reach, evaluated in one batch."""
    step, offsets, bounds = planner._table_layout
    ok, height, pitch = planner.footholds(profile, sides[step], stance_s + offsets)
    ok, height, pitch = ok.tolist(), height.tolist(), pitch.tolist()
    rows = list(zip(bounds[:-1], bounds[1:]))
    obstacle = np.where(np.isnan(profile.obstacle), -np.inf, profile.obstacle).tolist()
    return Tables(ok=[ok[a:b] for a, b in rows], height=[height[a:b] for a, b in rows],
                  pitch=[pitch[a:b] for a, b in rows],
                  stance_s=stance_s, sides=tuple(int(side) for side in sides),
                  obstacle=(obstacle[0], obstacle[1]),
                  reach=(float(planner.leg.toe), float(planner.leg.heel), float(profile.s0),
                         float(profile.ds), profile.samples - 1,
                         float(planner.config.max_swing_height)))


def swing_clear_in(planner, memo: Tables, side: int, s_from: float, h_from: float,
                   s_to: float, h_to: float, lifts_from: Optional[Tuple[int, int]] = None
                   ) -> bool:
    """
    Whether a foot can swing from one foothold to the next over the ground profile.

    ``lifts_from``: (row, cumulative index) of the foothold it leaves when the window placed
    it there; that foothold must also let it lift off (see ``FootstepConfig.lift_room``).
    Reads the search's per-side obstacle lists (``memo``), not NumPy arrays: it runs for
    every new swing the search visits.
    """
    toe, heel, s0, ds, last, max_swing = memo.reach
    i0 = max(math.floor((s_from + toe - s0) / ds), 0)
    i1 = min(math.ceil((s_to - heel - s0) / ds), last)
    # -inf (empty space) passes: there is nothing to hit.
    if i1 >= i0 and max(memo.obstacle[side][i0:i1 + 1]) > max(h_from, h_to) + max_swing:
        return False
    if lifts_from is None:
        return True
    cfg = planner.config
    return (rise_ahead_at(planner, memo, *lifts_from)
            <= min(cfg.lift_rise + max(h_to - h_from, 0.0), cfg.lift_step_up))


def rise_ahead_at(planner, memo: Tables, row: int, cumulative: int) -> float:
    """
    Return ``FootstepPlanner.rise_ahead`` of one foothold, in plain Python.

    ``FootstepPlanner.rise_ahead`` of one foothold of the table (row ``row``, cumulative interval
    index ``cumulative``), in plain Python on the lists and remembered. The same arithmetic as
    ``rise_ahead``, so the same value.
    """
    key = (row, cumulative)
    value = memo.rise_ahead.get(key)
    if value is not None:
        return value
    height = memo.height[row][cumulative]
    if height != height:  # NaN: no foothold there
        memo.rise_ahead[key] = math.nan
        return math.nan
    if planner.config.lift_room <= 0:
        memo.rise_ahead[key] = -math.inf
        return -math.inf
    toe, _, s0, ds, last, _ = memo.reach
    s = memo.stance_s + float(planner._table_layout[1][planner._table_layout[2][row] + cumulative])
    first = math.floor((s + toe - s0) / ds + 1e-9)
    end = math.floor((s + (toe + planner.config.lift_room) - s0) / ds + 1e-9)
    slope = math.tan(memo.pitch[row][cumulative])
    obstacle = memo.obstacle[memo.sides[row]]
    value = -math.inf
    for j in range(first + 1, end + 1):
        j = min(max(j, 0), last)
        past = obstacle[j]
        if past != -math.inf:
            value = max(value, past - slope * (s0 + ds * j - s) - height)
    memo.rise_ahead[key] = value
    return value


def plain_effort(planner, profile, config, lengths, sides, stance_s, stance_height, swing_s,
                 swing_height, s_init, previous_length, memo, banned) -> Optional[float]:
    """
    Return the effort of a footstep configuration, or None if it collides.

    Effort of a footstep configuration, or None if it is not collision-free: each footstep from the
    stance foot on, each swing from where that foot was (``memo.swings`` remembers the swing
    tests).
    """
    cfg = planner.config
    if config[0] in banned:
        return None
    up, down = cfg.max_step_up, cfg.max_step_down
    # Where each foot was before its step: an index into ``placed`` (-2 swing, -1 stance).
    placed = {-2: (swing_s, swing_height), -1: (stance_s, stance_height)}
    s, height_before, total, length_before = stance_s, stance_height, 0.0, previous_length
    cumulative = 0
    previous_key = {sides[0]: -2, 1 - sides[0]: -1}
    for i, j in enumerate(config):
        length = lengths[j]
        s += length
        cumulative += j
        side = sides[i]
        key = (i, cumulative)
        if not memo.ok[i][cumulative]:
            return None
        hold_height = memo.height[i][cumulative]
        rise = hold_height - height_before
        if rise > up or -rise > down:
            return None
        origin = previous_key[side]
        swing_key = (origin, key)
        clear = memo.swings.get(swing_key)
        if clear is None:
            s_from, h_from = placed[origin]
            clear = swing_clear_in(planner, memo, side, s_from, h_from, s, hold_height,
                                   None if origin in (-2, -1) else origin)
            memo.swings[swing_key] = clear
        if not clear:
            return None
        total += step_effort(planner, length, rise, memo.pitch[i][cumulative], length_before,
                             s_init)
        placed[key] = (s, hold_height)
        previous_key[side] = key
        height_before, length_before = hold_height, length
    return total


def step_effort(planner, length, rise, pitch, length_before, s_init) -> float:
    """
    Return one footstep's share of the effort.

    One footstep's share of the effort: length off the neutral one, height change, sole pitch and
    change of length, each normalised by its range.
    """
    w_length, w_height, w_pitch, w_smooth, span, up, pitch_range = planner._effort_terms
    return (w_length * ((length - s_init) / span) ** 2
            + w_height * (rise / up) ** 2
            + w_pitch * (pitch / pitch_range) ** 2
            + w_smooth * ((length - length_before) / span) ** 2)
