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
`digital-actor` command line: offline simulation, the interactive demo and the viewer.

Argument parsing, files and pictures live here, not in the core. Exit codes: 0 success, 1 a run
failed (its outputs could not be written), 2 bad input (a message names the file, line, value or
output path; nothing was planned), 130 interrupted. Outputs appear only when complete, all
together: an existing file is replaced only by a complete one.
"""
from __future__ import annotations

import argparse
import csv
from dataclasses import dataclass
import importlib.util
import json
import math
import os
import shutil
import stat
import sys
import tempfile
import time
from typing import List, Optional, Sequence

import numpy as np

EXIT_BAD_INPUT = 2


class InputError(ValueError):
    """Bad user input; the message names the file, line or value."""


@dataclass(frozen=True)
class CommandRow:
    """
    One row of a command file: a command from a time on.

    One row of a command file: from ``time`` on (s), walk at ``linear_x`` m/s and turn at
    ``angular_z`` rad/s; ``line`` is the row's line number in the file.
    """

    time: float
    linear_x: float
    angular_z: float
    line: int


def read_commands(path: str) -> List[CommandRow]:
    """
    Read a command CSV (header ``time,linear_x,angular_z``); each row holds until the next.

    Raises
    ------
    InputError
        Missing file, wrong header, malformed or non-finite numbers, times not increasing.

    """
    try:
        # utf-8-sig: spreadsheet programs start a CSV with a byte-order mark.
        with open(path, newline='', encoding='utf-8-sig') as f:
            rows = list(csv.reader(f))
    except OSError as error:
        raise InputError(f'{path}: cannot read command file: {error.strerror or error}') from None
    except UnicodeDecodeError:
        raise InputError(f'{path}: not a text CSV file') from None
    rows = [(i + 1, r) for i, r in enumerate(rows) if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError(f'{path}: empty command file')
    header = [c.strip() for c in rows[0][1]]
    if header != ['time', 'linear_x', 'angular_z']:
        raise InputError(f'{path}:{rows[0][0]}: header must be time,linear_x,angular_z, '
                         f'got {",".join(header)}')
    commands: List[CommandRow] = []
    for line, row in rows[1:]:
        if len(row) != 3:
            raise InputError(f'{path}:{line}: expected 3 values, got {len(row)}: {row}')
        try:
            values = [float(c) for c in row]
        except ValueError:
            raise InputError(f'{path}:{line}: not a number in {row}') from None
        if not all(math.isfinite(v) for v in values):
            raise InputError(f'{path}:{line}: non-finite value in {row}')
        if values[0] < 0 or (commands and values[0] <= commands[-1].time):
            raise InputError(f'{path}:{line}: time {values[0]:g} must be >= 0 and increase')
        commands.append(CommandRow(values[0], values[1], values[2], line))
    if not commands:
        raise InputError(f'{path}: no command rows after the header')
    return commands


#: What ``--render`` can write, by file name extension.
RENDER_FORMATS = ('.png', '.gif')
#: ``--out`` ending so is a rosbag2 bag with MCAP storage (a folder, as ``ros2 bag record``
#: makes), not a CSV file.
BAG_SUFFIX = '.mcap'


class _Outputs:
    """
    The output files of one run: checked before planning, put in place together at the end.

    Each output is first a hidden temporary beside its final path, created when it is
    checked, so that a path that cannot be written fails before any planning. Nothing
    replaces an existing file until every output is complete; an error or Ctrl-C leaves the
    existing files as they were and no temporary files behind.
    """

    def __init__(self, inputs: Sequence[str] = ()):
        self._inputs = {os.path.realpath(p): p for p in inputs}
        self._pending: List[tuple] = []  # (temporary, final path, is a bag)
        self._created_folders: List[str] = []

    def add(self, path: str, option: str, bag: bool = False,
            formats: Sequence[str] = ()) -> str:
        """
        Check ``path`` and return where to write it instead, until :meth:`publish`.

        A file gets a temporary file with the same extension; a bag (a folder that must not
        exist yet) gets a path inside a temporary folder, named like the bag without its
        extension (the bag's MCAP file is named after it). ``formats``, if given, are the
        file name extensions allowed.

        Raises
        ------
        InputError
            The path is a directory (or, for a bag, exists), has an extension not in
            ``formats``, is an input of the run, is named twice, or cannot be written.

        """
        if bag:
            path = os.path.normpath(path)  # 'run.mcap/' names the folder 'run.mcap'
        real = os.path.realpath(path)
        if bag and os.path.lexists(path):
            raise InputError(f'{option} {path}: exists already (a bag is never overwritten)')
        if os.path.isdir(path):
            raise InputError(f'{option} {path}: is a directory')
        extension = os.path.splitext(path)[1].lower()
        if formats and extension not in formats:
            raise InputError(f'{option} {path}: writes {" or ".join(formats)}, not '
                             f'{extension or "a file without an extension"}')
        if real in self._inputs:
            raise InputError(f'{option} {path}: would overwrite the input {self._inputs[real]}')
        if any(os.path.realpath(final) == real for _, final, _ in self._pending):
            raise InputError(f'{option} {path}: named for two outputs')
        folder = os.path.dirname(os.path.abspath(path))
        missing = []
        parent = folder
        while not os.path.lexists(parent):
            missing.append(parent)
            parent = os.path.dirname(parent)
        name = os.path.basename(path)
        try:
            os.makedirs(folder, exist_ok=True)
            self._created_folders.extend(missing)
            if bag:
                temporary = tempfile.mkdtemp(prefix=f'.{name}.', dir=folder)
            else:
                handle, temporary = tempfile.mkstemp(prefix=f'.{name}.', dir=folder,
                                                     suffix=os.path.splitext(path)[1])
                os.close(handle)
        except OSError as error:
            raise InputError(f'{option} {path}: cannot write: '
                             f'{error.strerror or error}') from None
        self._pending.append((temporary, path, bag))
        return os.path.join(temporary, os.path.splitext(name)[0]) if bag else temporary

    def publish(self) -> None:
        """Give each output its final name; a new file gets the mode the umask allows."""
        umask = os.umask(0)
        os.umask(umask)
        for temporary, path, bag in self._pending:
            if bag:
                continue
            try:
                mode = stat.S_IMODE(os.stat(path).st_mode)  # replacing: keep its mode
            except OSError:
                mode = 0o666 & ~umask
            os.chmod(temporary, mode)
        for temporary, path, bag in self._pending:
            if bag:
                inner = os.path.join(temporary, os.path.splitext(os.path.basename(path))[0])
                os.rename(inner, path)
                os.rmdir(temporary)
            else:
                os.replace(temporary, path)
        self._pending = []
        self._created_folders = []

    def discard(self) -> None:
        """Remove the temporaries not yet published, and folders made for them if empty."""
        for temporary, _, bag in self._pending:
            if bag:
                shutil.rmtree(temporary, ignore_errors=True)
                continue
            for leftover in (temporary, _render_partial(temporary)):
                try:
                    os.remove(leftover)
                except FileNotFoundError:
                    pass
        self._pending = []
        for folder in self._created_folders:  # deepest first
            try:
                os.rmdir(folder)
            except OSError:
                break
        self._created_folders = []


def _render_partial(path: str) -> str:
    # The renderer writes <base>.partial<extension> and renames it: see evaluation.render.
    base, extension = os.path.splitext(path)
    return f'{base}.partial{extension}'


def simulate(args) -> int:
    """Run ``digital-actor simulate``."""
    outputs = _Outputs(inputs=(args.scene, args.commands))
    try:
        return _simulate(args, outputs)
    finally:
        outputs.discard()  # whatever was not put in place: an error or Ctrl-C


def _simulate(args, outputs: '_Outputs') -> int:
    from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands, validate
    from digital_actor_planner.core.scene import load_scene, SceneError
    from digital_actor_planner.core.footsteps import FootstepConfig
    from digital_actor_planner.core.gait import GaitConfig
    from digital_actor_planner.core.skeleton import Skeleton

    skeleton = Skeleton()
    try:
        # Every output is checked (and its temporary made) before the long part: planning.
        bag = args.out.lower().endswith(BAG_SUFFIX)
        if bag and importlib.util.find_spec('rosbags') is None:
            raise InputError(f'--out {args.out}: writing a bag needs the rosbags package '
                             '(pip install -r requirements.txt)')
        out = outputs.add(args.out, '--out', bag=bag)
        summary_file = outputs.add(args.summary, '--summary') if args.summary else None
        render_file = (outputs.add(args.render, '--render', formats=RENDER_FORMATS)
                       if args.render else None)
        commands = read_commands(args.commands)
        scene = load_scene(args.scene, skeleton)
        options = ('window_steps', 'step_intervals', 'step_length_min', 'step_length_max')
        given = {name: getattr(args, name) for name in options
                 if getattr(args, name) is not None}
        rate = {} if args.rate is None else {'frame_rate': args.rate}
        config = ActorConfig(plan_upper_body=not args.no_upper_body,
                             footsteps=FootstepConfig(greedy_restart=not args.paper_search,
                                                      **given),
                             gait=GaitConfig(**rate))
        validate(config)
    except (InputError, SceneError, ValueError) as error:
        print(f'digital-actor simulate: error: {error}', file=sys.stderr)
        return EXIT_BAD_INPUT

    actor = Actor(skeleton, scene.environment, config, start=scene.start)
    events = []
    wall_start = time.perf_counter()

    def warn(row, message):
        print(f'digital-actor simulate: warning: {args.commands}:{commands[row].line}: {message}',
              file=sys.stderr)

    blocks = run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                          [c.angular_z for c in commands], on_warning=warn)
    for block in blocks:
        if block.status != 'stuck':
            continue
        if (not events or events[-1]['reason'] != block.reason
                or events[-1]['end'] < block.times[0] - 1.5 / config.frame_rate):
            events.append({'time': round(float(block.times[0]), 3), 'reason': block.reason,
                           'end': float(block.times[-1])})
        else:
            events[-1]['end'] = float(block.times[-1])
    wall = time.perf_counter() - wall_start
    times = np.concatenate([b.times for b in blocks]) if blocks else np.zeros(0)
    frames = np.vstack([b.frames for b in blocks]) if blocks else np.zeros((0, 22))
    steps = [b for b in blocks if b.status == 'walking']
    planning = [b.planning_time for b in steps]
    summary = {
        'scene': os.path.abspath(args.scene), 'commands': os.path.abspath(args.commands),
        'frames': int(times.size), 'simulated_time': float(times[-1]) if times.size else 0.0,
        'wall_time': wall,
        'real_time_factor': (float(times[-1]) / wall) if times.size and wall > 0 else None,
        'steps_taken': len(steps),
        'step_categories': {c: sum(1 for b in steps if b.category == c)
                            for c in ('level', 'uphill', 'downhill')},
        'planning_time_per_step': planning,
        'planning_time_p50': float(np.percentile(planning, 50)) if planning else None,
        'planning_time_p99': float(np.percentile(planning, 99)) if planning else None,
        'stuck_events': [{'time': e['time'], 'until': round(e['end'], 3), 'reason': e['reason']}
                         for e in events],
        'final_status': actor.status, 'final_reason': actor.reason,
        'final_pose': {n: float(v) for n, v in zip(skeleton.joint_names[:4],
                                                   actor.configuration[:4])},
        'window_steps': config.footsteps.window_steps,
        'step_intervals': config.footsteps.step_intervals,
        'greedy_restart': config.footsteps.greedy_restart,
    }
    try:
        if bag:
            from digital_actor_planner.recording import write_bag
            with open(skeleton.urdf_path) as urdf:
                description = urdf.read()
            write_bag(out, skeleton.joint_names, times, frames, blocks,
                      robot_description=description, meshes=scene.environment.meshes)
        else:
            _write_trajectory(out, skeleton.joint_names, times, frames)
        if summary_file:
            with open(summary_file, 'w') as f:
                json.dump(summary, f, indent=2)
        if render_file:
            from digital_actor_planner.evaluation import render
            footsteps = _landed_feet(skeleton, frames)
            if render_file.lower().endswith('.gif'):
                render.render_gif(render_file, skeleton, scene.environment.meshes, times,
                                  frames, footsteps=footsteps)
            else:
                render.render_png(render_file, skeleton, scene.environment.meshes, times,
                                  frames, footsteps=footsteps, title=os.path.basename(args.scene))
        outputs.publish()
    except (OSError, ValueError) as error:
        print(f'digital-actor simulate: error: cannot write the outputs: {error}',
              file=sys.stderr)
        return 1
    simulated = float(times[-1]) if times.size else 0.0
    print(f'{os.path.basename(args.scene)}: {len(steps)} steps, {simulated:.2f}'
          f' s simulated in {wall:.2f} s, final status {actor.status}'
          + (f' ({actor.reason})' if actor.reason else ''))
    return 0


def _landed_feet(skeleton, frames: np.ndarray) -> np.ndarray:
    """(f, 4) x, y, z, yaw of the distinct places the feet rested on, for pictures."""
    if frames.shape[0] == 0:
        return np.zeros((0, 4))
    transforms = skeleton.forward_kinematics(frames[::5])
    feet = []
    for link in ('left_foot', 'right_foot'):
        t = transforms[:, skeleton.link_index[link]]
        positions = t[:, :3, 3]
        yaws = np.arctan2(t[:, 1, 0], t[:, 0, 0])
        last = None
        for p, yaw in zip(positions, yaws):
            if last is None or np.linalg.norm(p[:2] - last[:2]) > 0.1:
                feet.append([p[0], p[1], p[2], yaw])
                last = p
    return np.array(feet)


def _write_trajectory(path: str, names: Sequence[str], times: np.ndarray,
                      frames: np.ndarray) -> None:
    with open(path, 'w', newline='') as f:
        writer = csv.writer(f)
        writer.writerow(['time'] + list(names))
        for t, q in zip(times, frames):
            writer.writerow([f'{t:.4f}'] + [f'{v:.6f}' for v in q])


def read_trajectory(path: str):
    """Read a trajectory CSV written by ``simulate``: (names, times (k,), frames (k, 22))."""
    with open(path, newline='') as f:
        reader = csv.reader(f)
        header = next(reader)
        data = np.array([[float(v) for v in row] for row in reader])
    return tuple(header[1:]), data[:, 0], data[:, 1:]


def _share_dir() -> str:
    here = os.path.dirname(os.path.abspath(__file__))
    source = os.path.normpath(os.path.join(here, '..'))
    if os.path.isdir(os.path.join(source, 'config', 'scenes')):
        return source
    return os.path.join(sys.prefix, 'share', 'digital_actor_planner')


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog='digital-actor',
                                     description=__doc__.strip().splitlines()[0])
    sub = parser.add_subparsers(dest='command', required=True)
    sim = sub.add_parser('simulate', help='plan a whole course offline and write the trajectory')
    sim.add_argument('--scene', required=True, help='scene YAML or a bare mesh file')
    sim.add_argument('--commands', required=True, help='CSV time,linear_x,angular_z')
    sim.add_argument('--out', required=True,
                     help='trajectory CSV to write; a name ending in .mcap writes a rosbag2 bag '
                          '(MCAP storage) of /joint_states, the markers and the path instead')
    sim.add_argument('--summary', help='JSON summary to write')
    sim.add_argument('--render', help='PNG (key poses) or GIF (animation) to write')
    # No defaults here: unset, the settings' declared defaults (FootstepConfig, GaitConfig).
    sim.add_argument('--window-steps', type=int, help='n, footsteps per window')
    sim.add_argument('--step-intervals', type=int, help='m, step length intervals')
    sim.add_argument('--step-length-min', type=float, help='m')
    sim.add_argument('--step-length-max', type=float, help='m')
    sim.add_argument('--rate', type=float, help='frames per second')
    sim.add_argument('--no-upper-body', action='store_true',
                     help='keep the motion patterns, skip upper-body planning')
    sim.add_argument('--paper-search', action='store_true',
                     help="footstep search as in the paper's section 4.2 alone (breadth-first, "
                          'then hill-climbing), without the second climb from a greedy start')
    sub.add_parser('demo', help='the interactive demo (browser viewer + planner node)',
                   add_help=False)
    sub.add_parser('view', help='attach a browser viewer to a running planner', add_help=False)
    sub.add_parser('warm-up', help="compile the planner's kernels once (set-up does it)",
                   add_help=False)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == 'warm-up':
        from digital_actor_planner import warmup
        return warmup.main(argv[1:])
    if argv and argv[0] in ('demo', 'view'):
        if argv[0] == 'demo':
            from digital_actor_planner import demo
            return demo.main(argv[1:])
        from digital_actor_planner.nodes import viewer
        return viewer.main(argv[1:])
    args = build_parser().parse_args(argv)
    try:
        return simulate(args)
    except KeyboardInterrupt:
        print('digital-actor simulate: interrupted; no output was written or replaced',
              file=sys.stderr)
        return 130


if __name__ == '__main__':
    sys.exit(main())
