# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Fixtures of every test: the real data (skipped cleanly when absent) and a model file.

Torch-free: the core, data and runtime tests run without torch. Under pytest-xdist each
worker runs on a core of its own.
"""

import os
from pathlib import Path

from helpers import DATA, write_untrained_model
import pytest


def pytest_configure(config: pytest.Config) -> None:
    """
    Give each pytest-xdist worker a core of its own, before torch is imported.

    Its trainings then take one thread and one process (``threads: auto``, ``workers:
    auto`` read the affinity), instead of every worker's threads and data-parallel
    processes contending for every core. Tests that ask for two processes still get them.
    """
    worker = os.environ.get('PYTEST_XDIST_WORKER')
    count = int(os.environ.get('PYTEST_XDIST_WORKER_COUNT', '1'))
    cores = sorted(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else []
    if worker and count > 1 and len(cores) >= count:
        share = len(cores) // count
        index = int(worker[2:])
        os.sched_setaffinity(0, cores[index * share:(index + 1) * share])


@pytest.fixture()
def model_file(tmp_path) -> Path:
    """Write an untrained but complete 200 Hz model file with residual std figures."""
    return write_untrained_model(tmp_path / 'model.safetensors', {
        'dataset': 'test', 'sample_rate_hz': 200.0,
        'validation': {'gyro_residual_std': [0.01, 0.02, 0.03]}})


@pytest.fixture()
def calib_file(tmp_path) -> Path:
    """Write an untrained 200 Hz calibration (the 12-parameter baseline) model file."""
    return write_untrained_model(tmp_path / 'calibrated.safetensors', {
        'dataset': 'test', 'sample_rate_hz': 200.0}, calibration_only=True)


@pytest.fixture(scope='session')
def data_dir() -> Path:
    """Return ../shared/data, or skip the test."""
    if not (DATA / 'euroc').is_dir():
        pytest.skip(f'real data not found at {DATA}')
    return DATA


@pytest.fixture(scope='session')
def euroc(data_dir: Path) -> Path:
    """Return the folder of the EuRoC ASL sequences."""
    return data_dir / 'euroc'
