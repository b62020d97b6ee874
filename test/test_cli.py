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

"""`digital-actor simulate`: files in, trajectory/summary/pictures out, clear errors."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

from digital_actor_planner.cli import read_commands, read_trajectory
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest
import trimesh

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')


def run_cli(*args, cwd=None):
    env = dict(os.environ, MPLBACKEND='Agg')
    return subprocess.run([sys.executable, '-m', 'digital_actor_planner.cli', *args],
                          capture_output=True, text=True, cwd=cwd, env=env, timeout=600)


def write_commands(path, rows, header='time,linear_x,angular_z'):
    path.write_text(header + '\n' + '\n'.join(rows) + '\n')
    return str(path)


@pytest.fixture(scope='module')
def stairs_run(tmp_path_factory):
    out = tmp_path_factory.mktemp('stairs')
    args = ['simulate', '--scene', os.path.join(SCENES, 'stairs_up.yaml'),
            '--commands', os.path.join(SCENES, 'stairs_up.csv'),
            '--out', str(out / 'traj.csv'), '--summary', str(out / 'summary.json'),
            '--render', str(out / 'poses.png')]
    result = run_cli(*args)
    assert result.returncode == 0, result.stderr
    return out, args, result


def test_trajectory_csv_has_the_22_joints_at_100_hz(stairs_run):
    out, _, _ = stairs_run
    names, times, frames = read_trajectory(str(out / 'traj.csv'))
    assert names == Skeleton().joint_names
    assert frames.shape == (times.size, 22)
    np.testing.assert_allclose(np.diff(times), 0.01, atol=1e-6)
    assert np.all(np.isfinite(frames))
    assert frames[-1, 0] > 4.0 and frames[-1, 2] > 0.75 + 0.8  # up the stairs


def test_summary_reports_steps_timing_and_status(stairs_run):
    out, _, _ = stairs_run
    summary = json.loads((out / 'summary.json').read_text())
    assert summary['steps_taken'] == len(summary['planning_time_per_step']) > 5
    assert summary['step_categories']['uphill'] >= 2
    assert summary['real_time_factor'] > 1.0
    assert summary['final_status'] in ('walking', 'idle')
    assert summary['stuck_events'] == []


def test_render_writes_a_picture(stairs_run):
    out, _, _ = stairs_run
    from PIL import Image
    image = np.asarray(Image.open(out / 'poses.png').convert('RGB'), dtype=float)
    assert image.shape[0] > 300 and image.std() > 10


def test_same_inputs_give_the_same_trajectory(stairs_run, tmp_path):
    out, args, _ = stairs_run
    again = list(args)
    again[again.index('--out') + 1] = str(tmp_path / 'again.csv')
    again = again[:again.index('--summary')]
    assert run_cli(*again).returncode == 0
    assert (tmp_path / 'again.csv').read_text() == (out / 'traj.csv').read_text()


def test_wall_reports_stuck_in_the_summary(tmp_path):
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'wall.yaml'),
                     '--commands', os.path.join(SCENES, 'wall.csv'),
                     '--out', str(tmp_path / 't.csv'), '--summary', str(tmp_path / 's.json'))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / 's.json').read_text())
    assert summary['final_status'] == 'stuck'
    assert summary['stuck_events'] and 'footstep' in summary['stuck_events'][0]['reason']


def test_paper_search_reproduces_figure_8_with_a_one_step_window(tmp_path):
    """
    ``--paper-search`` runs the paper's footstep search alone.

    `--paper-search` runs the paper's footstep search alone (the summary says so): with one
    footstep in the window the actor steps into the Figure 8 pit and is stuck there.
    """
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'figure8_trap.yaml'),
                     '--commands', os.path.join(SCENES, 'figure8_trap.csv'),
                     '--out', str(tmp_path / 't.csv'), '--summary', str(tmp_path / 's.json'),
                     '--window-steps', '1', '--paper-search')
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / 's.json').read_text())
    assert summary['greedy_restart'] is False and summary['window_steps'] == 1
    assert summary['final_status'] == 'stuck' and summary['final_pose']['root_x'] < 2.6


def test_a_bare_mesh_file_is_a_scene(tmp_path):
    floor = trimesh.creation.box(extents=(8.0, 3.0, 0.2))
    floor.apply_translation((3.0, 0.0, -0.1))
    floor.export(tmp_path / 'floor.obj')
    commands = write_commands(tmp_path / 'c.csv', ['0,0.8,0', '3,0,0'])
    result = run_cli('simulate', '--scene', str(tmp_path / 'floor.obj'), '--commands', commands,
                     '--out', str(tmp_path / 't.csv'))
    assert result.returncode == 0, result.stderr
    _, _, frames = read_trajectory(str(tmp_path / 't.csv'))
    assert frames[-1, 0] > 1.0


def test_speeds_beyond_the_limits_are_clamped_with_a_warning(tmp_path):
    commands = write_commands(tmp_path / 'c.csv', ['0,5.0,0', '2,0,0'])
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'flat.yaml'), '--commands',
                     commands, '--out', str(tmp_path / 't.csv'))
    assert result.returncode == 0, result.stderr
    assert 'c.csv:2' in result.stderr and 'clamped' in result.stderr


@pytest.mark.parametrize('rows, header, expected', [
    (['0,0.8,0', '1,nan,0'], None, 'c.csv:3: non-finite'),
    (['0,0.8,0', '1,0.5'], None, 'c.csv:3: expected 3 values'),
    (['0,0.8,0', '1,fast,0'], None, 'c.csv:3: not a number'),
    (['1,0.8,0', '0.5,0,0'], None, 'c.csv:3: time 0.5'),
    (['0,0.8,0'], 'time,v,w', 'c.csv:1: header'),
    ([], None, 'no command rows'),
])
def test_bad_command_files_exit_2_naming_the_line(tmp_path, rows, header, expected):
    commands = write_commands(tmp_path / 'c.csv', rows, header or 'time,linear_x,angular_z')
    out = tmp_path / 't.csv'
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'flat.yaml'), '--commands',
                     commands, '--out', str(out))
    assert result.returncode == 2
    assert expected in result.stderr
    assert not out.exists()


@pytest.mark.parametrize('content, expected', [
    (None, 'missing.yaml'),
    ('meshes: [{file: nothing.stl}]\n', 'nothing.stl'),
    ('meshes: [{file: floor.obj, pose: [0, 0]}]\n', 'pose'),
    ('meshes: []\n', 'meshes'),
    ('start: [1, 2, 3]\nmeshes: [{file: floor.obj}]\nbogus: 1\n', 'bogus'),
    ('meshes: [{file: floor.obj}]\nstart: [40, 0, 0]\n', 'no ground'),
    ('meshes: [{file: floor.obj}, {file: block.obj}]\nstart: [0, 0, 0]\n', 'inside an obstacle'),
    ('meshes: [{file: nan.obj}]\n', 'nan.obj'),
])
def test_bad_scenes_exit_2_naming_the_problem(tmp_path, content, expected):
    floor = trimesh.creation.box(extents=(8.0, 3.0, 0.2))
    floor.apply_translation((3.0, 0.0, -0.1))
    floor.export(tmp_path / 'floor.obj')
    post = trimesh.creation.box(extents=(0.2, 0.2, 2.0))  # where the left arm hangs
    post.apply_translation((0.0, 0.3, 1.0))
    post.export(tmp_path / 'block.obj')
    (tmp_path / 'nan.obj').write_text('v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n')
    scene = tmp_path / ('missing.yaml' if content is None else 'scene.yaml')
    if content is not None:
        scene.write_text(content)
    commands = write_commands(tmp_path / 'c.csv', ['0,0.8,0', '1,0,0'])
    out = tmp_path / 't.csv'
    result = run_cli('simulate', '--scene', str(scene), '--commands', commands, '--out', str(out))
    assert result.returncode == 2, result.stdout + result.stderr
    assert expected in result.stderr
    assert not out.exists()


def test_read_commands_accepts_the_shipped_files():
    for name in os.listdir(SCENES):
        if name.endswith('.csv'):
            rows = read_commands(os.path.join(SCENES, name))
            assert rows[-1].linear_x == 0.0 and rows[-1].angular_z == 0.0


def test_trajectory_columns_are_in_csv_order(stairs_run):
    out, _, _ = stairs_run
    with open(out / 'traj.csv') as f:
        header = next(csv.reader(f))
    assert header[0] == 'time' and header[1:5] == ['root_x', 'root_y', 'root_z', 'root_yaw']


def _simulate_here(capsys, *args):
    """``digital-actor simulate`` in this process (the checks of its outputs come first)."""
    from digital_actor_planner import cli
    code = cli.main(['simulate', *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _short_run(tmp_path):
    return ['--scene', os.path.join(SCENES, 'flat.yaml'),
            '--commands', write_commands(tmp_path / 'c.csv', ['0,0.8,0', '1.5,0,0'])]


@pytest.mark.parametrize('option, name, expected', [
    ('--out', 'folder', 'is a directory'),
    ('--summary', 'folder', 'is a directory'),
    ('--render', 'folder', 'is a directory'),
    ('--render', 'x.bmp', 'writes .png or .gif, not .bmp'),
    ('--render', 'picture', 'not a file without an extension'),
    ('--out', 'plain.txt/t.csv', 'cannot write'),
    ('--summary', 'plain.txt/deeper/s.json', 'cannot write'),
    ('--out', 'c.csv', 'would overwrite the input'),
    ('--summary', 'old.csv', 'named for two outputs'),
    ('--out', 'bag.mcap', 'exists already'),
])
def test_bad_outputs_exit_2_before_planning_and_leave_everything_as_it_was(
        tmp_path, capsys, option, name, expected):
    (tmp_path / 'folder').mkdir()
    (tmp_path / 'bag.mcap').mkdir()
    (tmp_path / 'plain.txt').write_text('a file, not a folder\n')
    (tmp_path / 'old.csv').write_text('the previous trajectory\n')
    args = _short_run(tmp_path)
    outputs = {'--out': str(tmp_path / 'old.csv')}
    outputs[option] = str(tmp_path / name)
    before = sorted(os.listdir(tmp_path))
    code, _, err = _simulate_here(capsys, *args, *[a for o in outputs.items() for a in o])
    assert code == 2, err
    assert str(tmp_path / name) in err and expected in err
    assert 'Traceback' not in err
    assert sorted(os.listdir(tmp_path)) == before  # no hidden temporaries, nothing replaced
    assert (tmp_path / 'old.csv').read_text() == 'the previous trajectory\n'


def test_an_unwritable_out_is_refused_naming_it(tmp_path, capsys):
    target = '/proc/digital_actor_trajectory.csv'  # no one can create files there, root neither
    code, _, err = _simulate_here(capsys, *_short_run(tmp_path), '--out', target)
    assert code == 2 and target in err and 'cannot write' in err, err


def test_outputs_get_normal_modes_and_a_failed_render_replaces_nothing(
        tmp_path, capsys, monkeypatch):
    from digital_actor_planner.evaluation import render
    args = _short_run(tmp_path)
    (tmp_path / 's.json').write_text('{}')
    os.chmod(tmp_path / 's.json', 0o640)  # a file replaced keeps its mode
    old_umask = os.umask(0o022)
    try:
        code, out, err = _simulate_here(capsys, *args, '--out', str(tmp_path / 'new' / 't.csv'),
                                        '--summary', str(tmp_path / 's.json'))
    finally:
        os.umask(old_umask)
    assert code == 0, err
    assert os.stat(tmp_path / 'new' / 't.csv').st_mode & 0o777 == 0o644
    assert os.stat(tmp_path / 's.json').st_mode & 0o777 == 0o640
    trajectory = (tmp_path / 'new' / 't.csv').read_text()
    summary = (tmp_path / 's.json').read_text()
    # the picture fails after planning: the trajectory and summary are not replaced either

    def broken(*_, **__):
        raise OSError(28, 'No space left on device')
    monkeypatch.setattr(render, 'render_png', broken)
    before = sorted(os.listdir(tmp_path)), sorted(os.listdir(tmp_path / 'new'))
    code, _, err = _simulate_here(capsys, *args[:2], '--commands',
                                  write_commands(tmp_path / 'c.csv', ['0,0.5,0', '1,0,0']),
                                  '--out', str(tmp_path / 'new' / 't.csv'),
                                  '--summary', str(tmp_path / 's.json'),
                                  '--render', str(tmp_path / 'p.png'))
    assert code == 1 and 'No space left on device' in err and 'Traceback' not in err
    assert (sorted(os.listdir(tmp_path)), sorted(os.listdir(tmp_path / 'new'))) == before
    assert (tmp_path / 'new' / 't.csv').read_text() == trajectory
    assert (tmp_path / 's.json').read_text() == summary


def test_ctrl_c_during_a_run_leaves_no_temporary_files(tmp_path):
    (tmp_path / 't.csv').write_text('the previous trajectory\n')
    env = dict(os.environ, MPLBACKEND='Agg')
    process = subprocess.Popen(
        [sys.executable, '-m', 'digital_actor_planner.cli', 'simulate',
         '--scene', os.path.join(SCENES, 'stairs_up.yaml'),
         '--commands', os.path.join(SCENES, 'stairs_up.csv'), '--out', str(tmp_path / 't.csv'),
         '--render', str(tmp_path / 'walk.gif')],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 600
        # the outputs' temporaries appear once they are checked, before planning starts
        while not any(n.startswith('.') for n in os.listdir(tmp_path)):
            assert process.poll() is None and time.monotonic() < deadline, process.stderr.read()
            time.sleep(0.05)
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 130, err
    assert 'Traceback' not in err and 'interrupted' in err
    assert os.listdir(tmp_path) == ['t.csv']
    assert (tmp_path / 't.csv').read_text() == 'the previous trajectory\n'


def test_a_command_file_with_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / 'excel.csv'
    path.write_bytes(b'\xef\xbb\xbftime,linear_x,angular_z\r\n0,0.8,0\r\n2,0,0\r\n')
    rows = read_commands(str(path))
    assert [(r.time, r.linear_x, r.angular_z) for r in rows] == [(0, 0.8, 0), (2, 0, 0)]


def test_a_scene_that_is_a_directory_is_named_as_one(tmp_path, capsys):
    commands = write_commands(tmp_path / 'c.csv', ['0,0.8,0', '1,0,0'])
    code, _, err = _simulate_here(capsys, '--scene', str(tmp_path), '--commands', commands,
                                  '--out', str(tmp_path / 't.csv'))
    assert code == 2 and f'{tmp_path}: is a directory' in err, err


def test_ctrl_c_while_the_gif_is_written_leaves_the_old_outputs_alone(
        tmp_path, capsys, monkeypatch):
    from PIL import Image
    (tmp_path / 't.csv').write_text('the previous trajectory\n')
    (tmp_path / 'walk.gif').write_bytes(b'the previous animation')
    written = []

    def interrupted(image, target, *args, **kwargs):
        # Ctrl-C with half the animation on disk.
        with open(target, 'wb') as half:
            half.write(b'GIF89a')
        written.append(target)
        raise KeyboardInterrupt
    monkeypatch.setattr(Image.Image, 'save', interrupted)
    code, _, err = _simulate_here(capsys, *_short_run(tmp_path), '--out', str(tmp_path / 't.csv'),
                                  '--render', str(tmp_path / 'walk.gif'))
    assert written, 'the GIF was never written'
    assert code == 130 and 'interrupted' in err, err
    assert sorted(os.listdir(tmp_path)) == ['c.csv', 't.csv', 'walk.gif']
    assert (tmp_path / 't.csv').read_text() == 'the previous trajectory\n'
    assert (tmp_path / 'walk.gif').read_bytes() == b'the previous animation'
