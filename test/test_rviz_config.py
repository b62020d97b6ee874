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

"""config/actor.rviz shows the actor of the namespace RViz is started in, and only that one."""
import os
import re
import xml.etree.ElementTree as ElementTree

from digital_actor_planner.launch_support import (
    frame_prefix, rviz_config, rviz_topics, world_frame)
import pytest
import yaml

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(REPO, 'config', 'actor.rviz')


@pytest.fixture(scope='module')
def text():
    with open(CONFIG) as config:
        return config.read()


def test_every_topic_is_relative(text):
    topics = rviz_topics(yaml.safe_load(text))
    assert topics, 'no display topics found'
    assert [t for t in topics if t.startswith('/')] == []


def test_the_planner_topics_are_the_ones_the_node_publishes(text):
    with open(os.path.join(REPO, 'digital_actor_planner', 'nodes', 'actor_planner.py')) as node:
        private = set(re.findall(r"'~/(\w+)'", node.read()))
    shown = [t.split('/', 1)[1] for t in rviz_topics(yaml.safe_load(text))
             if t.startswith('actor_planner/')]
    assert shown and set(shown) <= private, (shown, private)
    assert 'robot_description' in rviz_topics(yaml.safe_load(text))


def test_the_fixed_frame_is_the_urdf_root(text):
    root = ElementTree.parse(os.path.join(REPO, 'urdf', 'digital_actor.urdf')).getroot()
    children = {j.find('child').get('link') for j in root.iter('joint')}
    (urdf_root,) = [link.get('name') for link in root.iter('link')
                    if link.get('name') not in children]
    fixed = yaml.safe_load(text)['Visualization Manager']['Global Options']['Fixed Frame']
    assert fixed == urdf_root == world_frame('')


def test_a_namespaced_copy_changes_only_the_frames(text):
    original = yaml.safe_load(text)
    copy = yaml.safe_load(rviz_config(text, '/actor1'))
    assert copy['Visualization Manager']['Global Options']['Fixed Frame'] == 'actor1/world'
    assert rviz_topics(copy) == rviz_topics(original)
    models = [d for d in copy['Visualization Manager']['Displays']
              if d['Class'] == 'rviz_default_plugins/RobotModel']
    assert [d['TF Prefix'] for d in models] == ['actor1']
    assert rviz_config(text, '') == text


def test_an_absolute_topic_is_refused(text):
    broken = text.replace('Value: actor_planner/path', 'Value: /actor_planner/path')
    with pytest.raises(ValueError, match='/actor_planner/path'):
        rviz_config(broken, 'actor1')


@pytest.mark.parametrize('namespace, prefix', [('', ''), ('/', ''), ('actor1', 'actor1/'),
                                               ('/actor1', 'actor1/'), ('/a/b/', 'a/b/')])
def test_frame_prefix(namespace, prefix):
    assert frame_prefix(namespace) == prefix


def test_frame_prefix_refuses_an_empty_component():
    with pytest.raises(ValueError, match='a//b'):
        frame_prefix('a//b')
