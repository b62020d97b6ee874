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

"""The README a user reads: its parameter table is the node's declaration, its links resolve."""
import enum
import importlib.util
import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCUMENTS = ['README.md', 'CHANGELOG.md', 'config/scenes/README.md'] + [
    os.path.join('docs', name) for name in sorted(os.listdir(os.path.join(ROOT, 'docs')))
    if name.endswith('.md')]


def _parameter_table():
    spec = importlib.util.spec_from_file_location(
        'parameter_table', os.path.join(ROOT, 'scripts', 'parameter_table.py'))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _read(name):
    with open(os.path.join(ROOT, name), encoding='utf-8') as f:
        return f.read()


def test_readme_parameter_table_is_the_nodes_declaration():
    from digital_actor_planner.nodes.planner_params import parameter_declarations
    table = _parameter_table()
    readme = _read('README.md')
    expected = table.replace_table(readme, table.render_table(parameter_declarations()))
    assert readme == expected, (
        'README.md parameter table differs from nodes/planner_params.py; '
        'run: python scripts/parameter_table.py --write')


def test_every_declared_parameter_has_a_row_with_its_default():
    from digital_actor_planner.nodes.planner_params import parameter_declarations
    rows = {}
    for line in _read('README.md').splitlines():
        match = re.match(r'\| `(\w+)` \| (\w+(?:\[\])?) \| ([^|]+) \|', line)
        if match:
            rows[match.group(1)] = match.group(3).strip()
    for name, default, _ in parameter_declarations():
        assert name in rows, f'README has no row for parameter {name!r}'
        if isinstance(default, enum.Enum):
            assert rows[name] == 'unset', (name, rows[name])
        elif isinstance(default, bool):
            assert rows[name] == str(default).lower(), (name, rows[name])
        elif isinstance(default, (int, float)):
            assert float(rows[name]) == default, (name, rows[name])


def test_replacing_the_table_needs_its_markers():
    table = _parameter_table()
    try:
        table.replace_table('# no table here\n', '| a |\n')
    except ValueError as error:
        assert 'parameters' in str(error)
    else:
        raise AssertionError('a README without the markers was accepted')


def test_relative_links_and_pictures_point_at_files_in_the_repository():
    missing = []
    for name in DOCUMENTS:
        folder = os.path.dirname(os.path.join(ROOT, name))
        for target in re.findall(r'\]\(([^)\s]+)\)', _read(name)):
            if re.match(r'[a-z]+:', target) or target.startswith('#'):
                continue
            path = os.path.normpath(os.path.join(folder, target.split('#')[0]))
            if not path.startswith(ROOT + os.sep) or not os.path.exists(path):
                missing.append(f'{name}: {target}')
    assert not missing, missing


def test_readme_keeps_the_commands_ci_and_a_new_user_run():
    readme = _read('README.md')
    assert './quickstart.sh test' in readme
    assert './quickstart.sh demo' in readme
    with open(os.path.join(ROOT, '.ci', 'run'), encoding='utf-8') as f:
        assert './quickstart.sh test' in f.read()


def test_every_version_the_documents_name_is_the_pin():
    pins = dict(re.findall(r'^([A-Za-z0-9_.-]+)==(\S+)', _read('requirements.txt'), re.M))
    pins = {name.lower(): version for name, version in pins.items()}
    named, wrong = [], []
    for document in DOCUMENTS:
        if document == 'CHANGELOG.md':
            continue
        for name, version in re.findall(r'\b([A-Za-z][A-Za-z0-9_.-]*)==([0-9][^\s`)]*)',
                                        _read(document)):
            named.append(name)
            if pins.get(name.lower()) != version:
                wrong.append(f'{document}: {name}=={version}, pinned {pins.get(name.lower())}')
    assert 'viser' in named and 'trimesh' in named
    assert not wrong, wrong
