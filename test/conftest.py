# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""Shared fixtures: the real data beside the checkout, skipped cleanly when absent."""

from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[1].parent / 'shared' / 'data'


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
