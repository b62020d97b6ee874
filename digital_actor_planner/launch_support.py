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
ROS-free helpers of launch/actor.launch.py: frame names, required packages, the RViz config.

The launch file only adapts: it reads its arguments, asks these functions what to start and
with which names, and builds the actions. Kept here, in the package, so the rules are tested
without launch installed.

Two actors launched side by side in two namespaces share ``/tf`` (tf2 broadcasts on absolute
topics), so each one's TF frames carry its namespace as a prefix (``actor1/world``,
``actor1/pelvis``): robot_state_publisher's ``frame_prefix``, the planner's ``frame_id`` and
RViz's fixed frame and robot-model TF prefix all follow from :func:`frame_prefix`.
"""
from __future__ import annotations

import os
from typing import Callable, Dict, Iterable, List, Optional, Sequence

import yaml

#: mouse_teleop's ``frequency`` (Hz) in teleop_tools' own config: while a drag is held it
#: repeats the command at this rate. Its node default, 0, publishes only while the mouse
#: moves, so a held drag would fall silent and the planner's ``cmd_timeout`` stop the actor.
TELEOP_FREQUENCY = 10.0

#: The URDF's root link, the frame the planner's joint_states, markers and path are in.
WORLD_FRAME = 'world'

#: ROS packages whose executables actor.launch.py starts, by the launch argument that turns
#: each on (None: always started).
LAUNCHED_PACKAGES = (
    ('robot_state_publisher', None),
    ('rviz2', 'use_rviz'),
    ('mouse_teleop', 'use_teleop'),
)


class MissingPackageError(RuntimeError):
    """A ROS package the launch would start is not installed (the message says how to)."""


def frame_prefix(namespace: str) -> str:
    """
    Return the TF frame prefix for an actor in ``namespace``: ``'actor1/'``, or ``''`` at the root.

    Parameters
    ----------
    namespace : str
        ROS namespace as given to the launch (``'actor1'``, ``'/actor1'``, ``'/a/b/'``, ``''``).

    Returns
    -------
    str
        The namespace without its leading and trailing slashes, plus one ``/``; empty for the
        root namespace.

    """
    if not isinstance(namespace, str):
        raise ValueError(f'namespace must be a string, got {namespace!r}')
    name = namespace.strip().strip('/')
    if any(not part for part in name.split('/')) and name:
        raise ValueError(f'namespace {namespace!r} has an empty component')
    return f'{name}/' if name else ''


def world_frame(namespace: str) -> str:
    """Return the actor's fixed frame in ``namespace`` (``'actor1/world'``, or ``'world'``)."""
    return frame_prefix(namespace) + WORLD_FRAME


def is_true(value: str) -> bool:
    """
    Read a launch argument's text as a boolean, as launch's ``IfCondition`` reads it.

    Raises
    ------
    ValueError
        ``value`` is not one of ``true``, ``false``, ``1``, ``0`` (any case).

    """
    text = str(value).strip().lower()
    if text in ('true', '1'):
        return True
    if text in ('false', '0'):
        return False
    raise ValueError(f'expected true or false, got {value!r}')


def required_packages(arguments: Dict[str, str]) -> List[str]:
    """
    Return the ROS packages the launch starts executables from, given its arguments.

    Parameters
    ----------
    arguments : dict of str to str
        The launch arguments' values (``use_rviz``, ``use_teleop``; a missing one counts as
        true).

    Returns
    -------
    list of str
        Package names, in the order the launch starts them.

    """
    return [package for package, switch in LAUNCHED_PACKAGES
            if switch is None or switched_on(arguments, switch)]


def switched_on(arguments: Dict[str, str], name: str) -> bool:
    """
    Return launch argument ``name`` (true when absent) as a boolean.

    Raises
    ------
    ValueError
        Naming the argument, when its value is not true or false.

    """
    try:
        return is_true(arguments.get(name, 'true'))
    except ValueError as error:
        raise ValueError(f'launch argument {name}: {error}') from None


def install_hint(package: str, distribution: str = '') -> str:
    """How to install ROS ``package`` on a Debian/Ubuntu ROS install, in one line."""
    distribution = distribution or os.environ.get('ROS_DISTRO', '') or '<distro>'
    return f'sudo apt install ros-{distribution}-{package.replace("_", "-")}'


def check_packages(packages: Iterable[str], find: Callable[[str], str],
                   switches: Optional[Dict[str, str]] = None) -> None:
    """
    Raise :class:`MissingPackageError` naming every package ``find`` cannot locate.

    Parameters
    ----------
    packages : iterable of str
        ROS package names.
    find : callable
        ``ament_index_python.get_package_share_directory``: returns the package's share
        directory or raises (``PackageNotFoundError``, a ``KeyError``) when it is absent.
    switches : dict of str to str, optional
        Package -> the launch argument that turns it off, named in the message.

    Raises
    ------
    MissingPackageError
        Listing each missing package with the command that installs it.

    """
    switches = dict(switches or {})
    missing = []
    for package in packages:
        try:
            find(package)
        except (KeyError, LookupError, ValueError, OSError):
            missing.append(package)
    if not missing:
        return
    lines = []
    for package in missing:
        line = f'  {package}: {install_hint(package)}'
        if package in switches:
            line += f'  (or launch with {switches[package]}:=false)'
        lines.append(line)
    raise MissingPackageError(
        'not starting: ROS package(s) not found: ' + ', '.join(missing) + '\n' +
        '\n'.join(lines) + '\n  or, from the workspace: '
        'rosdep install --from-paths src --ignore-src -y')


def launched_package_switches() -> Dict[str, str]:
    """Package -> the launch argument that turns it off (the optional ones only)."""
    return {package: switch for package, switch in LAUNCHED_PACKAGES if switch is not None}


def rviz_config(text: str, namespace: str) -> str:
    """
    Make the RViz config ``text`` show the actor in ``namespace``.

    The shipped config's topics are relative, so RViz started in the namespace subscribes to
    that actor's; what a namespace changes is the TF frames: the fixed frame becomes the
    prefixed world frame and each RobotModel display looks its links up under the prefix.

    Parameters
    ----------
    text : str
        An RViz config (YAML) whose fixed frame is ``world``.
    namespace : str
        The actor's ROS namespace (``''``: the config is returned as it is).

    Returns
    -------
    str
        The config as YAML.

    Raises
    ------
    ValueError
        ``text`` is not an RViz config (no ``Visualization Manager``), or a display's topic is
        absolute (it would show another actor's data).

    """
    config = yaml.safe_load(text)
    if not isinstance(config, dict) or 'Visualization Manager' not in config:
        raise ValueError('not an RViz config: no "Visualization Manager" section')
    absolute = [topic for topic in rviz_topics(config) if topic.startswith('/')]
    if absolute:
        raise ValueError(f'RViz config subscribes to absolute topics {absolute}: '
                         'a namespaced actor needs relative ones')
    prefix = frame_prefix(namespace)
    if not prefix:
        return text
    manager = config['Visualization Manager']
    manager.setdefault('Global Options', {})['Fixed Frame'] = world_frame(namespace)
    for display in _displays(manager.get('Displays') or []):
        if display.get('Class') == 'rviz_default_plugins/RobotModel':
            # RViz joins the prefix and a link name with '/' itself.
            display['TF Prefix'] = prefix.rstrip('/')
    return yaml.safe_dump(config, default_flow_style=False, sort_keys=False)


def rviz_topics(config: dict) -> List[str]:
    """
    Every topic an RViz config's displays subscribe to (``Topic``/``Description Topic``).

    Parameters
    ----------
    config : dict
        The parsed RViz config.

    Returns
    -------
    list of str
        Topic names as written, in display order.

    """
    topics = []
    manager = config.get('Visualization Manager') or {}
    for display in _displays(manager.get('Displays') or []):
        for key in ('Topic', 'Description Topic'):
            value = display.get(key)
            if isinstance(value, dict):
                value = value.get('Value')
            if isinstance(value, str) and value:
                topics.append(value)
    return topics


def _displays(displays: Sequence[dict]) -> Iterable[dict]:
    """Every display, including those inside display groups."""
    for display in displays:
        if isinstance(display, dict):
            yield display
            yield from _displays(display.get('Displays') or [])
