# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
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
