# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""package.xml and the README declare everything the robot path imports (rosdep, pip)."""

import ast
from pathlib import Path
import re
import xml.etree.ElementTree as ET

ROOT = Path(__file__).resolve().parents[1]  # test/ is one level below the root
# ROS packages among the imports; everything else is pip/system Python
ROS_PACKAGES = {'rclpy', 'sensor_msgs', 'geometry_msgs', 'std_msgs', 'builtin_interfaces',
                'diagnostic_msgs', 'std_srvs', 'rcl_interfaces', 'rosgraph_msgs', 'launch',
                'launch_ros', 'ament_index_python'}


def test_every_imported_ros_package_is_an_exec_depend():
    declared = {e.text for e in ET.parse(ROOT / 'package.xml').getroot().iter('exec_depend')}
    imported = set()
    for path in [*ROOT.glob('denoise_imu_ros/**/*.py'), *ROOT.glob('launch/*.py')]:
        for name in re.findall(r'^\s*(?:from|import) (\w+)', path.read_text(), re.M):
            imported.add(name)
    assert imported & ROS_PACKAGES <= declared, sorted((imported & ROS_PACKAGES) - declared)
    assert {'rclpy', 'diagnostic_msgs', 'std_srvs', 'launch_ros'} <= imported


# the robot path's third-party modules: their rosdep keys, or none (pip, README's Install)
ROSDEP_KEYS = {'numpy': 'python3-numpy', 'scipy': 'python3-scipy', 'yaml': 'python3-yaml',
               'matplotlib': 'python3-matplotlib', 'tqdm': 'python3-tqdm',
               'rosbags': 'python3-rosbags-pip'}
PIP_ONLY = {'safetensors', 'vqf'}
ROBOT_ROOMS = ('core', 'data', 'runtime')  # the node, process-bag, play, check-data


def test_every_module_the_robot_path_imports_is_installed_by_rosdep_or_the_pip_line():
    import sys
    declared = {e.text for e in ET.parse(ROOT / 'package.xml').getroot().iter('exec_depend')}
    imported = set()
    for room in ROBOT_ROOMS:
        for path in (ROOT / 'denoise_imu_ros' / room).glob('*.py'):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    imported |= {a.name.split('.')[0] for a in node.names}
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    imported.add(node.module.split('.')[0])
    third = imported - ROS_PACKAGES - set(sys.stdlib_module_names)
    assert 'torch' not in third  # the robot path never needs it
    assert third <= set(ROSDEP_KEYS) | PIP_ONLY, sorted(third - set(ROSDEP_KEYS) - PIP_ONLY)
    assert {ROSDEP_KEYS[m] for m in third & set(ROSDEP_KEYS)} <= declared
    pip_line = re.search(r'^pip install (.*?)(?:#|$)', (ROOT / 'README.md').read_text(), re.M)
    assert pip_line and third & PIP_ONLY <= set(pip_line.group(1).split())
    assert 'python3-pytorch-pip' not in declared  # an unpinned CUDA torch on the robot
