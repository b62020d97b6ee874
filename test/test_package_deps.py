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
package.xml as rosdep reads it: every key resolves, and every import is declared.

One key rosdep cannot resolve and ``rosdep install --from-paths src --ignore-src`` installs
nothing, so each key must be a ROS package released for Jazzy and Kilted or a rosdep rule with
an Ubuntu and a Debian resolution. The rules are facts copied from rosdistro
(test/data/rosdep_keys.yaml). Imports are found by reading the package's and the tests' sources.
"""
import ast
import os
import re
import sys
import xml.etree.ElementTree as ElementTree

import pytest
import yaml

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SNAPSHOT = os.path.join(REPO, 'test', 'data', 'rosdep_keys.yaml')
DISTRIBUTIONS = ('jazzy', 'kilted')
# The platforms those distributions run on: Ubuntu 24.04 (Tier 1), Debian 12 (Jazzy, Tier 3).
PLATFORMS = (('ubuntu', 'noble'), ('debian', 'bookworm'))
DEPEND_TAGS = ('depend', 'build_depend', 'buildtool_depend', 'exec_depend', 'test_depend',
               'build_export_depend', 'doc_depend')

# Import name -> rosdep key. None: no rosdep key exists; package.xml must name the pip command
# in a comment, at the version requirements.txt pins.
MODULE_KEYS = {
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'yaml': 'python3-yaml',
    'trimesh': 'python3-trimesh-pip',
    'rosbags': 'python3-rosbags-pip',
    'fcl': 'python-fcl-pip',
    'numba': 'python3-numba',
    'matplotlib': 'python3-matplotlib',
    'PIL': 'python3-pil',
    'serial': 'python3-serial',
    'yourdfpy': 'python3-yourdfpy-pip',
    'pytest': 'python3-pytest',
    'viser': None,
    'msgspec': None,
}
# What trimesh does for the package only when these are installed (it imports them itself).
TRIMESH_BACKENDS = {
    'rtree': 'python3-rtree',      # ray queries: mesh.ray, mesh.contains (render, judge)
    'collada': 'python3-collada',  # .dae scenes
}
OPTIONAL_PIP = ('embreex',)  # faster ray queries than rtree; nothing fails without it
# Programs the tests run.
PROGRAMS = {'check_urdf': 'liburdfdom-tools', 'colcon': 'python3-colcon-common-extensions'}


@pytest.fixture(scope='module')
def snapshot():
    with open(SNAPSHOT) as data:
        return yaml.safe_load(data)


@pytest.fixture(scope='module')
def manifest():
    return ElementTree.parse(os.path.join(REPO, 'package.xml'))


def declared(manifest, tags=DEPEND_TAGS):
    return {element.text.strip() for tag in tags for element in manifest.getroot().iter(tag)}


def resolve(rule, family, codename):
    """Return what rosdep installs for ``rule`` on ``family``/``codename`` (None: nothing)."""
    entry = rule.get(family, rule.get('*'))
    if isinstance(entry, dict) and not set(entry) & {'pip', 'apt', 'source'}:
        entry = entry.get(codename, entry.get('*'))
    if isinstance(entry, dict):
        entry = next((entry[k] for k in ('apt', 'pip', 'source') if k in entry), None)
        entry = entry.get('packages') if isinstance(entry, dict) else entry
    return entry or None


def third_party_imports(folder):
    """
    Find the third-party modules imported by the sources under ``folder``.

    Top-level modules imported by the sources under ``folder``, outside the standard library and
    the project itself, with a file that imports each.
    """
    found = {}
    # The project's own: the package, and the test and bench modules the tests import.
    local = {'digital_actor_planner'} | {
        os.path.splitext(name)[0] for folder_name in ('test', 'bench')
        for _, _, names in os.walk(os.path.join(REPO, folder_name))
        for name in names if name.endswith('.py')}
    for root, _, files in os.walk(os.path.join(REPO, folder)):
        for name in files:
            if not name.endswith('.py') or 'node_modules' in root:
                continue
            path = os.path.join(root, name)
            with open(path) as source:
                tree = ast.parse(source.read(), path)
            for node in ast.walk(tree):
                modules = []
                if isinstance(node, ast.Import):
                    modules = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    modules = [node.module]
                elif isinstance(node, ast.Call) and getattr(node.func, 'attr', '') in (
                        'importorskip', 'import_module') and node.args and \
                        isinstance(node.args[0], ast.Constant):
                    modules = [node.args[0].value]
                for module in modules:
                    top = module.split('.')[0]
                    if top not in sys.stdlib_module_names and top not in local:
                        found.setdefault(top, os.path.relpath(path, REPO))
    return found


def test_every_key_resolves_for_jazzy_and_kilted_on_ubuntu_and_debian(manifest, snapshot):
    problems = []
    for key in sorted(declared(manifest)):
        if key in snapshot['rules']:
            for family, codename in PLATFORMS:
                if resolve(snapshot['rules'][key], family, codename) is None:
                    problems.append(f'{key}: rosdep installs nothing on {family} {codename}')
        elif any(key in snapshot['ros_packages'][d] for d in DISTRIBUTIONS):
            missing = [d for d in DISTRIBUTIONS if not snapshot['ros_packages'][d].get(key)]
            if missing:
                problems.append(f'{key}: no ROS package of that name in {missing}')
        else:
            problems.append(f'{key}: neither a rosdep rule nor a released ROS package in '
                            f'{os.path.relpath(SNAPSHOT, REPO)} (copy its entry from '
                            'rosdistro, or use the key rosdistro has)')
    assert not problems, '\n'.join(problems)


def test_the_snapshot_resolves_what_it_should():
    # The resolution rules themselves, on entries shaped as rosdistro writes them.
    assert resolve({'ubuntu': ['a']}, 'ubuntu', 'noble') == ['a']
    assert resolve({'ubuntu': {'*': ['a'], 'bionic': None}}, 'ubuntu', 'bionic') is None
    assert resolve({'debian': {'pip': {'packages': ['p']}}}, 'debian', 'bookworm') == ['p']
    assert resolve({'*': {'pip': {'packages': ['p']}}}, 'debian', 'bookworm') == ['p']
    assert resolve({'fedora': ['a']}, 'debian', 'bookworm') is None


def test_every_imported_module_of_the_package_is_declared(manifest):
    run = declared(manifest, ('depend', 'exec_depend'))
    imports = third_party_imports('digital_actor_planner')
    unknown = {m: path for m, path in imports.items() if m not in MODULE_KEYS and m not in run}
    assert not unknown, f'imports without a rosdep key in MODULE_KEYS or package.xml: {unknown}'
    undeclared = {m: MODULE_KEYS[m] for m in imports
                  if MODULE_KEYS.get(m) and MODULE_KEYS[m] not in run}
    assert not undeclared, f'imported but not an exec_depend: {undeclared}'
    missing_backends = {m: k for m, k in TRIMESH_BACKENDS.items() if k not in run}
    assert not missing_backends, missing_backends


def test_every_module_the_tests_import_is_declared(manifest):
    everything = declared(manifest)
    imports = third_party_imports('test')
    unknown = {m: path for m, path in imports.items()
               if MODULE_KEYS.get(m, m) not in everything and m not in OPTIONAL_PIP and
               MODULE_KEYS.get(m, m) is not None}
    assert not unknown, f'test imports not declared in package.xml: {unknown}'


def test_the_programs_the_tests_run_are_declared(manifest):
    everything = declared(manifest)
    sources = ''
    for name in os.listdir(os.path.join(REPO, 'test')):
        if name.endswith('.py'):
            with open(os.path.join(REPO, 'test', name)) as source:
                sources += source.read()
    used = {program: key for program, key in PROGRAMS.items()
            if re.search(rf"['\"]{program}['\"]", sources)}
    assert used, 'no program found in the tests: the scan is broken'
    assert {k for k in used.values() if k not in everything} == set()


def test_modules_without_a_key_are_named_with_their_pinned_pip_install(manifest):
    with open(os.path.join(REPO, 'package.xml')) as source:
        text = source.read()
    with open(os.path.join(REPO, 'requirements.txt')) as pins:
        pinned = dict(re.findall(r'^([A-Za-z0-9_.-]+)==(\S+)', pins.read(), re.M))
    for module in [m for m, key in MODULE_KEYS.items() if key is None] + list(OPTIONAL_PIP):
        assert f'pip install {module}=={pinned[module]}' in text, module


def test_no_test_dependency_without_a_test_that_uses_it(manifest):
    # ament_copyright, ament_pep257, launch_testing_ros: package.xml once named linters and
    # helpers no test here runs.
    tests = os.listdir(os.path.join(REPO, 'test'))
    for key in declared(manifest, ('test_depend',)):
        if key.startswith('ament_'):
            assert f'test_{key[len("ament_"):]}.py' in tests, key
    imports = third_party_imports('test')
    for key in declared(manifest, ('test_depend',)):
        if key.startswith('launch_testing'):
            assert key in imports, key
