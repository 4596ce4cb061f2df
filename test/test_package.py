# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""package.xml declares every ROS package the code imports (rosdep installs from it)."""

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
