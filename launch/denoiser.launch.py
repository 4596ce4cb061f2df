# Copyright 2026 denoise_imu_ros authors
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
"""Launch gyro_denoiser with config/gyro_denoiser.yaml; ``model`` and topics overridable."""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    """Describe the node, its parameter file and the remappable topics."""
    config = os.path.join(get_package_share_directory('denoise_imu_ros'), 'config',
                          'gyro_denoiser.yaml')
    return LaunchDescription([
        DeclareLaunchArgument('model', default_value='euroc',
                              description='shipped model name or .safetensors path'),
        DeclareLaunchArgument('input', default_value='imu/data_raw',
                              description='raw IMU topic'),
        DeclareLaunchArgument('use_sim_time', default_value='false'),
        Node(
            package='denoise_imu_ros',
            executable='gyro_denoiser',
            name='gyro_denoiser',
            parameters=[config, {'model': LaunchConfiguration('model'),
                                 'use_sim_time': LaunchConfiguration('use_sim_time')}],
            remappings=[('imu/data_raw', LaunchConfiguration('input'))],
            output='screen',
        ),
    ])
