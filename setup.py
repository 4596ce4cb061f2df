# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Build denoise_imu_ros as an ament_python package, with its compiled streaming step."""

from glob import glob

from setuptools import Extension, find_packages, setup

package_name = 'denoise_imu_ros'

setup(
    name=package_name,
    version='0.5.0',
    packages=find_packages(exclude=['test']),
    # the streaming network's per-sample step in C (loaded with ctypes, no Python API);
    # optional: without a compiler the numpy step runs instead
    ext_modules=[Extension(package_name + '.pipeline._step',
                           sources=['denoise_imu_ros/pipeline/_step.c'],
                           extra_compile_args=['-O3', '-fopenmp-simd'], libraries=['m'],
                           optional=True),
                 # training's fused BatchNorm, GELU and dropout (learn/fused.py), optional
                 # too: without it training runs PyTorch's layers
                 Extension(package_name + '.learn._block',
                           sources=['denoise_imu_ros/learn/_block.c'],
                           # no trapping: its comparisons vectorise as blends without AVX-512
                           extra_compile_args=['-O3', '-fopenmp-simd', '-fno-trapping-math'],
                           libraries=['m'],
                           optional=True)],
    package_data={package_name: ['models/*.safetensors', 'sample/*/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
    ],
    install_requires=['setuptools'],
    zip_safe=False,
    maintainer='denoise_imu_ros developers',
    maintainer_email='dev@denoise-imu-ros.invalid',
    description='Learned gyroscope correction for open-loop attitude estimation.',
    license='Apache-2.0',
    extras_require={'test': ['pytest']},
    entry_points={
        'console_scripts': [
            'denoise-imu = denoise_imu_ros.cli:main',
            'gyro_denoiser = denoise_imu_ros.runtime.node:main',
        ],
    },
)
